//! Calibrating a controller before an experiment, as an operator would: on open ground
//! (the experiment's ground, its obstacles removed), through the daemon's loop, with
//! the `controller.calibrate` command (`ControllerCommand::Calibrate`). A controller
//! calibrates when its report has a `calibration` signal (0 none, 1 running,
//! 2 calibrated); directional compliance measures its friction offset per body section
//! and reports it in its `sections_lateral` / `sections_dorsal` fields (column
//! `offset`), which the experiment's trials then get as the `friction_offset` of their
//! configuration.

use serde_json::{Value, json};

use super::LabError;
use super::compared::LabController;
use super::trial::{TrialConfig, plant_of, trial_loop};
use crate::controller_interface::ControllerCommand;
use crate::emu::world::WorldSpec;
use crate::emu::world::physics::PhysicsPlant;
use crate::rt::control_loop::Flow;
use crate::rt::messages::LoopRequest;

/// How long a calibration measures, in nominal gait cycles (SPEC §8: "a few").
pub const CALIBRATION_CYCLES: f64 = 3.0;
/// Sensor-noise seed of the calibration run.
const CALIBRATION_SEED: u64 = 0xCA1;

/// What a calibration measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibrated {
    /// The controller with its configuration overridden by what was measured.
    pub controller: LabController,
    /// The `friction_offset` override.
    pub offsets: Value,
    /// Simulated seconds measured.
    pub seconds: f64,
}

/// `ground` without its obstacles, the snake straight at the origin.
pub fn open_ground(ground: &WorldSpec) -> WorldSpec {
    WorldSpec {
        pegs: Vec::new(),
        poles: Vec::new(),
        rocks: Vec::new(),
        walls: Vec::new(),
        start: WorldSpec::default().start,
        ..ground.clone()
    }
}

/// Calibrates `controller` on `ground`'s open ground if it calibrates (`None` if not).
pub fn calibrate(
    controller: &LabController,
    ground: &WorldSpec,
    config: &TrialConfig,
) -> Result<Option<Calibrated>, LabError> {
    let world = open_ground(ground);
    let physics = config.physics(CALIBRATION_SEED);
    let plant = PhysicsPlant::new(&world, physics).map_err(|source| LabError::Physics {
        trial: format!("calibration of {}", controller.label),
        source,
    })?;
    let omega = config.gaits.get(controller.gait).temporal_freq_rad_s.abs();
    let seconds = CALIBRATION_CYCLES * std::f64::consts::TAU / omega.max(1e-3);
    let request = LoopRequest::ControllerCommand {
        gait: controller.gait,
        command: ControllerCommand::Calibrate {
            duration_s: seconds,
        },
    };
    let (mut lp, names, _, _, _) = trial_loop(controller, plant, config, None, &[request])?;
    let Some(state) = names.iter().position(|n| n == "calibration") else {
        return Ok(None);
    };
    let (layout, _) = super::trial::slithering_setup(config.modules);
    let fields: Vec<String> = controller
        .build(&layout, config.gaits.get(controller.gait))?
        .info
        .report
        .fields
        .iter()
        .map(|f| f.name.clone())
        .collect();
    let field = |name: &str| fields.iter().position(|n| n == name);
    let (lateral, dorsal) = (field("sections_lateral"), field("sections_dorsal"));
    // The blend into the gait first (the controller measures only while it drives).
    let limit = seconds + 4.0 * config.blend_time_s + 10.0;
    let steps = (limit / config.dt_s).round() as usize;
    for _ in 0..steps {
        if lp.step() == Flow::Finished {
            break;
        }
        let Some((_, report)) = lp.controllers().report() else {
            continue;
        };
        if report.signals[state] != 2.0 {
            continue;
        }
        // The sections' `offset` column (the fourth); a plane without its field (planar:
        // no dorsal wave) gets zeros, one per section.
        let sections = lateral.map_or(0, |f| report.fields[f].len());
        let offsets_of = |f: Option<usize>| -> Vec<f64> {
            (0..sections)
                .map(|k| f.map_or(0.0, |f| report.fields[f].columns[3][k]))
                .map(|v| if v.is_finite() { v } else { 0.0 })
                .collect()
        };
        let offsets =
            json!({ "lateral_rad": offsets_of(lateral), "dorsal_rad": offsets_of(dorsal) });
        let mut c = controller.clone();
        let config = c.selection.config.get_or_insert_with(|| json!({}));
        crate::controller_interface::config::merge(config, &json!({ "friction_offset": offsets }));
        return Ok(Some(Calibrated {
            controller: c,
            offsets,
            seconds,
        }));
    }
    let t = plant_of(&lp).time_s();
    Err(LabError::BadValue(format!(
        "controller {}: the calibration did not finish in {t:.0} s on open ground",
        controller.label
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::GaitKind;

    #[test]
    fn a_directional_controller_is_calibrated_and_the_others_are_left_alone() {
        let config = TrialConfig {
            modules: 16,
            ..TrialConfig::default()
        };
        let ground = WorldSpec::default();
        let open = LabController::named(GaitKind::Slithering, "open_loop").unwrap();
        assert!(calibrate(&open, &ground, &config).unwrap().is_none());
        let dc = LabController::named(GaitKind::Slithering, "dc_switching").unwrap();
        let c = calibrate(&dc, &ground, &config)
            .unwrap()
            .expect("it calibrates");
        assert!((c.seconds - 3.0 * std::f64::consts::TAU).abs() < 1e-9);
        let lateral = c.offsets["lateral_rad"].as_array().unwrap();
        assert_eq!(lateral.len(), 3);
        // The ground's friction shifts the amplitude: measured, not zero.
        assert!(
            lateral.iter().any(|v| v.as_f64().unwrap().abs() > 1e-4),
            "{lateral:?}"
        );
        // The calibrated controller builds with its offsets.
        let (layout, params) = crate::lab::trial::slithering_setup(16);
        let built = c.controller.build(&layout, &params).unwrap();
        assert_eq!(built.info.config["friction_offset"], c.offsets);
    }
}
