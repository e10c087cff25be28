//! A gymnasium-style environment API and a parallel vector of environments.
//!
//! An [`Env`] is anything the learner can train on: the grasping simulator and the textbook
//! control tasks alike. Its action is an [`Action`]: `continuous` real values (for the grasp:
//! the synergy increments and the two wrist increments of SPEC eq. 2) and, when
//! [`ActionSpec::lift`] is set, a binary lift decision rho.
//!
//! [`VecEnv`] steps many environments at once on its own, explicitly sized rayon thread pool
//! and resets finished episodes on the same step, keeping the final observation for value
//! bootstrapping on truncation. Every episode is seeded from (base seed, environment index,
//! episode count) by [`episode_seed`], so results do not depend on the number of threads.

use rayon::prelude::*;
use std::sync::{Mutex, PoisonError};

/// The shape of an environment's action.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ActionSpec {
    /// Number of continuous action components (at least 1).
    pub continuous: usize,
    /// Whether the action also carries the binary lift decision rho (SPEC eq. 3).
    pub lift: bool,
}

impl std::fmt::Display for ActionSpec {
    /// As a message says it: "8 continuous actions and the lift decision".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} continuous action{}{}",
            self.continuous,
            if self.continuous == 1 { "" } else { "s" },
            if self.lift {
                " and the lift decision"
            } else {
                ""
            }
        )
    }
}

/// One action: the continuous components and the lift decision.
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    /// The continuous components, `ActionSpec::continuous` of them. They are the raw samples
    /// of the policy: environments clip them to their own range.
    pub cont: Vec<f32>,
    /// The lift decision rho; always `false` for environments without a lift action.
    pub lift: bool,
}

/// Extra information about a step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepInfo {
    /// Whether the episode succeeded, reported on the step that ends it by environments that
    /// have a notion of success (the grasp: the object is held after the lift).
    pub success: Option<bool>,
    /// The simulation failed (diverged or produced non-finite values) and the episode was
    /// cut short. The learner then does not trust the final observation: it neither
    /// bootstraps from it nor counts the episode as a regular end.
    pub physics_failure: bool,
}

/// The result of one environment step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The observation after the step.
    pub obs: Vec<f32>,
    /// The reward for the step.
    pub reward: f32,
    /// The episode reached a terminal state (no value bootstrapping).
    pub terminated: bool,
    /// The episode was cut short by a time limit (the value of `obs` is bootstrapped).
    pub truncated: bool,
    /// Extra information.
    pub info: StepInfo,
}

/// A reinforcement-learning environment with a gymnasium-style interface.
pub trait Env: Send {
    /// Length of the observation vector.
    fn obs_dim(&self) -> usize;
    /// The shape of the action.
    fn action_spec(&self) -> ActionSpec;
    /// Starts a new episode, seeded by `seed`, and returns its first observation.
    fn reset(&mut self, seed: u64) -> Vec<f32>;
    /// Applies `a` and advances the episode by one control step.
    fn step(&mut self, a: &Action) -> Step;
    /// The environment as [`std::any::Any`], for a caller that reads what its concrete
    /// type offers (the Python vector env reads a grasping environment's object and
    /// episode summary); `None` unless the type opts in.
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        None
    }
}

/// Errors of [`VecEnv`].
#[derive(Debug, thiserror::Error)]
pub enum EnvError {
    /// A vector of environments needs at least one environment.
    #[error("a vector environment needs at least one environment")]
    Empty,
    /// The environments disagree on their observation size or action shape.
    #[error(
        "environment {index} has obs_dim {obs_dim} and action {action:?}, \
         environment 0 has obs_dim {obs_dim0} and action {action0:?}"
    )]
    Mismatch {
        /// Index of the first disagreeing environment.
        index: usize,
        /// Its observation size.
        obs_dim: usize,
        /// Its action shape.
        action: ActionSpec,
        /// The observation size of environment 0.
        obs_dim0: usize,
        /// The action shape of environment 0.
        action0: ActionSpec,
    },
    /// An environment has no continuous action component.
    #[error("the action needs at least one continuous component")]
    NoContinuousAction,
    /// An environment returned an observation of the wrong length.
    #[error("environment {index} returned an observation of length {got}, expected {expected}")]
    ObsLength {
        /// Index of the environment.
        index: usize,
        /// The length returned.
        got: usize,
        /// The declared `obs_dim`.
        expected: usize,
    },
    /// An environment returned a non-finite observation or reward.
    #[error("environment {index} returned a non-finite {what}")]
    NonFinite {
        /// Index of the environment.
        index: usize,
        /// "observation", "reward" or "reset observation".
        what: &'static str,
    },
    /// The number of actions does not match the number of environments.
    #[error("got {got} actions for {expected} environments")]
    ActionCount {
        /// Actions given.
        got: usize,
        /// Environments.
        expected: usize,
    },
    /// An action has the wrong number of continuous components.
    #[error("action {index} has {got} continuous components, expected {expected}")]
    ActionLength {
        /// Index of the action.
        index: usize,
        /// Components given.
        got: usize,
        /// Components expected.
        expected: usize,
    },
    /// The thread pool could not be built.
    #[error("cannot build the environment thread pool: {0}")]
    ThreadPool(#[from] rayon::ThreadPoolBuildError),
}

