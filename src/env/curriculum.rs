//! The curriculum of eq. 6 (Sec. IV-E).
//!
//! The object's start pose is randomised around its nominal pose:
//! `pos_start = pos_o + delta_pos`, `delta_pos ~ U(-delta_p, +delta_p)` on x and y, and
//! `rot_start = rot_o + delta_rot`, `delta_rot ~ U(-delta_o, +delta_o)` about z (yaw), with
//! `delta_p = 1.2 (r_s + 0.2)` and `delta_o = 0.1 r_s`, where `r_s` is the recent grasp
//! success rate. The paper gives no units; here `delta_p` is in CENTIMETRES and `delta_o`
//! in RADIANS: at r_s = 0 the object moves up to +-2.4 mm, at r_s = 1 up to +-14.4 mm and
//! +-0.1 rad (5.7 deg). The range grows as the agent gets better.

use rand::Rng;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// Curriculum settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CurriculumConfig {
    /// Whether the range follows the success rate (eq. 6); when false, `fixed_rate` is used.
    pub enabled: bool,
    /// Number of recent episodes in the success-rate window.
    pub window: usize,
    /// Success rate used when the curriculum is disabled (e.g. 1.0 for the hardest
    /// evaluation setting, 0.0 for the easiest).
    pub fixed_rate: f64,
}

impl Default for CurriculumConfig {
    fn default() -> Self {
        CurriculumConfig {
            enabled: true,
            window: 100,
            fixed_rate: 1.0,
        }
    }
}

/// Longest success-rate window accepted.
pub const MAX_WINDOW: usize = 1_000_000;

impl CurriculumConfig {
    /// The curriculum off, at success rate `rate` (an evaluation's `--difficulty`).
    pub fn fixed(rate: f64) -> Self {
        CurriculumConfig {
            enabled: false,
            fixed_rate: rate,
            ..CurriculumConfig::default()
        }
    }

    /// Checks the values; `Err` names the field (relative to `[env.curriculum]`) and says
    /// what is wrong. A window of 0 would never record an outcome and freeze the
    /// curriculum at its easiest level.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if self.enabled && !(1..=MAX_WINDOW).contains(&self.window) {
            return Err((
                "window",
                format!(
                    "{} must be in 1..={MAX_WINDOW} while the curriculum is enabled (0 would \
                     freeze it at the easiest level)",
                    self.window
                ),
            ));
        }
        if !(0.0..=1.0).contains(&self.fixed_rate) {
            return Err((
                "fixed_rate",
                format!(
                    "{} must be in [0, 1]",
                    crate::util::num::short(self.fixed_rate)
                ),
            ));
        }
        Ok(())
    }
}

/// Eq. 6 ranges for a success rate `r_s` in [0, 1]: (`delta_p` in metres, `delta_o` in
/// radians).
pub fn ranges(r_s: f64) -> (f64, f64) {
    let r = r_s.clamp(0.0, 1.0);
    (1.2 * (r + 0.2) / 100.0, 0.1 * r)
}

/// A start-pose perturbation drawn from eq. 6.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Perturbation {
    /// Offset along world x (m).
    pub dx: f64,
    /// Offset along world y (m).
    pub dy: f64,
    /// Yaw offset (rad).
    pub dyaw: f64,
}

/// The curriculum state: a moving window of recent outcomes.
#[derive(Debug, Clone, PartialEq)]
pub struct Curriculum {
    config: CurriculumConfig,
    recent: VecDeque<bool>,
}

impl Curriculum {
    /// A curriculum with an empty window (`r_s` = 0 until episodes finish).
    pub fn new(config: CurriculumConfig) -> Self {
        Curriculum {
            config,
            recent: VecDeque::new(),
        }
    }

    /// Records the outcome of a finished episode.
    pub fn record(&mut self, success: bool) {
        if self.config.window == 0 {
            return;
        }
        if self.recent.len() == self.config.window {
            self.recent.pop_front();
        }
        self.recent.push_back(success);
    }

    /// The success rate `r_s` that sets the ranges (the window's mean, or the fixed rate).
    pub fn rate(&self) -> f64 {
        if !self.config.enabled {
            return self.config.fixed_rate.clamp(0.0, 1.0);
        }
        if self.recent.is_empty() {
            return 0.0;
        }
        self.recent.iter().filter(|&&s| s).count() as f64 / self.recent.len() as f64
    }

    /// Draws a start-pose perturbation for the current level.
    pub fn sample(&self, rng: &mut impl Rng) -> Perturbation {
        let (dp, d_o) = ranges(self.rate());
        let mut u = |d: f64| {
            if d > 0.0 {
                rng.random_range(-d..=d)
            } else {
                0.0
            }
        };
        Perturbation {
            dx: u(dp),
            dy: u(dp),
            dyaw: u(d_o),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fixed_curriculum_is_off_at_its_rate() {
        let c = CurriculumConfig::fixed(0.25);
        assert!(!c.enabled);
        assert_eq!(c.fixed_rate, 0.25);
        assert_eq!(c.window, CurriculumConfig::default().window);
    }
    use rand::SeedableRng;

    #[test]
    fn eq6_ranges_hand_computed() {
        let (p, o) = ranges(0.0);
        assert!((p - 0.0024).abs() < 1e-15 && o == 0.0);
        let (p, o) = ranges(0.5);
        assert!((p - 0.0084).abs() < 1e-15 && (o - 0.05).abs() < 1e-15);
        let (p, o) = ranges(1.0);
        assert!((p - 0.0144).abs() < 1e-15 && (o - 0.1).abs() < 1e-15);
        assert_eq!(ranges(7.0), ranges(1.0));
    }

    #[test]
    fn validation_names_the_field() {
        let ok = CurriculumConfig::default();
        assert!(ok.validate().is_ok());
        let zero = CurriculumConfig {
            window: 0,
            ..ok.clone()
        };
        assert_eq!(zero.validate().unwrap_err().0, "window");
        // A disabled curriculum does not use its window.
        let off = CurriculumConfig {
            enabled: false,
            ..zero
        };
        assert!(off.validate().is_ok());
        let rate = CurriculumConfig {
            fixed_rate: 2.0,
            ..ok
        };
        assert_eq!(rate.validate().unwrap_err().0, "fixed_rate");
    }

    #[test]
    fn window_tracks_recent_success() {
        let mut c = Curriculum::new(CurriculumConfig {
            window: 4,
            ..Default::default()
        });
        assert_eq!(c.rate(), 0.0);
        for s in [true, true, false, false, true, true] {
            c.record(s);
        }
        // window holds false, false, true, true
        assert_eq!(c.rate(), 0.5);
        let off = Curriculum::new(CurriculumConfig {
            enabled: false,
            fixed_rate: 0.25,
            ..Default::default()
        });
        assert_eq!(off.rate(), 0.25);
    }

    #[test]
    fn samples_stay_in_range_and_are_seeded() {
        let mut c = Curriculum::new(CurriculumConfig::default());
        for _ in 0..10 {
            c.record(true);
        }
        let (dp, d_o) = ranges(1.0);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..1000 {
            let p = c.sample(&mut rng);
            assert!(p.dx.abs() <= dp && p.dy.abs() <= dp && p.dyaw.abs() <= d_o);
        }
        let a = c.sample(&mut rand_chacha::ChaCha8Rng::seed_from_u64(9));
        let b = c.sample(&mut rand_chacha::ChaCha8Rng::seed_from_u64(9));
        assert_eq!(a, b);
    }
}
