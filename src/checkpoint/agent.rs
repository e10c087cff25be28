//! A checkpoint folder made ready to act: the one loader of a trained agent, for
//! evaluation, the grid's evaluations, the regression check, `grasp run` and Python.
//!
//! [`TrainedAgent::load`] reads the network's weights, the training setup saved beside
//! them (`config.toml`: the grasping MDP, the synergy components, the simulator config)
//! and the synergy model (`synergy.json`), and checks that they fit together: a grasping
//! network (continuous actions and a lift), as many continuous actions as the setup's
//! action space, and the observation length of the setup's layout. It then builds the
//! agent's environment for an object and a simulator config
//! ([`TrainedAgent::environment`]).

use super::{checkpoint_setup, files, CheckpointError};
use crate::env::curriculum::CurriculumConfig;
use crate::env::grasp::{EnvConfig, GraspEnv, GraspEnvError};
use crate::env::obs::Modality;
use crate::ppo::LoadedPolicy;
use crate::robot::Robot;
use crate::sim::config::SimConfigError;
use crate::sim::{ObjectSpec, SimConfig};
use crate::synergy::SynergyModel;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What to assume where a checkpoint folder lacks a file (a checkpoint not written by
/// `grasp train`); each `None` takes the default named.
#[derive(Debug, Clone, Default)]
pub struct Assumed {
    /// Without `config.toml`: the grasping MDP (default: [`EnvConfig::default`]).
    pub env: Option<EnvConfig>,
    /// Without `config.toml`: the synergy components (default: the network's continuous
    /// actions less the wrist's two).
    pub n_components: Option<usize>,
    /// Without `synergy.json`: the synergy model file (default: the shipped model).
    pub synergy: Option<PathBuf>,
}

/// A trained policy and everything it acts in, loaded once from its checkpoint folder.
pub struct TrainedAgent {
    dir: PathBuf,
    network: Arc<LoadedPolicy>,
    /// The grasping MDP's settings it acts in: its training run's, with domain
    /// randomisation, the object curriculum and the placement reset (see
    /// [`checkpoint_setup`]). Public so that an evaluation can set its conditions.
    pub env: EnvConfig,
    synergy: SynergyModel,
    /// `Some(sim config file)` from `config.toml` (`Some(None)`: the built-in one);
    /// `None` without `config.toml`.
    trained_sim: Option<Option<PathBuf>>,
    has_synergy_file: bool,
}

impl std::fmt::Debug for TrainedAgent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TrainedAgent")
            .field("dir", &self.dir)
            .field("modality", &self.env.modality)
            .field("n_components", &self.synergy.n_components())
            .field("trained_sim", &self.trained_sim)
            .finish_non_exhaustive()
    }
}

impl TrainedAgent {
    /// Loads the checkpoint folder `dir`, assuming the defaults of [`Assumed`] for any
    /// file it lacks.
    pub fn load(dir: &Path) -> Result<TrainedAgent, CheckpointError> {
        Self::load_assuming(dir, &Assumed::default())
    }

    /// Loads the checkpoint folder `dir`, assuming `assumed` for any file it lacks.
    pub fn load_assuming(dir: &Path, assumed: &Assumed) -> Result<TrainedAgent, CheckpointError> {
        let err = |path: PathBuf, message: String| CheckpointError { path, message };
        if !dir.is_dir() {
            return Err(err(
                dir.to_path_buf(),
                "not a checkpoint folder (does not exist)".into(),
            ));
        }
        let network = crate::ppo::load_policy(dir)
            .map_err(|e| err(dir.join(crate::ppo::CHECKPOINT_FILE), e.to_string()))?;
        let spec = network.policy.action_spec();
        if !spec.lift || spec.continuous < 3 {
            return Err(err(
                dir.join(crate::ppo::CHECKPOINT_FILE),
                format!(
                    "not a grasping policy: {} continuous actions, lift {}",
                    spec.continuous, spec.lift
                ),
            ));
        }
        let (env, n, trained_sim) = match checkpoint_setup(dir)? {
            Some(s) => {
                // n synergies, the wrist's two increments and, with the grip, one more.
                let expected = s.env.action.continuous(s.n_components);
                if spec.continuous != expected {
                    return Err(err(
                        dir.join(files::CONFIG),
                        format!(
                            "config.toml says {} synergy components{} ({expected} continuous \
                             actions) but the network acts in {}",
                            s.n_components,
                            if s.env.action.grip_scale > 0.0 {
                                " and a grip"
                            } else {
                                ""
                            },
                            spec.continuous
                        ),
                    ));
                }
                (s.env, s.n_components, Some(s.sim_config))
            }
            None => (
                assumed.env.clone().unwrap_or_default(),
                assumed.n_components.unwrap_or(spec.continuous - 2),
                None,
            ),
        };
        env.validate()
            .map_err(|e| err(dir.join(files::CONFIG), e.to_string()))?;
        let beside = dir.join(files::SYNERGY);
        let has_synergy_file = beside.is_file();
        let synergy_path = if has_synergy_file {
            Some(beside)
        } else {
            assumed.synergy.clone()
        };
        let full = match &synergy_path {
            Some(p) => SynergyModel::load(p).map_err(|e| err(p.clone(), e.to_string()))?,
            None => crate::synergy::default_model(),
        };
        let synergy = full.truncated(n).map_err(|e| {
            err(
                synergy_path.unwrap_or_else(|| dir.join(files::SYNERGY)),
                format!("using {n} synergy components: {e}"),
            )
        })?;
        // A policy trained with an asymmetric critic reads the same frames; its critic's
        // privileged values are zeros outside training.
        let layout = env.layout(n);
        if layout.len() != network.policy.obs_dim() {
            return Err(err(
                dir.join(crate::ppo::CHECKPOINT_FILE),
                format!(
                    "the network expects observations of length {}, but {:?} with {n} \
                     components and history {} gives {}",
                    network.policy.obs_dim(),
                    env.modality,
                    env.history,
                    layout.len()
                ),
            ));
        }
        Ok(TrainedAgent {
            dir: dir.to_path_buf(),
            network: Arc::new(network),
            env,
            synergy,
            trained_sim,
            has_synergy_file,
        })
    }

