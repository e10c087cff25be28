//! The grasping environment: the MDP of Sec. IV on top of the simulator.
//!
//! An episode:
//! 1. **reset**: an object is drawn from the set, its start pose perturbed by the
//!    curriculum (eq. 6); the hand is placed above it for a top-down grasp in the start
//!    posture (grasp point = TH/LF fingertip midpoint `grasp_depth` below the object's
//!    top, never below its centre);
//! 2. **stage 1**: the hand follows the human-like closing trajectory T (a smooth path
//!    from the start posture to a power grasp, in joint or synergy space: see
//!    [`super::closing`]) until ANY fingertip touches the object or T ends;
//! 3. **stage 2**: each [`Env::step`] applies eq. 2 to the finger targets and the wrist
//!    increments for one control period (anchored on the measured angles or the previous
//!    command, see [`super::action::Anchor`]), or lifts when `rho = 1` and judges the
//!    grasp. An episode that has not lifted after `max_steps` control steps either ends
//!    there as a failure ([`AtMaxSteps::Fail`]: its last step is terminal with `r_b = 0`,
//!    eq. 4's final step, not a time-limit truncation for PPO to bootstrap through, which
//!    would value running out of time like continuing to squeeze) or lifts
//!    ([`AtMaxSteps::Lift`], as the paper's episodes all end with a lift attempt).
//!
//! Rewards follow eq. 4 and 5 ([`super::reward`]); observations [`super::obs`].

// ObjectSpec is Copy today but is meant to carry convex hulls; keep the explicit clones.
#![allow(clippy::clone_on_copy)]

use super::action::{clip_unit, component_std, hand_targets, lift_targets};
use super::api::{Action, ActionSpec, Env, Step, StepInfo};
pub use super::closing::closing_target;
use super::closing::ClosingPath;
use super::curriculum::Curriculum;
use super::object_curriculum::ObjectCurriculum;
use super::obs::{surface_vectors, FrameStack, Modality, ObsLayout, Sensing, N_SURFACE};
use super::phases::{Phase, PhaseTally};
use super::reward;
use super::stream::ObjectStream;
use crate::perception::pregrasp::{AntipodalPregrasp, PlannedGrasp, PregraspPlanner};
use crate::robot::Robot;
use crate::sim::{
    script, FailureReport, HandSim, LiftOutcome, ObjectSpec, PhysicsFailure, Scene, SimConfig,
    SimError,
};
use crate::synergy::SynergyModel;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use std::time::Instant;

mod config;
mod probe;
mod retry;
pub use config::{AtMaxSteps, EnvConfig, GraspEnvError, MAX_STEPS};
pub use retry::NoRetry;
use retry::RetryStart;

/// Most 5 mm steps a reset raises the hand to start clear of the object.
const CLEARANCE_STEPS: usize = 20;

/// Lowest grasp point a height perturbation of `[env.placement]` moves to (m above the
/// table).
const MIN_PERTURBED_HEIGHT: f64 = 0.01;

/// What happened in one finished episode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EpisodeSummary {
    /// Name of the object.
    pub object: String,
    /// The object was held after the lift.
    pub success: bool,
    /// Stage-2 control steps taken (the lift step included).
    pub steps: usize,
    /// Sum of rewards.
    pub episode_return: f64,
    /// Whether the agent lifted (false: it ran out of control steps, or the physics failed).
    pub lifted: bool,
    /// The physics failed during the episode.
    pub physics_failure: bool,
    /// What failed and when (kind, the body pair, depth, physics step), when the
    /// simulator detected it.
    pub failure: Option<FailureReport>,
    /// The deepest penetration of the object by the hand or the table during the
    /// episode (m; 0 when nothing penetrated), failures below the threshold included.
    pub deepest_contact: f64,
    /// What the object touched in that deepest contact (a hand link or `table`; `None`
    /// when nothing penetrated).
    pub deepest_contact_with: Option<String>,
    /// Stage 1 ended on a fingertip contact (false: trajectory T ended first).
    pub touched_in_stage1: bool,
    /// The thumb's tactile bit when the lift began (false when the episode did not lift).
    pub thumb_contact_at_lift: bool,
    /// The grip held through the lift: the 22 finger joints' absolute PD efforts summed
    /// and averaged over the lift (N m; 0 when the episode did not lift).
    pub grip_effort: f64,
    /// The object's lowest point above the table top when the lift was judged (m; 0 when
    /// the episode did not lift). A lift succeeds from `lift.success_height` up.
    pub object_height: f64,
    /// The object touched the hand when the lift was judged (false when the episode did
    /// not lift). A failed lift with the object still in the hand held it too low: tipped,
    /// pivoting or slipping in the grasp.
    pub in_hand: bool,
    /// How far the object turned during the lift (rad; 0 when the episode did not lift):
    /// large when it tipped, pivoted about the fingers or swung in the grasp.
    pub object_turn: f64,
}

