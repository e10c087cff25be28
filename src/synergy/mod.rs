//! Hand synergies (Sec. III of the paper): pose datasets and their principal components.
//!
//! - [`collect`]: `grasp pca collect`, grasp postures of the GRASP taxonomy made in the
//!   simulator.
//! - [`dataset`]: CSV pose datasets of the 22 finger joints, validated against the joint
//!   limits, with precise errors (file, line, column).
//! - [`pca`]: [`SynergyModel`], the PCA of a dataset (mean, components, the full
//!   eigenvalue spectrum), saved as a versioned JSON file.
//! - [`map`]: the maps P (joints -> synergy coordinates), P^-1 (back) and the target of
//!   eq. 2, `theta_target = P^-1(d_eps + P(theta_f))`, made feasible by
//!   [`map::project_feasible`].
//! - [`draw`]: hand-posture figures of the first synergies (the paper's Fig. 2b).
//!
//! All joint vectors are `[f64; 22]` in the synergy order of
//! [`FINGER_JOINTS`], in radians.

pub mod collect;
pub mod dataset;
pub mod draw;
pub mod map;
pub mod pca;

pub use dataset::{Dataset, DatasetError, LoadOptions};
pub use map::project_feasible;
pub use pca::{SynergyError, SynergyModel, PAPER_COMPONENTS};

use crate::robot::joints::{hand_facts, FINGER_JOINTS};
use crate::robot::Side;

/// Number of finger joints in the synergy space.
pub const N_FINGER_JOINTS: usize = FINGER_JOINTS.len();

/// The shipped synergy model's JSON (`assets/synergy/model.json`, see its README).
pub const DEFAULT_MODEL_JSON: &str = include_str!("../../assets/synergy/model.json");

/// The shipped synergy model: 10 components fitted to the 3000 postures of
/// `assets/synergy/poses.csv` made by `grasp pca collect` (see `assets/synergy/README.md`).
/// Take the paper's `n` in {3, 5, 8, 10} with [`SynergyModel::truncated`].
pub fn default_model() -> SynergyModel {
    // The embedded file is generated and tested (tests/pca_collect.rs): failing here is a
    // build defect, not a user error.
    SynergyModel::from_json(
        std::path::Path::new("assets/synergy/model.json"),
        DEFAULT_MODEL_JSON,
    )
    .unwrap_or_else(|e| panic!("the shipped synergy model is invalid: {e}"))
}

/// Error of [`model_or_shipped`]: which step failed, its cause following.
#[derive(Debug, thiserror::Error)]
pub enum ModelChoiceError {
    /// The model file could not be loaded.
    #[error("loading synergy model {}", .0.display())]
    Load(std::path::PathBuf, #[source] SynergyError),
    /// The model has not that many components.
    #[error("using {0} synergy components")]
    Components(usize, #[source] SynergyError),
}

/// The synergy model of `path` (the shipped one when `None`, [`default_model`]) truncated
/// to `n` components: what a `--synergy`/`--components` pair names.
pub fn model_or_shipped(
    path: Option<&std::path::Path>,
    n: usize,
) -> Result<SynergyModel, ModelChoiceError> {
    let model = match path {
        Some(p) => SynergyModel::load(p).map_err(|e| ModelChoiceError::Load(p.to_path_buf(), e))?,
        None => default_model(),
    };
    model
        .truncated(n)
        .map_err(|e| ModelChoiceError::Components(n, e))
}

/// Lower and upper limits (radians) of the 22 finger joints of `side`, in
/// [`FINGER_JOINTS`] order, read from [`hand_facts`]. Both hands have the same limits.
pub fn finger_limits(side: Side) -> [(f64, f64); N_FINGER_JOINTS] {
    let facts = hand_facts(side);
    let mut out = [(0.0, 0.0); N_FINGER_JOINTS];
    for (slot, name) in out.iter_mut().zip(FINGER_JOINTS) {
        if let Some(f) = facts.iter().find(|f| f.name == name) {
            *slot = (f.lower, f.upper);
        }
    }
    out
}

#[cfg(test)]
#[allow(clippy::approx_constant)] // the published joint limits (0.7854, 1.0472, ...)
mod tests {
    use super::*;

    #[test]
    fn the_default_model_has_ten_components() {
        let m = default_model();
        assert_eq!(m.n_components(), 10);
        assert!(m.explained_variance_ratio()[0] > 0.3);
        for n in PAPER_COMPONENTS {
            assert_eq!(m.truncated(n).unwrap().n_components(), n);
        }
    }

    #[test]
    fn finger_limits_follow_the_joint_table() {
        let l = finger_limits(Side::Left);
        assert_eq!(l[0], (-0.3491, 0.3491)); // FFJ4
        assert_eq!(l[1], (-0.2618, 1.5708)); // FFJ3
        assert_eq!(l[12], (0.0, 0.7854)); // LFJ5
        assert_eq!(l[17], (-1.0472, 1.0472)); // THJ5
        assert_eq!(l[21], (-0.2618, 1.5708)); // THJ1
        assert_eq!(finger_limits(Side::Right), l);
        assert!(l.iter().all(|(lo, hi)| lo < hi));
    }
}
