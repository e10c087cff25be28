//! Where hand and object start an episode ([`Scene`]): the hand's start posture, grasp
//! point and yaw, and the object's place on the table; the top-down placements and their
//! perturbations are built here.

use super::*;

/// Where hand and object start an episode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scene {
    /// The 24 start joint angles (paper order).
    pub start: [f64; 24],
    /// Object centre x, y on the table (m); it rests on the table top.
    pub object_xy: [f64; 2],
    /// Object yaw about z (rad).
    pub object_yaw: f64,
    /// Grasp point (TH/LF tip midpoint) in the world (m).
    pub grasp_point: [f64; 3],
    /// Hand yaw: direction of the thumb-to-little-finger line (rad).
    pub hand_yaw: f64,
}

impl Scene {
    /// The hand above the object's centre: grasp point at the centre plus `z_offset`, the
    /// object at the origin with yaw 0, the hand at `hand_yaw`.
    pub fn above(object: &ObjectSpec, start: [f64; 24], z_offset: f64, hand_yaw: f64) -> Scene {
        Scene {
            start,
            object_xy: [0.0, 0.0],
            object_yaw: 0.0,
            grasp_point: [0.0, 0.0, object.rest_height() + z_offset],
            hand_yaw,
        }
    }

    /// A top-down grasp of any object: the object at the origin with yaw 0, the grasp point
    /// on its vertical axis `depth` m below its top, but never below its centre (so a flat
    /// object is gripped around its middle and a tall one near its top), the hand at
    /// `hand_yaw`. For the default 8 cm box, `depth = 0.01` is [`Scene::above`] with
    /// `z_offset = 0.03`.
    pub fn top_down(object: &ObjectSpec, start: [f64; 24], depth: f64, hand_yaw: f64) -> Scene {
        let h = object.rest_height();
        let z = (2.0 * h - depth).max(h);
        Scene {
            start,
            object_xy: [0.0, 0.0],
            object_yaw: 0.0,
            grasp_point: [0.0, 0.0, z],
            hand_yaw,
        }
    }

    /// This scene with uniform noise: x/y of the grasp point within `+-xy_noise` m and the
    /// hand yaw within `+-yaw_noise` rad, drawn from `ChaCha8Rng::seed_from_u64(seed)`.
    pub fn with_noise(mut self, xy_noise: f64, yaw_noise: f64, seed: u64) -> Scene {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut u = |a: f64| {
            if a > 0.0 {
                rng.random_range(-a..=a)
            } else {
                0.0
            }
        };
        self.grasp_point[0] += u(xy_noise);
        self.grasp_point[1] += u(xy_noise);
        self.hand_yaw += u(yaw_noise);
        self
    }

    /// [`Scene::above`] with uniform noise: x/y of the grasp point within `+-xy_noise` m and
    /// the hand yaw within `+-yaw_noise` rad, drawn from `ChaCha8Rng::seed_from_u64(seed)`.
    pub fn randomized(
        object: &ObjectSpec,
        start: [f64; 24],
        z_offset: f64,
        xy_noise: f64,
        yaw_noise: f64,
        seed: u64,
    ) -> Scene {
        Scene::above(object, start, z_offset, 0.0).with_noise(xy_noise, yaw_noise, seed)
    }

    pub(super) fn check(&self) -> Result<(), SimError> {
        let bad = |what| Err(SimError::NonFiniteScene { what });
        if self.start.iter().any(|v| !v.is_finite()) {
            return bad("start posture");
        }
        if self.object_xy.iter().any(|v| !v.is_finite()) || !self.object_yaw.is_finite() {
            return bad("object pose");
        }
        if self.grasp_point.iter().any(|v| !v.is_finite()) {
            return bad("grasp point");
        }
        if !self.hand_yaw.is_finite() {
            return bad("hand yaw");
        }
        Ok(())
    }
}
