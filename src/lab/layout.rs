//! A layout: one world scenario of an experiment, either its base scenario with the
//! master seed set to `seed_base + k` (new random obstacles and starts for each `k`) or
//! a scenario file given as is; and the seeds its trials derive from its identity.

use std::path::Path;

use super::LabError;
use crate::emu::world::scenario::WorldScenario;

/// One layout of an experiment.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Its name in the tables: `seed<N>` or the file's stem.
    pub name: String,
    pub scenario: WorldScenario,
    /// The world's identity, from which its trials' seeds derive (with the start and
    /// the repeat): never its place in a run's list, so the same world gets the same
    /// starts and noise in any run.
    pub identity: u64,
}

impl Layout {
    /// The board of `base` with master seed `seed`.
    pub fn seeded(base: &WorldScenario, seed: u64) -> Self {
        let mut scenario = base.clone();
        scenario.seed = seed;
        Self {
            name: format!("seed{seed}"),
            scenario,
            identity: seed,
        }
    }

    /// An explicit layout from a scenario file.
    pub fn from_file(path: &Path) -> Result<Self, LabError> {
        let scenario = WorldScenario::load(path)?;
        let name = path.file_stem().map_or_else(
            || path.display().to_string(),
            |s| s.to_string_lossy().into(),
        );
        let text = std::fs::read_to_string(path).map_err(|source| LabError::Io {
            path: path.to_owned(),
            source,
        })?;
        let identity = scenario_identity(&scenario, &text);
        Ok(Self {
            name,
            scenario,
            identity,
        })
    }
}

/// A scenario file's identity: its own `seed` if `text` sets one, otherwise a hash of
/// what it describes (not of its path, comments or layout), so two seedless files of
/// different worlds get different noise and one world under two names the same.
pub fn scenario_identity(scenario: &WorldScenario, text: &str) -> u64 {
    let sets_seed = text
        .parse::<toml::Table>()
        .is_ok_and(|t| t.contains_key("seed"));
    if sets_seed {
        scenario.seed
    } else {
        identity_of(
            serde_json::to_string(scenario)
                .unwrap_or_default()
                .as_bytes(),
        )
    }
}

/// A stable 64-bit identity of `bytes` (FNV-1a; the same on every machine and build).
pub fn identity_of(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xCBF2_9CE4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01B3)
    })
}

/// A sensor-noise seed for start `start` of the layout seeded `layout_seed`: the same
/// for every controller, so controllers meet the same noise (common random numbers).
pub fn trial_seed(layout_seed: u64, start: u64) -> u64 {
    // SplitMix64 finaliser of a combination: neighbouring inputs give unrelated seeds.
    let mut z = layout_seed
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(start.wrapping_mul(0xD1B5_4A32_D192_ED03));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The sensor-noise seed of a pose's repeat: repeat 0 keeps the seed a pose had before
/// repeats existed, so one-repeat experiments reproduce.
pub fn noise_seed(identity: u64, start: usize, repeat: usize) -> u64 {
    let seed = trial_seed(identity, start as u64);
    if repeat == 0 {
        seed
    } else {
        trial_seed(seed, repeat as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_files_identity_is_its_seed_or_what_it_describes() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            Layout::from_file(&p).unwrap().identity
        };
        let peg = "[[peg]]\nx_m = 0.5\ny_m = 0.0\ndiameter_m = 0.04\n";
        let other = "[[peg]]\nx_m = 0.7\ny_m = 0.0\ndiameter_m = 0.04\n";
        // Seedless: the world decides, not the name or the comments.
        let a = write("a.toml", peg);
        assert_eq!(a, write("b.toml", &format!("# the same world\n{peg}")));
        assert_ne!(a, write("c.toml", other));
        // A file that sets its seed is that seed, 0 included.
        assert_eq!(write("d.toml", &format!("seed = 0\n{peg}")), 0);
        assert_eq!(write("e.toml", &format!("seed = 42\n{other}")), 42);
        assert_eq!(
            Layout::seeded(&WorldScenario::default(), 1003).identity,
            1003
        );
    }

    #[test]
    fn trial_seeds_differ_by_layout_and_start() {
        let a = trial_seed(1000, 0);
        assert_eq!(a, trial_seed(1000, 0));
        assert_ne!(a, trial_seed(1000, 1));
        assert_ne!(a, trial_seed(1001, 0));
    }
}