impl EpisodeSummary {
    /// A lift that was judged and failed (no physics failure): either
    /// [`Self::failed_in_hand`] or [`Self::failed_out_of_hand`].
    pub fn failed_lift(&self) -> bool {
        self.lifted && !self.success && !self.physics_failure
    }

    /// A lift that failed with the object still touching the hand, below the success
    /// height (no physics failure): the grasp held the object but tipped it, let it pivot
    /// or slip. See [`Self::failed_out_of_hand`] for the other failed lifts.
    pub fn failed_in_hand(&self) -> bool {
        self.failed_lift() && self.in_hand
    }

    /// A lift that failed with the object out of the hand when it was judged (no physics
    /// failure): dropped, or never picked up.
    pub fn failed_out_of_hand(&self) -> bool {
        self.failed_lift() && !self.in_hand
    }
}

/// What an episode's lift left for its summary.
#[derive(Debug, Clone, Copy)]
struct LiftRecord {
    /// The thumb's tactile bit when the lift began.
    thumb: bool,
    /// The grip held through the lift (N m).
    grip: f64,
    /// The object's lowest point above the table when judged (m).
    height: f64,
    /// The object touched the hand when judged.
    in_hand: bool,
    /// How far the object turned during the lift (rad).
    turn: f64,
}

/// The grasping environment for one simulated hand.
pub struct GraspEnv {
    cfg: EnvConfig,
    /// The configured start posture (the baselines start from it).
    start: [f64; 24],
    closed: [f64; 24],
    /// Stage 1's trajectory T of the policy episodes (from `path.start()`).
    path: ClosingPath,
    sim: HandSim,
    objects: Vec<(String, ObjectSpec)>,
    /// Which of `objects` the simulator holds (`None`: another object, e.g. a randomised
    /// copy).
    current_object: Option<usize>,
    /// Index in `objects` of the episode's object.
    episode_object: usize,
    /// The procedural stream, when the environment trains on it (see [`Self::with_stream`]).
    stream: Option<ObjectStream>,
    /// Noise of the observed sensors, re-seeded at each reset (domain randomisation).
    noise: rand_chacha::ChaCha8Rng,
    synergy: SynergyModel,
    eps_std: Vec<f64>,
    finger_limits: [(f64, f64); 22],
    wrist_limits: [(f64, f64); 2],
    layout: ObsLayout,
    stack: FrameStack,
    curriculum: Curriculum,
    /// The object curriculum, when enabled for a set of more than one object.
    object_curriculum: Option<ObjectCurriculum>,
    steps: usize,
    episode_return: f64,
    touched_in_stage1: bool,
    /// The episode's lift, once it lifted.
    lift_record: Option<LiftRecord>,
    last: Option<EpisodeSummary>,
    /// Physics steps and wall time per episode phase, over all episodes.
    phases: PhaseTally,
    /// The planner of the hand's start, when not the default top-down placement.
    pregrasp: Option<Box<dyn PregraspPlanner>>,
    /// Whether every episode starts from `pregrasp`'s plan (`grasp eval --pregrasp`)
    /// rather than the share `[env.placement] antipodal` draws.
    pregrasp_always: bool,
    /// Where the object lies for the trial's next attempt ([`GraspEnv::prepare_retry`]).
    retry: Option<RetryStart>,
    /// The planner's placements in the trial's attempts so far (the retry avoids them).
    tried: Vec<PlannedGrasp>,
    done: bool,
}

