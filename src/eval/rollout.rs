//! `grasp rollout` as one request: episodes of a scripted or random agent on the grasping
//! MDP, for debugging. They run in parallel. Episode `i` always plays the scene of seed
//! `(seed, i)`, so the outcomes do not depend on the number of threads. Each episode is
//! recorded where the request asks; a recording that cannot be written does not end the
//! rollout and is reported instead.

use super::record::{
    record_agent_episode, record_baseline_episode, write_recording, RecordOptions, RecordingEntry,
};
use super::request::MeasureError;
use super::EvalError;
use crate::env::curriculum::CurriculumConfig;
use crate::env::grasp::{run_episode, EnvConfig, EpisodeSummary, GraspEnv, RandomAgent};
use crate::robot::{Robot, Side};
use crate::sim::{ObjectSpec, SimConfig};
use crate::util::step::StepContext;
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Mutex;

/// The agent of a rollout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScriptedAgent {
    /// Uniform random actions (lift probability 0.15).
    Random,
    /// Baseline 1 (close all fingers).
    Baseline1,
    /// Baseline 2 (FF, MF and RF stop at their touch).
    Baseline2,
}

impl ScriptedAgent {
    /// The agent named `baseline1`, `baseline2` or `random`.
    pub fn parse(name: &str) -> Result<ScriptedAgent, String> {
        match name {
            "random" => Ok(ScriptedAgent::Random),
            "baseline1" => Ok(ScriptedAgent::Baseline1),
            "baseline2" => Ok(ScriptedAgent::Baseline2),
            other => Err(format!(
                "unknown policy '{other}': expected baseline1, baseline2 or random"
            )),
        }
    }
}

/// What `grasp rollout` is asked to run (see the module docs).
#[derive(Debug, Clone)]
pub struct RolloutRequest {
    /// The agent.
    pub agent: ScriptedAgent,
    /// Its name in the recordings (`baseline2`, ...).
    pub name: String,
    /// The object set (as `--objects`).
    pub objects: String,
    /// Episodes.
    pub episodes: usize,
    /// The synergy model (the shipped one when `None`).
    pub synergy: Option<PathBuf>,
    /// Synergy components the agent acts in.
    pub components: usize,
    /// The simulator config (the built-in one when `None`).
    pub sim_config: Option<PathBuf>,
    /// The curriculum success rate that sets the start-pose randomisation.
    pub difficulty: f64,
    /// Worker threads (`None`: the available cores; never more than the episodes).
    pub threads: Option<usize>,
    /// Recordings (`name` is not read: the agent's `name` is used).
    pub record: Option<RecordOptions>,
    /// The seed of the scenes (`grasp --seed`).
    pub seed: u64,
}

/// What a rollout gave.
#[derive(Debug, Clone)]
pub struct RolloutOutput {
    /// The finished episodes, by index.
    pub episodes: Vec<(usize, EpisodeSummary)>,
    /// The recordings written.
    pub recordings: Vec<RecordingEntry>,
    /// The recordings that could not be written, and why.
    pub record_errors: Vec<String>,
    /// The worker threads used.
    pub threads: usize,
}

/// One episode's result: its index, its summary and its recording.
type Done = (usize, EpisodeSummary, Option<RecordingEntry>);

/// Runs the episodes of `req` (see the module docs); a set `stop` starts no new episode.
pub fn rollout(
    req: &RolloutRequest,
    stop: Option<&AtomicBool>,
) -> Result<RolloutOutput, MeasureError> {
    let n_threads = crate::util::threads::from_flag(req.threads)
        .map_err(MeasureError::Flags)?
        .min(req.episodes);
    let robot = Robot::builtin(Side::Left);
    let model = crate::synergy::model_or_shipped(req.synergy.as_deref(), req.components)?;
    let sim_cfg = SimConfig::load_flag(req.sim_config.as_deref())?;
    let objects = ObjectSpec::simulable_set(&req.objects)?;
    let env_cfg = EnvConfig {
        curriculum: CurriculumConfig::fixed(req.difficulty),
        ..EnvConfig::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n_threads)
        .build()
        .step(|| "building the thread pool".into())?;
    let chunks: Vec<Vec<usize>> = (0..n_threads)
        .map(|t| (t..req.episodes).step_by(n_threads).collect())
        .collect();
    let record_errors = Mutex::new(Vec::new());
    let n_actions = model.n_components() + 2;
    let results: Vec<Vec<Done>> = pool.install(|| {
        chunks
            .par_iter()
            .map(|idx| -> Result<Vec<Done>, MeasureError> {
                let mut env = GraspEnv::new(
                    &robot,
                    objects.clone(),
                    model.clone(),
                    sim_cfg.clone(),
                    env_cfg.clone(),
                )
                .map_err(EvalError::from)?;
                idx.iter()
                    .take_while(|_| !crate::util::signal::is_set(stop))
                    .map(|&i| {
                        let s = crate::env::api::episode_seed(req.seed, 0, i as u64);
                        let Some(rec_opts) = &req.record else {
                            let r = match req.agent {
                                ScriptedAgent::Random => run_episode(
                                    &mut env,
                                    &mut RandomAgent::new(n_actions, 0.15, s),
                                    s,
                                ),
                                b => env
                                    .run_baseline(b == ScriptedAgent::Baseline2, s)
                                    .map_err(EvalError::from)?,
                            };
                            return Ok((i, r, None));
                        };
                        let rec = match req.agent {
                            ScriptedAgent::Random => record_agent_episode(
                                &mut env,
                                &mut RandomAgent::new(n_actions, 0.15, s),
                                &req.name,
                                s,
                                rec_opts.every,
                            ),
                            b => record_baseline_episode(
                                &mut env,
                                b == ScriptedAgent::Baseline2,
                                &req.name,
                                s,
                                rec_opts.every,
                            )
                            .map_err(EvalError::from)?,
                        };
                        if rec_opts.only_failures && !rec.summary.physics_failure {
                            return Ok((i, rec.summary, None));
                        }
                        let entry = match write_recording(&rec_opts.dir, &rec, i, 0) {
                            Ok(e) => Some(e),
                            Err(e) => {
                                if let Ok(mut v) = record_errors.lock() {
                                    v.push(e.to_string());
                                }
                                None
                            }
                        };
                        Ok((i, rec.summary, entry))
                    })
                    .collect()
            })
            .collect::<Result<Vec<_>, _>>()
    })?;
    let mut done: Vec<Done> = results.into_iter().flatten().collect();
    done.sort_by_key(|d| d.0);
    let recordings = done.iter().filter_map(|d| d.2.clone()).collect();
    Ok(RolloutOutput {
        episodes: done.into_iter().map(|d| (d.0, d.1)).collect(),
        recordings,
        record_errors: record_errors.into_inner().unwrap_or_default(),
        threads: n_threads,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_agents_are_named_as_the_flag_spells_them() {
        assert_eq!(ScriptedAgent::parse("random"), Ok(ScriptedAgent::Random));
        assert_eq!(
            ScriptedAgent::parse("baseline1"),
            Ok(ScriptedAgent::Baseline1)
        );
        assert_eq!(
            ScriptedAgent::parse("baseline2"),
            Ok(ScriptedAgent::Baseline2)
        );
        assert_eq!(
            ScriptedAgent::parse("ppo"),
            Err("unknown policy 'ppo': expected baseline1, baseline2 or random".to_string())
        );
    }
}
