//! PPO learns: the MLP and the GRU policy each balance the continuous CartPole well above
//! the random level, the Bernoulli lift head learns when to stop on a tiny lift-style task,
//! the same seed gives bitwise the same metrics, and checkpoints round-trip.
//!
//! Thresholds come from measured runs with these exact seeds (see the report in the commit
//! history); each leaves a wide margin.

use grasp::env::api::{Action, ActionSpec, Env, Step, StepInfo};
use grasp::env::cartpole::CartPole;
use grasp::policy::{PolicyConfig, PolicyKind};
use grasp::ppo::{PpoConfig, PpoError, Trainer, UpdateMetrics};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn cartpoles(n: usize, max_steps: u32) -> Vec<Box<dyn Env>> {
    (0..n)
        .map(|_| Box::new(CartPole::new(max_steps)) as Box<dyn Env>)
        .collect()
}

/// Runs `updates` updates and returns the metrics, printing a learning curve.
fn run(label: &str, trainer: &mut Trainer, updates: usize) -> Vec<UpdateMetrics> {
    let mut out = Vec::new();
    for _ in 0..updates {
        let m = trainer.train_update().expect("update");
        println!(
            "{label} update {:3} step {:6} return {:7.1} len {:6.1} success {:?} kl {:.4} ev {:?} {:.0} tr/s",
            m.update,
            m.global_step,
            m.stats.episode_return.unwrap_or(f64::NAN),
            m.stats.episode_length.unwrap_or(f64::NAN),
            m.stats.success_rate,
            m.stats.approx_kl,
            m.stats.explained_variance,
            m.transitions_per_sec
        );
        out.push(m);
    }
    out
}

