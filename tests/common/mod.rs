//! Helpers shared by the integration tests.

use grasp::robot::{Posture, Robot, Side};
use grasp::sim::script;
use grasp::synergy::SynergyModel;
use rand::{Rng, SeedableRng};

/// A 5-component synergy model fitted to 300 noisy postures between the C-shape and the
/// power grasp (seed 1): a small stand-in for the shipped model that keeps tests
/// independent of it.
pub fn test_model() -> SynergyModel {
    let robot = Robot::builtin(Side::Left);
    let lim = robot.finger_limits();
    let a = Posture::CShape.angles();
    let b = script::power_grasp();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let rows: Vec<[f64; 22]> = (0..300)
        .map(|_| {
            let t: f64 = rng.random();
            std::array::from_fn(|k| {
                (a[k + 2] + t * (b[k + 2] - a[k + 2]) + rng.random_range(-0.05..0.05))
                    .clamp(lim[k].0, lim[k].1)
            })
        })
        .collect();
    SynergyModel::fit(&rows, 5).expect("fit")
}
