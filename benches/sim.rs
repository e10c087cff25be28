//! Simulator throughput: one physics step while the hand grips a box, one control step,
//! a reset, and one control step of 20 envs in a rayon pool sized to the cores.

use criterion::{criterion_group, criterion_main, Criterion};
use grasp::robot::{Posture, Robot, Side};
use grasp::sim::script::power_grasp;
use grasp::sim::{HandSim, ObjectSpec, Scene, SimConfig};
use rayon::prelude::*;
use std::hint::black_box;

fn gripping_sim() -> (HandSim, Scene) {
    let obj = ObjectSpec::default_box();
    let mut sim = HandSim::new(
        &Robot::builtin(Side::Left),
        obj.clone(),
        SimConfig::default(),
    )
    .expect("default sim builds");
    let scene = Scene::above(&obj, Posture::Open.angles(), 0.03, 0.0);
    sim.reset(&scene).expect("default scene");
    sim.set_targets(&power_grasp()).expect("finite targets");
    for _ in 0..5 {
        sim.step_control();
    }
    (sim, scene)
}

fn bench(c: &mut Criterion) {
    let (mut sim, scene) = gripping_sim();
    let mut g = c.benchmark_group("sim");
    g.sample_size(20);
    g.bench_function("physics_step_gripping", |b| {
        b.iter(|| black_box(sim.step_physics()))
    });
    g.bench_function("control_step_gripping", |b| {
        b.iter(|| black_box(sim.step_control()))
    });
    g.bench_function("reset", |b| b.iter(|| sim.reset(black_box(&scene))));
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool");
    let mut sims: Vec<HandSim> = (0..20).map(|_| gripping_sim().0).collect();
    g.bench_function("control_step_20_envs", |b| {
        b.iter(|| {
            pool.install(|| {
                sims.par_iter_mut().for_each(|s| {
                    black_box(s.step_control());
                })
            })
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
