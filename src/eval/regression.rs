//! The CI regression check: a small fixed-seed evaluation (scripted baseline 2 and the
//! shipped policy on a few objects) and an environment-throughput figure, compared with
//! committed reference figures, so that a change that silently breaks the physics or
//! the learned policy's behaviour turns CI red.
//!
//! Success counts must stay within [`Reference::tolerance_episodes`] of the reference
//! (the physics is deterministic for one binary, but CPUs and compilers may round
//! differently); throughput must stay above [`Reference::min_throughput_ratio`] times the
//! reference (CI machines differ in speed) when both were measured in the same build
//! profile ([`Figures::build`]): a release build steps the environment about 1.4x faster
//! than the dev profile `.ci/run` uses (32 against 22.5 steps/s on the reference machine),
//! so across profiles only the counts are compared.

use super::{evaluate, AgentSpec, EvalAgent, EvalError, TrialPlan};
use crate::env::api::{Env, VecEnv};
use crate::env::bench::{random_agent, Until};
use crate::env::grasp::{EnvConfig, GraspEnv, GraspEnvError};
use crate::robot::{Robot, Side};
use crate::sim::{ObjectSpec, SimConfig};
use crate::synergy::SynergyModel;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Version of the reference format.
pub const REFERENCE_VERSION: u32 = 1;

/// One agent's figure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AgentFigure {
    /// `baseline2` or the policy folder's name.
    pub agent: String,
    /// Successful episodes.
    pub successes: usize,
    /// Episodes run.
    pub episodes: usize,
    /// Per object, in order: successes.
    pub per_object: Vec<usize>,
}

/// The measured figures of one regression run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Figures {
    /// Objects evaluated.
    pub objects: Vec<String>,
    /// Trials per object.
    pub trials: usize,
    /// Seed of the trials.
    pub seed: u64,
    /// Per agent.
    pub agents: Vec<AgentFigure>,
    /// Grasp-environment steps per second (random agent, fixed number of steps).
    pub env_steps_per_s: f64,
    /// Environments and threads of the throughput measurement.
    pub throughput_envs: usize,
    /// Threads of the throughput measurement.
    pub throughput_threads: usize,
    /// The build profile that measured the throughput (a reference written before this
    /// field existed was measured in release).
    #[serde(default)]
    pub build: BuildProfile,
}

/// The cargo build profile of a measurement, `"dev"` or `"release"` in the JSON.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BuildProfile {
    /// A binary with debug assertions: cargo's dev and test profiles, which `.ci/run` uses.
    Dev,
    /// An optimised binary without debug assertions.
    #[default]
    Release,
}

impl BuildProfile {
    /// The profile of this binary.
    pub fn current() -> Self {
        if cfg!(debug_assertions) {
            BuildProfile::Dev
        } else {
            BuildProfile::Release
        }
    }
}

impl std::fmt::Display for BuildProfile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BuildProfile::Dev => "dev",
            BuildProfile::Release => "release",
        })
    }
}

/// The committed reference (`ci/reference.json`): figures plus tolerances.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// [`REFERENCE_VERSION`].
    pub version: u32,
    /// Success counts may differ by this many episodes per agent.
    pub tolerance_episodes: usize,
    /// Throughput may fall to this fraction of the reference.
    pub min_throughput_ratio: f64,
    /// The reference figures.
    pub figures: Figures,
}

impl Reference {
    /// Whether `now`'s throughput is compared with this reference's: only when both were
    /// measured in the same build profile.
    pub fn compares_throughput(&self, now: &Figures) -> bool {
        now.build == self.figures.build
    }

    /// A reference from `figures` with the default tolerances (±1 episode, 0.3x).
    pub fn from_figures(figures: Figures) -> Self {
        Reference {
            version: REFERENCE_VERSION,
            tolerance_episodes: 1,
            min_throughput_ratio: 0.3,
            figures,
        }
    }
}

