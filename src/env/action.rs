//! Actions of the grasping MDP (Sec. IV-C): `a_t = { d_eps (n), d_theta_w (2), rho }`.
//!
//! The policy outputs `n + 2` unbounded Gaussian samples and a Bernoulli `rho`. The env
//! clips each continuous value to [-1, 1] and scales it:
//! - synergy increment k: `d_eps_k = clip(a_k) * eps_scale * sqrt(lambda_k)`, i.e. in units
//!   of the component's standard deviation in the pose dataset (default `eps_scale` 0.25:
//!   at most a quarter of a standard deviation per control step);
//! - wrist increments: `d_theta_w = clip(a) * wrist_scale` radians (default 0.05 rad).
//!
//! `rho = 1` asks to lift; the continuous part is then ignored (eq. 3 masks it).
//!
//! Eq. 2 adds the increments to an anchor posture ([`Anchor`]): the measured angles (the
//! paper's `P(theta_f)`) or the previous command. Anchored on the measured angles, a finger
//! blocked by the object is never commanded more than one increment past where it stands,
//! so the squeeze it can hold through the lift is `kp` times one increment (about 0.1 N m
//! with the default gains and scales). Anchored on the previous command, the increments
//! accumulate and the squeeze can grow to the joint's effort limit, as the scripted
//! baselines' does.

use crate::synergy::SynergyModel;
use serde::{Deserialize, Serialize};

/// The posture eq. 2's increments are added to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Anchor {
    /// The measured joint angles, projected onto the synergy span (the paper's eq. 2,
    /// `P^-1(d_eps + P(theta_f))`; the setting of every checkpoint trained before this
    /// option existed).
    #[default]
    Measured,
    /// The previous command (the targets after clamping and coupling):
    /// `P^-1(d_eps + P(theta_cmd))`. The increments accumulate where a finger is blocked.
    /// (Moving the command along the synergy directions without the projection,
    /// `theta_cmd + C^T d_eps`, was measured too: a random agent's first-update success
    /// fell from 17.8 % to 6.5 % of 107 episodes, so the projection stays.)
    Target,
}

impl Anchor {
    /// The anchor posture: `measured` or `commanded`.
    pub fn pick<'a>(self, measured: &'a [f64; 24], commanded: &'a [f64; 24]) -> &'a [f64; 24] {
        match self {
            Anchor::Measured => measured,
            Anchor::Target => commanded,
        }
    }
}

/// Scales of the continuous action and the anchor of eq. 2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActionConfig {
    /// Synergy increment per unit action, in standard deviations of the component.
    pub eps_scale: f64,
    /// Wrist increment per unit action (rad).
    pub wrist_scale: f64,
    /// What the increments are added to.
    pub anchor: Anchor,
    /// Beyond the paper (0: off, the paper's action): the action gets one more continuous
    /// component, the grip `g`, and the finger targets are blended towards the power
    /// grasp (baseline 1's closed posture) by `w = clip(g, 0, 1) * grip_scale`:
    /// `theta_target = (1 - w) eq.2 + w theta_closed`. With `w = 1` the fingers squeeze
    /// as baseline 1's do; the policy learns when. In [0, 1].
    pub grip_scale: f64,
    /// Beyond the paper (0: off): how fast the grip may close. At the episode's k-th
    /// control step (k = 1, 2, ...; an attempt's, after a retry) the blend weight is
    /// capped at `k * grip_ramp`, so the grip reaches `grip_scale` over
    /// `grip_scale / grip_ramp` steps instead of at once ([`ActionConfig::ramped_grip`]).
    /// Needs the grip (`grip_scale > 0`). In [0, 1].
    pub grip_ramp: f64,
    /// Beyond the paper (0: off): control steps at the start of the episode (of an
    /// attempt, after a retry) during which the grip stays off (`w = 0`); the ramp, if
    /// any, counts from the step after ([`ActionConfig::ramped_grip`]). Needs the grip;
    /// below the episode's `max_steps`.
    pub grip_delay: usize,
    /// Whether training's own episodes ramp and delay the grip too (default true). With
    /// false the policy trains with the grip at once (`grasp train`, and the Python
    /// module, whose environments are training's) and the ramp and the delay apply where
    /// the checkpoint acts afterwards: `grasp eval`, `grasp run`, `grasp rollout` (see
    /// [`crate::env::grasp::EnvConfig::for_training`]).
    pub grip_ramp_in_training: bool,
    /// Beyond the paper (0: off): when the policy lifts, its finger targets move this
    /// share of the way towards the power grasp (baseline 1's closed posture) and stay
    /// there through the lift, so fingers resting on the object press harder while it
    /// is raised ([`lift_targets`]). Works with or without the grip. In [0, 1].
    pub lift_squeeze: f64,
    /// Whether training's own episodes squeeze at the lift too (default true). With
    /// false the policy trains without it and the squeeze applies where the checkpoint
    /// acts afterwards, as `grip_ramp_in_training` does for the grip's ramp and delay.
    pub lift_squeeze_in_training: bool,
}

