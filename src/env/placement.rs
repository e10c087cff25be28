//! Where an episode's hand starts (beyond the paper): `[env.placement]`.
//!
//! The paper trains and tests from one placement: the hand top-down over the object's
//! centre, its grasp point `grasp_depth` below the object's top. On the robot (`grasp run`)
//! and in the paper's Table I protocol (`grasp eval --pregrasp antipodal`) the hand starts
//! instead from a grasp pose planned on the depth cloud
//! ([`crate::perception::pregrasp::AntipodalPregrasp`]): off the centre, yawed along the
//! planned grasp axis, at the planner's height. A policy trained from the centre alone
//! sees those starts only at test time.
//!
//! A training config can mix the two and perturb both. For each episode, from a generator
//! of its own seeded by the episode's seed (so the object, its pose and every other draw
//! are those of the same episode without placement settings):
//! 1. with probability `antipodal` the hand starts from the antipodal pre-grasp on the
//!    simulated depth cloud (its 2 mm noise, and the centre placement where the planner
//!    finds no grasp), otherwise from the top-down centre placement;
//! 2. the grasp point is moved by an offset drawn uniformly in a horizontal disc of radius
//!    `offset` and by a height drawn uniformly in `[-height, height]`, and the hand's yaw
//!    by an angle uniform in `[-yaw, yaw]`;
//! 3. where the hand would then overlap the object it is raised clear, as any placement is.
//!
//! Everything is off by default. Evaluation turns it off whatever a checkpoint was trained
//! with (`grasp eval --pregrasp` chooses the placement there), so every agent is judged on
//! identical start poses.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The placement settings of training episodes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlacementConfig {
    /// Share of episodes that start from the antipodal pre-grasp (0..=1); the rest start
    /// top-down over the object's centre.
    pub antipodal: f64,
    /// Largest change of the hand's yaw (rad), uniform in `[-yaw, yaw]`.
    pub yaw: f64,
    /// Largest horizontal offset of the grasp point (m), uniform in a disc.
    pub offset: f64,
    /// Largest change of the grasp point's height (m), uniform in `[-height, height]`.
    pub height: f64,
}

impl Default for PlacementConfig {
    /// Every episode from the top-down centre placement, unperturbed (the paper's).
    fn default() -> Self {
        PlacementConfig {
            antipodal: 0.0,
            yaw: 0.0,
            offset: 0.0,
            height: 0.0,
        }
    }
}

/// Largest `offset` and `height` accepted (m): a few centimetres is the scale of a
/// camera-arm calibration error or a planner's choice; more moves the hand off the object.
pub const MAX_SHIFT_M: f64 = 0.05;

/// One episode's placement, drawn by [`PlacementConfig::draw`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlacementDraw {
    /// Whether the episode starts from the antipodal pre-grasp.
    pub antipodal: bool,
    /// Added to the grasp point (m): x, y, z.
    pub shift: [f64; 3],
    /// Added to the hand's yaw (rad).
    pub yaw: f64,
}

impl PlacementDraw {
    /// No pre-grasp, no perturbation.
    pub const NONE: PlacementDraw = PlacementDraw {
        antipodal: false,
        shift: [0.0; 3],
        yaw: 0.0,
    };
}

/// Mixed into the episode's seed for the placement's own generator.
const SEED_SALT: u64 = 0x706c_6163_656d_656e;

impl PlacementConfig {
    /// Whether any setting differs from the default (the paper's placement).
    pub fn is_active(&self) -> bool {
        *self != PlacementConfig::default()
    }

    /// Checks every range; the error names the field.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        use crate::util::num::within;
        within("placement.antipodal", self.antipodal, 0.0, 1.0, "")?;
        within("placement.yaw", self.yaw, 0.0, std::f64::consts::PI, " rad")?;
        within("placement.offset", self.offset, 0.0, MAX_SHIFT_M, " m")?;
        within("placement.height", self.height, 0.0, MAX_SHIFT_M, " m")
    }

    /// The placement of the episode of `seed` (the same seed gives the same draw). With
    /// the defaults nothing is drawn.
    pub fn draw(&self, seed: u64) -> PlacementDraw {
        if !self.is_active() {
            return PlacementDraw::NONE;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ SEED_SALT);
        let antipodal = self.antipodal > 0.0 && rng.random::<f64>() < self.antipodal;
        // Uniform in the disc: radius sqrt(u) * offset.
        let r = self.offset * rng.random::<f64>().sqrt();
        let a = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let dz = self.height * rng.random_range(-1.0..=1.0);
        let yaw = self.yaw * rng.random_range(-1.0..=1.0);
        PlacementDraw {
            antipodal,
            shift: [r * a.cos(), r * a.sin(), dz],
            yaw,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_draw_nothing_and_validate() {
        let d = PlacementConfig::default();
        assert!(!d.is_active());
        assert!(d.validate().is_ok());
        assert_eq!(d.draw(7), PlacementDraw::NONE);
    }

    #[test]
    fn draws_stay_within_their_ranges_and_repeat_per_seed() {
        let c = PlacementConfig {
            antipodal: 0.5,
            yaw: 0.3,
            offset: 0.02,
            height: 0.01,
        };
        let mut planned = 0;
        for seed in 0..2000 {
            let d = c.draw(seed);
            assert_eq!(d, c.draw(seed));
            let [x, y, z] = d.shift;
            assert!((x * x + y * y).sqrt() <= 0.02 + 1e-12);
            assert!(z.abs() <= 0.01 && d.yaw.abs() <= 0.3);
            planned += usize::from(d.antipodal);
        }
        // Binomial(2000, 0.5): 1000 +- 22 (one sd); 6 sd either side.
        assert!((868..=1132).contains(&planned), "{planned}");
        // All or nothing at the ends.
        let all = PlacementConfig {
            antipodal: 1.0,
            ..PlacementConfig::default()
        };
        assert!((0..100).all(|s| all.draw(s).antipodal));
        let shift_only = PlacementConfig {
            offset: 0.01,
            ..PlacementConfig::default()
        };
        assert!((0..100).all(|s| !shift_only.draw(s).antipodal));
    }

    #[test]
    fn out_of_range_values_name_the_field() {
        let bad = [
            (
                PlacementConfig {
                    antipodal: 1.5,
                    ..Default::default()
                },
                "placement.antipodal",
            ),
            (
                PlacementConfig {
                    yaw: -0.1,
                    ..Default::default()
                },
                "placement.yaw",
            ),
            (
                PlacementConfig {
                    offset: 0.2,
                    ..Default::default()
                },
                "placement.offset",
            ),
            (
                PlacementConfig {
                    height: f64::NAN,
                    ..Default::default()
                },
                "placement.height",
            ),
        ];
        for (c, field) in bad {
            assert_eq!(c.validate().unwrap_err().0, field);
        }
    }
}
