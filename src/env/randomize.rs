//! Per-episode domain randomisation: the object's mass, friction, size and yaw, and noise
//! on the sensor readings the policy observes.
//!
//! Each range is a config value (`[env.randomization]`); the defaults keep the physics
//! honest (friction at most 1 against the hand's by the MIN rule, masses capped at the
//! built-in objects' 600 g). The noise matches the raw-sensor model of `grasp run`'s sim
//! backend: its tendon noise (2 units at 1000 units per N m) is 0.002 N m on each
//! actuator effort before the torque levels are taken, and its joint noise 0.001 rad.
//! Touch detection in stage 1 reads the simulator's own contact bits, not the noisy copy.
//!
//! Randomisation is off by default; evaluation turns it off whatever a checkpoint was
//! trained with, so every agent is judged on the same objects.

use crate::sim::ObjectSpec;
use crate::util::levels::torque_level;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Ranges of the per-episode randomisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Randomization {
    /// Whether episodes are randomised at all.
    pub enabled: bool,
    /// Factor on the object's mass, drawn log-uniformly in `[lo, hi]`.
    #[serde(deserialize_with = "mass_scale")]
    pub mass_scale: [f64; 2],
    /// Largest mass after scaling (kg).
    pub max_mass_kg: f64,
    /// The object's friction coefficient, drawn uniformly (replaces the object's own).
    #[serde(deserialize_with = "friction")]
    pub friction: [f64; 2],
    /// Uniform factor on the object's size, drawn uniformly.
    #[serde(deserialize_with = "size_scale")]
    pub size_scale: [f64; 2],
    /// Largest |yaw| added to the object's start pose (rad; pi = any heading).
    pub yaw: f64,
    /// Standard deviation of the noise on each actuator effort before its torque level
    /// is taken (N m).
    pub effort_noise: f64,
    /// Standard deviation of the noise on each observed joint angle (rad).
    pub joint_noise: f64,
}

impl Default for Randomization {
    fn default() -> Self {
        Randomization {
            enabled: false,
            mass_scale: [0.5, 2.0],
            max_mass_kg: 0.6,
            friction: [0.5, 1.0],
            size_scale: [0.8, 1.2],
            yaw: std::f64::consts::PI,
            effort_noise: 0.002,
            joint_noise: 0.001,
        }
    }
}

impl Randomization {
    /// The ranges set to other than their defaults (`enabled` aside): with `enabled =
    /// false` they randomise nothing, which a config that sets them likely did not mean.
    pub fn changed(&self) -> Vec<&'static str> {
        let d = Randomization::default();
        [
            ("mass_scale", self.mass_scale != d.mass_scale),
            ("max_mass_kg", self.max_mass_kg != d.max_mass_kg),
            ("friction", self.friction != d.friction),
            ("size_scale", self.size_scale != d.size_scale),
            ("yaw", self.yaw != d.yaw),
            ("effort_noise", self.effort_noise != d.effort_noise),
            ("joint_noise", self.joint_noise != d.joint_noise),
        ]
        .into_iter()
        .filter_map(|(name, differs)| differs.then_some(name))
        .collect()
    }
}

/// A `[lo, hi]` range: exactly two numbers (serde's fixed-size arrays would drop extra
/// elements without a word).
fn pair<'de, D: serde::Deserializer<'de>>(d: D, field: &str) -> Result<[f64; 2], D::Error> {
    let v = Vec::<f64>::deserialize(d)?;
    <[f64; 2]>::try_from(v.as_slice()).map_err(|_| {
        serde::de::Error::custom(format!(
            "`{field}` has {} numbers: a range is exactly 2, [lo, hi]",
            v.len()
        ))
    })
}

fn mass_scale<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    pair(d, "randomization.mass_scale")
}

fn friction<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    pair(d, "randomization.friction")
}

fn size_scale<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    pair(d, "randomization.size_scale")
}

/// A standard normal draw, as the sim backend's raw-sensor model draws its noise.
fn normal(rng: &mut impl Rng) -> f64 {
    StandardNormal.sample(rng)
}

fn draw(rng: &mut impl Rng, r: [f64; 2]) -> f64 {
    if r[1] > r[0] {
        rng.random_range(r[0]..=r[1])
    } else {
        r[0]
    }
}

