//! The grasping MDP's settings ([`EnvConfig`], read from a config's `[env]` table), their
//! checks, and the environment's errors.

use crate::env::action::ActionConfig;
use crate::env::closing::ClosingSpace;
use crate::env::curriculum::CurriculumConfig;
use crate::env::object_curriculum::ObjectCurriculumConfig;
use crate::env::obs::{Modality, ObsLayout};
use crate::env::placement::PlacementConfig;
use crate::env::randomize::Randomization;
use crate::env::reward::RewardConfig;
use crate::env::stream::StreamConfig;
use crate::robot::Posture;
use crate::sim::SimError;
use crate::util::num::{within, within_above};
use serde::{Deserialize, Serialize};

/// What happens when an episode reaches `max_steps` without a lift.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AtMaxSteps {
    /// The episode ends as a failure (terminal, `r_b = 0`); the setting of every checkpoint
    /// trained before this option existed.
    #[default]
    Fail,
    /// The hand lifts after the last step's action and the lift is judged (eq. 4's final
    /// step), as every episode of the paper ends with a lift attempt.
    Lift,
}

/// Most stage-2 control steps an episode may have (`[env] max_steps`; the paper's is 20).
pub const MAX_STEPS: usize = 1000;

/// Settings of the grasping MDP.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvConfig {
    /// Sensing modality (M1, M2, M3; M3G beyond the paper).
    pub modality: Modality,
    /// Number of stacked observation frames `h`.
    pub history: usize,
    /// Control steps of stage 2 after which an episode that has not lifted ends as a
    /// failure (terminal, reward 0).
    pub max_steps: usize,
    /// Start posture: `open` or `c-shape`.
    pub start_posture: String,
    /// Depth of the grasp point (TH/LF fingertip midpoint) below the object's top (m),
    /// never below its centre: the hand starts above the object, offset along z.
    pub grasp_depth: f64,
    /// Duration of the stage-1 closing trajectory T (s).
    pub closing_time: f64,
    /// Period at which stage 1 updates targets and checks the tactile sensors (s),
    /// rounded to whole physics steps: with the default 0.02 s at 1/240 s that is 5 steps
    /// (0.0208 s), so the default's 75 updates take 1.5625 s.
    pub closing_period: f64,
    /// Where stage 1's closing trajectory T interpolates (see [`crate::env::closing`]).
    pub closing: ClosingSpace,
    /// What happens at `max_steps` without a lift.
    pub at_max_steps: AtMaxSteps,
    /// Action scales.
    pub action: ActionConfig,
    /// Curriculum (eq. 6); each environment keeps its own window.
    pub curriculum: CurriculumConfig,
    /// Object curriculum (beyond the paper, off by default): training objects drawn by
    /// their recent failure rate ([`crate::env::object_curriculum`]); evaluation turns it off.
    pub object_curriculum: ObjectCurriculumConfig,
    /// Per-episode domain randomisation (off by default; evaluation turns it off).
    pub randomization: Randomization,
    /// The procedural stream's settings, used when training on `objects = "procedural"`.
    pub stream: StreamConfig,
    /// Shaped reward terms beyond eq. 4-5 (all off by default).
    pub reward: RewardConfig,
    /// Asymmetric critic (beyond the paper, off by default): the observation ends with
    /// [`crate::env::obs::critic_state`], privileged simulator state that only the critic
    /// reads; the actor keeps the modality's observation.
    pub critic_state: bool,
    /// Where training episodes start the hand (beyond the paper, off by default; see
    /// [`crate::env::placement`]); evaluation turns it off.
    pub placement: PlacementConfig,
}

impl Default for EnvConfig {
    fn default() -> Self {
        EnvConfig {
            modality: Modality::M3,
            history: 3,
            max_steps: 20,
            start_posture: "open".into(),
            grasp_depth: 0.01,
            closing_time: 1.5,
            closing_period: 0.02,
            closing: ClosingSpace::Joint,
            at_max_steps: AtMaxSteps::Fail,
            action: ActionConfig::default(),
            curriculum: CurriculumConfig {
                window: 20,
                ..CurriculumConfig::default()
            },
            object_curriculum: ObjectCurriculumConfig::default(),
            randomization: Randomization::default(),
            stream: StreamConfig::default(),
            reward: RewardConfig::default(),
            critic_state: false,
            placement: PlacementConfig::default(),
        }
    }
}

