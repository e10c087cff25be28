//! `grasp eval`'s measurement as one request: [`EvalRequest`] holds what the command line
//! names (the agents, the objects, the trials, the placement, the conditions, the
//! recordings); [`measure`] loads every agent in its own setup ([`TrainedAgent`]), picks
//! the one physics they are evaluated in ([`super::physics::common_sim_config`]), builds
//! the placement planner (and the critic that ranks it) and evaluates each agent on the
//! same scenes. The caller hears the warnings and the progress ([`EvalEvent`]) and prints
//! the results. Errors name the command line's flags.

use super::conditions::{ConditionsError, EvalConditions};
use super::record::{agent_file_name, RecordOptions};
use super::{
    evaluate_until, AgentResult, AgentSpec, CountedPregrasp, EvalAgent, EvalError, PregraspStats,
    RankStats, RankedPregrasp, TrialPlan,
};
use crate::checkpoint::{Assumed, CheckpointError, TrainedAgent};
use crate::env::curriculum::CurriculumConfig;
use crate::env::grasp::{EnvConfig, GraspEnv, GraspEnvError};
use crate::env::obs::Modality;
use crate::perception::pregrasp::{AntipodalPregrasp, PregraspPlanner};
use crate::ppo::LoadedPolicy;
use crate::robot::{Robot, Side};
use crate::sim::{ObjectSetError, ObjectSpec, SimConfig};
use crate::synergy::SynergyModel;
use crate::util::step::{StepContext, StepError};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// Where an episode's hand starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// Over the object's centre, `grasp_depth` below its top (the training placement).
    TopDown,
    /// `grasp run`'s antipodal pre-grasp on the simulated depth cloud.
    Antipodal,
}

impl Placement {
    /// The name as `--pregrasp` spells it.
    pub fn name(self) -> &'static str {
        match self {
            Placement::TopDown => "top-down",
            Placement::Antipodal => "antipodal",
        }
    }
}

/// What `grasp eval` is asked to measure (see the module docs).
#[derive(Debug, Clone)]
pub struct EvalRequest {
    /// The agents: `baseline1`, `baseline2` or checkpoint folders.
    pub policy: Vec<String>,
    /// Checkpoints sample their actions instead of taking the mode.
    pub stochastic: bool,
    /// The object set (as `--objects`).
    pub objects: String,
    /// Trials per object.
    pub trials: usize,
    /// Attempts per trial.
    pub attempts: usize,
    /// The synergy model of the baselines and of checkpoints saved without one.
    pub synergy: Option<PathBuf>,
    /// The baselines' synergy components (a checkpoint's must agree).
    pub components: Option<usize>,
    /// The baselines' sensing modality (a checkpoint's must agree).
    pub modality: Option<Modality>,
    /// The curriculum success rate that sets the start-pose randomisation.
    pub difficulty: f64,
    /// The simulator config for every agent; `None`: the checkpoints' own.
    pub sim_config: Option<PathBuf>,
    /// Worker threads (`None`: the available cores).
    pub threads: Option<usize>,
    /// Where the hand starts.
    pub pregrasp: Placement,
    /// Perturbed conditions (TOML) for every agent.
    pub perturb: Option<PathBuf>,
    /// The planner's best placements a critic compares (1: the planner's best).
    pub rank_top: usize,
    /// The checkpoint whose critic ranks; `None`: the first checkpoint of `policy`.
    pub ranker: Option<PathBuf>,
    /// Episode recordings (each agent's named after its label).
    pub record: Option<RecordOptions>,
    /// The agents' names in the outputs, in order (none: their paths).
    pub labels: Vec<String>,
    /// The seed of the scenes (`grasp --seed`).
    pub seed: u64,
}

/// What [`measure`] says as it goes.
#[derive(Debug, Clone, PartialEq)]
pub enum EvalEvent {
    /// Something the user should know (a setup assumed, a physics overridden).
    Warning(String),
    /// Progress: the physics chosen, the agent that starts, the placements made.
    Progress(String),
}

