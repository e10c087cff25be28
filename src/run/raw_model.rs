//! The raw-sensor model of a simulated hand ([`RawModel`]): what the real hand's sensors
//! would read given the simulated joint angles, fingertip forces and actuator efforts
//! (tactile offsets, gains and noise, tendon scale, offset, linear drift, a random-walk
//! drift and noise, joint-angle noise). The equations are in
//! [`super::sim_backend`]'s module docs. Written once for every simulated backend: the
//! backend supplies the physics, the model the signals.

use crate::hardware::{HwError, RawSensors};
use crate::robot::joints::{N_ACTUATORS, N_JOINTS, N_TACTILE};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Parameters of the raw-sensor model (see the module docs for the equations).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RawModelConfig {
    /// Tactile reading with no force, per fingertip FF, MF, RF, LF, TH (sensor units).
    pub tactile_offset: [f64; N_TACTILE],
    /// Tactile units per newton of contact force, per fingertip.
    pub tactile_gain: [f64; N_TACTILE],
    /// Standard deviation of the tactile noise (units).
    pub tactile_noise: f64,
    /// Tendon units per N m of actuator effort.
    pub tendon_scale: f64,
    /// Constant tendon offset (units).
    pub tendon_offset: f64,
    /// Linear tendon drift (units per second of backend time).
    pub tendon_drift_rate: f64,
    /// Random-walk tendon drift (units per square-root second).
    pub tendon_drift_walk: f64,
    /// Standard deviation of the tendon noise (units).
    pub tendon_noise: f64,
    /// Standard deviation of the joint-angle noise (rad).
    pub joint_noise: f64,
    /// Backend time at construction (s): where the linear drift starts.
    pub clock_start_s: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for RawModelConfig {
    fn default() -> Self {
        RawModelConfig {
            tactile_offset: [312.0, 298.0, 305.0, 287.0, 321.0],
            tactile_gain: [100.0, 95.0, 105.0, 98.0, 102.0],
            tactile_noise: 0.3,
            tendon_scale: 1000.0,
            tendon_offset: 1500.0,
            tendon_drift_rate: 2.0,
            tendon_drift_walk: 1.0,
            tendon_noise: 2.0,
            joint_noise: 0.001,
            clock_start_s: 0.0,
            seed: 0,
        }
    }
}

impl RawModelConfig {
    /// Checks that every number is finite, gains and scales positive, noises
    /// non-negative; the error names the field.
    pub fn validate(&self) -> Result<(), HwError> {
        let bad = |field: String, detail: String| Err(HwError::InvalidCommand { field, detail });
        for k in 0..N_TACTILE {
            if !self.tactile_offset[k].is_finite() {
                return bad(format!("tactile_offset[{k}]"), "must be finite".into());
            }
            if !(self.tactile_gain[k].is_finite() && self.tactile_gain[k] > 0.0) {
                return bad(format!("tactile_gain[{k}]"), "must be positive".into());
            }
        }
        for (name, v) in [
            ("tendon_offset", self.tendon_offset),
            ("tendon_drift_rate", self.tendon_drift_rate),
            ("clock_start_s", self.clock_start_s),
        ] {
            if !v.is_finite() {
                return bad(name.into(), format!("{v} is not finite"));
            }
        }
        if !(self.tendon_scale.is_finite() && self.tendon_scale > 0.0) {
            return bad("tendon_scale".into(), "must be positive".into());
        }
        for (name, v) in [
            ("tactile_noise", self.tactile_noise),
            ("tendon_drift_walk", self.tendon_drift_walk),
            ("tendon_noise", self.tendon_noise),
            ("joint_noise", self.joint_noise),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name.into(), format!("{v} must be finite and >= 0"));
            }
        }
        Ok(())
    }
}

/// The raw-sensor model's state: its config, the noise generator (one `ChaCha8Rng`
/// seeded by [`RawModelConfig::seed`], a fixed number of draws per reading) and the
/// tendons' random walk with the time of its last step.
#[derive(Debug, Clone)]
pub struct RawModel {
    cfg: RawModelConfig,
    rng: ChaCha8Rng,
    walk: [f64; N_ACTUATORS],
    walk_time: f64,
}