impl GraspEnv {
    /// Builds the environment: one simulator (its template is rebuilt when the episode's
    /// object changes), the synergy model of eq. 2 and the object set.
    pub fn new(
        robot: &Robot,
        objects: Vec<(String, ObjectSpec)>,
        synergy: SynergyModel,
        sim_cfg: SimConfig,
        cfg: EnvConfig,
    ) -> Result<GraspEnv, GraspEnvError> {
        let posture = cfg.validate()?;
        let first = objects
            .first()
            .map(|o| o.1.clone())
            .ok_or(GraspEnvError::NoObjects)?;
        let sim = HandSim::new(robot, first, sim_cfg)?;
        let layout = cfg.layout(synergy.n_components());
        let stack = FrameStack::new(&layout);
        let eps_std = component_std(&synergy);
        let limits = robot.hand_limits();
        let finger_limits = robot.finger_limits();
        let (start, closed) = (posture.angles(), script::power_grasp());
        let path = ClosingPath::new(cfg.closing, &start, &closed, &synergy, &finger_limits);
        let n_objects = objects.len();
        // Training's share of pre-grasp starts plans as `grasp run` does.
        let pregrasp = (cfg.placement.antipodal > 0.0)
            .then(|| Box::new(AntipodalPregrasp::default()) as Box<dyn PregraspPlanner>);
        Ok(GraspEnv {
            start,
            closed,
            path,
            sim,
            current_object: Some(0),
            episode_object: 0,
            objects,
            stream: None,
            noise: rand_chacha::ChaCha8Rng::seed_from_u64(0),
            synergy,
            eps_std,
            finger_limits,
            wrist_limits: [limits[0], limits[1]],
            layout,
            stack,
            curriculum: Curriculum::new(cfg.curriculum.clone()),
            object_curriculum: (cfg.object_curriculum.enabled && n_objects > 1)
                .then(|| ObjectCurriculum::new(cfg.object_curriculum.clone(), n_objects)),
            cfg,
            steps: 0,
            episode_return: 0.0,
            touched_in_stage1: false,
            lift_record: None,
            last: None,
            phases: PhaseTally::default(),
            pregrasp,
            pregrasp_always: false,
            retry: None,
            tried: Vec::new(),
            done: true,
        })
    }

    /// Starts every episode (policy and baseline alike) from `planner`'s placement
    /// instead of the default top-down one (see [`crate::perception::pregrasp`]),
    /// whatever `[env.placement]` says of the share.
    pub fn with_pregrasp(mut self, planner: Box<dyn PregraspPlanner>) -> Self {
        self.pregrasp = Some(planner);
        self.pregrasp_always = true;
        self
    }

    /// Switches the environment to the procedural object stream: from the next reset on,
    /// it builds a fresh stream object every `cfg.stream.reuse` episodes (see
    /// [`super::stream`]) instead of drawing from its object set.
    pub fn with_stream(mut self) -> Self {
        self.stream = Some(ObjectStream::new(self.cfg.stream.clone()));
        // One stream object at a time: nothing to choose between.
        self.object_curriculum = None;
        self
    }

    /// The observation layout.
    pub fn layout(&self) -> &ObsLayout {
        &self.layout
    }

    /// The simulator (read-only), e.g. for recordings.
    pub fn sim(&self) -> &HandSim {
        &self.sim
    }

    /// The simulator, mutably, for instrumentation such as episode recordings
    /// ([`HandSim::start_recording`]). Changing the scene or the targets mid-episode
    /// breaks the MDP.
    pub fn sim_mut(&mut self) -> &mut HandSim {
        &mut self.sim
    }

    /// The curriculum's current success rate `r_s`.
    pub fn curriculum_rate(&self) -> f64 {
        self.curriculum.rate()
    }

