//! Every experiment `snake-lab` runs, in `snake-lab list` order. A new experiment is a
//! folder under `lab/` implementing [`crate::lab::experiment::Experiment`] and one line
//! here.

use std::fmt::Write as _;

use super::cli::{Lab, Plugin};
use super::compared::NAVIGATORS;
use super::crossing::Crossing;
use super::displacement::Displacement;
use super::pegboard::Pegboard;
use super::pole::PoleClimb;
use super::sidewinding::SidewindingPegs;
use crate::controller_interface::registry::known_names;
use crate::controllers::REGISTRY;
use crate::gait::GaitKind;

/// The experiments, each as its unconfigured value.
pub static EXPERIMENTS: &[&dyn Lab] = &[
    &Plugin(Pegboard::UNCONFIGURED),
    &Plugin(Displacement::PEG_ARRAY),
    &Plugin(Displacement::ROCK_PILE),
    &Plugin(SidewindingPegs),
    &Plugin(PoleClimb::UNCONFIGURED),
    &Plugin(super::flat_ground::FlatGround::UNCONFIGURED),
    &Plugin(Crossing::UNCONFIGURED),
];

/// The experiment named `name`.
pub fn find(name: &str) -> Option<&'static dyn Lab> {
    EXPERIMENTS.iter().copied().find(|e| e.name() == name)
}

/// What `snake-lab list` says of experiment `e`: its name and summary, the controllers
/// it compares by default, every other name `--controllers` takes (the navigator's
/// where it compares gaits; every gait's controllers where it runs any), and what a
/// `--variant` overrides.
pub fn describe(e: &dyn Lab) -> String {
    let mut s = format!("{}: {}\n", e.name(), e.summary());
    let _ = writeln!(s, "  default: {}", e.controllers().join(", "));
    let gait_option = e
        .command()
        .get_arguments()
        .any(|a| a.get_id().as_str() == "gait");
    // In the order a name resolves (`LabController::named_any`): its own gait first.
    let every_gait = |s: &mut String| {
        let others = GaitKind::ALL.into_iter().filter(|&g| g != e.gait());
        for g in std::iter::once(e.gait()).chain(others) {
            let names = names_of(g);
            if !names.is_empty() {
                let _ = writeln!(s, "    {}: {names}", g.name());
            }
        }
    };
    if e.any_gait() {
        let _ = writeln!(
            s,
            "  navigator: {} (switches gaits and controllers itself, docs/navigation.md)",
            NAVIGATORS.join(", ")
        );
        let _ = writeln!(
            s,
            "  controllers of any gait (a name runs in the first gait below that has it):"
        );
        every_gait(&mut s);
    } else if gait_option {
        let _ = writeln!(
            s,
            "  controllers of the gait --gait names (default {}):",
            e.gait().name()
        );
        every_gait(&mut s);
    } else {
        let _ = writeln!(
            s,
            "  controllers ({}): {}",
            e.gait().name(),
            names_of(e.gait())
        );
    }
    let _ = writeln!(
        s,
        "  --variant LABEL=JSON: over {} unless its JSON names another{}",
        e.variant_base(),
        if e.any_gait() {
            " (of any gait, or the navigator)"
        } else {
            ""
        }
    );
    s
}

/// The controllers and presets of `gait`, each once, in the registry's order.
fn names_of(gait: GaitKind) -> String {
    let all = known_names(REGISTRY, gait);
    let mut seen = std::collections::HashSet::new();
    all.split(", ")
        .filter(|n| seen.insert(*n))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listing_names_what_each_experiment_can_run() {
        let crossing = describe(find("crossing").unwrap());
        assert!(
            crossing
                .contains("  navigator: navigator, navigator_sidewind_only, navigator_turn_only"),
            "{crossing}"
        );
        assert!(crossing.contains("    sidewinding: "), "{crossing}");
        assert!(
            crossing.contains("  default: open_loop, a_ws_omega, dc_switching, ac_sfc\n"),
            "{crossing}"
        );
        let pegs = describe(find("peg-array").unwrap());
        assert!(!pegs.contains("navigator"), "{pegs}");
        assert!(
            pegs.contains("  default: dc_nc, dc_ndc, dc_pdc, dc_switching\n"),
            "{pegs}"
        );
        assert!(pegs.contains("dc_full_switching"), "{pegs}");
        assert!(pegs.contains("over dc_switching"), "{pegs}");
        let flat = describe(find("flat-ground").unwrap());
        assert!(flat.contains("--gait"), "{flat}");
        assert!(flat.contains("    rolling: "), "{flat}");
        // The navigator's names run where it is listed.
        for n in NAVIGATORS {
            let c = crate::lab::compared::LabController::named_any(GaitKind::Slithering, n);
            assert!(c.unwrap().navigator.is_some(), "{n}");
        }
    }
}
