//! Synergy PCA speed: fitting 3600 x 22 postures (about the size of the paper's dataset)
//! and the per-step maps for a batch of 20 environments (P, P^-1 and eq. 2).
//!
//! Run: `cargo bench --bench pca -- --warm-up-time 1 --measurement-time 3`

use criterion::{criterion_group, criterion_main, Criterion};
use grasp::robot::Side;
use grasp::synergy::{finger_limits, SynergyModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::hint::black_box;

/// `m` feasible postures: mid-range plus 6 correlated latent factors plus noise.
fn postures(m: usize, seed: u64) -> Vec<[f64; 22]> {
    let limits = finger_limits(Side::Left);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let loadings: Vec<[f64; 22]> = (0..6)
        .map(|_| std::array::from_fn(|_| rng.sample::<f64, _>(StandardNormal) * 0.3))
        .collect();
    (0..m)
        .map(|_| {
            let z: Vec<f64> = (0..6).map(|_| rng.sample(StandardNormal)).collect();
            std::array::from_fn(|j| {
                let (lo, hi) = limits[j];
                let half = 0.45 * (hi - lo);
                let dev: f64 = z.iter().zip(&loadings).map(|(z, l)| z * l[j]).sum::<f64>()
                    + 0.02 * rng.sample::<f64, _>(StandardNormal);
                0.5 * (lo + hi) + half * (dev / half).tanh()
            })
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let data = postures(3600, 7);
    c.bench_function("pca_fit_3600x22_n5", |b| {
        b.iter(|| SynergyModel::fit(black_box(&data), 5).unwrap())
    });

    let model = SynergyModel::fit(&data, 5).unwrap();
    let limits = finger_limits(Side::Left);
    let thetas: Vec<[f64; 22]> = data[..20].to_vec();
    let d_eps: Vec<f64> = (0..100).map(|i| 0.01 * ((i % 7) as f64 - 3.0)).collect();
    let mut eps = vec![0.0; 100];
    let mut back = vec![[0.0; 22]; 20];
    let mut out = vec![[0.0; 22]; 20];
    c.bench_function("pca_project_batch20_n5", |b| {
        b.iter(|| model.project_batch(black_box(&thetas), &mut eps))
    });
    c.bench_function("pca_reconstruct_batch20_n5", |b| {
        b.iter(|| model.reconstruct_batch(black_box(&eps), &mut back))
    });
    c.bench_function("pca_eq2_target_batch20_n5", |b| {
        b.iter(|| model.target_batch(black_box(&thetas), black_box(&d_eps), &limits, &mut out))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