/// Mean of the episode returns reported by the last `k` updates.
fn late_return(ms: &[UpdateMetrics], k: usize) -> f64 {
    let v: Vec<f64> = ms
        .iter()
        .rev()
        .take(k)
        .filter_map(|m| m.stats.episode_return)
        .collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn mlp_config() -> PpoConfig {
    PpoConfig {
        seed: 3,
        num_envs: 8,
        env_threads: 1,
        num_steps: 128,
        num_minibatches: 4,
        update_epochs: 4,
        total_timesteps: 30_000,
        learning_rate: 1e-3,
        policy: PolicyConfig {
            kind: PolicyKind::Mlp,
            mlp_hidden: 64,
            ..PolicyConfig::default()
        },
        ..PpoConfig::default()
    }
}

fn gru_config() -> PpoConfig {
    PpoConfig {
        seed: 5,
        num_envs: 8,
        env_threads: 1,
        num_steps: 32,
        num_minibatches: 2,
        update_epochs: 4,
        total_timesteps: 24_000,
        learning_rate: 1e-3,
        policy: PolicyConfig {
            kind: PolicyKind::Gru,
            embed_dim: 32,
            gru_hidden: 32,
            ..PolicyConfig::default()
        },
        ..PpoConfig::default()
    }
}

#[test]
fn mlp_learns_cartpole() {
    let cfg = mlp_config();
    let updates = cfg.num_updates() as usize;
    let mut t = Trainer::new(cfg, cartpoles(8, 200)).unwrap();
    let ms = run("mlp", &mut t, updates);
    let first = ms[0].stats.episode_return.unwrap();
    let last = late_return(&ms, 5);
    println!("mlp: first {first:.1}, last {last:.1}");
    assert!(first < 40.0, "random level should be low: {first}");
    assert!(last > 150.0, "MLP did not learn CartPole: {last}");
}

#[test]
fn gru_learns_cartpole() {
    let cfg = gru_config();
    let updates = cfg.num_updates() as usize;
    let mut t = Trainer::new(cfg, cartpoles(8, 200)).unwrap();
    let ms = run("gru", &mut t, updates);
    let first = ms[0].stats.episode_return.unwrap();
    let last = late_return(&ms, 5);
    println!("gru: first {first:.1}, last {last:.1}");
    assert!(first < 40.0, "random level should be low: {first}");
    assert!(last > 150.0, "GRU did not learn CartPole: {last}");
}

/// A lift-style task, a pure "when to stop" decision: a point drifts along a line by 0.1
/// per step (plus 0.02 * clip(a), a continuous action that barely matters) from
/// x ~ U(-1, -0.4). Lifting (rho = 1) ends the episode with reward 1 and success when
/// |x| < 0.15, else reward 0 and failure; once x > 0.5 the episode is truncated as a
/// failure. Lifting at random (p = 0.5 per step) succeeds a few percent of the time.
struct StopInTarget {
    x: f32,
}

impl Env for StopInTarget {
    fn obs_dim(&self) -> usize {
        1
    }
    fn action_spec(&self) -> ActionSpec {
        ActionSpec {
            continuous: 1,
            lift: true,
        }
    }
    fn reset(&mut self, seed: u64) -> Vec<f32> {
        self.x = ChaCha8Rng::seed_from_u64(seed).random_range(-1.0..-0.4);
        vec![self.x]
    }
    fn step(&mut self, a: &Action) -> Step {
        if a.lift {
            let ok = self.x.abs() < 0.15;
            return Step {
                obs: vec![self.x],
                reward: if ok { 1.0 } else { 0.0 },
                terminated: true,
                truncated: false,
                info: StepInfo {
                    success: Some(ok),
                    physics_failure: false,
                },
            };
        }
        self.x += 0.1 + 0.02 * a.cont[0].clamp(-1.0, 1.0);
        let trunc = self.x > 0.5;
        Step {
            obs: vec![self.x],
            reward: 0.0,
            terminated: false,
            truncated: trunc,
            info: StepInfo {
                success: trunc.then_some(false),
                physics_failure: false,
            },
        }
    }
}

#[test]
fn lift_head_learns_when_to_stop() {
    let cfg = PpoConfig {
        seed: 2,
        num_envs: 8,
        env_threads: 1,
        num_steps: 64,
        num_minibatches: 4,
        total_timesteps: 20_000,
        learning_rate: 1e-3,
        gamma: 0.95,
        policy: PolicyConfig {
            kind: PolicyKind::Mlp,
            ..PolicyConfig::default()
        },
        ..PpoConfig::default()
    };
    let updates = cfg.num_updates() as usize;
    let envs: Vec<Box<dyn Env>> = (0..8)
        .map(|_| Box::new(StopInTarget { x: 0.0 }) as Box<dyn Env>)
        .collect();
    let mut t = Trainer::new(cfg, envs).unwrap();
    let ms = run("lift", &mut t, updates);
    let rate = |m: &UpdateMetrics| m.stats.success_rate.unwrap();
    let first = rate(&ms[0]);
    let last: f64 = ms.iter().rev().take(5).map(rate).sum::<f64>() / 5.0;
    println!("lift: first success {first:.2}, last {last:.2}");
    assert!(first < 0.2, "random success should be low: {first}");
    assert!(last > 0.8, "the lift head did not learn: {last}");
}

fn short_config(kind: PolicyKind) -> PpoConfig {
    PpoConfig {
        seed: 9,
        num_envs: 4,
        env_threads: 2,
        num_steps: 16,
        num_minibatches: 2,
        update_epochs: 2,
        total_timesteps: 640,
        policy: PolicyConfig {
            kind,
            embed_dim: 16,
            gru_hidden: 16,
            mlp_hidden: 16,
            ..PolicyConfig::default()
        },
        ..PpoConfig::default()
    }
}

/// Metrics without the timing fields.
fn untimed(mut m: UpdateMetrics) -> UpdateMetrics {
    m.rollout_secs = 0.0;
    m.optimize_secs = 0.0;
    m.transitions_per_sec = 0.0;
    m
}

#[test]
fn same_seed_gives_bitwise_the_same_metrics() {
    for kind in [PolicyKind::Gru, PolicyKind::Mlp] {
        let go = || {
            let mut t = Trainer::new(short_config(kind), cartpoles(4, 20)).unwrap();
            (0..2)
                .map(|_| untimed(t.train_update().unwrap()))
                .collect::<Vec<_>>()
        };
        let a = go();
        let b = go();
        assert_eq!(a, b, "{kind:?}");
        let mut other = short_config(kind);
        other.seed = 10;
        let mut t = Trainer::new(other, cartpoles(4, 20)).unwrap();
        let c = untimed(t.train_update().unwrap());
        assert_ne!(a[0], c, "{kind:?}: a different seed should differ");
    }
}

#[test]
fn checkpoint_round_trip_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = short_config(PolicyKind::Gru);
    let mut t = Trainer::new(cfg.clone(), cartpoles(4, 20)).unwrap();
    t.train_update().unwrap();
    let path = t.save_checkpoint(dir.path()).unwrap();
    assert!(path.ends_with("checkpoint.safetensors"));

    // Resuming restores weights, counters and the Adam state.
    let r = Trainer::resume(dir.path(), cartpoles(4, 20)).unwrap();
    assert_eq!(r.update_index(), 1);
    assert_eq!(r.global_step(), t.global_step());
    assert_eq!(r.obs_normalizer(), t.obs_normalizer());
    for (name, v) in t.policy().params().vars() {
        let w = |x: &candle_core::Var| x.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        assert_eq!(w(v), w(&r.policy().params().vars()[name]), "{name}");
    }
    // Training goes on from there, reproducibly.
    let mut r1 = Trainer::resume(dir.path(), cartpoles(4, 20)).unwrap();
    let mut r2 = Trainer::resume(dir.path(), cartpoles(4, 20)).unwrap();
    let m1 = untimed(r1.train_update().unwrap());
    assert_eq!(m1.update, 2);
    assert_eq!(m1, untimed(r2.train_update().unwrap()));

    // A standalone policy load for evaluation.
    let lp = grasp::ppo::load_policy(dir.path()).unwrap();
    assert_eq!(lp.policy.hidden_dim(), 16);
    assert!(lp.obs_rms.is_some());

    // Missing file.
    let empty = tempfile::tempdir().unwrap();
    let e = Trainer::resume(empty.path(), cartpoles(4, 20))
        .err()
        .unwrap();
    assert!(matches!(e, PpoError::CheckpointIo { .. }), "{e}");
    assert!(e.to_string().contains("checkpoint.safetensors"), "{e}");

    // Corrupt file.
    let bad = tempfile::tempdir().unwrap();
    std::fs::write(
        bad.path().join("checkpoint.safetensors"),
        b"not a checkpoint",
    )
    .unwrap();
    let e = Trainer::resume(bad.path(), cartpoles(4, 20)).err().unwrap();
    assert!(matches!(e, PpoError::CheckpointFormat { .. }), "{e}");

    // Truncated file.
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(
        bad.path().join("checkpoint.safetensors"),
        &bytes[..bytes.len() / 2],
    )
    .unwrap();
    let e = Trainer::resume(bad.path(), cartpoles(4, 20)).err().unwrap();
    assert!(matches!(e, PpoError::CheckpointFormat { .. }), "{e}");

    // Wrong shape: a file whose `critic.weight` was stored with another shape.
    let mut ck = grasp::ppo::checkpoint::read_checkpoint(&path).unwrap();
    let w = ck.tensors.get_mut("critic.weight").unwrap();
    w.shape = vec![w.shape[1], w.shape[0]];
    let tensors: Vec<_> = ck.tensors.values().cloned().collect();
    let shaped = tempfile::tempdir().unwrap();
    grasp::ppo::checkpoint::write_checkpoint(
        &shaped.path().join("checkpoint.safetensors"),
        &ck.state,
        &tensors,
    )
    .unwrap();
    let e = Trainer::resume(shaped.path(), cartpoles(4, 20))
        .err()
        .unwrap();
    assert!(matches!(e, PpoError::CheckpointShape { .. }), "{e}");
    assert!(e.to_string().contains("critic.weight"), "{e}");

    // Wrong architecture: a trainer with a bigger GRU refuses the file.
    let mut big = cfg.clone();
    big.policy.gru_hidden = 32;
    let mut tb = Trainer::new(big, cartpoles(4, 20)).unwrap();
    let e = tb.load_checkpoint(dir.path()).unwrap_err();
    assert!(matches!(e, PpoError::CheckpointMismatch { .. }), "{e}");

    // Wrong shapes with the same config: a checkpoint from an env with another obs size.
    let mut cfg5 = cfg.clone();
    cfg5.num_envs = 4;
    let e = {
        let envs: Vec<Box<dyn Env>> = (0..4)
            .map(|_| Box::new(StopInTarget { x: 0.0 }) as Box<dyn Env>)
            .collect();
        let mut other = Trainer::new(cfg5, envs).unwrap();
        other.load_checkpoint(dir.path()).unwrap_err()
    };
    assert!(matches!(e, PpoError::CheckpointMismatch { .. }), "{e}");
}