/// Errors of the grasping environment.
#[derive(Debug, thiserror::Error)]
pub enum GraspEnvError {
    /// A configuration value is out of range.
    #[error("invalid env config: {field}: {message}")]
    Config {
        /// The field.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The object set is empty.
    #[error("the object set is empty")]
    NoObjects,
    /// The simulator refused the setup.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// The `(field, message)` of a config section's range check ([`within`] and the
/// sections' own `validate`) as the environment's config error.
impl From<(&'static str, String)> for GraspEnvError {
    fn from((field, message): (&'static str, String)) -> Self {
        GraspEnvError::Config { field, message }
    }
}

impl EnvConfig {
    /// The observation layout of this MDP for `n` synergy components: the modality's
    /// frames (the previous action with the grip's value when there is one), then the
    /// critic's privileged state when `critic_state` is on. The environment and the
    /// robot pipeline both build it here.
    pub fn layout(&self, n: usize) -> ObsLayout {
        ObsLayout::with_action_len(self.modality, n, self.action.continuous(n), self.history)
            .with_critic_state(self.critic_state)
    }

    /// The configuration of training's own episodes: this one, without the grip's ramp
    /// and delay where `action.grip_ramp_in_training` is false and without the squeeze at
    /// the lift where `action.lift_squeeze_in_training` is false (the checkpoints keep
    /// this configuration, so the policy acts with them everywhere else).
    pub fn for_training(&self) -> EnvConfig {
        let mut c = self.clone();
        if !c.action.grip_ramp_in_training {
            c.action.grip_ramp = 0.0;
            c.action.grip_delay = 0;
        }
        if !c.action.lift_squeeze_in_training {
            c.action.lift_squeeze = 0.0;
        }
        c
    }

    /// Checks ranges; errors name the field.
    pub fn validate(&self) -> Result<Posture, GraspEnvError> {
        let bad = |field, message: String| Err(GraspEnvError::Config { field, message });
        if self.history == 0 {
            return bad("history", "must be at least 1".into());
        }
        if self.max_steps == 0 {
            return bad("max_steps", "must be at least 1".into());
        }
        // A policy that never lifts runs every step: 10^6 held `grasp eval` of one trial
        // for hours (a control step is about 1/35 s of computation).
        if self.max_steps > MAX_STEPS {
            return bad(
                "max_steps",
                format!(
                    "{} must be in 1..={MAX_STEPS} (stage-2 control steps per episode; a \
                     policy that never lifts runs them all)",
                    self.max_steps
                ),
            );
        }
        within("grasp_depth", self.grasp_depth, 0.0, 0.2, " m")?;
        within_above("closing_time", self.closing_time, 0.0, 10.0, " s")?;
        // At least 1 ms: a tiny period passes `> 0` but never finishes stage 1.
        if !(self.closing_period >= 1e-3 && self.closing_period <= self.closing_time) {
            return bad(
                "closing_period",
                format!(
                    "{} must be in [0.001 s, closing_time]",
                    crate::util::num::short(self.closing_period)
                ),
            );
        }
        let a = &self.action;
        within_above("action.eps_scale", a.eps_scale, 0.0, 5.0, "")?;
        within("action.wrist_scale", a.wrist_scale, 0.0, 0.5, " rad")?;
        within("action.grip_scale", a.grip_scale, 0.0, 1.0, "")?;
        within("action.grip_ramp", a.grip_ramp, 0.0, 1.0, "")?;
        within("action.lift_squeeze", a.lift_squeeze, 0.0, 1.0, "")?;
        if self.action.grip_ramp > 0.0 && self.action.grip_scale == 0.0 {
            return bad(
                "action.grip_ramp",
                "ramps the grip, but the grip is off (set action.grip_scale > 0)".into(),
            );
        }
        if self.action.grip_delay > 0 && self.action.grip_scale == 0.0 {
            return bad(
                "action.grip_delay",
                "delays the grip, but the grip is off (set action.grip_scale > 0)".into(),
            );
        }
        if self.action.grip_delay >= self.max_steps {
            return bad(
                "action.grip_delay",
                format!(
                    "{} steps leave no step with the grip: must be below max_steps ({})",
                    self.action.grip_delay, self.max_steps
                ),
            );
        }
        if !(0.0..=1.0).contains(&self.curriculum.fixed_rate) {
            return bad("curriculum.fixed_rate", "must be in [0, 1]".into());
        }
        if self.object_curriculum.enabled {
            self.object_curriculum.validate()?;
        }
        self.randomization.validate()?;
        self.reward.validate()?;
        self.placement.validate()?;
        if self.stream.reuse == 0 {
            return bad("stream.reuse", "must be at least 1".into());
        }
        match self.start_posture.as_str() {
            "open" => Ok(Posture::Open),
            "c-shape" => Ok(Posture::CShape),
            other => bad(
                "start_posture",
                format!("unknown posture '{other}': expected open or c-shape"),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn episode_length_is_bounded() {
        let mut c = EnvConfig {
            max_steps: MAX_STEPS,
            ..EnvConfig::default()
        };
        assert!(c.validate().is_ok());
        c.max_steps = 1_000_000;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("max_steps: 1000000 must be in 1..=1000"), "{e}");
        c.max_steps = 0;
        assert!(c.validate().unwrap_err().to_string().contains("max_steps"));
    }
}
