//! The directional-compliance paper's experiments (reference 001 §IV, SPEC §8): a
//! controller runs for a fixed time from a pose (position and heading) among the
//! obstacles, or until its body's centre leaves them ([`field::FieldEdge`]), and is
//! scored by how far that centre was displaced, in body lengths per minute. Two terrains: the planar peg array and the rock pile
//! (3-D). Every pose is run several times, the trials differing only in their
//! sensor-noise seed (the paper: 5 poses × 4 trials). Definitions: docs/lab.md.

pub mod field;
pub mod metrics;
pub mod plots;
pub mod report;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::emu::world::WorldSpec;
use crate::gait::{GaitKind, GaitParams};
use crate::lab::LabError;
use crate::lab::experiment::{About, Defaults, Experiment};
use crate::lab::file_stem;
use crate::lab::layout::Layout;
use crate::lab::protocol::{self, Protocol};
use crate::lab::report::SummaryContext;
use crate::lab::runner::TrialResult;
use crate::lab::trial::{TrialConfig, TrialRecord};
use crate::module::MODULE_LENGTH_M;
pub use field::FieldEdge;
use metrics::{DisplacementMetrics, displacement_metrics};

/// The peg array's protocol, the one directional compliance is evaluated with
/// (`scenarios/protocols/peg-array.toml`: the world, the nominal, the poses and trials),
/// built in.
pub const PEG_ARRAY_TOML: &str = include_str!("../../../scenarios/protocols/peg-array.toml");
/// The rock pile's protocol (`scenarios/protocols/rock-pile.toml`), built in.
pub const ROCK_PILE_TOML: &str = include_str!("../../../scenarios/protocols/rock-pile.toml");

/// The paper's robot: sixteen modules.
pub const MODULES: usize = 16;

/// Which of the paper's environments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Terrain {
    /// Planar: the lateral wave only, three windows (odd modules active).
    PegArray,
    /// Three-dimensional: a dorsal and a lateral wave, three windows per plane.
    RockPile,
}

/// The experiment of one terrain.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Displacement {
    pub terrain: Terrain,
    /// The protocol of its scenario (the built-in one's unless `--scenario` names a
    /// file without one).
    #[serde(default)]
    pub protocol: Option<Protocol>,
    /// The nominal parameters of the trials' gait, once final (for the summary).
    #[serde(default)]
    pub nominal: Option<GaitParams>,
}

/// Their own options: which layouts, and the body. The defaults are the protocol
/// directional compliance is evaluated with (`scenarios/protocols/`): the paper's one
/// layout, 5 random poses, 4 trials per pose, 2 minutes each, on the evaluated world
/// with its nominal.
#[derive(Debug, Clone, clap::Args)]
pub struct DisplacementArgs {
    /// Seeded layouts: the scenario with master seeds seed-base .. seed-base + N - 1
    /// (default: the scenario's protocol's, else 1).
    #[arg(long)]
    pub layouts: Option<usize>,
    /// Master seed of the first layout (default: the scenario's own).
    #[arg(long)]
    pub seed_base: Option<u64>,
    /// The scenario the layouts come from: a world scenario, or a protocol file (a
    /// world with a [protocol] table: nominal, layouts, starts, repeats, seconds;
    /// docs/lab.md). Default: the built-in scenarios/protocols/peg-array.toml or
    /// scenarios/protocols/rock-pile.toml.
    #[arg(long, value_name = "FILE")]
    pub scenario: Option<PathBuf>,
    /// Modules of the snake (the paper's robot has 16).
    #[arg(long, default_value_t = MODULES)]
    pub modules: usize,
}

/// The paper's four controllers on each terrain, in its order.
pub const PEG_ARRAY_CONTROLLERS: &[&str] = &["dc_nc", "dc_ndc", "dc_pdc", "dc_switching"];
pub const ROCK_PILE_CONTROLLERS: &[&str] = &["dc3d_nc", "dc3d_ndc", "dc3d_pdc", "dc3d_switching"];

impl Displacement {
    pub const PEG_ARRAY: Displacement = Displacement {
        terrain: Terrain::PegArray,
        protocol: None,
        nominal: None,
    };
    pub const ROCK_PILE: Displacement = Displacement {
        terrain: Terrain::RockPile,
        protocol: None,
        nominal: None,
    };