impl ActionConfig {
    /// How a checkpoint's grip and lift act, for the progress line: "" with neither a grip
    /// nor a squeeze at the lift, else the grip's scale, delay and ramp and the squeeze, e.g.
    /// " (grip 0.25, ramped by 0.15 per step)" or " (grip 0.25, off for the first 1 step;
    /// squeezed by 0.25 at the lift)".
    pub fn grip_note(&self) -> String {
        use crate::util::num::short;
        let mut parts = Vec::new();
        if self.grip_scale > 0.0 {
            let mut grip = format!("grip {}", short(self.grip_scale));
            if self.grip_delay > 0 {
                let steps = if self.grip_delay == 1 {
                    "step"
                } else {
                    "steps"
                };
                grip += &format!(", off for the first {} {steps}", self.grip_delay);
            }
            if self.grip_ramp > 0.0 {
                grip += &format!(", ramped by {} per step", short(self.grip_ramp));
            }
            parts.push(grip);
        }
        if self.lift_squeeze > 0.0 {
            parts.push(format!(
                "squeezed by {} at the lift",
                short(self.lift_squeeze)
            ));
        }
        if parts.is_empty() {
            String::new()
        } else {
            format!(" ({})", parts.join("; "))
        }
    }

    /// Continuous action components for `n` synergies: `n + 2`, plus 1 with the grip.
    pub fn continuous(&self, n: usize) -> usize {
        n + 2 + usize::from(self.grip_scale > 0.0)
    }

    /// The grip's blend weight `w` at the episode's `step`-th control step (1, 2, ...):
    /// 0 while `step <= grip_delay`, then `min(w, (step - grip_delay) * grip_ramp)` with
    /// the ramp on, `w` without it.
    pub fn ramped_grip(&self, w: f64, step: usize) -> f64 {
        if step <= self.grip_delay {
            0.0
        } else if self.grip_ramp > 0.0 {
            w.min((step - self.grip_delay) as f64 * self.grip_ramp)
        } else {
            w
        }
    }
}

impl Default for ActionConfig {
    fn default() -> Self {
        ActionConfig {
            eps_scale: 0.25,
            wrist_scale: 0.05,
            anchor: Anchor::Measured,
            grip_scale: 0.0,
            grip_ramp: 0.0,
            grip_delay: 0,
            grip_ramp_in_training: true,
            lift_squeeze: 0.0,
            lift_squeeze_in_training: true,
        }
    }
}

/// A decoded action in physical units.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// Synergy increments `d_eps` (synergy-space units, i.e. radians along the component).
    pub d_eps: Vec<f64>,
    /// Wrist increments (WRJ2, WRJ1), radians.
    pub d_wrist: [f64; 2],
    /// Lift decision.
    pub lift: bool,
    /// Blend weight `w` towards the power grasp (0 without the grip component).
    pub grip: f64,
}

/// The hand targets the lift holds: `targets` with every finger joint moved the share
/// `lift_squeeze` of the way towards `closed`, within `finger_limits`; the wrist as it
/// is. `targets` themselves with the squeeze off. The environment and the robot pipeline
/// both use this function.
pub fn lift_targets(
    cfg: &ActionConfig,
    targets: &[f64; 24],
    closed: &[f64; 24],
    finger_limits: &[(f64, f64); 22],
) -> [f64; 24] {
    let mut out = *targets;
    blend_towards(&mut out[2..], closed, cfg.lift_squeeze, finger_limits);
    out
}

/// Moves the 22 finger targets `fingers` the share `w` of the way towards the fingers of
/// `closed` (paper order, 24 joints), each within its `finger_limits`; nothing with `w`
/// of 0. The grip's blend ([`hand_targets`]) and the squeeze at the lift
/// ([`lift_targets`]).
fn blend_towards(
    fingers: &mut [f64],
    closed: &[f64; 24],
    w: f64,
    finger_limits: &[(f64, f64); 22],
) {
    if w > 0.0 {
        for ((t, c), (lo, hi)) in fingers.iter_mut().zip(&closed[2..]).zip(finger_limits) {
            *t = (*t + w * (c - *t)).clamp(*lo, *hi);
        }
    }
}