/// The seed of episode `episode` of environment `env_index`, derived from `base` with the
/// SplitMix64 finaliser: distinct for every (base, index, episode) in practice and
/// independent of the order in which environments run.
pub fn episode_seed(base: u64, env_index: usize, episode: u64) -> u64 {
    let mut z = splitmix(base ^ 0x9e37_79b9_7f4a_7c15);
    z = splitmix(z ^ (env_index as u64).wrapping_mul(0xbf58_476d_1ce4_e5b9));
    splitmix(z ^ episode.wrapping_mul(0x94d0_49bb_1331_11eb))
}

/// SplitMix64 mixing function (Steele, Lea and Flood 2014).
fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Statistics of one finished episode.
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeRecord {
    /// Index of the environment that ran it.
    pub env_index: usize,
    /// Sum of the raw rewards.
    pub ret: f64,
    /// Number of steps.
    pub length: u64,
    /// Success as reported by the environment on the final step.
    pub success: Option<bool>,
    /// The episode ended in a physics failure.
    pub physics_failure: bool,
}

/// The result of stepping all environments of a [`VecEnv`].
#[derive(Debug, Clone)]
pub struct VecStep {
    /// Next observations, `num_envs * obs_dim` values, environment-major. For environments
    /// whose episode ended this is already the first observation of the next episode.
    pub obs: Vec<f32>,
    /// Rewards, one per environment.
    pub rewards: Vec<f32>,
    /// Terminated flags.
    pub terminated: Vec<bool>,
    /// Truncated flags.
    pub truncated: Vec<bool>,
    /// The last observation of each episode that ended on this step (`None` otherwise).
    pub final_obs: Vec<Option<Vec<f32>>>,
    /// Step information.
    pub infos: Vec<StepInfo>,
}

/// Per-environment bookkeeping.
struct Slot {
    env: Box<dyn Env>,
    episode: u64,
    ret: f64,
    length: u64,
}

/// What stepping one environment returns: the step, the final observation of an
/// episode that ended (the step's observation is then the next episode's first), and its
/// record.
type Out = (Step, Option<Vec<f32>>, Option<EpisodeRecord>);

/// Steps environment `i` with `a`, resetting it (seeded from `base`) when its episode ends.
fn step_slot(s: &mut Slot, i: usize, a: &Action, base: u64) -> Out {
    let mut st = s.env.step(a);
    s.ret += f64::from(st.reward);
    s.length += 1;
    if st.terminated || st.truncated {
        let rec = EpisodeRecord {
            env_index: i,
            ret: s.ret,
            length: s.length,
            success: st.info.success,
            physics_failure: st.info.physics_failure,
        };
        s.episode += 1;
        s.ret = 0.0;
        s.length = 0;
        let first = s.env.reset(episode_seed(base, i, s.episode));
        let last = std::mem::replace(&mut st.obs, first);
        (st, Some(last), Some(rec))
    } else {
        (st, None, None)
    }
}

/// A vector of environments stepped in parallel with automatic reset.
pub struct VecEnv {
    slots: Vec<Slot>,
    pool: rayon::ThreadPool,
    base_seed: u64,
    obs_dim: usize,
    spec: ActionSpec,
    finished: Vec<EpisodeRecord>,
}