    /// The terrain's built-in protocol file.
    pub fn scenario_toml(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => PEG_ARRAY_TOML,
            Terrain::RockPile => ROCK_PILE_TOML,
        }
    }

    /// Where the built-in protocol file is in the repository, as the summary names it.
    pub fn scenario_name(&self) -> &'static str {
        match self.terrain {
            Terrain::PegArray => "scenarios/protocols/peg-array.toml",
            Terrain::RockPile => "scenarios/protocols/rock-pile.toml",
        }
    }
}

impl Experiment for Displacement {
    type Goal = FieldEdge;
    type Metrics = DisplacementMetrics;
    type Args = DisplacementArgs;

    fn about(&self) -> About {
        // The built-in protocols' defaults (a unit test checks they agree).
        let defaults = Defaults {
            starts: 5,
            repeats: 4,
            seconds: 120.0,
        };
        match self.terrain {
            Terrain::PegArray => About {
                name: "peg-array",
                summary: "directional compliance on a planar peg array (SPEC §8): body lengths \
                          per minute",
                title: "Directional compliance on the peg array (SPEC §8, planar)",
                gait: GaitKind::Slithering,
                controllers: PEG_ARRAY_CONTROLLERS,
                any_gait: false,
                variant_base: "dc_switching",
                defaults,
            },
            Terrain::RockPile => About {
                name: "rock-pile",
                summary: "directional compliance in 3-D over a rock pile (SPEC §8): body \
                          lengths per minute",
                title: "Directional compliance on the rock pile (SPEC §8, 3-D)",
                gait: GaitKind::Slithering,
                controllers: ROCK_PILE_CONTROLLERS,
                any_gait: false,
                variant_base: "dc3d_switching",
                defaults,
            },
        }
    }

    fn protocol(&self) -> Option<&Protocol> {
        self.protocol.as_ref()
    }
    fn with_trial(mut self, trial: &TrialConfig) -> Self {
        self.nominal = Some(*trial.gaits.get(self.gait()));
        self
    }

    fn configure(
        &self,
        args: &DisplacementArgs,
        trial: &mut TrialConfig,
    ) -> Result<(Self, Vec<Layout>), LabError> {
        if !(2..=64).contains(&args.modules) {
            return Err(LabError::BadValue(format!(
                "--modules must be 2 ..= 64, not {}",
                args.modules
            )));
        }
        trial.modules = args.modules;
        let (base, protocol) = match &args.scenario {
            Some(path) => protocol::load(path)?,
            None => {
                let name = format!("{} (built in)", self.scenario_name());
                protocol::parse(self.scenario_toml(), &name, None)?
            }
        };
        let count = args
            .layouts
            .or(protocol.as_ref().and_then(|p| p.spec.layouts))
            .unwrap_or(1);
        let seed_base = args.seed_base.unwrap_or(base.seed);
        let layouts = (0..count as u64)
            .map(|k| Layout::seeded(&base, seed_base.wrapping_add(k)))
            .collect();
        let configured = Displacement {
            terrain: self.terrain,
            protocol,
            nominal: None,
        };
        Ok((configured, layouts))
    }

    fn world(
        &self,
        layout: &Layout,
        modules: usize,
        start: u64,
    ) -> Result<(WorldSpec, FieldEdge), LabError> {
        let world = layout.scenario.generate_trial(modules, start)?;
        let edge = FieldEdge::of(&world);
        Ok((world, edge))
    }

    fn metrics(&self, _goal: &FieldEdge, rec: &TrialRecord) -> DisplacementMetrics {
        let modules = rec.start_links_m.len().saturating_sub(1).max(1);
        displacement_metrics(rec, modules as f64 * MODULE_LENGTH_M)
    }