    /// Empties the curriculum's success window, as in a new environment: the next
    /// episodes' start poses are those a fresh environment draws from the same seeds.
    pub fn restart_curriculum(&mut self) {
        self.curriculum = Curriculum::new(self.cfg.curriculum.clone());
    }

    /// The objects of this environment (name, simulator description).
    pub fn objects(&self) -> &[(String, ObjectSpec)] {
        &self.objects
    }

    /// The name of the current (or last) episode's object.
    pub fn episode_object(&self) -> &str {
        &self.objects[self.episode_object].0
    }

    /// The summary of the last finished episode.
    pub fn last_episode(&self) -> Option<&EpisodeSummary> {
        self.last.as_ref()
    }

    /// Physics steps and wall time this environment spent in each phase of its episodes
    /// so far.
    pub fn phases(&self) -> &PhaseTally {
        &self.phases
    }

    /// Places object and hand for the episode of `seed` (object choice and eq. 6
    /// perturbation), without closing, the hand in the start posture of the policy's
    /// stage 1. The same seed gives the same scene, so different agents can be compared
    /// on identical initial object poses.
    pub fn reset_scene(&mut self, seed: u64) -> Result<(), SimError> {
        self.reset_scene_from(seed, self.path.start())
    }

    /// [`GraspEnv::reset_scene_from`], its time counted in the reset phase.
    fn timed_reset(&mut self, seed: u64, start: [f64; 24]) -> Result<(), SimError> {
        let t = Instant::now();
        let r = self.reset_scene_from(seed, start);
        self.phases.reset.add(0, t);
        r
    }

    /// [`GraspEnv::reset_scene`] with the hand in posture `start`.
    fn reset_scene_from(&mut self, seed: u64, start: [f64; 24]) -> Result<(), SimError> {
        let (mut scene, kept) = match self.retry.take() {
            // A retry: the same object, where the last attempt left it.
            Some(r) => {
                let scene = self.retry_scene(start, &r);
                self.sim.reset_with_object_pose(&scene, &r.pose)?;
                (scene, Some(r.pose))
            }
            None => {
                self.tried.clear();
                (self.fresh_scene(seed, start)?, None)
            }
        };
        let reset = |sim: &mut HandSim, scene: &Scene| match &kept {
            Some(pose) => sim.reset_with_object_pose(scene, pose),
            None => sim.reset(scene),
        };
        let draw = self.cfg.placement.draw(seed);
        let mut moved = false;
        if self.pregrasp_always || draw.antipodal {
            // No plan (or a non-finite one): the default placement stands.
            if let Some(g) = self
                .pregrasp
                .as_mut()
                .and_then(|planner| planner.plan(&self.sim, seed, &self.tried))
                .filter(PlannedGrasp::is_finite)
            {
                scene.grasp_point = g.grasp_point;
                scene.hand_yaw = g.hand_yaw;
                self.tried.push(g);
                moved = true;
            }
        }
        if draw.shift != [0.0; 3] || draw.yaw != 0.0 {
            let [dx, dy, dz] = draw.shift;
            let [x, y, z] = scene.grasp_point;
            // Lowered at most to MIN_PERTURBED_HEIGHT above the table (never below where
            // the placement put it).
            scene.grasp_point = [x + dx, y + dy, (z + dz).max(z.min(MIN_PERTURBED_HEIGHT))];
            scene.hand_yaw += draw.yaw;
            moved = true;
        }
        if moved {
            reset(&mut self.sim, &scene)?;
        }
        clear_hand(&mut self.sim, &mut scene, reset)?;
        self.steps = 0;
        self.episode_return = 0.0;
        self.touched_in_stage1 = false;
        self.lift_record = None;
        self.done = false;
        Ok(())
    }

