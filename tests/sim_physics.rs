//! Physics behaviour of the simulator: grasp and lift, slipping, tactile and torque
//! sensing, determinism, stability, failure handling. Optimised dev profile; a few seconds.

use grasp::robot::joints::hand_index;
use grasp::robot::{Posture, Robot, Side};
use grasp::sim::script::{close_and_lift, power_grasp, ScriptOptions};
use grasp::sim::{HandSim, ObjectSpec, PhysicsFailure, Scene, SimConfig};

fn sim_with(obj: &ObjectSpec) -> HandSim {
    HandSim::new(
        &Robot::builtin(Side::Left),
        obj.clone(),
        SimConfig::default(),
    )
    .unwrap()
}

fn grasp_scene(obj: &ObjectSpec) -> Scene {
    Scene::above(obj, Posture::Open.angles(), 0.03, 0.0)
}

#[test]
fn closed_hand_lifts_a_box_and_a_slippery_box_drops() {
    let grippy = ObjectSpec::cuboid([0.025, 0.025, 0.04], 0.1, 0.8);
    let mut sim = sim_with(&grippy);
    sim.reset(&grasp_scene(&grippy)).unwrap();
    let r = close_and_lift(&mut sim, ScriptOptions::default(), &power_grasp());
    let lift = r.lift.unwrap();
    assert!(lift.failure.is_none(), "{lift:?}");
    assert!(lift.success, "{lift:?}");
    assert!(lift.object_lowest_z > 0.10, "{lift:?}");
    // The fingers squeeze through the lift: blocked joints push with a good part of
    // their effort limits (2 N m each).
    assert!(lift.grip_effort > 2.0, "{lift:?}");

    let slippery = ObjectSpec::cuboid([0.025, 0.025, 0.04], 0.1, 0.05);
    sim.set_object(slippery.clone()).unwrap();
    sim.reset(&grasp_scene(&slippery)).unwrap();
    let r = close_and_lift(&mut sim, ScriptOptions::default(), &power_grasp());
    let lift = r.lift.unwrap();
    assert!(lift.failure.is_none(), "{lift:?}");
    assert!(!lift.success, "{lift:?}");
    assert!(lift.object_lowest_z < 0.05, "{lift:?}");
}

#[test]
fn both_drive_models_hold_a_heavy_box_and_a_decided_lift_ends_early() {
    use grasp::sim::config::DriveModel;
    let heavy = ObjectSpec::cuboid([0.025, 0.025, 0.04], 0.5, 0.8);
    for drive in [DriveModel::Spring, DriveModel::MotorRow] {
        let cfg = SimConfig {
            drive,
            ..SimConfig::default()
        };
        let mut sim = HandSim::new(&Robot::builtin(Side::Left), heavy.clone(), cfg).unwrap();
        sim.reset(&grasp_scene(&heavy)).unwrap();
        let r = close_and_lift(&mut sim, ScriptOptions::default(), &power_grasp());
        let lift = r.lift.unwrap();
        assert!(lift.success, "{drive:?}: {lift:?}");
    }
    // The slippery box stays on the table: with stop_when_dropped the lift ends once the
    // whole hand is above it, with the same outcome as the full lift.
    let slippery = ObjectSpec::cuboid([0.025, 0.025, 0.04], 0.1, 0.05);
    let mut outcome = Vec::new();
    for stop in [true, false] {
        let mut cfg = SimConfig::default();
        cfg.lift.stop_when_dropped = stop;
        let mut sim = HandSim::new(&Robot::builtin(Side::Left), slippery.clone(), cfg).unwrap();
        sim.reset(&grasp_scene(&slippery)).unwrap();
        let r = close_and_lift(&mut sim, ScriptOptions::default(), &power_grasp());
        let lift = r.lift.unwrap();
        assert!(!lift.success && !lift.in_contact, "{lift:?}");
        outcome.push(sim.physics_steps());
    }
    assert!(outcome[0] < outcome[1], "{outcome:?}");
}

#[test]
fn open_hand_never_lifts_the_box() {
    let obj = ObjectSpec::default_box();
    let mut sim = sim_with(&obj);
    sim.reset(&grasp_scene(&obj)).unwrap();
    let opts = ScriptOptions {
        close: false,
        ..Default::default()
    };
    let r = close_and_lift(&mut sim, opts, &power_grasp());
    let lift = r.lift.unwrap();
    assert!(!lift.success, "{lift:?}");
    assert!(lift.object_lowest_z < 0.01, "{lift:?}");
    // An open hand holds its posture against gravity only: little grip.
    assert!(lift.grip_effort < 1.0, "{lift:?}");
}