    fn csv_keys(&self) -> [&'static str; 4] {
        ["controller", "layout", "pose", "repeat"]
    }
    fn csv_header(&self) -> &'static str {
        report::CSV_HEADER
    }
    fn csv_row(&self, result: &TrialResult<Self>) -> String {
        report::csv_row(result)
    }
    fn summary_tables(&self, results: &[TrialResult<Self>], _ctx: &SummaryContext) -> String {
        let mut s = String::new();
        if let Some(p) = &self.protocol {
            let _ = writeln!(s, "{}\n", p.describe());
        }
        if let Some(n) = &self.nominal {
            let _ = writeln!(
                s,
                "Nominal {} parameters of every trial: amplitude_lat_rad {}, \
                 amplitude_dor_rad {}, spatial_freq_rad {}, temporal_freq_rad_s {}.\n",
                self.gait().name(),
                n.amplitude_lat_rad,
                n.amplitude_dor_rad,
                n.spatial_freq_rad,
                n.temporal_freq_rad_s
            );
        }
        s.push_str(&report::summary_tables(results));
        s
    }
    fn trial_plots(
        &self,
        dir: &Path,
        r: &TrialResult<Self>,
        (world, _, rec): (&WorldSpec, &FieldEdge, &TrialRecord),
    ) -> Result<Vec<PathBuf>, LabError> {
        use crate::lab::plots::{path_plot, signals_plot};
        let stem = file_stem(&r.controller);
        let title = format!("{}: layout {}, pose {}", r.controller, r.layout, r.start);
        let path = dir.join(format!("path-{stem}.png"));
        path_plot(&path, &title, world, None, rec)?;
        let signals = dir.join(format!("signals-{stem}.png"));
        signals_plot(&signals, &title, rec)?;
        let absitions = dir.join(format!("absitions-{stem}.png"));
        plots::absition_plot(&absitions, &title, rec)?;
        Ok(vec![path, signals, absitions])
    }
    fn run_plots(
        &self,
        dir: &Path,
        results: &[TrialResult<Self>],
    ) -> Result<Vec<PathBuf>, LabError> {
        let p = dir.join("velocity.png");
        let title = format!(
            "{}: velocity per pose (black) and overall (red, ± sd)",
            self.name()
        );
        plots::velocity_plot(&p, &title, results)?;
        Ok(vec![p])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_the_evaluated_protocol() {
        for e in [Displacement::PEG_ARRAY, Displacement::ROCK_PILE] {
            let (world, p) = protocol::parse(e.scenario_toml(), e.scenario_name(), None).unwrap();
            let p = p.expect("the built-in scenario is a protocol");
            let d = e.defaults();
            assert_eq!(p.spec.layouts, Some(1));
            assert_eq!(p.spec.starts, Some(d.starts));
            assert_eq!(p.spec.repeats, Some(d.repeats));
            assert_eq!(p.spec.seconds, Some(d.seconds));
            // The nominal of docs/lab-results/dc-corrected/*-protocol.
            let n = p.spec.nominal.unwrap();
            assert_eq!(n.amplitude_lat_rad, Some(1.2));
            assert_eq!(n.spatial_freq_rad, Some(std::f64::consts::TAU));
            let mut args = DisplacementArgs {
                layouts: None,
                seed_base: None,
                scenario: None,
                modules: MODULES,
            };
            let mut trial = TrialConfig::default();
            let (configured, layouts) = e.configure(&args, &mut trial).unwrap();
            assert_eq!(configured.protocol.map(|c| c.spec), Some(p.spec));
            assert_eq!(layouts.len(), 1);
            assert_eq!(layouts[0].scenario.seed, world.seed);
            args.layouts = Some(3);
            assert_eq!(e.configure(&args, &mut trial).unwrap().1.len(), 3);
        }
        // The peg array's world is the one the evaluation ran on (smooth pegs).
        let evaluated =
            include_str!("../../../docs/lab-results/peg-array-sleeve/peg-array-sleeve.toml");
        let (world, _) = protocol::parse(PEG_ARRAY_TOML, "built in", None).unwrap();
        assert_eq!(world, world_of(evaluated));
        let (world, _) = protocol::parse(ROCK_PILE_TOML, "built in", None).unwrap();
        let rocks = include_str!("../../../scenarios/rock-pile-3d.toml");
        assert_eq!(world, world_of(rocks));
    }

    fn world_of(text: &str) -> crate::emu::world::scenario::WorldScenario {
        crate::emu::world::scenario::WorldScenario::parse(text).unwrap()
    }
}