/// Compares `now` with `reference`; returns one line per regressed figure (empty: pass).
/// A different setup (objects, trials, seed, agents) is reported as such. The throughput
/// is compared only when both were measured in the same build profile.
pub fn compare(now: &Figures, reference: &Reference) -> Vec<String> {
    let r = &reference.figures;
    let mut out = Vec::new();
    if (now.objects.as_slice(), now.trials, now.seed) != (r.objects.as_slice(), r.trials, r.seed) {
        out.push(format!(
            "setup differs from the reference: objects {:?} x {} trials, seed {} (reference \
             {:?} x {}, seed {}); rerun with --update",
            now.objects, now.trials, now.seed, r.objects, r.trials, r.seed
        ));
        return out;
    }
    for ra in &r.agents {
        match now.agents.iter().find(|a| a.agent == ra.agent) {
            None => out.push(format!("agent {} is missing", ra.agent)),
            Some(a) => {
                if a.successes.abs_diff(ra.successes) > reference.tolerance_episodes {
                    out.push(format!(
                        "{} successes: {}/{} vs reference {}/{} (tolerance ±{})",
                        a.agent,
                        a.successes,
                        a.episodes,
                        ra.successes,
                        ra.episodes,
                        reference.tolerance_episodes
                    ));
                }
            }
        }
    }
    let floor = reference.min_throughput_ratio * r.env_steps_per_s;
    if now.env_steps_per_s.is_nan()
        || (reference.compares_throughput(now) && now.env_steps_per_s < floor)
    {
        out.push(format!(
            "env_steps_per_s: {:.1} is below {:.2} x the reference {:.1} = {:.1}",
            now.env_steps_per_s, reference.min_throughput_ratio, r.env_steps_per_s, floor
        ));
    }
    out
}

/// What to measure.
#[derive(Debug, Clone, PartialEq)]
pub struct RegressionSetup {
    /// Objects (name, simulator description).
    pub objects: Vec<(String, ObjectSpec)>,
    /// Trials per object.
    pub trials: usize,
    /// Seed.
    pub seed: u64,
    /// The policy checkpoint folder.
    pub policy: PathBuf,
    /// Threads.
    pub threads: usize,
    /// Environments of the throughput measurement.
    pub throughput_envs: usize,
    /// Environment steps of the throughput measurement (all environments together).
    pub throughput_steps: usize,
}

/// Runs the evaluation of baseline 2 and the policy (in the setup saved beside it) and
/// the throughput measurement.
pub fn measure(setup: &RegressionSetup) -> Result<Figures, EvalError> {
    let robot = Robot::builtin(Side::Left);
    let names: Vec<String> = setup.objects.iter().map(|o| o.0.clone()).collect();
    let sim = SimConfig::default();
    let baseline_model = crate::synergy::default_model()
        .truncated(5)
        .map_err(|e| EvalError::Agent(e.to_string()))?;
    let mut agent = crate::checkpoint::TrainedAgent::load(&setup.policy)?;
    if !agent.has_config() {
        return Err(EvalError::Checkpoint {
            path: setup.policy.join(crate::checkpoint::files::CONFIG),
            message: "missing: the regression policy must be a `grasp train` checkpoint".into(),
        });
    }
    agent.at_difficulty(1.0);
    let runs: [(AgentSpec, String, EnvConfig, &SynergyModel); 2] = [
        (
            AgentSpec::Baseline2,
            "baseline2".into(),
            EnvConfig {
                curriculum: crate::env::curriculum::CurriculumConfig::fixed(1.0),
                ..EnvConfig::default()
            },
            &baseline_model,
        ),
        (
            AgentSpec::Checkpoint(setup.policy.clone()),
            setup
                .policy
                .file_name()
                .map_or_else(|| "policy".into(), |n| n.to_string_lossy().into_owned()),
            agent.env.clone(),
            agent.synergy(),
        ),
    ];
    let mut agents = Vec::new();
    for (spec, name, env_cfg, model) in runs {
        let make_env = |o: usize| -> Result<GraspEnv, GraspEnvError> {
            GraspEnv::new(
                &robot,
                vec![setup.objects[o].clone()],
                model.clone(),
                sim.clone(),
                env_cfg.clone(),
            )
        };
        let r = evaluate(
            &names,
            &TrialPlan::once(setup.trials, setup.seed),
            setup.threads,
            &make_env,
            EvalAgent {
                spec: &spec,
                network: spec.checkpoint().map(|_| agent.network()),
            },
            None,
        )?;
        agents.push(AgentFigure {
            agent: name,
            successes: r.objects.iter().map(|o| o.successes).sum(),
            episodes: r.objects.iter().map(|o| o.trials).sum(),
            per_object: r.objects.iter().map(|o| o.successes).collect(),
        });
    }
    let env_steps_per_s = throughput(setup, &robot, &baseline_model, &sim)?;
    Ok(Figures {
        objects: names,
        trials: setup.trials,
        seed: setup.seed,
        agents,
        env_steps_per_s,
        throughput_envs: setup.throughput_envs,
        throughput_threads: setup.threads,
        build: BuildProfile::current(),
    })
}

