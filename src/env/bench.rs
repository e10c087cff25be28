//! Throughput of the learner's harness: a random agent (Gaussian actions, lift with a fixed
//! probability) stepping a [`VecEnv`], resets and stage 1 included.

use super::api::{Action, EnvError, VecEnv};
use super::grasp::GraspEnv;
use super::phases::PhaseTally;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;
use std::time::Instant;

/// Probability that the random agent lifts at a step: episodes of about 6.7 steps, near
/// the paper's 5.8 and the shipped policy's 7-9.
pub const RANDOM_LIFT_PROB: f64 = 0.15;

/// Throughput figures of one measurement.
#[derive(Debug, Clone, Serialize)]
pub struct EnvFigures {
    /// Environments stepped together.
    pub envs: usize,
    /// Environment steps over all envs.
    pub env_steps: u64,
    /// Episodes finished.
    pub episodes: u64,
    /// Episodes that ended in a detected physics failure.
    pub physics_failures: u64,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Environment steps per wall second.
    pub env_steps_per_s: f64,
    /// Episodes per wall second.
    pub episodes_per_s: f64,
    /// Physics steps and time per episode phase, summed over the environments (`None`
    /// when they are not grasping environments).
    pub phases: Option<PhaseTally>,
}

/// The phase tallies of `venv`'s grasping environments, summed (`None` when it has none).
pub fn phase_tally(venv: &VecEnv) -> Option<PhaseTally> {
    (0..venv.num_envs())
        .filter_map(|i| venv.env(i)?.as_any()?.downcast_ref::<GraspEnv>())
        .map(|g| *g.phases())
        .reduce(|a, b| a.plus(&b))
}

/// How long a measurement runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Until {
    /// About this many wall seconds.
    Seconds(f64),
    /// At least this many environment steps over all envs.
    Steps(u64),
}

/// Steps `venv` (reset with `seed`) with random actions drawn from `seed` until `until`.
pub fn random_agent(venv: &mut VecEnv, seed: u64, until: Until) -> Result<EnvFigures, EnvError> {
    let n = venv.action_spec().continuous;
    let envs = venv.num_envs();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let tally0 = phase_tally(venv);
    let start = Instant::now();
    venv.reset(seed)?;
    let (mut env_steps, mut episodes, mut physics_failures) = (0u64, 0u64, 0u64);
    let more = |steps: u64| match until {
        Until::Seconds(s) => start.elapsed().as_secs_f64() < s,
        Until::Steps(n) => steps < n.max(1),
    };
    while more(env_steps) {
        let actions: Vec<Action> = (0..envs)
            .map(|_| Action {
                cont: (0..n).map(|_| StandardNormal.sample(&mut rng)).collect(),
                lift: rng.random_bool(RANDOM_LIFT_PROB),
            })
            .collect();
        let s = venv.step(&actions)?;
        env_steps += envs as u64;
        episodes += s
            .terminated
            .iter()
            .zip(&s.truncated)
            .filter(|(t, u)| **t || **u)
            .count() as u64;
        physics_failures += s.infos.iter().filter(|i| i.physics_failure).count() as u64;
    }
    let wall_s = start.elapsed().as_secs_f64().max(1e-9);
    Ok(EnvFigures {
        envs,
        env_steps,
        episodes,
        physics_failures,
        wall_s,
        env_steps_per_s: env_steps as f64 / wall_s,
        episodes_per_s: episodes as f64 / wall_s,
        phases: phase_tally(venv).map(|t| t.since(&tally0.unwrap_or_default())),
    })
}