/// Clips a raw policy output to [-1, 1] (NaN becomes 0).
pub fn clip_unit(x: f32) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        f64::from(x.clamp(-1.0, 1.0))
    }
}

/// Decodes the raw continuous outputs `raw` (`n + 2` values) with the component standard
/// deviations `std` (`n` values, `sqrt(lambda_k)`).
pub fn decode(cfg: &ActionConfig, std: &[f64], raw: &[f32], lift: bool) -> Decoded {
    let n = std.len();
    let get = |k: usize| clip_unit(raw.get(k).copied().unwrap_or(0.0));
    Decoded {
        d_eps: (0..n).map(|k| get(k) * cfg.eps_scale * std[k]).collect(),
        d_wrist: [get(n) * cfg.wrist_scale, get(n + 1) * cfg.wrist_scale],
        lift,
        grip: if cfg.grip_scale > 0.0 {
            get(n + 2).max(0.0) * cfg.grip_scale
        } else {
            0.0
        },
    }
}

/// The action's unit per synergy component: `sqrt(lambda_k)` of the model's first `n`
/// components (negative round-off eigenvalues count as 0).
pub fn component_std(model: &SynergyModel) -> Vec<f64> {
    model.eigenvalues()[..model.n_components()]
        .iter()
        .map(|l| l.max(0.0).sqrt())
        .collect()
}