impl VecEnv {
    /// Wraps `envs`, stepping them on a dedicated pool of `num_threads` threads (at least 1).
    /// Episode `k` of environment `i` is reset with `episode_seed(base_seed, i, k)`.
    pub fn new(
        envs: Vec<Box<dyn Env>>,
        num_threads: usize,
        base_seed: u64,
    ) -> Result<Self, EnvError> {
        let first = envs.first().ok_or(EnvError::Empty)?;
        let obs_dim = first.obs_dim();
        let spec = first.action_spec();
        if spec.continuous == 0 {
            return Err(EnvError::NoContinuousAction);
        }
        for (index, e) in envs.iter().enumerate() {
            if e.obs_dim() != obs_dim || e.action_spec() != spec {
                return Err(EnvError::Mismatch {
                    index,
                    obs_dim: e.obs_dim(),
                    action: e.action_spec(),
                    obs_dim0: obs_dim,
                    action0: spec,
                });
            }
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(num_threads.max(1))
            .thread_name(|i| format!("grasp-env-{i}"))
            .build()?;
        let slots = envs
            .into_iter()
            .map(|env| Slot {
                env,
                episode: 0,
                ret: 0.0,
                length: 0,
            })
            .collect();
        Ok(Self {
            slots,
            pool,
            base_seed,
            obs_dim,
            spec,
            finished: Vec::new(),
        })
    }

    /// Number of environments.
    pub fn num_envs(&self) -> usize {
        self.slots.len()
    }

    /// Environment `i` (as it stands after the last step: an environment whose episode
    /// ended has already started the next one).
    pub fn env(&self, i: usize) -> Option<&dyn Env> {
        self.slots.get(i).map(|s| s.env.as_ref())
    }

    /// Length of one observation.
    pub fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    /// The shape of the action.
    pub fn action_spec(&self) -> ActionSpec {
        self.spec
    }

    /// The base seed.
    pub fn base_seed(&self) -> u64 {
        self.base_seed
    }

    /// Restarts every environment: the episode counters restart at zero with base seed
    /// `base_seed`, unfinished episodes are dropped from the statistics. Returns the first
    /// observations, `num_envs * obs_dim` values.
    pub fn reset(&mut self, base_seed: u64) -> Result<Vec<f32>, EnvError> {
        self.base_seed = base_seed;
        let obs_dim = self.obs_dim;
        let results: Vec<Vec<f32>> = self.pool.install(|| {
            self.slots
                .par_iter_mut()
                .enumerate()
                .map(|(i, s)| {
                    s.episode = 0;
                    s.ret = 0.0;
                    s.length = 0;
                    s.env.reset(episode_seed(base_seed, i, 0))
                })
                .collect()
        });
        let mut out = Vec::with_capacity(results.len() * obs_dim);
        for (index, o) in results.into_iter().enumerate() {
            check_obs(index, &o, obs_dim, "reset observation")?;
            out.extend_from_slice(&o);
        }
        Ok(out)
    }

    /// Steps every environment with its action; environments whose episode ends are reset
    /// at once with their next episode seed.
    pub fn step(&mut self, actions: &[Action]) -> Result<VecStep, EnvError> {
        if actions.len() != self.slots.len() {
            return Err(EnvError::ActionCount {
                got: actions.len(),
                expected: self.slots.len(),
            });
        }
        for (index, a) in actions.iter().enumerate() {
            if a.cont.len() != self.spec.continuous {
                return Err(EnvError::ActionLength {
                    index,
                    got: a.cont.len(),
                    expected: self.spec.continuous,
                });
            }
        }
        let base = self.base_seed;
        // One shared queue, longest jobs first: a lift ends its episode, and its
        // environment then resets and runs stage 1 in the same job (several control
        // steps' physics). Each pool thread takes the next job when it is free, so the
        // long jobs do not end up together at the end of one thread's share.
        let n = self.slots.len();
        let mut jobs: Vec<(usize, &mut Slot)> = self.slots.iter_mut().enumerate().collect();
        jobs.sort_by_key(|(i, _)| !actions[*i].lift);
        let queue = Mutex::new(jobs.into_iter());
        let done: Mutex<Vec<(usize, Out)>> = Mutex::new(Vec::with_capacity(n));
        self.pool.broadcast(|_| loop {
            let Some((i, s)) = queue.lock().unwrap_or_else(PoisonError::into_inner).next() else {
                break;
            };
            let out = step_slot(s, i, &actions[i], base);
            done.lock()
                .unwrap_or_else(PoisonError::into_inner)
                .push((i, out));
        });
        let mut done = done.into_inner().unwrap_or_else(PoisonError::into_inner);
        done.sort_by_key(|(i, _)| *i);
        let results: Vec<Out> = done.into_iter().map(|(_, out)| out).collect();
        let mut out = VecStep {
            obs: Vec::with_capacity(n * self.obs_dim),
            rewards: Vec::with_capacity(n),
            terminated: Vec::with_capacity(n),
            truncated: Vec::with_capacity(n),
            final_obs: Vec::with_capacity(n),
            infos: Vec::with_capacity(n),
        };
        for (index, (st, last, rec)) in results.into_iter().enumerate() {
            check_obs(index, &st.obs, self.obs_dim, "observation")?;
            if !st.reward.is_finite() {
                return Err(EnvError::NonFinite {
                    index,
                    what: "reward",
                });
            }
            if let Some(last) = &last {
                if last.len() != self.obs_dim {
                    return Err(EnvError::ObsLength {
                        index,
                        got: last.len(),
                        expected: self.obs_dim,
                    });
                }
            }
            out.obs.extend_from_slice(&st.obs);
            out.rewards.push(st.reward);
            out.terminated.push(st.terminated);
            out.truncated.push(st.truncated);
            out.final_obs.push(last);
            out.infos.push(st.info);
            if let Some(rec) = rec {
                self.finished.push(rec);
            }
        }
        Ok(out)
    }

    /// Takes the records of the episodes finished since the last call.
    pub fn drain_finished(&mut self) -> Vec<EpisodeRecord> {
        std::mem::take(&mut self.finished)
    }
}

/// Checks an observation's length and finiteness.
fn check_obs(index: usize, o: &[f32], expected: usize, what: &'static str) -> Result<(), EnvError> {
    if o.len() != expected {
        return Err(EnvError::ObsLength {
            index,
            got: o.len(),
            expected,
        });
    }
    if o.iter().any(|v| !v.is_finite()) {
        return Err(EnvError::NonFinite { index, what });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts steps; ends after `len` steps (terminated when `len` is odd, else truncated).
    /// The observation is [seed as f32 fraction, step].
    struct Counter {
        len: u32,
        t: u32,
        seed: u64,
    }

    impl Env for Counter {
        fn obs_dim(&self) -> usize {
            2
        }
        fn action_spec(&self) -> ActionSpec {
            ActionSpec {
                continuous: 1,
                lift: false,
            }
        }
        fn reset(&mut self, seed: u64) -> Vec<f32> {
            self.t = 0;
            self.seed = seed;
            vec![(seed % 1000) as f32, 0.0]
        }
        fn step(&mut self, a: &Action) -> Step {
            self.t += 1;
            let done = self.t >= self.len;
            Step {
                obs: vec![(self.seed % 1000) as f32, self.t as f32],
                reward: a.cont[0],
                terminated: done && !self.len.is_multiple_of(2),
                truncated: done && self.len.is_multiple_of(2),
                info: StepInfo {
                    success: done.then_some(true),
                    physics_failure: false,
                },
            }
        }
    }

    fn counters(lens: &[u32]) -> Vec<Box<dyn Env>> {
        lens.iter()
            .map(|&len| Box::new(Counter { len, t: 0, seed: 0 }) as Box<dyn Env>)
            .collect()
    }

    fn run(threads: usize) -> (Vec<Vec<f32>>, Vec<EpisodeRecord>) {
        let mut v = VecEnv::new(counters(&[2, 3, 4]), threads, 7).unwrap();
        let mut all = vec![v.reset(7).unwrap()];
        let act: Vec<Action> = (0..3)
            .map(|i| Action {
                cont: vec![i as f32 + 1.0],
                lift: false,
            })
            .collect();
        for _ in 0..6 {
            all.push(v.step(&act).unwrap().obs);
        }
        (all, v.drain_finished())
    }

    #[test]
    fn auto_reset_keeps_final_obs_and_reseeds() {
        let mut v = VecEnv::new(counters(&[2]), 1, 5).unwrap();
        let o0 = v.reset(5).unwrap();
        assert_eq!(o0[0], (episode_seed(5, 0, 0) % 1000) as f32);
        let a = [Action {
            cont: vec![0.5],
            lift: false,
        }];
        let s1 = v.step(&a).unwrap();
        assert!(s1.final_obs[0].is_none());
        let s2 = v.step(&a).unwrap();
        assert!(s2.truncated[0] && !s2.terminated[0]);
        assert_eq!(s2.final_obs[0], Some(vec![o0[0], 2.0]));
        assert_eq!(s2.obs, vec![(episode_seed(5, 0, 1) % 1000) as f32, 0.0]);
        let rec = v.drain_finished();
        assert_eq!(rec.len(), 1);
        assert_eq!(rec[0].length, 2);
        assert!((rec[0].ret - 1.0).abs() < 1e-12);
        assert_eq!(rec[0].success, Some(true));
        assert!(v.drain_finished().is_empty());
    }

    #[test]
    fn results_do_not_depend_on_thread_count() {
        let (a1, r1) = run(1);
        let (a2, r2) = run(3);
        assert_eq!(a1, a2);
        assert_eq!(r1, r2);
        // env 0 (len 2) finished 3 episodes, env 1 (len 3) 2, env 2 (len 4) 1.
        assert_eq!(r1.len(), 6);
    }

    #[test]
    fn lifts_run_first_but_results_stay_in_environment_order() {
        // The queue hands out lift actions first; every output still belongs to its
        // environment, whatever the lift flags (Counter ignores them).
        let step = |lifts: [bool; 4], threads: usize| {
            let mut v = VecEnv::new(counters(&[2, 3, 4, 5]), threads, 3).unwrap();
            v.reset(3).unwrap();
            let act: Vec<Action> = (0..4)
                .map(|i| Action {
                    cont: vec![i as f32 + 1.0],
                    lift: lifts[i],
                })
                .collect();
            let steps: Vec<VecStep> = (0..3).map(|_| v.step(&act).unwrap()).collect();
            (
                steps.iter().map(|s| s.rewards.clone()).collect::<Vec<_>>(),
                steps.iter().map(|s| s.obs.clone()).collect::<Vec<_>>(),
                v.drain_finished(),
            )
        };
        let plain = step([false; 4], 1);
        assert_eq!(plain.0[0], vec![1.0, 2.0, 3.0, 4.0]);
        for threads in [1, 2, 4] {
            assert_eq!(step([false, true, false, true], threads), plain);
            assert_eq!(step([true, true, true, false], threads), plain);
        }
        // env 0 ended at step 2, env 1 at step 3: drained in environment order.
        assert_eq!(
            plain.2.iter().map(|r| r.env_index).collect::<Vec<_>>(),
            vec![0, 1]
        );
    }

    #[test]
    fn episode_seeds_differ() {
        let mut s = std::collections::HashSet::new();
        for i in 0..10 {
            for k in 0..10 {
                assert!(s.insert(episode_seed(1, i, k)));
            }
        }
        assert_ne!(episode_seed(1, 0, 0), episode_seed(2, 0, 0));
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(matches!(VecEnv::new(vec![], 1, 0), Err(EnvError::Empty)));
        let mut v = VecEnv::new(counters(&[2, 2]), 1, 0).unwrap();
        v.reset(0).unwrap();
        let e = v
            .step(&[Action {
                cont: vec![0.0],
                lift: false,
            }])
            .unwrap_err();
        assert!(matches!(
            e,
            EnvError::ActionCount {
                got: 1,
                expected: 2
            }
        ));
        let bad = vec![
            Action {
                cont: vec![0.0],
                lift: false,
            },
            Action {
                cont: vec![],
                lift: false,
            },
        ];
        assert!(matches!(
            v.step(&bad).unwrap_err(),
            EnvError::ActionLength { index: 1, .. }
        ));
        let nan = vec![
            Action {
                cont: vec![0.0],
                lift: false,
            },
            Action {
                cont: vec![f32::NAN],
                lift: false,
            },
        ];
        let e = v.step(&nan).unwrap_err();
        assert!(e.to_string().contains("environment 1"), "{e}");
    }
}