    /// A fresh episode's object and default placement (object choice, eq. 6's
    /// perturbation, domain randomisation), the simulator reset to it.
    fn fresh_scene(&mut self, seed: u64, start: [f64; 24]) -> Result<Scene, SimError> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        if let Some(next) = self.stream.as_mut().and_then(|s| s.next(&mut rng)) {
            self.objects = vec![next];
            self.current_object = None;
        }
        let k = match &self.object_curriculum {
            Some(c) if self.stream.is_none() => c.sample(&mut rng),
            _ => rng.random_range(0..self.objects.len()),
        };
        let p = self.curriculum.sample(&mut rng);
        let dr = &self.cfg.randomization;
        let randomized = if dr.enabled {
            let o = dr.object(&self.objects[k].1, &mut rng);
            let yaw = dr.yaw(&mut rng);
            self.sim.set_object(o.clone())?;
            // The simulator holds a randomised copy: the next episode sets its own.
            self.current_object = None;
            self.noise = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x6e6f_6973_655f_7273);
            Some((o, yaw))
        } else {
            if self.current_object != Some(k) {
                self.sim.set_object(self.objects[k].1.clone())?;
                self.current_object = Some(k);
            }
            None
        };
        self.episode_object = k;
        let (object, yaw) = match &randomized {
            Some((o, yaw)) => (o, *yaw),
            None => (&self.objects[k].1, 0.0),
        };
        let mut scene = Scene::top_down(object, start, self.cfg.grasp_depth, 0.0);
        scene.object_xy = [p.dx, p.dy];
        scene.object_yaw = p.dyaw + yaw;
        // The hand starts clear of the object: where the start posture would overlap a
        // large object, the hand is raised in 5 mm steps (at most 10 cm; the caller).
        self.sim.reset(&scene)?;
        Ok(scene)
    }

    /// The closing trajectory T: the number of target updates over `closing_time` and
    /// the physics steps between two updates.
    fn closing_schedule(&self) -> (usize, usize) {
        let n = (self.cfg.closing_time / self.cfg.closing_period)
            .round()
            .max(1.0) as usize;
        let per = (self.cfg.closing_period / self.sim.config().dt)
            .round()
            .max(1.0) as usize;
        (n, per)
    }

    /// Stage 1: follows the closing trajectory T until any fingertip touches the object.
    /// Returns whether a touch ended it.
    fn stage1(&mut self) -> bool {
        let (n, per) = self.closing_schedule();
        for i in 1..=n {
            let t = self.path.target(i, n);
            if self.sim.set_targets(&t).is_err() {
                return false;
            }
            for _ in 0..per {
                if !self.sim.step_physics() {
                    return false;
                }
            }
            if self.sim.sensors().tactile.contains(&1) {
                return true;
            }
        }
        false
    }

    /// The policy's observation: the stacked frames, then the critic's privileged state
    /// when the layout has one (zeros where the simulator has none, before a reset).
    fn observation(&self) -> Vec<f32> {
        let mut o = self.stack.stacked();
        if self.layout.critic_state > 0 {
            match self.sim.critic_geometry() {
                Some(g) => {
                    let obj = self.sim.object();
                    o.extend(super::obs::critic_state(
                        &g,
                        &self.sim.tip_forces(),
                        obj.mass,
                        obj.friction,
                    ))
                }
                None => o.extend(std::iter::repeat_n(0.0, self.layout.critic_state)),
            }
        }
        o
    }

    fn push_frame(&mut self, prev_action: &[f32]) {
        let s = self.sim.sensors();
        let surface = if self.cfg.modality == Modality::M3G {
            self.sim
                .critic_geometry()
                .map_or([0.0; N_SURFACE], |g| surface_vectors(&g))
        } else {
            [0.0; N_SURFACE]
        };
        let tactile = s.tactile.map(|b| b == 1);
        let dr = &self.cfg.randomization;
        let sensed = if dr.enabled {
            let sc = &self.sim.config().sensors;
            Sensing {
                tactile,
                torque_levels: dr.noisy_levels(
                    &s.effort,
                    sc.torque_scale,
                    &sc.torque_thresholds,
                    &mut self.noise,
                ),
                joint_angles: dr.noisy_angles(&s.q, &mut self.noise),
                surface,
            }
        } else {
            Sensing {
                tactile,
                torque_levels: s.torque_level,
                joint_angles: s.q,
                surface,
            }
        };
        let frame = self.layout.frame(prev_action, &sensed);
        self.stack.push(frame);
    }

    fn finish(&mut self, success: bool, lifted: bool, physics_failure: bool) {
        let failure = self.sim.failure_report();
        let physics_failure = physics_failure || failure.is_some();
        if !physics_failure {
            self.curriculum.record(success);
            if let Some(c) = self.object_curriculum.as_mut() {
                c.record(self.episode_object, success);
            }
        }
        self.last = Some(EpisodeSummary {
            object: self.objects[self.episode_object].0.clone(),
            success,
            steps: self.steps,
            episode_return: self.episode_return,
            lifted,
            physics_failure,
            failure,
            deepest_contact: self.sim.deepest_contact().map_or(0.0, |c| c.depth),
            deepest_contact_with: self.sim.deepest_contact().map(|c| c.with.clone()),
            touched_in_stage1: self.touched_in_stage1,
            thumb_contact_at_lift: self.lift_record.is_some_and(|g| g.thumb),
            grip_effort: self.lift_record.map_or(0.0, |g| g.grip),
            object_height: self.lift_record.map_or(0.0, |g| g.height),
            in_hand: self.lift_record.is_some_and(|g| g.in_hand),
            object_turn: self.lift_record.map_or(0.0, |g| g.turn),
        });
        self.done = true;
    }

    fn failed_step(&mut self) -> Step {
        self.finish(false, false, true);
        Step {
            obs: self.observation(),
            reward: 0.0,
            terminated: true,
            truncated: false,
            info: StepInfo {
                success: Some(false),
                physics_failure: true,
            },
        }
    }

    /// The simulator's lift, with the thumb's contact at its start and the grip held
    /// through it kept for the episode's summary.
    fn lift_and_judge(&mut self) -> LiftOutcome {
        let thumb = self.sim.sensors().tactile[4] == 1;
        let (t, before) = (Instant::now(), self.sim.physics_steps());
        let out = self.sim.lift_and_judge();
        self.phases.lift.add(self.sim.physics_steps() - before, t);
        self.lift_record = Some(LiftRecord {
            thumb,
            grip: out.grip_effort,
            height: out.object_lowest_z,
            in_hand: out.in_contact,
            turn: out.object_turn,
        });
        out
    }

    /// Lifts, judges and ends the episode (the final step of eq. 4), the fingers first
    /// squeezed where `action.lift_squeeze` asks ([`lift_targets`]).
    fn lift(&mut self) -> Step {
        if self.cfg.action.lift_squeeze > 0.0 {
            let held = lift_targets(
                &self.cfg.action,
                &self.sim.targets(),
                &self.closed,
                &self.finger_limits,
            );
            if self.sim.set_targets(&held).is_err() {
                return self.failed_step();
            }
        }
        let out = self.lift_and_judge();
        let failure = out.failure.is_some();
        let r = if out.success { 1.0 } else { 0.0 };
        self.episode_return += r;
        self.steps += 1;
        self.finish(out.success, true, failure);
        Step {
            obs: self.observation(),
            reward: r as f32,
            terminated: true,
            truncated: false,
            info: StepInfo {
                success: Some(out.success),
                physics_failure: failure,
            },
        }
    }

    /// Runs a scripted baseline (Sec. V-D) on the scene of `seed` and judges it:
    /// baseline 1 closes all fingers in position mode along T (each joint stops at its
    /// target or where its motor saturates at the torque limit); baseline 2 does the same
    /// and freezes FF, MF and RF once their fingertip touches. Both lift at a fixed time
    /// (T plus a 0.3 s settle). The baselines close in joint space from the configured
    /// start posture whatever `closing` says: they are the paper's fixed reference.
    pub fn run_baseline(
        &mut self,
        stop_on_touch: bool,
        seed: u64,
    ) -> Result<EpisodeSummary, SimError> {
        if let Err(e) = self.timed_reset(seed, self.start) {
            // Refused like a policy episode's scene (see `Env::reset`): a reported
            // failure, not a run on the previous episode's world.
            self.sim.fail(PhysicsFailure::RefusedScene {
                reason: e.to_string(),
            });
            self.steps = 0;
            self.episode_return = 0.0;
            self.lift_record = None;
            self.finish(false, false, true);
            return Ok(self.last.clone().unwrap_or_else(|| unreachable!()));
        }
        let (n, per) = self.closing_schedule();
        let mut frozen = [false; 3];
        let mut targets = self.start;
        let finger_joints: [std::ops::Range<usize>; 3] = [2..6, 6..10, 10..14];
        let settle = (0.3 / self.cfg.closing_period).round() as usize;
        let mut ok = true;
        let t = Instant::now();
        'outer: for i in 1..=n + settle {
            for (j, t) in targets.iter_mut().enumerate() {
                let f = finger_joints.iter().position(|r| r.contains(&j));
                if f.is_some_and(|f| frozen[f]) {
                    continue;
                }
                *t = closing_target(&self.start, &self.closed, j, i, n);
            }
            if self.sim.set_targets(&targets).is_err() {
                ok = false;
                break;
            }
            for _ in 0..per {
                if !self.sim.step_physics() {
                    ok = false;
                    break 'outer;
                }
            }
            if stop_on_touch {
                let t = self.sim.sensors().tactile;
                for f in 0..3 {
                    frozen[f] |= t[f] == 1;
                }
            }
        }
        self.phases.closing.add(self.sim.physics_steps(), t);
        if !ok {
            self.finish(false, false, true);
        } else {
            let out = self.lift_and_judge();
            self.steps = 1;
            self.episode_return = f64::from(u8::from(out.success));
            self.finish(out.success, true, out.failure.is_some());
        }
        Ok(self.last.clone().unwrap_or_else(|| unreachable!()))
    }
}

