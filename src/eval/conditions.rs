//! Evaluation under perturbed conditions: `grasp eval --perturb FILE`.
//!
//! By default an evaluation judges every agent on unrandomised objects and sensors, its
//! hand placed as `--pregrasp` says (see [`crate::checkpoint::checkpoint_setup`]). A conditions file
//! instead applies, to every agent alike, a training config's start-pose perturbations
//! (`[placement]`, the schema of `[env.placement]`) and object and sensor randomisation
//! (`[randomization]`, the schema of `[env.randomization]`):
//!
//! ```toml
//! [placement]            # e.g. a camera-arm calibration error
//! offset = 0.01
//! height = 0.005
//! yaw = 0.02
//! [randomization]        # e.g. unknown mass and friction
//! enabled = true
//! size_scale = [1.0, 1.0]
//! yaw = 0.0
//! ```
//!
//! Each draw comes from the episode's seed (the placement from a generator of its own), so
//! every agent meets the same perturbations trial by trial and the paired tests stay
//! paired.

use crate::env::grasp::EnvConfig;
use crate::env::placement::PlacementConfig;
use crate::env::randomize::Randomization;
use crate::util::config::{load_toml, ConfigError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Perturbations applied to every agent of an evaluation.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EvalConditions {
    /// Where episodes start the hand (as `[env.placement]`).
    pub placement: PlacementConfig,
    /// Object and sensor randomisation (as `[env.randomization]`; off unless `enabled`).
    pub randomization: Randomization,
}

/// A conditions file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ConditionsError {
    /// Unreadable or malformed TOML.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A value out of its range.
    #[error("conditions {path}: `{field}` {message}")]
    Value {
        /// The conditions file.
        path: PathBuf,
        /// The offending field (`placement.offset`, `randomization.friction`, ...).
        field: String,
        /// What is wrong.
        message: String,
    },
}

impl EvalConditions {
    /// Reads and checks the conditions file at `path`.
    pub fn load(path: &Path) -> Result<EvalConditions, ConditionsError> {
        let c: EvalConditions = load_toml(path)?;
        c.validate(path)?;
        Ok(c)
    }

    /// Checks every value's range (the training config's rules).
    pub fn validate(&self, path: &Path) -> Result<(), ConditionsError> {
        let bad = |(field, message): (&str, String)| ConditionsError::Value {
            path: path.to_path_buf(),
            field: field.trim_start_matches("env.").to_string(),
            message,
        };
        self.placement.validate().map_err(bad)?;
        self.randomization.validate().map_err(bad)?;
        // A conditions file is read to perturb: ranges set under `enabled = false` (the
        // default) would leave every trial unperturbed while the results record them.
        let set = self.randomization.changed();
        if !self.randomization.enabled && !set.is_empty() {
            return Err(bad((
                "randomization.enabled",
                format!(
                    "is false: the {} set here would randomise nothing (set `enabled = \
                     true`, or remove them)",
                    set.join(", ")
                ),
            )));
        }
        Ok(())
    }

    /// Whether the conditions change anything (the default file changes nothing).
    pub fn is_default(&self) -> bool {
        *self == EvalConditions::default()
    }

    /// `env` with these conditions in place of the evaluation's defaults.
    pub fn apply(&self, env: &mut EnvConfig) {
        env.placement = self.placement;
        env.randomization = self.randomization.clone();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("grasp_conditions_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn a_conditions_file_sets_placement_and_randomization_of_every_env() {
        let p = write(
            "ok.toml",
            "[placement]\noffset = 0.01\nheight = 0.005\nyaw = 0.02\nantipodal = 1.0\n\
             [randomization]\nenabled = true\nsize_scale = [1.0, 1.0]\nyaw = 0.0\n",
        );
        let c = EvalConditions::load(&p).unwrap();
        assert!(!c.is_default());
        let mut env = EnvConfig::default();
        c.apply(&mut env);
        assert_eq!(env.placement.offset, 0.01);
        assert_eq!(env.placement.height, 0.005);
        assert_eq!(env.placement.yaw, 0.02);
        assert_eq!(env.placement.antipodal, 1.0);
        assert!(env.randomization.enabled);
        assert_eq!(env.randomization.size_scale, [1.0, 1.0]);
        assert_eq!(env.randomization.yaw, 0.0);
        // Unnamed values keep the training defaults.
        assert_eq!(env.randomization.mass_scale, [0.5, 2.0]);
        assert_eq!(env.randomization.friction, [0.5, 1.0]);
        // An empty file changes nothing.
        assert!(EvalConditions::load(&write("empty.toml", ""))
            .unwrap()
            .is_default());
    }

    #[test]
    fn bad_conditions_name_the_file_and_field() {
        let p = write("far.toml", "[placement]\noffset = 0.2\n");
        let e = EvalConditions::load(&p).unwrap_err().to_string();
        assert!(
            e.contains("far.toml") && e.contains("placement.offset"),
            "{e}"
        );
        let p = write("mu.toml", "[randomization]\nfriction = [0.5, 1.5]\n");
        let e = EvalConditions::load(&p).unwrap_err().to_string();
        assert!(e.contains("randomization.friction"), "{e}");
        let p = write("typo.toml", "[placement]\nofset = 0.01\n");
        let e = EvalConditions::load(&p).unwrap_err().to_string();
        assert!(e.contains("typo.toml") && e.contains("line 2"), "{e}");
        let p = write("nan.toml", "[placement]\nyaw = nan\n");
        let e = EvalConditions::load(&p).unwrap_err().to_string();
        assert!(e.contains("placement.yaw"), "{e}");
    }

    #[test]
    fn ranges_without_enabled_are_refused_not_ignored() {
        // Without `enabled = true` these ranges perturbed nothing, and the results
        // recorded them as the evaluation's conditions.
        let p = write(
            "off.toml",
            "[randomization]\nfriction = [0.1, 0.2]\nmass_scale = [5.0, 10.0]\n",
        );
        let e = EvalConditions::load(&p).unwrap_err().to_string();
        assert!(
            e.contains("off.toml")
                && e.contains("randomization.enabled")
                && e.contains("mass_scale, friction")
                && e.contains("enabled = true"),
            "{e}"
        );
        // Off with the defaults (or nothing) is fine, and so is on with any ranges.
        let p = write("off_ok.toml", "[randomization]\nenabled = false\n");
        assert!(EvalConditions::load(&p).unwrap().is_default());
        let p = write(
            "on.toml",
            "[randomization]\nenabled = true\nfriction = [0.1, 0.2]\n",
        );
        assert!(EvalConditions::load(&p).is_ok());
    }
}