#[test]
fn tactile_turns_on_only_on_contact() {
    let obj = ObjectSpec::default_box();
    let mut sim = sim_with(&obj);
    // Object out of reach: 20 cm below the grasp point... the hand is high above it.
    sim.reset(&Scene::above(&obj, Posture::Open.angles(), 0.25, 0.0))
        .unwrap();
    for _ in 0..3 {
        assert!(sim.step_control());
        assert_eq!(sim.sensors().tactile, [0; 5]);
    }
    // Closing in the air touches nothing.
    sim.set_targets(&power_grasp()).unwrap();
    for _ in 0..3 {
        assert!(sim.step_control());
        assert_eq!(sim.sensors().tactile, [0; 5]);
    }
    // Over the object, before closing: no contact; after closing: the fingers touch.
    sim.reset(&grasp_scene(&obj)).unwrap();
    assert!(sim.step_control());
    assert_eq!(sim.sensors().tactile, [0; 5]);
    let r = close_and_lift(
        &mut sim,
        ScriptOptions {
            lift: false,
            ..Default::default()
        },
        &power_grasp(),
    );
    let last = &r.steps.last().unwrap().sensors;
    assert!(
        last.tactile.iter().filter(|t| **t == 1).count() >= 3,
        "{last:?}"
    );
    for f in 0..5 {
        assert_eq!(last.tactile[f] == 1, last.tip_force[f] > 0.05, "{last:?}");
    }
}

#[test]
fn torque_level_rises_when_a_finger_presses_on_a_fixed_obstacle() {
    // A 20 kg box does not move under a finger: it acts as a fixed obstacle.
    let obj = ObjectSpec::cuboid([0.04, 0.04, 0.04], 20.0, 0.8);
    let mut sim = sim_with(&obj);
    sim.reset(&grasp_scene(&obj)).unwrap();
    let mut t = sim.targets();
    // Close FF only, far past the obstacle.
    t[hand_index("FFJ3").unwrap()] = 1.5;
    t[hand_index("FFJ2").unwrap()] = 1.2;
    t[hand_index("FFJ1").unwrap()] = 1.2;
    sim.set_targets(&t).unwrap();
    for _ in 0..3 {
        assert!(sim.step_control());
    }
    let s = sim.sensors();
    // Actuators: 3 = FFJ3 (pressing), 6 = MFJ3 (free, holding its start posture).
    assert!(s.tactile[0] == 1, "{s:?}");
    assert!(s.torque_level[3] >= 4, "FFJ3 level {}", s.torque_level[3]);
    assert!(
        (2..=3).contains(&s.torque_level[6]),
        "MFJ3 level {}",
        s.torque_level[6]
    );
    assert!(s.effort[3] > 0.1, "FFJ3 effort {}", s.effort[3]);
}

#[test]
fn two_runs_with_one_seed_are_bit_identical() {
    let obj = ObjectSpec::default_box();
    let run = || {
        let mut sim = sim_with(&obj);
        let scene = Scene::randomized(&obj, Posture::Open.angles(), 0.03, 0.01, 0.1, 42);
        sim.reset(&scene).unwrap();
        let r = close_and_lift(&mut sim, ScriptOptions::default(), &power_grasp());
        let (q, _) = sim.joint_state();
        (q, sim.object_pose_raw(), r.lift.unwrap())
    };
    let (q1, p1, l1) = run();
    let (q2, p2, l2) = run();
    assert_eq!(q1, q2);
    assert_eq!(p1, p2);
    assert_eq!(l1, l2);
    // A reset of the same sim gives the same run too.
    let mut sim = sim_with(&obj);
    let scene = Scene::randomized(&obj, Posture::Open.angles(), 0.03, 0.01, 0.1, 42);
    for _ in 0..2 {
        sim.reset(&scene).unwrap();
        close_and_lift(&mut sim, ScriptOptions::default(), &power_grasp());
        assert_eq!(sim.joint_state().0, q1);
        assert_eq!(sim.object_pose_raw(), p1);
    }
}

#[test]
fn nan_target_is_an_error_not_a_panic() {
    let mut sim = sim_with(&ObjectSpec::default_box());
    let mut t = power_grasp();
    t[0] = f64::NAN;
    assert!(sim.set_targets(&t).is_err());
    t[0] = f64::INFINITY;
    assert!(sim.set_targets(&t).is_err());
    assert!(sim.step_control());
}

#[test]
fn object_rests_stably_with_the_hand_away() {
    let obj = ObjectSpec::default_box();
    let mut sim = sim_with(&obj);
    sim.reset(&Scene::above(&obj, Posture::Open.angles(), 0.3, 0.0))
        .unwrap();
    let p0 = sim.object_position();
    for _ in 0..10 {
        assert!(sim.step_control());
    }
    let d = (sim.object_position() - p0).norm();
    assert!(d < 1e-3, "drift {d} m");
}

#[test]
fn broken_physics_ends_the_episode_without_panic() {
    let obj = ObjectSpec::default_box();
    let mut cfg = SimConfig::default();
    cfg.failure.max_speed = 1e-3;
    let mut sim = HandSim::new(&Robot::builtin(Side::Left), obj.clone(), cfg).unwrap();
    sim.reset(&grasp_scene(&obj)).unwrap();
    sim.set_targets(&power_grasp()).unwrap();
    assert!(!sim.step_control());
    assert!(matches!(
        sim.failure(),
        Some(PhysicsFailure::TooFast { .. })
    ));
    let lift = sim.lift_and_judge();
    assert!(!lift.success && lift.failure.is_some());
    // A reset clears it.
    sim.reset(&grasp_scene(&obj)).unwrap();
    assert!(sim.failure().is_none());
}