impl Env for GraspEnv {
    fn obs_dim(&self) -> usize {
        self.layout.len()
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }

    fn action_spec(&self) -> ActionSpec {
        ActionSpec {
            continuous: self.cfg.action.continuous(self.synergy.n_components()),
            lift: true,
        }
    }

    fn reset(&mut self, seed: u64) -> Vec<f32> {
        self.stack.clear();
        if let Err(e) = self.timed_reset(seed, self.path.start()) {
            // A scene the simulator refuses is reported as a physics failure on the
            // first step (never run on the previous episode's final world).
            self.sim.fail(PhysicsFailure::RefusedScene {
                reason: e.to_string(),
            });
            self.steps = 0;
            self.episode_return = 0.0;
            self.touched_in_stage1 = false;
            self.lift_record = None;
            self.done = false;
            return self.observation();
        }
        let (t, before) = (Instant::now(), self.sim.physics_steps());
        self.touched_in_stage1 = self.stage1();
        self.phases
            .closing
            .add(self.sim.physics_steps() - before, t);
        let zero = vec![0.0; self.cfg.action.continuous(self.synergy.n_components())];
        self.push_frame(&zero);
        self.observation()
    }

    fn step(&mut self, a: &Action) -> Step {
        if self.sim.failure().is_some() {
            return self.failed_step();
        }
        if a.lift {
            return self.lift();
        }
        let (t, before, lift0) = (Instant::now(), self.sim.physics_steps(), self.phases.lift);
        let step = self.policy_step(a);
        // A step at the step cap may end in the lift, which counts as its own phase.
        let mut spent = Phase::default();
        spent.add(self.sim.physics_steps() - before, t);
        self.phases.policy = self
            .phases
            .policy
            .plus(spent.minus(self.phases.lift.minus(lift0)));
        step
    }
}