impl RawModel {
    /// The model of `cfg` (checked by [`RawModelConfig::validate`]), its walk at zero at
    /// time [`RawModelConfig::clock_start_s`].
    pub fn new(cfg: RawModelConfig) -> Result<RawModel, HwError> {
        cfg.validate()?;
        Ok(RawModel {
            rng: ChaCha8Rng::seed_from_u64(cfg.seed),
            walk: [0.0; N_ACTUATORS],
            walk_time: cfg.clock_start_s,
            cfg,
        })
    }

    /// The model's config.
    pub fn config(&self) -> &RawModelConfig {
        &self.cfg
    }

    /// One reading at backend time `t` (s) of a hand at joint angles `q` (rad) whose
    /// fingertips feel the normal forces `tip_force` (N; FF, MF, RF, LF, TH, a calibration
    /// press included) and whose actuators exert `effort` (N m). Draws, in this order, the
    /// joint noise (24), the tactile noise (5), the walk's steps since the last reading
    /// (20) and the tendon noise (20).
    pub fn reading(
        &mut self,
        t: f64,
        q: &[f64; N_JOINTS],
        tip_force: &[f64; N_TACTILE],
        effort: &[f64; N_ACTUATORS],
    ) -> RawSensors {
        let raw = &self.cfg;
        let rng = &mut self.rng;
        let mut gauss = |sigma: f64| {
            let z: f64 = StandardNormal.sample(rng);
            sigma * z
        };
        let joint_angles: [f64; N_JOINTS] = std::array::from_fn(|k| q[k] + gauss(raw.joint_noise));
        let tactile_raw: [f64; N_TACTILE] = std::array::from_fn(|k| {
            raw.tactile_offset[k] + raw.tactile_gain[k] * tip_force[k] + gauss(raw.tactile_noise)
        });
        let dt = (t - self.walk_time).max(0.0);
        let walk_sigma = raw.tendon_drift_walk * dt.sqrt();
        for w in self.walk.iter_mut() {
            *w += gauss(walk_sigma);
        }
        self.walk_time = t;
        let tendon_raw: [f64; N_ACTUATORS] = std::array::from_fn(|j| {
            raw.tendon_scale * effort[j]
                + raw.tendon_offset
                + raw.tendon_drift_rate * t
                + self.walk[j]
                + gauss(raw.tendon_noise)
        });
        RawSensors {
            stamp: t,
            joint_angles,
            tactile_raw,
            tendon_raw,
        }
    }
}

/// Checks a calibration press: `finger` a fingertip index (0..5: FF, MF, RF, LF, TH) and
/// `force_n` a finite, non-negative force (N); the error names the field.
pub fn check_press(finger: usize, force_n: f64) -> Result<(), HwError> {
    if finger >= N_TACTILE {
        return Err(HwError::InvalidCommand {
            field: "finger".into(),
            detail: format!("{finger} is not a fingertip index 0..5"),
        });
    }
    if !(force_n.is_finite() && force_n >= 0.0) {
        return Err(HwError::InvalidCommand {
            field: "press force".into(),
            detail: format!("{force_n} N must be finite and >= 0"),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_readings_and_the_walk_grows_with_time() {
        let cfg = RawModelConfig {
            seed: 7,
            ..RawModelConfig::default()
        };
        let (q, f, e) = ([0.1; N_JOINTS], [0.0; N_TACTILE], [0.0; N_ACTUATORS]);
        let mut a = RawModel::new(cfg.clone()).unwrap();
        let mut b = RawModel::new(cfg).unwrap();
        let (ra, rb) = (a.reading(0.5, &q, &f, &e), b.reading(0.5, &q, &f, &e));
        assert_eq!(ra, rb);
        assert_eq!(ra.stamp, 0.5);
        // A press of 10 N on RF adds gain * 10 (noise sigma 0.3, 6 sigma bound).
        let mut f = f;
        f[2] = 10.0;
        let p = a.reading(0.5, &q, &f, &e);
        assert!((p.tactile_raw[2] - (305.0 + 1050.0)).abs() < 1.8);
        assert!(RawModel::new(RawModelConfig {
            tactile_noise: -1.0,
            ..RawModelConfig::default()
        })
        .is_err());
    }
}
