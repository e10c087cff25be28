//! PPO speed with the GRU policy at the paper's scale: batch-20 inference (one control step
//! of the 20 environments, with sampling and log-probabilities) and one whole PPO update of
//! 20 environments x 64 steps (rollout on a trivial environment, GAE, 4 epochs x 4
//! minibatches of whole sequences).
//!
//! The observation matches the grasp task's stacked M3 observation: h = 3 copies of
//! (7 previous actions + 5 contacts + 24 torque levels + 24 joint angles) = 180 values; the
//! action is 5 synergy + 2 wrist increments and the lift decision.
//!
//! Run: `cargo bench --bench ppo`.

use candle_core::{DType, Device, Tensor};
use criterion::{criterion_group, criterion_main, Criterion};
use grasp::env::api::{Action, ActionSpec, Env, Step, StepInfo};
use grasp::policy::{build_policy, PolicyConfig, PolicyKind};
use grasp::ppo::{PpoConfig, Trainer};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Duration;

const OBS: usize = 180;
const SPEC: ActionSpec = ActionSpec {
    continuous: 7,
    lift: true,
};

/// A trivial environment of the grasp task's shape: random observations, episodes of
/// about 6 steps, reward on lifting.
struct Dummy {
    rng: ChaCha8Rng,
    t: u32,
}

impl Env for Dummy {
    fn obs_dim(&self) -> usize {
        OBS
    }
    fn action_spec(&self) -> ActionSpec {
        SPEC
    }
    fn reset(&mut self, seed: u64) -> Vec<f32> {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
        self.t = 0;
        (0..OBS).map(|_| self.rng.random_range(-1.0..1.0)).collect()
    }
    fn step(&mut self, a: &Action) -> Step {
        self.t += 1;
        let end = a.lift || self.t >= 12;
        Step {
            obs: (0..OBS).map(|_| self.rng.random_range(-1.0..1.0)).collect(),
            reward: if a.lift { 1.0 } else { 0.01 },
            terminated: a.lift,
            truncated: !a.lift && end,
            info: StepInfo {
                success: end.then_some(a.lift),
                physics_failure: false,
            },
        }
    }
}

fn bench(c: &mut Criterion) {
    let cfg = PolicyConfig {
        kind: PolicyKind::Gru,
        ..PolicyConfig::default()
    };
    let policy = build_policy(&cfg, OBS, SPEC, 1).unwrap();
    println!("GRU policy: {} parameters", policy.params().count());
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let obs: Vec<f32> = (0..20 * OBS).map(|_| rng.random_range(-1.0..1.0)).collect();
    let obs = Tensor::from_vec(obs, (1, 20, OBS), &Device::Cpu).unwrap();
    let starts = Tensor::zeros((1, 20), DType::F32, &Device::Cpu).unwrap();
    let h = policy.initial_state(20).unwrap();
    c.bench_function("gru_forward_batch20_sample", |b| {
        b.iter(|| {
            let out = policy.forward_seq(&obs, &starts, h.as_ref()).unwrap();
            let s = out.dist.sample(&mut rng).unwrap();
            let cont = Tensor::from_vec(s.cont, (20, 7), &Device::Cpu).unwrap();
            let rho = Tensor::from_vec(s.rho, 20, &Device::Cpu).unwrap();
            black_box(out.dist.log_prob(&cont, Some(&rho)).unwrap());
        })
    });

    let ppo = PpoConfig {
        num_envs: 20,
        num_steps: 64,
        env_threads: 1,
        policy: cfg,
        ..PpoConfig::default()
    };
    let envs: Vec<Box<dyn Env>> = (0..20)
        .map(|_| {
            Box::new(Dummy {
                rng: ChaCha8Rng::seed_from_u64(0),
                t: 0,
            }) as Box<dyn Env>
        })
        .collect();
    let mut trainer = Trainer::new(ppo, envs).unwrap();
    let mut group = c.benchmark_group("ppo_update");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(20));
    group.bench_function("gru_20envs_x_64steps", |b| {
        b.iter(|| black_box(trainer.train_update().unwrap()))
    });
    group.finish();
    let m = trainer.train_update().unwrap();
    println!(
        "last update: rollout {:.3} s, optimise {:.3} s, {:.0} transitions/s",
        m.rollout_secs, m.optimize_secs, m.transitions_per_sec
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = bench
}
criterion_main!(benches);