/// Grasp-environment steps per second of a seeded random agent on `throughput_envs`
/// environments in a [`VecEnv`], over `throughput_steps` steps (resets and stage 1
/// included, as in training).
fn throughput(
    setup: &RegressionSetup,
    robot: &Robot,
    model: &SynergyModel,
    sim: &SimConfig,
) -> Result<f64, EvalError> {
    let n_envs = setup.throughput_envs.max(1);
    let envs = (0..n_envs)
        .map(|_| -> Result<Box<dyn Env>, EvalError> {
            Ok(Box::new(GraspEnv::new(
                robot,
                setup.objects.clone(),
                model.clone(),
                sim.clone(),
                EnvConfig::default(),
            )?))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let agent_err = |e: crate::env::api::EnvError| EvalError::Agent(e.to_string());
    let mut venv = VecEnv::new(envs, setup.threads, setup.seed).map_err(agent_err)?;
    let until = Until::Steps(setup.throughput_steps as u64);
    let f = random_agent(&mut venv, setup.seed, until).map_err(agent_err)?;
    Ok(f.env_steps_per_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn figures(b2: usize, policy: usize, speed: f64) -> Figures {
        Figures {
            objects: vec!["a".into(), "b".into()],
            trials: 3,
            seed: 0,
            agents: vec![
                AgentFigure {
                    agent: "baseline2".into(),
                    successes: b2,
                    episodes: 6,
                    per_object: vec![b2, 0],
                },
                AgentFigure {
                    agent: "quick".into(),
                    successes: policy,
                    episodes: 6,
                    per_object: vec![policy, 0],
                },
            ],
            env_steps_per_s: speed,
            throughput_envs: 4,
            throughput_threads: 2,
            build: BuildProfile::Dev,
        }
    }

    #[test]
    fn within_tolerance_passes() {
        let r = Reference::from_figures(figures(3, 2, 100.0));
        assert!(compare(&figures(3, 2, 100.0), &r).is_empty());
        // ±1 episode and 0.3x the speed are allowed.
        assert!(compare(&figures(4, 1, 30.0), &r).is_empty());
        assert!(compare(&figures(2, 3, 500.0), &r).is_empty());
    }

    #[test]
    fn each_regressed_figure_is_named() {
        let r = Reference::from_figures(figures(3, 2, 100.0));
        let v = compare(&figures(1, 2, 100.0), &r);
        assert_eq!(v.len(), 1);
        assert!(
            v[0].starts_with("baseline2 successes: 1/6 vs reference 3/6"),
            "{v:?}"
        );
        let v = compare(&figures(3, 5, 29.0), &r);
        assert_eq!(v.len(), 2, "{v:?}");
        assert!(v[0].starts_with("quick successes"));
        assert!(v[1].starts_with("env_steps_per_s: 29.0 is below 0.30 x"));
        // NaN throughput is a regression too.
        assert_eq!(compare(&figures(3, 2, f64::NAN), &r).len(), 1);
        let mut other = figures(3, 2, 100.0);
        other.trials = 2;
        assert!(compare(&other, &r)[0].contains("setup differs"));
        let mut missing = figures(3, 2, 100.0);
        missing.agents.pop();
        assert_eq!(compare(&missing, &r), ["agent quick is missing"]);
    }

    #[test]
    fn throughput_is_compared_only_within_one_build_profile() {
        let r = Reference::from_figures(figures(3, 2, 100.0));
        let mut release = figures(3, 2, 29.0);
        release.build = BuildProfile::Release;
        assert!(!r.compares_throughput(&release));
        assert!(compare(&release, &r).is_empty());
        // The counts are still compared across profiles.
        release.agents[0].successes = 1;
        assert_eq!(compare(&release, &r).len(), 1);
        // A reference written before the profile was recorded was a release one.
        let text = serde_json::to_string(&r)
            .unwrap()
            .replace(",\"build\":\"dev\"", "");
        let old: Reference = serde_json::from_str(&text).unwrap();
        assert_eq!(old.figures.build, BuildProfile::Release);
        // An unknown profile is an error naming the field's values, not a silent skip.
        let bad = serde_json::to_string(&r)
            .unwrap()
            .replace("\"build\":\"dev\"", "\"build\":\"debug\"");
        let err = serde_json::from_str::<Reference>(&bad)
            .unwrap_err()
            .to_string();
        assert!(err.contains("unknown variant `debug`"), "{err}");
    }

    #[test]
    fn reference_round_trips_and_rejects_unknown_keys() {
        let r = Reference::from_figures(figures(3, 2, 100.0));
        let text = serde_json::to_string_pretty(&r).unwrap();
        let back: Reference = serde_json::from_str(&text).unwrap();
        assert_eq!(back, r);
        let bad = text.replacen("\"version\"", "\"versoin\"", 1);
        assert!(serde_json::from_str::<Reference>(&bad).is_err());
    }
}