impl GraspEnv {
    /// One control step of the policy's action `a` (not a lift).
    fn policy_step(&mut self, a: &Action) -> Step {
        let s = self.sim.sensors();
        let commanded = self.sim.targets();
        let base = self.cfg.action.anchor.pick(&s.q, &commanded);
        // Eq. 5's theta: the posture the increments were added to.
        let theta_f: [f64; 22] = std::array::from_fn(|k| base[k + 2]);
        let targets = hand_targets(
            &self.cfg.action,
            &self.eps_std,
            &self.synergy,
            &self.finger_limits,
            &self.wrist_limits,
            base,
            &self.closed,
            &a.cont,
            self.steps + 1,
        );
        let target_f: [f64; 22] = std::array::from_fn(|k| targets[k + 2]);
        let before = self.sim.object_position();
        if self.sim.set_targets(&targets).is_err() || !self.sim.step_control() {
            return self.failed_step();
        }
        self.steps += 1;
        let timed_out = self.steps >= self.cfg.max_steps;
        if timed_out && self.cfg.at_max_steps == AtMaxSteps::Lift {
            // The last action was applied; the lift is the episode's final step. Its
            // reward is eq. 4's r_b, counted as the step the lift ends (see `lift`).
            self.steps -= 1;
            return self.lift();
        }
        // Out of time: eq. 4's final step, r_b = 0 (the object was not picked up).
        let moved = (self.sim.object_position() - before).norm();
        let r = reward::step_reward(&target_f, &theta_f, timed_out.then_some(false))
            - reward::displacement_penalty(&self.cfg.reward, moved);
        self.episode_return += r;
        let prev: Vec<f32> = a.cont.iter().map(|&x| clip_unit(x) as f32).collect();
        self.push_frame(&prev);
        if timed_out {
            self.finish(false, false, false);
        }
        Step {
            obs: self.observation(),
            reward: r as f32,
            terminated: timed_out,
            truncated: false,
            info: StepInfo {
                success: timed_out.then_some(false),
                physics_failure: false,
            },
        }
    }
}

