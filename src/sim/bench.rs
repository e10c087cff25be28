//! Throughput measurement of the simulator: scripted close-and-lift episodes on one env,
//! and on many envs stepped in parallel in one explicitly sized rayon pool.

use super::config::SimConfig;
use super::object::ObjectSpec;
use super::script::{close_and_lift, power_grasp, ScriptOptions};
use super::world::{HandSim, Scene, SimError};
use crate::robot::{Posture, Robot};
use rayon::prelude::*;
use serde::Serialize;
use std::time::{Duration, Instant};

/// Error of a benchmark run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The simulator could not be built.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The thread pool could not be built.
    #[error("cannot build a rayon pool of {threads} threads: {message}")]
    Pool {
        /// Requested threads.
        threads: usize,
        /// rayon's message.
        message: String,
    },
    /// A setting is out of range.
    #[error("bench: {0}")]
    Settings(String),
}

/// Most environments one benchmark steps (`grasp bench sim` and `bench env`).
pub const MAX_ENVS: usize = 1024;

/// Throughput figures of one configuration.
#[derive(Debug, Clone, Serialize)]
pub struct BenchFigures {
    /// Environments stepped together.
    pub envs: usize,
    /// Threads of the pool.
    pub threads: usize,
    /// Episodes completed (reset, close, hold, lift, judge).
    pub episodes: u64,
    /// Episodes that ended in a detected physics failure.
    pub physics_failures: u64,
    /// Physics steps over all envs.
    pub physics_steps: u64,
    /// Control steps over all envs (simulated time / control period).
    pub control_steps: f64,
    /// Simulated seconds over all envs.
    pub sim_seconds: f64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Physics steps per wall second.
    pub physics_steps_per_s: f64,
    /// Simulated seconds per wall second.
    pub sim_seconds_per_s: f64,
    /// Control steps per wall second.
    pub control_steps_per_s: f64,
}

#[derive(Default, Clone, Copy)]
struct Tally {
    episodes: u64,
    failures: u64,
    steps: u64,
    sim: f64,
}

fn run_env(sim: &mut HandSim, seed: u64, deadline: Instant) -> Tally {
    let obj = sim.object().clone();
    let mut t = Tally::default();
    let mut k = 0;
    while Instant::now() < deadline {
        let scene = Scene::randomized(&obj, Posture::Open.angles(), 0.03, 0.01, 0.1, seed + k);
        k += 1;
        if sim.reset(&scene).is_err() {
            break;
        }
        close_and_lift(sim, ScriptOptions::default(), &power_grasp());
        t.episodes += 1;
        t.failures += u64::from(sim.failure().is_some());
        t.steps += sim.physics_steps();
        t.sim += sim.time();
    }
    t
}

/// Runs scripted episodes on `envs` environments for about `seconds` of wall time, in a
/// rayon pool of `threads` threads (one env: on the calling thread).
pub fn run(
    robot: &Robot,
    cfg: &SimConfig,
    envs: usize,
    threads: usize,
    seconds: f64,
) -> Result<BenchFigures, BenchError> {
    if envs == 0 || envs > MAX_ENVS {
        return Err(BenchError::Settings(format!(
            "envs = {envs}: must be in 1..={MAX_ENVS}"
        )));
    }
    if let Err(m) = crate::util::threads::check(threads) {
        return Err(BenchError::Settings(format!("threads = {m}")));
    }
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 3600.0) {
        return Err(BenchError::Settings(format!(
            "seconds = {}: must be in (0, 3600]",
            crate::util::num::short(seconds)
        )));
    }
    let mut sims = (0..envs)
        .map(|_| HandSim::new(robot, ObjectSpec::default_box(), cfg.clone()))
        .collect::<Result<Vec<_>, _>>()?;
    let start = Instant::now();
    let deadline = start + Duration::try_from_secs_f64(seconds).unwrap_or_default();
    let tallies: Vec<Tally> = if envs == 1 {
        vec![run_env(&mut sims[0], 0, deadline)]
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| BenchError::Pool {
                threads,
                message: e.to_string(),
            })?;
        pool.install(|| {
            sims.par_iter_mut()
                .enumerate()
                .map(|(i, s)| run_env(s, 1000 * i as u64, deadline))
                .collect()
        })
    };
    let wall = start.elapsed().as_secs_f64();
    let episodes = tallies.iter().map(|t| t.episodes).sum();
    let physics_failures = tallies.iter().map(|t| t.failures).sum();
    let physics_steps = tallies.iter().map(|t| t.steps).sum();
    let sim_seconds: f64 = tallies.iter().map(|t| t.sim).sum();
    let control_steps = sim_seconds / cfg.control_period;
    Ok(BenchFigures {
        envs,
        threads: if envs == 1 { 1 } else { threads },
        episodes,
        physics_failures,
        physics_steps,
        control_steps,
        sim_seconds,
        wall_seconds: wall,
        physics_steps_per_s: physics_steps as f64 / wall,
        sim_seconds_per_s: sim_seconds / wall,
        control_steps_per_s: control_steps / wall,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::Side;

    #[test]
    fn bad_settings_are_errors() {
        let r = Robot::builtin(Side::Left);
        let c = SimConfig::default();
        assert!(run(&r, &c, 0, 1, 1.0).is_err());
        assert!(run(&r, &c, 1, 0, 1.0).is_err());
        assert!(run(&r, &c, 1, 1, f64::NAN).is_err());
    }

    #[test]
    fn figures_are_consistent() {
        let r = Robot::builtin(Side::Left);
        let c = SimConfig::default();
        let f = run(&r, &c, 2, 2, 0.05).unwrap();
        assert!(f.episodes >= 2);
        assert!((f.physics_steps as f64 * c.dt - f.sim_seconds).abs() < 1e-9);
        assert!((f.control_steps - f.sim_seconds / c.control_period).abs() < 1e-9);
    }
}