/// The 24 hand targets of a continuous action `raw` (`n + 2` policy outputs) from the
/// anchor posture `q` (paper order; see [`Anchor`]): the fingers by eq. 2,
/// `P^-1(d_eps + P(theta_f))` made feasible for `finger_limits`, the wrist by
/// `q_w + d_theta_w` clamped to `wrist_limits`; with the grip, the fingers blended towards
/// `closed` (see [`ActionConfig::grip_scale`]), at most as far as the ramp allows at the
/// episode's `step`-th control step (1, 2, ...; [`ActionConfig::grip_ramp`]). The
/// environment and the robot pipeline both use this function, so a policy acts
/// identically in both.
#[allow(clippy::too_many_arguments)]
pub fn hand_targets(
    cfg: &ActionConfig,
    std: &[f64],
    model: &SynergyModel,
    finger_limits: &[(f64, f64); 22],
    wrist_limits: &[(f64, f64); 2],
    q: &[f64; 24],
    closed: &[f64; 24],
    raw: &[f32],
    step: usize,
) -> [f64; 24] {
    let theta_f: [f64; 22] = std::array::from_fn(|k| q[k + 2]);
    let d = decode(cfg, std, raw, false);
    let mut target_f = model.target(&theta_f, &d.d_eps, finger_limits);
    blend_towards(
        &mut target_f,
        closed,
        cfg.ramped_grip(d.grip, step),
        finger_limits,
    );
    let mut targets = [0.0; 24];
    for (w, (lo, hi)) in wrist_limits.iter().enumerate() {
        targets[w] = (q[w] + d.d_wrist[w]).clamp(*lo, *hi);
    }
    targets[2..].copy_from_slice(&target_f);
    targets
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_grip_note_names_the_scale_the_delay_the_ramp_and_the_squeeze() {
        let mut a = ActionConfig::default();
        assert_eq!(a.grip_note(), "");
        a.grip_scale = 0.25;
        assert_eq!(a.grip_note(), " (grip 0.25)");
        a.grip_delay = 1;
        assert_eq!(a.grip_note(), " (grip 0.25, off for the first 1 step)");
        a.grip_delay = 2;
        a.grip_ramp = 0.15;
        assert_eq!(
            a.grip_note(),
            " (grip 0.25, off for the first 2 steps, ramped by 0.15 per step)"
        );
        a.lift_squeeze = 0.25;
        assert_eq!(
            a.grip_note(),
            " (grip 0.25, off for the first 2 steps, ramped by 0.15 per step; squeezed by \
             0.25 at the lift)"
        );
        let squeeze_only = ActionConfig {
            lift_squeeze: 0.5,
            ..ActionConfig::default()
        };
        assert_eq!(squeeze_only.grip_note(), " (squeezed by 0.5 at the lift)");
    }

    use super::*;

    /// The first 5 components of the shipped synergy model and the left hand's limits, for
    /// [`hand_targets`] from one posture.
    struct Hand {
        model: SynergyModel,
        std: Vec<f64>,
        fl: [(f64, f64); 22],
        wl: [(f64, f64); 2],
        closed: [f64; 24],
    }

    impl Hand {
        fn new() -> Hand {
            let model = crate::synergy::default_model().truncated(5).unwrap();
            let std = component_std(&model);
            let robot = crate::robot::Robot::builtin(crate::robot::Side::Left);
            let hl = robot.hand_limits();
            Hand {
                std,
                model,
                fl: robot.finger_limits(),
                wl: [hl[0], hl[1]],
                closed: crate::sim::script::power_grasp(),
            }
        }

        /// [`hand_targets`] of `raw` from `q` at control step `step`.
        fn targets(
            &self,
            cfg: &ActionConfig,
            q: &[f64; 24],
            raw: &[f32],
            step: usize,
        ) -> [f64; 24] {
            let (m, fl, wl) = (&self.model, &self.fl, &self.wl);
            hand_targets(cfg, &self.std, m, fl, wl, q, &self.closed, raw, step)
        }

        /// [`Hand::targets`] from the open hand of the action that is all zero but the
        /// grip `g` (5 synergies, so the grip is the 8th output).
        fn gripped(&self, cfg: &ActionConfig, g: f32, step: usize) -> [f64; 24] {
            let mut raw = [0.0f32; 8];
            raw[7] = g;
            self.targets(cfg, &crate::robot::Posture::Open.angles(), &raw, step)
        }
    }

    #[test]
    fn hand_targets_zero_action_projects_and_wrist_increments_clamp() {
        let h = Hand::new();
        let (std, wl) = (&h.std, h.wl);
        assert_eq!(std.len(), 5);
        assert!((std[0] - h.model.eigenvalues()[0].sqrt()).abs() < 1e-15);
        let q = crate::robot::Posture::CShape.angles();
        // Zero synergy increments: the fingers go to the feasible projection of theta_f;
        // wrist increments of +1 unit = +0.05 rad, WRJ2 clamped at its upper limit.
        let mut qw = q;
        qw[0] = wl[0].1 - 0.01;
        let raw = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0];
        let t = h.targets(&ActionConfig::default(), &qw, &raw, 1);
        assert_eq!(t[0], wl[0].1);
        assert!((t[1] - (qw[1] + 0.05)).abs() < 1e-12);
        let theta_f: [f64; 22] = std::array::from_fn(|k| q[k + 2]);
        let expect = h.model.target(&theta_f, &[0.0; 5], &h.fl);
        assert_eq!(&t[2..], &expect[..]);
    }

    #[test]
    fn the_grip_blends_the_fingers_towards_the_power_grasp() {
        let h = Hand::new();
        let (fl, closed) = (&h.fl, &h.closed);
        let q = crate::robot::Posture::Open.angles();
        let cfg = ActionConfig {
            grip_scale: 1.0,
            ..ActionConfig::default()
        };
        assert_eq!(cfg.continuous(5), 8);
        assert_eq!(ActionConfig::default().continuous(5), 7);
        let at = |g: f32| h.gripped(&cfg, g, 1);
        let plain = h.targets(&ActionConfig::default(), &q, &[0.0; 7], 1);
        // g <= 0: eq. 2 as without the grip; g = 1: the power grasp; g = 0.5: halfway.
        assert_eq!(at(-0.7), plain);
        let full = at(1.0);
        let half = at(0.5);
        for k in 2..24 {
            assert!(
                (full[k] - closed[k].clamp(fl[k - 2].0, fl[k - 2].1)).abs() < 1e-12,
                "joint {k}"
            );
            assert!(
                (half[k] - 0.5 * (plain[k] + full[k])).abs() < 1e-12,
                "joint {k}"
            );
        }
        assert_eq!(&full[..2], &plain[..2]);
    }

    #[test]
    fn the_grip_ramp_caps_the_blend_per_step_hand_computed() {
        let cfg = ActionConfig {
            grip_scale: 0.25,
            grip_ramp: 0.05,
            ..ActionConfig::default()
        };
        // w = clip(g) * 0.25 = 0.25 for g = 1: capped at 0.05 at step 1, 0.10 at step 2,
        // 0.20 at step 4, reached at step 5; a smaller w passes unchanged.
        assert!((cfg.ramped_grip(0.25, 1) - 0.05).abs() < 1e-15);
        assert!((cfg.ramped_grip(0.25, 2) - 0.10).abs() < 1e-15);
        assert!((cfg.ramped_grip(0.25, 4) - 0.20).abs() < 1e-15);
        assert_eq!(cfg.ramped_grip(0.25, 5), 0.25);
        assert_eq!(cfg.ramped_grip(0.03, 1), 0.03);
        assert_eq!(cfg.ramped_grip(0.0, 3), 0.0);
        // Off: w at any step.
        let off = ActionConfig {
            grip_ramp: 0.0,
            ..cfg.clone()
        };
        assert_eq!(off.ramped_grip(0.25, 1), 0.25);

        // In hand_targets (values exact in binary): with the ramp at 0.125, g = 1 at step 1
        // blends as g = 0.5 (w = 0.125) does unramped, and at step 2 as g = 1 (w = 0.25).
        let cfg = ActionConfig {
            grip_ramp: 0.125,
            ..cfg
        };
        let h = Hand::new();
        assert_eq!(h.gripped(&cfg, 1.0, 1), h.gripped(&off, 0.5, 1));
        assert_eq!(h.gripped(&cfg, 1.0, 2), h.gripped(&off, 1.0, 2));
        assert_ne!(h.gripped(&cfg, 1.0, 1), h.gripped(&off, 1.0, 1));
    }

    #[test]
    fn the_grip_delay_holds_the_grip_off_then_the_ramp_counts_on_hand_computed() {
        let delayed = ActionConfig {
            grip_scale: 0.25,
            grip_delay: 1,
            ..ActionConfig::default()
        };
        // Delay 1, no ramp: off at step 1, whole from step 2.
        assert_eq!(delayed.ramped_grip(0.25, 1), 0.0);
        assert_eq!(delayed.ramped_grip(0.25, 2), 0.25);
        assert_eq!(delayed.ramped_grip(0.1, 7), 0.1);
        // Delay 2 with the ramp at 0.125: off at steps 1-2, 0.125 at step 3, 0.25 at 4.
        let both = ActionConfig {
            grip_delay: 2,
            grip_ramp: 0.125,
            ..delayed.clone()
        };
        assert_eq!(both.ramped_grip(0.25, 2), 0.0);
        assert_eq!(both.ramped_grip(0.25, 3), 0.125);
        assert_eq!(both.ramped_grip(0.25, 4), 0.25);

        // In hand_targets: g = 1 at step 1 with the delay moves the fingers as g = 0 does,
        // and at step 2 as g = 1 without it.
        let off = ActionConfig {
            grip_delay: 0,
            ..delayed.clone()
        };
        let h = Hand::new();
        assert_eq!(h.gripped(&delayed, 1.0, 1), h.gripped(&off, 0.0, 1));
        assert_eq!(h.gripped(&delayed, 1.0, 2), h.gripped(&off, 1.0, 2));
        assert_ne!(h.gripped(&delayed, 1.0, 1), h.gripped(&off, 1.0, 1));
    }

    #[test]
    fn decode_clips_and_scales_hand_computed() {
        let cfg = ActionConfig::default();
        let d = decode(&cfg, &[0.4, 0.2], &[0.5, -3.0, 1.0, f32::NAN], false);
        // 0.5 * 0.25 * 0.4 = 0.05; clip(-3) = -1 -> -1 * 0.25 * 0.2 = -0.05.
        assert!((d.d_eps[0] - 0.05).abs() < 1e-12);
        assert!((d.d_eps[1] + 0.05).abs() < 1e-12);
        assert_eq!(d.d_wrist, [0.05, 0.0]);
        assert!(!d.lift);
    }

    #[test]
    fn lift_targets_move_the_fingers_a_share_towards_the_power_grasp() {
        let h = Hand::new();
        let mut t = crate::robot::Posture::Open.angles();
        t[0] = 0.1;
        t[1] = -0.2;
        let mut cfg = ActionConfig::default();
        assert_eq!(lift_targets(&cfg, &t, &h.closed, &h.fl), t);
        cfg.lift_squeeze = 0.25;
        let s = lift_targets(&cfg, &t, &h.closed, &h.fl);
        assert_eq!((s[0], s[1]), (0.1, -0.2), "the wrist is left as it is");
        for j in 0..22 {
            let want = (t[j + 2] + 0.25 * (h.closed[j + 2] - t[j + 2])).clamp(h.fl[j].0, h.fl[j].1);
            assert_eq!(s[j + 2], want, "joint {j}");
        }
        // Hand-computed: 0.3 rad open, 1.5 rad closed, a quarter of the way: 0.6 rad.
        let mut open = [0.0; 24];
        let mut closed = [0.0; 24];
        open[5] = 0.3;
        closed[5] = 1.5;
        let limits = [(-2.0, 2.0); 22];
        assert!((lift_targets(&cfg, &open, &closed, &limits)[5] - 0.6).abs() < 1e-15);
        // Within the joint's limits: an upper limit of 0.5 rad holds it there.
        let mut tight = limits;
        tight[3] = (-2.0, 0.5);
        assert_eq!(lift_targets(&cfg, &open, &closed, &tight)[5], 0.5);
        cfg.lift_squeeze = 1.0;
        assert_eq!(lift_targets(&cfg, &open, &closed, &limits), closed);
    }
}
