//! A protocol file: a world scenario with a `[protocol]` table saying how an experiment
//! runs on it (the gait's nominal parameters, layouts, starts, repeats, time limit), so
//! that an evaluated run is one named file, `scenarios/protocols/`, and the experiment's
//! default (`snake-lab peg-array`, `snake-lab rock-pile`). The rest of the file is a
//! world scenario as `docs/scenarios.md` describes. What the command line gives wins
//! over the protocol, the protocol over the experiment's built-in defaults.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::LabError;
use crate::emu::world::scenario::{ScenarioError, WorldScenario};
use crate::gait::ParamPatch;

/// A scenario's `[protocol]`: every key optional.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProtocolSpec {
    /// The experiment's gait's nominal parameters, a partial set as `params.set` takes
    /// them (`--nominal` patches them further).
    pub nominal: Option<ParamPatch>,
    /// Seeded layouts.
    pub layouts: Option<usize>,
    /// Starts (poses) per layout.
    pub starts: Option<usize>,
    /// Trials per start, differing only in their sensor-noise seed.
    pub repeats: Option<usize>,
    /// Time limit of a trial, simulated s.
    pub seconds: Option<f64>,
}

/// A protocol and the file it came from (for the summary and messages).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Protocol {
    pub spec: ProtocolSpec,
    /// The file, as given (a built-in one's path in the repository, "(built in)").
    pub source: String,
}

/// A scenario file's world and its protocol, if it has one. `source` names the file
/// in messages; `path` (a file read from disk) is where the world's relative paths
/// resolve (a built-in text has none: the current directory).
pub fn parse(
    text: &str,
    source: &str,
    path: Option<&Path>,
) -> Result<(WorldScenario, Option<Protocol>), LabError> {
    let parse_err = |e: toml::de::Error| {
        LabError::Scenario(ScenarioError::Parse {
            path: source.into(),
            source: e,
        })
    };
    let mut table: toml::Table = text.parse().map_err(parse_err)?;
    let Some(spec) = table.remove("protocol") else {
        let world = match path {
            Some(p) => WorldScenario::load(p)?,
            None => WorldScenario::parse(text)?,
        };
        return Ok((world, None));
    };
    let spec: ProtocolSpec = spec
        .try_into()
        .map_err(|e: toml::de::Error| LabError::BadValue(format!("{source}: [protocol]: {e}")))?;
    check(&spec, source)?;
    let mut world: WorldScenario = toml::Value::Table(table).try_into().map_err(parse_err)?;
    world.source = path.map(Path::to_path_buf);
    world.validate()?;
    Ok((
        world,
        Some(Protocol {
            spec,
            source: source.to_owned(),
        }),
    ))
}

/// Reads the scenario file at `path`: its world and its protocol, if it has one.
pub fn load(path: &Path) -> Result<(WorldScenario, Option<Protocol>), LabError> {
    let text = std::fs::read_to_string(path).map_err(|source| {
        LabError::Scenario(ScenarioError::Read {
            path: path.to_owned(),
            source,
        })
    })?;
    parse(&text, &path.display().to_string(), Some(path))
}

/// The counts a run refuses, refused when the file is read.
fn check(spec: &ProtocolSpec, source: &str) -> Result<(), LabError> {
    let bad = |msg: &str| LabError::BadValue(format!("{source}: [protocol]: {msg}"));
    if spec.layouts == Some(0) {
        return Err(bad("layouts must be at least 1"));
    }
    if spec.starts == Some(0) {
        return Err(bad("starts must be at least 1"));
    }
    if spec.repeats == Some(0) {
        return Err(bad("repeats must be at least 1"));
    }
    if let Some(s) = spec.seconds
        && !(s.is_finite() && s > 0.0)
    {
        return Err(bad(&format!("seconds must be positive, not {s}")));
    }
    Ok(())
}

impl Protocol {
    /// One line for a summary: the file the run's defaults came from.
    pub fn describe(&self) -> String {
        format!(
            "Protocol: `{}` (its nominal, layouts, starts, repeats and time limit, where \
             the command line gives none).",
            self.source
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WORLD: &str = "seed = 7\n[friction]\nmu = 0.5\n";

    #[test]
    fn a_protocol_table_is_read_apart_from_the_world() {
        let text = format!(
            "{WORLD}[protocol]\nnominal = {{ amplitude_lat_rad = 1.2 }}\nstarts = 5\nrepeats = 4\nseconds = 120\n"
        );
        let (world, p) = parse(&text, "x.toml", None).unwrap();
        assert_eq!(world.seed, 7);
        assert_eq!(world.friction.mu, 0.5);
        let p = p.unwrap();
        assert_eq!(p.spec.nominal.unwrap().amplitude_lat_rad, Some(1.2));
        assert_eq!(p.spec.starts, Some(5));
        assert_eq!(p.spec.repeats, Some(4));
        assert_eq!(p.spec.seconds, Some(120.0));
        assert_eq!(p.spec.layouts, None);
        assert!(p.describe().contains("`x.toml`"), "{}", p.describe());
        // Without one, the file is a plain world scenario.
        let (plain, none) = parse(WORLD, "y.toml", None).unwrap();
        assert!(none.is_none());
        assert_eq!(plain.seed, 7);
    }

    #[test]
    fn a_bad_protocol_names_the_file_and_the_key() {
        let err = |extra: &str| {
            parse(&format!("{WORLD}[protocol]\n{extra}\n"), "x.toml", None)
                .unwrap_err()
                .to_string()
        };
        let e = err("trials = 3");
        assert!(e.contains("x.toml") && e.contains("trials"), "{e}");
        let e = err("nominal = { amp = 1 }");
        assert!(e.contains("amp"), "{e}");
        let e = err("starts = 0");
        assert!(e.contains("starts must be at least 1"), "{e}");
        let e = err("seconds = -1");
        assert!(e.contains("seconds must be positive"), "{e}");
        // The world beside it is still checked as a world.
        let e = parse("[protocol]\n[oops]\n", "z.toml", None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("z.toml") && e.contains("oops"), "{e}");
    }
}
