//! The environments of a training config, as `grasp train` steps them: one
//! [`GraspEnv`] (or cart-pole) per `num_envs`, each on the config's object set or the
//! procedural stream, with its synergy model, simulator config and MDP settings, and the
//! environments' curriculum levels published for the metrics.
//!
//! The Python module (`grasp_rl`, feature `python`) builds its environments here too, so
//! a config file means the same MDP to both.

use super::objects::object_set;
use super::TrainError;
use crate::checkpoint::files;
use crate::checkpoint::{EnvKind, TrainConfig};
use crate::env::api::{Action, ActionSpec, Env, Step};
use crate::env::cartpole::CartPole;
use crate::env::grasp::GraspEnv;
use crate::env::stream::ObjectStream;
use crate::robot::{Robot, Side};
use crate::sim::SimConfig;
use crate::synergy::SynergyModel;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;

/// The default `synergy` of a config: the shipped model, which is also embedded in the
/// binary ([`crate::synergy::DEFAULT_MODEL_JSON`]).
pub const DEFAULT_SYNERGY_PATH: &str = "assets/synergy/model.json";

/// The environments' curriculum levels (eq. 6's `r_s`), shared between the environments,
/// which publish theirs after every reset and step, and their reader (the training loop,
/// the Python module). Cloning shares the levels.
#[derive(Debug, Clone)]
pub struct CurriculumLevels {
    inner: Arc<Levels>,
}

#[derive(Debug)]
struct Levels {
    rates: Vec<AtomicU64>,
    /// Set by [`CurriculumLevels::restart`]: the environment empties its success window at
    /// its next reset.
    restart: Vec<AtomicBool>,
}

impl CurriculumLevels {
    fn new(n: usize) -> Self {
        CurriculumLevels {
            inner: Arc::new(Levels {
                rates: (0..n).map(|_| AtomicU64::new(0)).collect(),
                restart: (0..n).map(|_| AtomicBool::new(false)).collect(),
            }),
        }
    }

    /// The level of environment `index` (0 when out of range).
    pub fn level(&self, index: usize) -> f64 {
        self.inner
            .rates
            .get(index)
            .map_or(0.0, |r| f64::from_bits(r.load(Ordering::Relaxed)))
    }

    /// The mean level over the environments.
    pub fn mean(&self) -> f64 {
        let n = self.inner.rates.len();
        (0..n).map(|i| self.level(i)).sum::<f64>() / n.max(1) as f64
    }

    /// Makes every environment empty its curriculum window at its next reset, as if new:
    /// a seeded restart then gives the same episodes as a fresh environment.
    pub fn restart(&self) {
        for r in &self.inner.restart {
            r.store(true, Ordering::Relaxed);
        }
    }

    fn publish(&self, index: usize, rate: f64) {
        if let Some(r) = self.inner.rates.get(index) {
            r.store(rate.to_bits(), Ordering::Relaxed);
        }
    }

    fn take_restart(&self, index: usize) -> bool {
        self.inner
            .restart
            .get(index)
            .is_some_and(|r| r.swap(false, Ordering::Relaxed))
    }
}

/// A grasp environment that publishes its curriculum level after every reset and step.
struct ProbedGrasp {
    env: GraspEnv,
    levels: CurriculumLevels,
    index: usize,
}

impl ProbedGrasp {
    fn publish(&self) {
        self.levels.publish(self.index, self.env.curriculum_rate());
    }
}

impl Env for ProbedGrasp {
    fn obs_dim(&self) -> usize {
        self.env.obs_dim()
    }
    fn action_spec(&self) -> ActionSpec {
        self.env.action_spec()
    }
    fn reset(&mut self, seed: u64) -> Vec<f32> {
        if self.levels.take_restart(self.index) {
            self.env.restart_curriculum();
        }
        let o = self.env.reset(seed);
        self.publish();
        o
    }
    fn step(&mut self, a: &Action) -> Step {
        let s = self.env.step(a);
        self.publish();
        s
    }
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        // The grasping environment inside (its object and episode summary).
        self.env.as_any()
    }
}

/// Loads the synergy model of `cfg`, checking that it exists, keeping its first
/// `n_components` components (a model with fewer is an error). The default path
/// ([`DEFAULT_SYNERGY_PATH`]) is read from the binary when the working folder does not
/// hold it (a run started outside the repository, the Python module): it is the same file.
pub fn load_synergy(cfg: &TrainConfig) -> Result<SynergyModel, TrainError> {
    let path = &cfg.synergy;
    let model = if path.exists() {
        SynergyModel::load(path)?
    } else if path == Path::new(DEFAULT_SYNERGY_PATH) {
        crate::synergy::default_model()
    } else {
        return Err(TrainError::SynergyMissing { path: path.clone() });
    };
    if model.n_components() < cfg.n_components {
        return Err(TrainError::SynergyComponents {
            path: path.clone(),
            found: model.n_components(),
            wanted: cfg.n_components,
        });
    }
    Ok(model.truncated(cfg.n_components)?)
}

