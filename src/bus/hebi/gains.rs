//! Gains and control strategy for the modules, by role: `[hebi.gains.all]`, then
//! `[hebi.gains.lateral]` / `[hebi.gains.dorsal]` for the joints bending in that plane.
//! Names are hebi.h's command fields in snake case (`position_kp`, `effort_output_lowpass`,
//! ...); each is range-checked at `--check-config` and sent once at start-up.

use std::collections::BTreeMap;

use super::ffi::field::CMD_POSITION_KP;

/// A role's settings: gain name → value, and `control_strategy` (0 off, 1 direct PWM,
/// 2, 3, 4: HEBI's strategies).
pub type GainSet = BTreeMap<String, f64>;

const LOOPS: [&str; 3] = ["position", "velocity", "effort"];
/// Per loop, in hebi.h's order (PositionKp … PositionOutputLowpass, then velocity, effort).
const TERMS: [&str; 13] = [
    "kp",
    "ki",
    "kd",
    "feed_forward",
    "dead_zone",
    "i_clamp",
    "punch",
    "min_target",
    "max_target",
    "target_lowpass",
    "min_output",
    "max_output",
    "output_lowpass",
];

pub const STRATEGY: &str = "control_strategy";

/// The command float field of gain `name`, if it is one.
pub fn field_of(name: &str) -> Option<u32> {
    let (lp, term) = name.split_once('_')?;
    let l = LOOPS.iter().position(|x| *x == lp)?;
    let t = TERMS.iter().position(|x| *x == term)?;
    Some(CMD_POSITION_KP + (l * TERMS.len() + t) as u32)
}

/// Settings for one module, ready to write.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModuleSettings {
    pub strategy: Option<i32>,
    /// (command float field, value)
    pub floats: Vec<(u32, f32)>,
}

/// Why a gain set is refused: the key and the reason.
pub fn check(set: &GainSet) -> Result<(), (String, String)> {
    for (name, &v) in set {
        let bad = |why: &str| Err((name.clone(), format!("{} {why}", crate::num::Num(v))));
        if name == STRATEGY {
            if !(v.fract() == 0.0 && (0.0..=4.0).contains(&v)) {
                return bad("is not a HEBI control strategy (0 off, 1 direct PWM, 2, 3, 4)");
            }
            continue;
        }
        if field_of(name).is_none() {
            return Err((
                name.clone(),
                format!(
                    "is not a gain; the gains are {{position,velocity,effort}}_{{{}}} and {STRATEGY}",
                    TERMS.join(",")
                ),
            ));
        }
        if !v.is_finite() {
            return bad("is not a number");
        }
        let term = name.split_once('_').map_or("", |(_, t)| t);
        match term {
            "kp" | "ki" | "kd" | "dead_zone" | "i_clamp" | "punch" if v < 0.0 => {
                return bad("must be at least 0");
            }
            "feed_forward" if !(0.0..=1.0).contains(&v) => return bad("must be in [0, 1]"),
            "target_lowpass" | "output_lowpass" if !(v > 0.0 && v <= 1.0) => {
                return bad("must be in (0, 1] (1 = no filter)");
            }
            _ => {}
        }
    }
    for lp in LOOPS {
        for (lo, hi) in [("min_target", "max_target"), ("min_output", "max_output")] {
            let (a, b) = (format!("{lp}_{lo}"), format!("{lp}_{hi}"));
            if let (Some(x), Some(y)) = (set.get(&a), set.get(&b))
                && x > y
            {
                return Err((a, format!("{} is above {b} = {}", x, y)));
            }
        }
    }
    Ok(())
}

/// One module's settings: `all`, overridden by its role's.
pub fn merge(all: &GainSet, role: &GainSet) -> ModuleSettings {
    let mut s = ModuleSettings::default();
    for (name, &v) in all.iter().chain(role) {
        if name == STRATEGY {
            s.strategy = Some(v as i32);
        } else if let Some(f) = field_of(name) {
            s.floats.retain(|(g, _)| *g != f);
            s.floats.push((f, v as f32));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(kv: &[(&str, f64)]) -> GainSet {
        kv.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn names_map_to_hebi_h_fields() {
        assert_eq!(field_of("position_kp"), Some(2));
        assert_eq!(field_of("position_output_lowpass"), Some(14));
        assert_eq!(field_of("velocity_kp"), Some(15));
        assert_eq!(field_of("effort_kp"), Some(28));
        assert_eq!(field_of("effort_output_lowpass"), Some(40));
        assert_eq!(field_of("position_gain"), None);
        assert_eq!(field_of("kp"), None);
    }

    #[test]
    fn out_of_range_gains_are_refused_by_name() {
        assert!(check(&set(&[("position_kp", 5.0), (STRATEGY, 3.0)])).is_ok());
        for (k, v) in [
            ("position_kp", -1.0),
            ("velocity_kd", f64::NAN),
            ("effort_feed_forward", 1.5),
            ("position_target_lowpass", 0.0),
            (STRATEGY, 5.0),
            (STRATEGY, 2.5),
            ("position_kq", 1.0),
        ] {
            let (key, why) = check(&set(&[(k, v)])).unwrap_err();
            assert_eq!(key, k, "{why}");
        }
        let (key, _) = check(&set(&[
            ("effort_min_output", 2.0),
            ("effort_max_output", 1.0),
        ]))
        .unwrap_err();
        assert_eq!(key, "effort_min_output");
    }

    #[test]
    fn a_role_overrides_all() {
        let m = merge(
            &set(&[("position_kp", 5.0), (STRATEGY, 3.0)]),
            &set(&[("position_kp", 8.0), ("effort_kp", 0.2)]),
        );
        assert_eq!(m.strategy, Some(3));
        assert_eq!(m.floats, vec![(28, 0.2), (2, 8.0)]);
    }
}
