//! TEMPORARY local copy for compiling the MuJoCo backend (replaced by the table branch's).
pub use super::sim_backend::RawModelConfig;
use crate::hardware::{HwError, RawSensors, N_HAND_JOINTS, N_TACTILE, N_TENDONS};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

pub struct RawModel {
    cfg: RawModelConfig,
    rng: ChaCha8Rng,
    walk: [f64; N_TENDONS],
    walk_time: f64,
}

impl RawModel {
    pub fn new(cfg: RawModelConfig) -> Result<RawModel, HwError> {
        cfg.validate()?;
        Ok(RawModel {
            rng: ChaCha8Rng::seed_from_u64(cfg.seed),
            walk: [0.0; N_TENDONS],
            walk_time: cfg.clock_start_s,
            cfg,
        })
    }

    pub fn reading(
        &mut self,
        t: f64,
        q: &[f64; N_HAND_JOINTS],
        tip: &[f64; N_TACTILE],
        effort: &[f64; N_TENDONS],
    ) -> RawSensors {
        let raw = &self.cfg;
        let rng = &mut self.rng;
        let mut gauss = |sigma: f64| {
            let z: f64 = StandardNormal.sample(rng);
            sigma * z
        };
        let joint_angles: [f64; N_HAND_JOINTS] =
            std::array::from_fn(|k| q[k] + gauss(raw.joint_noise));
        let tactile_raw: [f64; N_TACTILE] = std::array::from_fn(|k| {
            raw.tactile_offset[k] + raw.tactile_gain[k] * tip[k] + gauss(raw.tactile_noise)
        });
        let dt = (t - self.walk_time).max(0.0);
        let walk_sigma = raw.tendon_drift_walk * dt.sqrt();
        for w in self.walk.iter_mut() {
            *w += gauss(walk_sigma);
        }
        self.walk_time = t;
        let tendon_raw: [f64; N_TENDONS] = std::array::from_fn(|j| {
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