/// Error of a measurement or a rollout ([`super::rollout`]): a refused flag, a failed step
/// with its cause, or the evaluation's own.
#[derive(Debug, thiserror::Error)]
pub enum MeasureError {
    /// A flag's value, or flags that do not go together.
    #[error("{0}")]
    Flags(String),
    /// A step of the set-up or of the work failed; the cause follows.
    #[error(transparent)]
    Step(#[from] StepError),
    /// The objects cannot be simulated.
    #[error(transparent)]
    Objects(#[from] ObjectSetError),
    /// A checkpoint's setup contradicts the flags.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The conditions file is bad.
    #[error(transparent)]
    Conditions(#[from] ConditionsError),
    /// The synergy model cannot be used.
    #[error(transparent)]
    Synergy(#[from] crate::synergy::ModelChoiceError),
    /// The evaluation failed.
    #[error(transparent)]
    Eval(#[from] EvalError),
}

/// The agent named by one `policy` entry; checkpoints act by sampling when `stochastic`.
fn agent_spec(s: &str, stochastic: bool) -> Result<AgentSpec, MeasureError> {
    Ok(match s {
        "baseline1" => AgentSpec::Baseline1,
        "baseline2" => AgentSpec::Baseline2,
        path => {
            let p = PathBuf::from(path);
            if !p.join(crate::ppo::CHECKPOINT_FILE).is_file() {
                return Err(MeasureError::Flags(format!(
                    "unknown policy '{path}': expected baseline1, baseline2 or a checkpoint folder containing {}",
                    crate::ppo::CHECKPOINT_FILE
                )));
            }
            AgentSpec::learned(p, stochastic)
        }
    })
}

/// The environment settings and synergy model of one agent.
struct AgentEnv {
    spec: AgentSpec,
    env: EnvConfig,
    model: SynergyModel,
    /// The simulator config the checkpoint was trained with (`None` for baselines and
    /// checkpoints without a config.toml); `Some(None)`: the built-in one.
    trained_sim: Option<Option<PathBuf>>,
    /// A checkpoint's loaded network.
    network: Option<Arc<LoadedPolicy>>,
}

/// Resolves each agent's environment: checkpoints from their own config.toml
/// ([`TrainedAgent`]), baselines (and checkpoints without one) from the request.
fn agent_envs(
    req: &EvalRequest,
    specs: Vec<AgentSpec>,
    say: &dyn Fn(EvalEvent),
) -> Result<Vec<AgentEnv>, MeasureError> {
    let flag_env = EnvConfig {
        modality: req.modality.unwrap_or(Modality::M3),
        ..EnvConfig::default()
    };
    let flag_components = req.components.unwrap_or(5);
    let warn = |m: String| say(EvalEvent::Warning(m));
    specs
        .into_iter()
        .map(|spec| {
            let Some(dir) = spec.checkpoint() else {
                let mut env = flag_env.clone();
                env.curriculum = CurriculumConfig::fixed(req.difficulty);
                return Ok(AgentEnv {
                    spec,
                    env,
                    model: crate::synergy::model_or_shipped(
                        req.synergy.as_deref(),
                        flag_components,
                    )?,
                    trained_sim: None,
                    network: None,
                });
            };
            let assumed = Assumed {
                env: Some(flag_env.clone()),
                n_components: Some(flag_components),
                synergy: req.synergy.clone(),
            };
            let mut agent = TrainedAgent::load_assuming(dir, &assumed)
                .step(|| format!("loading checkpoint {}", dir.display()))?;
            if !agent.has_config() {
                warn(format!(
                    "{} has no config.toml; using --modality/--components",
                    dir.display()
                ));
            }
            agent.check_flags(req.modality, req.components)?;
            if agent.has_synergy_file() {
                if req.synergy.is_some() && agent.has_config() {
                    warn(format!(
                        "{} uses the synergy.json saved beside it, not --synergy",
                        dir.display()
                    ));
                }
            } else if agent.has_config() {
                warn(format!(
                    "{} has no synergy.json; its policy acts in {}",
                    dir.display(),
                    req.synergy.as_ref().map_or_else(
                        || "the shipped synergy model (assets/synergy/model.json)".to_string(),
                        |p| format!("--synergy {}", p.display())
                    )
                ));
            }
            agent.at_difficulty(req.difficulty);
            Ok(AgentEnv {
                env: agent.env.clone(),
                model: agent.synergy().clone(),
                trained_sim: agent.trained_sim_path().map(|p| p.map(Path::to_path_buf)),
                network: Some(agent.network().clone()),
                spec,
            })
        })
        .collect()
}

/// The simulator config every agent is evaluated in
/// ([`super::physics::common_sim_config`]: `sim_config`, else the checkpoints' own, else
/// the built-in one).
fn eval_sim_config(
    flag: Option<&Path>,
    agents: &[AgentEnv],
    say: &dyn Fn(EvalEvent),
) -> Result<SimConfig, MeasureError> {
    let flag = match flag {
        Some(p) => Some((p, SimConfig::load_flag(Some(p))?)),
        None => None,
    };
    let trained: Vec<(&Path, Option<&Path>)> = agents
        .iter()
        .filter_map(|ag| Some((ag.spec.checkpoint()?, ag.trained_sim.as_ref()?.as_deref())))
        .collect();
    let (cfg, note) =
        super::physics::common_sim_config(flag, &trained, &mut |m| say(EvalEvent::Warning(m)))?;
    if let Some(n) = note {
        say(EvalEvent::Progress(n));
    }
    Ok(cfg)
}

/// Each agent's recordings are named after it (its label where given): two agents of one
/// name would overwrite each other's files, which is an error.
fn recording_names(
    req: &EvalRequest,
    agents: &[AgentEnv],
    objects: &[String],
) -> Result<Vec<String>, MeasureError> {
    let rec_names: Vec<String> = agents
        .iter()
        .enumerate()
        .map(|(i, ag)| {
            req.labels
                .get(i)
                .cloned()
                .unwrap_or_else(|| ag.spec.label())
        })
        .collect();
    if let Some(r) = &req.record {
        for (i, n) in rec_names.iter().enumerate() {
            let file = agent_file_name(n);
            if let Some(j) = (0..i).find(|&j| agent_file_name(&rec_names[j]) == file) {
                return Err(MeasureError::Flags(format!(
                    "--record {}: agents '{}' and '{n}' would both be recorded as \
                     '{file}_<object>_<trial>' and overwrite each other: name them apart \
                     with --labels",
                    r.dir.display(),
                    rec_names[j]
                )));
            }
        }
        super::record::check_file_names(&rec_names, objects).map_err(|e| {
            MeasureError::Flags(format!(
                "--record {}: {e}: name the agents apart with --labels",
                r.dir.display()
            ))
        })?;
    }
    Ok(rec_names)
}

/// The critic that ranks the planner's placements (`rank_top` above 1): its checkpoint,
/// network and setup.
struct Ranker {
    dir: PathBuf,
    critic: Arc<LoadedPolicy>,
    env: AgentEnv,
}

/// The ranker `req` asks for: `ranker`, else the first checkpoint of `policy`, in its own
/// setup (perturbed as the agents are); `None` with `rank_top` 1.
fn ranker(
    req: &EvalRequest,
    agents: &[AgentEnv],
    conditions: Option<&EvalConditions>,
    say: &dyn Fn(EvalEvent),
) -> Result<Option<Ranker>, MeasureError> {
    if req.rank_top < 2 {
        return Ok(None);
    }
    if conditions.is_some_and(|c| c.randomization.enabled) {
        return Err(MeasureError::Flags(format!(
            "--rank-top {} with --perturb's [randomization]: the ranker's probes would close \
             on the nominal object, not the episode's randomised one; rank without it",
            req.rank_top
        )));
    }
    let dir = match &req.ranker {
        Some(d) => d.clone(),
        None => agents
            .iter()
            .find_map(|ag| ag.spec.checkpoint().map(Path::to_path_buf))
            .ok_or_else(|| {
                MeasureError::Flags(format!(
                    "--rank-top {} needs a critic to rank with: give --ranker CHECKPOINT or a \
                     checkpoint in --policy",
                    req.rank_top
                ))
            })?,
    };
    let Some(mut env) = agent_envs(req, vec![AgentSpec::learned(dir.clone(), false)], say)?.pop()
    else {
        return Err(MeasureError::Flags("the ranker's setup".into()));
    };
    if let Some(c) = conditions {
        c.apply(&mut env.env);
    }
    let Some(critic) = env.network.clone() else {
        return Err(MeasureError::Flags("the ranker's network".into()));
    };
    Ok(Some(Ranker { dir, critic, env }))
}

/// Evaluates every agent of `req` on the same scenes (see the module docs), telling `say`
/// what it assumes and does; a set `stop` starts no new trial, and the agents with no
/// finished trial are left out.
pub fn measure(
    req: &EvalRequest,
    say: &(dyn Fn(EvalEvent) + Sync),
    stop: Option<&AtomicBool>,
) -> Result<Vec<AgentResult>, MeasureError> {
    let specs = req
        .policy
        .iter()
        .map(|s| agent_spec(s, req.stochastic))
        .collect::<Result<Vec<_>, _>>()?;
    let robot = Robot::builtin(Side::Left);
    let objects = ObjectSpec::simulable_set(&req.objects)?;
    let names: Vec<String> = objects.iter().map(|o| o.0.clone()).collect();
    let mut agents = agent_envs(req, specs, say)?;
    let conditions = match &req.perturb {
        Some(p) => Some(EvalConditions::load(p)?),
        None => None,
    };
    if let Some(c) = &conditions {
        for ag in &mut agents {
            c.apply(&mut ag.env);
        }
    }
    let sim_cfg = eval_sim_config(req.sim_config.as_deref(), &agents, say)?;
    // The environment of agent `ag` (or of the ranker) on object `o` alone.
    let env_on = |ag: &AgentEnv, o: usize| {
        GraspEnv::new(
            &robot,
            vec![objects[o].clone()],
            ag.model.clone(),
            sim_cfg.clone(),
            ag.env.clone(),
        )
    };
    let ranker = ranker(req, &agents, conditions.as_ref(), say)?;
    let rec_names = recording_names(req, &agents, &names)?;
    let n_threads = crate::util::threads::from_flag(req.threads).map_err(MeasureError::Flags)?;
    let mut results = Vec::new();
    for (i, ag) in agents.iter().enumerate() {
        let record = req.record.as_ref().map(|r| RecordOptions {
            name: Some(rec_names[i].clone()),
            ..r.clone()
        });
        let counts: Arc<[AtomicUsize; 2]> = Arc::new(Default::default());
        let chosen = RankedPregrasp::tally(req.rank_top);
        let make_env = |o: usize| {
            let env = env_on(ag, o)?;
            let inner: Box<dyn PregraspPlanner> = match &ranker {
                None => Box::new(AntipodalPregrasp::default()),
                Some(r) => Box::new(RankedPregrasp::new(
                    AntipodalPregrasp::default(),
                    req.rank_top,
                    env_on(&r.env, o)?,
                    r.critic.clone(),
                    chosen.clone(),
                )),
            };
            Ok::<_, GraspEnvError>(match req.pregrasp {
                Placement::TopDown => env,
                Placement::Antipodal => env.with_pregrasp(Box::new(CountedPregrasp {
                    inner,
                    counts: counts.clone(),
                })),
            })
        };
        say(EvalEvent::Progress(format!(
            "evaluating {}{} on {} objects x {} trials ...",
            ag.spec.label(),
            ag.env.action.grip_note(),
            names.len(),
            req.trials
        )));
        if crate::util::signal::is_set(stop) {
            break;
        }
        results.push(evaluate_until(
            &names,
            &TrialPlan {
                trials: req.trials,
                seed: req.seed,
                attempts: req.attempts,
            },
            n_threads,
            &make_env,
            EvalAgent {
                spec: &ag.spec,
                network: ag.network.as_ref(),
            },
            record.as_ref(),
            stop,
        )?);
        if results.last().is_some_and(|r| r.objects.is_empty()) {
            // Stopped before any of its trials finished.
            results.pop();
            break;
        }
        if let Some(r) = results.last_mut() {
            r.conditions = conditions.clone();
        }
        if req.pregrasp == Placement::Antipodal {
            let [planned, fallback] = [0, 1].map(|k| counts[k].load(Ordering::Relaxed));
            let ranked = ranker.as_ref().map(|rk| RankStats {
                top: req.rank_top,
                ranker: rk.dir.display().to_string(),
                chosen: chosen.iter().map(|n| n.load(Ordering::Relaxed)).collect(),
            });
            say(EvalEvent::Progress(format!(
                "  pre-grasp: {planned} episodes from an antipodal plan, {fallback} at the default placement (no plan on the cloud)"
            )));
            if let Some(rk) = &ranked {
                say(EvalEvent::Progress(format!(
                    "  ranked by the critic of {} among the planner's top {}: chosen by place {:?}",
                    rk.ranker, rk.top, rk.chosen
                )));
            }
            if let Some(r) = results.last_mut() {
                r.pregrasp = Some(PregraspStats {
                    placement: req.pregrasp.name().to_string(),
                    planned,
                    default_placement: fallback,
                    ranked,
                });
            }
        }
    }
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placements_are_named_as_the_flag_spells_them() {
        assert_eq!(Placement::TopDown.name(), "top-down");
        assert_eq!(Placement::Antipodal.name(), "antipodal");
    }

    #[test]
    fn an_unknown_agent_is_refused_before_any_object_is_built() {
        let req = EvalRequest {
            policy: vec!["baseline1".into(), "no/such/folder".into()],
            stochastic: false,
            objects: "no such set".into(),
            trials: 1,
            attempts: 1,
            synergy: None,
            components: None,
            modality: None,
            difficulty: 1.0,
            sim_config: None,
            threads: Some(1),
            pregrasp: Placement::TopDown,
            perturb: None,
            rank_top: 1,
            ranker: None,
            record: None,
            labels: Vec::new(),
            seed: 0,
        };
        let e = measure(&req, &|_| {}, None).err().map(|e| e.to_string());
        assert_eq!(
            e.as_deref(),
            Some(
                "unknown policy 'no/such/folder': expected baseline1, baseline2 or a checkpoint \
                 folder containing checkpoint.safetensors"
            )
        );
    }
}
