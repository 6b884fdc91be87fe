//! The emulator's model file (TOML): the model's parameters (servo, noise, first plane)
//! and, for the joint-space plant, scripted torques and obstacles. Not a world scenario
//! (`emu::world::scenario`, `scenarios/`): that one describes the world.
//! Every key is optional; `config/snake-emu.example.toml` documents them all.

use std::path::{Path, PathBuf};

use super::plant::{NoiseConfig, Obstacle, PlantConfig, ScriptedTorque};
use super::servo::ServoParams;
use crate::gait::Plane;

/// Contents of a model file.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ModelFile {
    /// Plane of joint 0 (`"lateral"` or `"dorsal"`); the others alternate.
    pub first_plane: Plane,
    /// Reported module temperature, °C.
    pub temperature_c: f32,
    /// Reported bus voltage, V.
    pub voltage_v: f32,
    pub servo: ServoParams,
    pub noise: NoiseConfig,
    /// `[[torque]]` tables: constant external torques.
    #[serde(rename = "torque")]
    pub torques: Vec<ScriptedTorque>,
    /// `[[obstacle]]` tables: one-sided springs.
    #[serde(rename = "obstacle")]
    pub obstacles: Vec<Obstacle>,
}

impl Default for ModelFile {
    fn default() -> Self {
        let p = PlantConfig::new(1);
        Self {
            first_plane: p.first_plane,
            temperature_c: p.temperature_c,
            voltage_v: p.voltage_v,
            servo: p.servo,
            noise: p.noise,
            torques: Vec::new(),
            obstacles: Vec::new(),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    #[error("model file {path}: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("model file {path}: {source}")]
    Parse {
        path: PathBuf,
        #[source]
        source: toml::de::Error,
    },
}

impl ModelFile {
    /// Read and parse `path` (unknown keys are errors).
    pub fn load(path: &Path) -> Result<Self, ModelFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| ModelFileError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text).map_err(|source| ModelFileError::Parse {
            path: path.to_owned(),
            source,
        })
    }

    pub fn parse(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// The plant this model file describes, for `modules` modules and noise `seed`.
    pub fn plant_config(&self, modules: usize, seed: u64) -> PlantConfig {
        PlantConfig {
            modules,
            first_plane: self.first_plane,
            servo: self.servo,
            noise: self.noise,
            seed,
            temperature_c: self.temperature_c,
            voltage_v: self.voltage_v,
            torques: self.torques.clone(),
            obstacles: self.obstacles.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::plant::ObstacleSide;

    #[test]
    fn empty_file_is_the_defaults() {
        assert_eq!(ModelFile::parse("").unwrap(), ModelFile::default());
    }

    #[test]
    fn a_full_model_file_parses() {
        let s = ModelFile::parse(
            r#"
            first_plane = "dorsal"
            voltage_v = 47.5
            [servo]
            spring_stiffness_nm_per_rad = 80.0
            [noise]
            encoder_rad = 0.0
            [[torque]]
            joint = 3
            torque_nm = -1.5
            start_s = 2.0
            end_s = 4.0
            [[obstacle]]
            joint = 5
            angle_rad = 0.3
            side = "negative"
            "#,
        )
        .unwrap();
        assert_eq!(s.first_plane, Plane::Dorsal);
        assert_eq!(s.servo.spring_stiffness_nm_per_rad, 80.0);
        assert_eq!(s.servo.max_torque_nm, 7.0);
        assert_eq!(s.noise.encoder_rad, 0.0);
        assert_eq!(s.torques[0].joint, 3);
        assert_eq!(s.obstacles[0].side, ObstacleSide::Negative);
        assert_eq!(s.obstacles[0].stiffness_nm_per_rad, 50.0);
        let p = s.plant_config(18, 9);
        assert_eq!((p.modules, p.seed, p.voltage_v), (18, 9, 47.5));
    }

    #[test]
    fn unknown_keys_are_errors_naming_the_file() {
        assert!(ModelFile::parse("stiffness = 3").is_err());
        assert!(ModelFile::parse("[servo]\nstifness = 3").is_err());
        assert!(ModelFile::parse("[[obstacle]]\njoint = 1\nangle_rad = 0\nside = \"up\"").is_err());
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, "[noise]\nfoo = 1\n").unwrap();
        let msg = ModelFile::load(&path).unwrap_err().to_string();
        assert!(msg.contains("bad.toml") && msg.contains("foo"), "{msg}");
        let missing = ModelFile::load(&dir.path().join("none.toml"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("none.toml"), "{missing}");
    }

    #[test]
    fn example_config_parses() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/snake-emu.example.toml");
        let s = ModelFile::load(&path).unwrap();
        crate::emu::plant::JointSpacePlant::new(s.plant_config(18, 0)).unwrap();
    }
}