impl Randomization {
    /// Checks every range; the error names the field.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let range = |field: &'static str, r: [f64; 2], lo: f64, hi: f64| {
            if r.iter().all(|v| v.is_finite()) && lo <= r[0] && r[0] <= r[1] && r[1] <= hi {
                Ok(())
            } else {
                Err((
                    field,
                    format!(
                        "[{}] must be an ordered pair in [{lo}, {hi}]",
                        r.iter()
                            .map(|v| crate::util::num::short(*v))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ))
            }
        };
        range("randomization.mass_scale", self.mass_scale, 0.1, 10.0)?;
        range("randomization.friction", self.friction, 0.0, 1.0)?;
        range("randomization.size_scale", self.size_scale, 0.5, 2.0)?;
        use crate::util::num::within;
        within(
            "randomization.max_mass_kg",
            self.max_mass_kg,
            0.001,
            20.0,
            "",
        )?;
        within("randomization.yaw", self.yaw, 0.0, std::f64::consts::PI, "")?;
        within(
            "randomization.effort_noise",
            self.effort_noise,
            0.0,
            1.0,
            "",
        )?;
        within("randomization.joint_noise", self.joint_noise, 0.0, 0.5, "")
    }

    /// The object of one episode: mass, friction and size drawn from `rng` (a shape that
    /// cannot be scaled keeps its size).
    pub fn object(&self, spec: &ObjectSpec, rng: &mut impl Rng) -> ObjectSpec {
        let (lo, hi) = (self.mass_scale[0].ln(), self.mass_scale[1].ln());
        let mass_factor = draw(rng, [lo, hi]).exp();
        let friction = draw(rng, self.friction);
        let size = draw(rng, self.size_scale);
        let mut out = spec.clone();
        // Never above the cap, unless the object itself is heavier (then never above it).
        out.mass = (spec.mass * mass_factor).min(self.max_mass_kg.max(spec.mass));
        out.friction = friction;
        if let Some(shape) = spec.shape.scaled(size) {
            out.shape = shape;
        }
        out
    }

    /// The yaw added to the episode's start pose.
    pub fn yaw(&self, rng: &mut impl Rng) -> f64 {
        draw(rng, [-self.yaw, self.yaw])
    }

    /// The torque levels of `effort` (N m) with noise, as `levels` computes them from the
    /// simulator: `level(scale * (e + n))`.
    pub fn noisy_levels(
        &self,
        effort: &[f64; 20],
        scale: f64,
        thresholds: &[f64],
        rng: &mut impl Rng,
    ) -> [u8; 20] {
        effort.map(|e| torque_level(scale * (e + self.effort_noise * normal(rng)), thresholds))
    }

    /// Joint angles with noise.
    pub fn noisy_angles(&self, q: &[f64; 24], rng: &mut impl Rng) -> [f64; 24] {
        q.map(|x| x + self.joint_noise * normal(rng))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_names_the_ranges_set_off_their_defaults() {
        assert!(Randomization::default().changed().is_empty());
        let r = Randomization {
            friction: [0.6, 0.9],
            yaw: 0.5,
            ..Randomization::default()
        };
        assert_eq!(r.changed(), ["friction", "yaw"]);
        // `enabled` is not a range.
        let on = Randomization {
            enabled: true,
            ..Randomization::default()
        };
        assert!(on.changed().is_empty());
    }
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn defaults_validate_and_bad_ranges_name_the_field() {
        Randomization::default().validate().unwrap();
        let bad = Randomization {
            friction: [0.5, 1.2],
            ..Randomization::default()
        };
        assert_eq!(bad.validate().unwrap_err().0, "randomization.friction");
        let bad = Randomization {
            size_scale: [1.2, 0.8],
            ..Randomization::default()
        };
        assert_eq!(bad.validate().unwrap_err().0, "randomization.size_scale");
        let bad = Randomization {
            joint_noise: f64::NAN,
            ..Randomization::default()
        };
        assert_eq!(bad.validate().unwrap_err().0, "randomization.joint_noise");
    }

    #[test]
    fn objects_stay_in_their_ranges_and_repeat_by_seed() {
        let r = Randomization::default();
        // 5 x 5 x 8 cm, 0.4 kg: x2 would be 0.8 kg, capped at 0.6.
        let spec = ObjectSpec::cuboid([0.025, 0.025, 0.04], 0.4, 0.8);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let (mut capped, mut light) = (0, 0);
        for _ in 0..500 {
            let o = r.object(&spec, &mut rng);
            assert!((0.2 - 1e-12..=0.6).contains(&o.mass), "{}", o.mass);
            capped += usize::from(o.mass == 0.6);
            light += usize::from(o.mass < 0.3);
            assert!((0.5..=1.0).contains(&o.friction));
            let h = o.shape.half_extents()[0];
            assert!(
                (0.8 * 0.025 - 1e-12..=1.2 * 0.025 + 1e-12).contains(&h),
                "{h}"
            );
            o.validate().unwrap();
        }
        // log-uniform x0.5..2: P(x > 1.5) = ln(4/3)/ln(4) = 0.21, P(x < 0.75) = 0.21.
        assert!((70..=150).contains(&capped), "{capped}");
        assert!((70..=150).contains(&light), "{light}");
        let a = r.object(&spec, &mut ChaCha8Rng::seed_from_u64(5));
        let b = r.object(&spec, &mut ChaCha8Rng::seed_from_u64(5));
        assert_eq!(a, b);
    }

    #[test]
    fn effort_noise_moves_levels_only_near_a_threshold() {
        let r = Randomization::default();
        let th = [-20.0, -10.0, 0.0, 10.0, 20.0];
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        // 0.05 N m at scale 100 is 5, between thresholds 0 and 10: noise of 0.002 N m
        // (0.2 units) never moves it; 0.1 N m sits on a threshold and flips about half
        // the time.
        let mut flips = 0;
        for _ in 0..200 {
            let l = r.noisy_levels(&[0.05; 20], 100.0, &th, &mut rng);
            assert!(l.iter().all(|&x| x == 3));
            let l = r.noisy_levels(&[0.1; 20], 100.0, &th, &mut rng);
            flips += l.iter().filter(|&&x| x == 3).count();
        }
        assert!((1600..=2400).contains(&flips), "{flips} of 4000");
        let q = r.noisy_angles(&[0.5; 24], &mut rng);
        assert!(q.iter().all(|x| (x - 0.5).abs() < 0.01) && q.iter().any(|&x| x != 0.5));
    }
}