/// The simulator config of `cfg`: its `sim_config` file, or the built-in defaults (see
/// [`SimConfig::load_or_default`]).
pub fn sim_config(cfg: &TrainConfig) -> Result<SimConfig, TrainError> {
    Ok(SimConfig::load_or_default(cfg.sim_config.as_deref())?)
}

/// `n` grasping environments of `cfg` (its object set or the procedural stream, synergy
/// model, simulator config and `[env]` settings) and the synergy model they act in.
pub fn grasp_envs(
    cfg: &TrainConfig,
    n: usize,
) -> Result<(Vec<GraspEnv>, SynergyModel), TrainError> {
    if cfg.env.kind != EnvKind::Grasp {
        return Err(TrainError::ConfigValue {
            path: PathBuf::from(files::CONFIG),
            field: "env.kind".into(),
            message: format!("{:?} is not the grasping environment", cfg.env.kind),
        });
    }
    let model = load_synergy(cfg)?;
    let sim = sim_config(cfg)?;
    let on_stream = cfg.objects == crate::objects::stream::STREAM_SET;
    // On the stream, each environment starts on one stream object and builds the next
    // ones itself (see `env::stream`).
    let objects = if on_stream {
        let stream = ObjectStream::new(cfg.env.grasp.stream.clone());
        stream.first_object().map(|o| vec![o])
    } else {
        object_set(&cfg.objects)
    }
    .map_err(|message| TrainError::Objects {
        objects: cfg.objects.clone(),
        message,
    })?;
    let robot = Robot::builtin(Side::Left);
    let mut envs = Vec::with_capacity(n);
    for _ in 0..n {
        let env = GraspEnv::new(
            &robot,
            objects.clone(),
            model.clone(),
            sim.clone(),
            cfg.env.grasp.for_training(),
        )?;
        envs.push(if on_stream { env.with_stream() } else { env });
    }
    Ok((envs, model))
}

/// Wraps grasping environments so that each publishes its curriculum level.
pub fn with_levels(envs: Vec<GraspEnv>) -> (Vec<Box<dyn Env>>, CurriculumLevels) {
    let levels = CurriculumLevels::new(envs.len());
    let boxed = envs
        .into_iter()
        .enumerate()
        .map(|(index, env)| {
            let p = ProbedGrasp {
                env,
                levels: levels.clone(),
                index,
            };
            p.publish();
            Box::new(p) as Box<dyn Env>
        })
        .collect();
    (boxed, levels)
}

/// The environments of a run: `num_envs` of them, the curriculum levels (grasp runs) and
/// the synergy model (grasp runs).
pub struct TrainEnvs {
    /// The environments, in order.
    pub envs: Vec<Box<dyn Env>>,
    /// Their curriculum levels (grasp runs).
    pub levels: Option<CurriculumLevels>,
    /// The synergy model they act in (grasp runs).
    pub synergy: Option<SynergyModel>,
}

/// Builds the `num_envs` environments of `cfg`, as `grasp train` trains on them.
pub fn build_envs(cfg: &TrainConfig) -> Result<TrainEnvs, TrainError> {
    match cfg.env.kind {
        EnvKind::Cartpole => Ok(TrainEnvs {
            envs: (0..cfg.num_envs)
                .map(|_| Box::new(CartPole::new(cfg.env.cartpole_max_steps)) as Box<dyn Env>)
                .collect(),
            levels: None,
            synergy: None,
        }),
        EnvKind::Grasp => {
            let (envs, model) = grasp_envs(cfg, cfg.num_envs)?;
            let (envs, levels) = with_levels(envs);
            Ok(TrainEnvs {
                envs,
                levels: Some(levels),
                synergy: Some(model),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_are_shared_and_a_restart_is_taken_once() {
        let levels = CurriculumLevels::new(2);
        let reader = levels.clone();
        levels.publish(1, 0.5);
        assert_eq!(reader.level(1), 0.5);
        assert_eq!(reader.mean(), 0.25);
        assert_eq!(reader.level(7), 0.0);
        reader.restart();
        assert!(levels.take_restart(0) && !levels.take_restart(0));
        assert!(levels.take_restart(1));
    }

    #[test]
    fn default_files_are_read_from_the_binary_elsewhere() {
        let mut cfg = TrainConfig::parse(Path::new("t.toml"), "name = \"t\"\n").unwrap();
        cfg.synergy = PathBuf::from("no/such/model.json");
        assert!(matches!(
            load_synergy(&cfg),
            Err(TrainError::SynergyMissing { .. })
        ));
        cfg.synergy = PathBuf::from(DEFAULT_SYNERGY_PATH);
        assert_eq!(load_synergy(&cfg).unwrap().n_components(), 5);
        cfg.sim_config = Some(PathBuf::from(crate::sim::config::DEFAULT_PATH));
        assert_eq!(sim_config(&cfg).unwrap(), SimConfig::default());
        cfg.sim_config = Some(PathBuf::from("no/such/sim.toml"));
        assert!(sim_config(&cfg).is_err());
    }
}
