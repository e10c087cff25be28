//! The grasping MDP end to end on the simulator: baselines, a random agent, determinism.

mod common;

use grasp::env::api::{Action, Env};
use grasp::env::grasp::{run_episode, EnvConfig, GraspEnv, RandomAgent};
use grasp::robot::{Robot, Side};
use grasp::sim::{ObjectSpec, SimConfig};

fn env() -> GraspEnv {
    env_with(EnvConfig::default())
}

fn env_with(cfg: EnvConfig) -> GraspEnv {
    let robot = Robot::builtin(Side::Left);
    let model = common::test_model();
    let objects = vec![
        ("box".to_string(), ObjectSpec::default_box()),
        ("cylinder".to_string(), ObjectSpec::default_cylinder()),
    ];
    GraspEnv::new(&robot, objects, model, SimConfig::default(), cfg).expect("env")
}

#[test]
fn baseline2_grasps_the_test_box_and_the_random_agent_rarely_does() {
    let mut e = env();
    let b2: usize = (0..4)
        .map(|s| usize::from(e.run_baseline(true, s).unwrap().success))
        .sum();
    assert!(b2 >= 2, "baseline 2 succeeded {b2}/4");
    let mut agent = RandomAgent::new(7, 0.15, 5);
    let random: usize = (0..4)
        .map(|s| usize::from(run_episode(&mut e, &mut agent, 100 + s).success))
        .sum();
    assert!(random <= 1, "random agent succeeded {random}/4");
}

#[test]
fn observations_follow_the_layout_and_episodes_are_deterministic() {
    let mut e = env();
    // M3, PCA5, h = 3: 3 x (7 + 5 + 20 + 24) = 168.
    assert_eq!(e.obs_dim(), 168);
    let o1 = e.reset(7);
    assert_eq!(o1.len(), 168);
    // The first two frames are zero padding; the last holds real joint angles.
    assert!(o1[..112].iter().all(|&v| v == 0.0));
    assert!(o1[112..].iter().any(|&v| v != 0.0));
    let run = |e: &mut GraspEnv| {
        let mut agent = RandomAgent::new(7, 0.2, 9);
        run_episode(e, &mut agent, 42)
    };
    let a = run(&mut e);
    let b = run(&mut e);
    assert_eq!(a, b);
}

#[test]
fn an_episode_that_never_lifts_ends_as_a_terminal_failure() {
    let mut e = env_with(EnvConfig {
        max_steps: 3,
        ..EnvConfig::default()
    });
    e.reset(5);
    // Squeeze: every continuous component at its maximum, no lift.
    let squeeze = Action {
        cont: vec![1.0; e.action_spec().continuous],
        lift: false,
    };
    let steps: Vec<_> = (0..3).map(|_| e.step(&squeeze)).collect();
    for s in &steps[..2] {
        assert!(!s.terminated && !s.truncated && s.info.success.is_none());
    }
    let last = &steps[2];
    // Eq. 4's final step: r_b = 0, and terminal (no bootstrapping through a timeout).
    assert!(last.terminated && !last.truncated, "{last:?}");
    assert_eq!(last.reward, 0.0);
    assert_eq!(last.info.success, Some(false));
    let summary = e.last_episode().expect("finished");
    assert!(!summary.success && !summary.lifted && !summary.physics_failure);
    assert_eq!(summary.steps, 3);
    let earlier: f64 = steps[..2].iter().map(|s| f64::from(s.reward)).sum();
    assert!((summary.episode_return - earlier).abs() < 1e-6);
}

#[test]
fn at_max_steps_lift_ends_the_episode_with_a_judged_lift() {
    use grasp::env::grasp::AtMaxSteps;
    let mut e = env_with(EnvConfig {
        max_steps: 2,
        at_max_steps: AtMaxSteps::Lift,
        ..EnvConfig::default()
    });
    e.reset(5);
    let hold = Action {
        cont: vec![0.0; e.action_spec().continuous],
        lift: false,
    };
    let first = e.step(&hold);
    assert!(!first.terminated && first.info.success.is_none());
    let last = e.step(&hold);
    // The second step's action is applied, then the lift: the final step of eq. 4, its
    // reward r_b the judged outcome.
    assert!(last.terminated && !last.truncated, "{last:?}");
    let summary = e.last_episode().expect("finished");
    assert!(summary.lifted, "{summary:?}");
    assert_eq!(summary.steps, 2);
    assert_eq!(last.info.success, Some(summary.success));
    assert_eq!(last.reward, f32::from(u8::from(summary.success)));
}

#[test]
fn anchoring_on_the_command_accumulates_the_squeeze() {
    use grasp::env::action::Anchor;
    // The same squeeze from the same start: anchored on the previous command, the key
    // closing joints' targets run ahead of the blocked fingers and keep growing; anchored
    // on the measured angles, each target is one increment past the finger.
    let gap = |anchor: Anchor| {
        let mut cfg = EnvConfig::default();
        cfg.action.anchor = anchor;
        let mut e = env_with(cfg);
        e.reset(5);
        let squeeze = Action {
            cont: vec![1.0; e.action_spec().continuous],
            lift: false,
        };
        for _ in 0..4 {
            e.step(&squeeze);
        }
        let (q, _) = e.sim().joint_state();
        let t = e.sim().targets();
        grasp::robot::joints::KEY_CLOSING_JOINTS
            .iter()
            .filter_map(|n| grasp::robot::joints::hand_index(n))
            .map(|j| t[j] - q[j])
            .sum::<f64>()
    };
    let measured = gap(Anchor::Measured);
    let target = gap(Anchor::Target);
    assert!(
        target > measured + 0.1,
        "target {target} vs measured {measured}"
    );
}

#[test]
fn the_procedural_stream_and_randomisation_vary_episodes_reproducibly() {
    use grasp::env::randomize::Randomization;
    use grasp::env::stream::StreamConfig;
    let cfg = EnvConfig {
        randomization: Randomization {
            enabled: true,
            ..Randomization::default()
        },
        stream: StreamConfig { seed: 0, reuse: 2 },
        ..EnvConfig::default()
    };
    let run = |seeds: &[u64]| -> Vec<(String, f64, f64, f64)> {
        let mut e = env_with(cfg.clone()).with_stream();
        seeds
            .iter()
            .map(|&s| {
                let mut agent = RandomAgent::new(3, 0.3, 5);
                let summary = run_episode(&mut e, &mut agent, s);
                let o = e.sim().object();
                (summary.object, o.mass, o.friction, summary.episode_return)
            })
            .collect()
    };
    let a = run(&[1, 2, 3, 4]);
    // A stream object every 2 episodes, never the fixed boxes; the randomised mass and
    // friction differ between episodes on the same object.
    let names: Vec<&String> = a.iter().map(|r| &r.0).collect();
    assert!(names.iter().all(|n| n.starts_with("proc-0-")), "{names:?}");
    assert_eq!(a[0].0, a[1].0);
    assert_ne!(a[1].0, a[2].0);
    assert_eq!(a[2].0, a[3].0);
    assert!(a[0].1 != a[1].1 && a[0].2 != a[1].2);
    for r in &a {
        assert!((0.5..=1.0).contains(&r.2) && r.1 <= 0.6 + 1e-12);
    }
    // The same seeds in a fresh env: the same objects, masses, frictions and returns.
    assert_eq!(a, run(&[1, 2, 3, 4]));
}