/// Something that chooses grasp actions from observations: a learned policy or a
/// scripted rule. Recurrent agents reset their memory in [`Agent::reset`].
pub trait Agent {
    /// Called at the start of each episode.
    fn reset(&mut self);
    /// The action for the stacked observation `obs`.
    fn act(&mut self, obs: &[f32]) -> Action;
}

/// The random agent: every continuous component ~ N(0, 1), lift with probability
/// `lift_prob` per step. Seeded.
pub struct RandomAgent {
    rng: rand_chacha::ChaCha8Rng,
    n: usize,
    lift_prob: f64,
}

impl RandomAgent {
    /// A random agent for `n` continuous components.
    pub fn new(n: usize, lift_prob: f64, seed: u64) -> Self {
        RandomAgent {
            rng: rand_chacha::ChaCha8Rng::seed_from_u64(seed),
            n,
            lift_prob,
        }
    }
}

impl Agent for RandomAgent {
    fn reset(&mut self) {}

    fn act(&mut self, _obs: &[f32]) -> Action {
        let normal = rand_distr::StandardNormal;
        Action {
            cont: (0..self.n)
                .map(|_| rand_distr::Distribution::<f64>::sample(&normal, &mut self.rng) as f32)
                .collect(),
            lift: self.rng.random_bool(self.lift_prob.clamp(0.0, 1.0)),
        }
    }
}

/// Runs one episode of `agent` on the scene of `seed` and returns its summary.
pub fn run_episode(env: &mut GraspEnv, agent: &mut dyn Agent, seed: u64) -> EpisodeSummary {
    agent.reset();
    let mut obs = env.reset(seed);
    loop {
        let a = agent.act(&obs);
        let s = env.step(&a);
        obs = s.obs;
        if s.terminated || s.truncated {
            break;
        }
    }
    env.last_episode()
        .cloned()
        .unwrap_or_else(|| unreachable!("a finished episode has a summary"))
}

/// Raises the hand of `scene` in 5 mm steps (at most [`CLEARANCE_STEPS`]) while it
/// overlaps the object, resetting `sim` with `reset` at each step: every placement starts
/// clear of the object.
fn clear_hand(
    sim: &mut HandSim,
    scene: &mut Scene,
    reset: impl Fn(&mut HandSim, &Scene) -> Result<(), SimError>,
) -> Result<(), SimError> {
    for _ in 0..CLEARANCE_STEPS {
        if !sim.hand_overlaps_object() {
            break;
        }
        scene.grasp_point[2] += 0.005;
        reset(sim, scene)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