    /// The checkpoint folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The network with its weights (shared: every actor of an evaluation reads the same
    /// one).
    pub fn network(&self) -> &Arc<LoadedPolicy> {
        &self.network
    }

    /// The synergy model the policy acts in, with its components.
    pub fn synergy(&self) -> &SynergyModel {
        &self.synergy
    }

    /// Whether the folder holds the training setup (`config.toml`).
    pub fn has_config(&self) -> bool {
        self.trained_sim.is_some()
    }

    /// Whether the folder holds its synergy model (`synergy.json`).
    pub fn has_synergy_file(&self) -> bool {
        self.has_synergy_file
    }

    /// The simulator config file it was trained with: `Some(None)` for the built-in one,
    /// `None` without `config.toml`.
    pub fn trained_sim_path(&self) -> Option<Option<&Path>> {
        self.trained_sim.as_ref().map(|p| p.as_deref())
    }

    /// The simulator config it was trained with (the built-in one without `config.toml`),
    /// by [`SimConfig::load_or_default`]'s rule.
    pub fn trained_sim(&self) -> Result<SimConfig, SimConfigError> {
        SimConfig::load_or_default(self.trained_sim_path().flatten())
    }

    /// Checks the user's `--modality` / `--components` against a checkpoint with its
    /// `config.toml`: a value that differs is an error naming both.
    pub fn check_flags(
        &self,
        modality: Option<Modality>,
        components: Option<usize>,
    ) -> Result<(), CheckpointError> {
        if !self.has_config() {
            return Ok(());
        }
        let err = |message: String| CheckpointError {
            path: self.dir.join(files::CONFIG),
            message,
        };
        if let Some(m) = modality.filter(|m| *m != self.env.modality) {
            return Err(err(format!(
                "the checkpoint was trained with modality {:?}, not {m:?}: drop --modality",
                self.env.modality
            )));
        }
        let n = self.synergy.n_components();
        if let Some(c) = components.filter(|c| *c != n) {
            return Err(err(format!(
                "the checkpoint was trained with {n} synergy components, not {c}: drop \
                 --components"
            )));
        }
        Ok(())
    }

    /// Its MDP at a fixed difficulty (the curriculum off), as every evaluation runs it.
    pub fn at_difficulty(&mut self, difficulty: f64) -> &mut Self {
        self.env.curriculum = CurriculumConfig::fixed(difficulty);
        self
    }

    /// The agent's environment: `object` alone, in simulator config `sim`, with its MDP
    /// [`TrainedAgent::env`].
    pub fn environment(
        &self,
        robot: &Robot,
        object: (String, ObjectSpec),
        sim: SimConfig,
    ) -> Result<GraspEnv, GraspEnvError> {
        GraspEnv::new(
            robot,
            vec![object],
            self.synergy.clone(),
            sim,
            self.env.clone(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/policies")
            .join(name)
    }

    #[test]
    fn a_shipped_checkpoint_loads_with_its_setup() {
        let a = TrainedAgent::load(&shipped("fig5_gru_m3_pca8")).unwrap();
        assert_eq!(a.synergy().n_components(), 8);
        assert!(a.has_config() && a.has_synergy_file());
        assert!(!a.env.randomization.enabled);
        assert_eq!(
            a.env.layout(8).len(),
            a.network().policy.obs_dim(),
            "the layout check passed"
        );
    }

    #[test]
    fn missing_files_fall_back_to_the_assumptions_and_misfits_are_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let e = TrainedAgent::load(&tmp.path().join("nope")).unwrap_err();
        assert!(e.to_string().contains("not a checkpoint folder"), "{e}");
        // Only the weights: the defaults (M3, history 3, n = 7 - 2 = 5, shipped model).
        let src = shipped("quick_gru_m3_pca5");
        let dir = tmp.path().join("bare");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(
            src.join(crate::ppo::CHECKPOINT_FILE),
            dir.join(crate::ppo::CHECKPOINT_FILE),
        )
        .unwrap();
        let a = TrainedAgent::load(&dir).unwrap();
        assert!(!a.has_config() && !a.has_synergy_file());
        assert_eq!(a.synergy().n_components(), 5);
        assert_eq!(a.trained_sim_path(), None);
        // Assuming another modality changes the layout: refused, naming both lengths.
        let m2 = Assumed {
            env: Some(EnvConfig {
                modality: crate::env::obs::Modality::M2,
                ..EnvConfig::default()
            }),
            ..Assumed::default()
        };
        let e = TrainedAgent::load_assuming(&dir, &m2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("expects observations of length 168"), "{e}");
        assert!(e.contains("M2"), "{e}");
    }
}
