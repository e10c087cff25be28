//! Tests of `world`.

use super::*;
use crate::robot::{Posture, Side};

fn assert_send<T: Send>() {}

#[test]
fn sim_is_send() {
    assert_send::<HandSim>();
}

/// A 0.5 kg box resting on the table for 60 steps, the hand far above it.
fn resting_box() -> HandSim {
    let robot = Robot::builtin(Side::Left);
    let obj = ObjectSpec::cuboid([0.03, 0.03, 0.03], 0.5, 0.8);
    let mut sim = HandSim::new(&robot, obj.clone(), SimConfig::default()).unwrap();
    sim.reset(&Scene::above(&obj, Posture::Open.angles(), 0.3, 0.0))
        .unwrap();
    for _ in 0..60 {
        assert!(sim.step_physics());
    }
    sim
}

#[test]
fn critic_geometry_finds_the_palm_and_the_box_below_the_hand() {
    // The hand 30 cm above a 6 cm box at rest: the box is below the palm, still, and
    // every phalanx's nearest box point is 15-60 cm away, on the box's top face.
    let sim = resting_box();
    let g = sim.critic_geometry().expect("palm and object found");
    let top = g.object.translation.vector.z + 0.03;
    assert!(
        g.palm.translation.vector.z > top + 0.1,
        "{}",
        g.palm.translation.vector.z
    );
    assert!(g.object_linvel.norm() < 0.01 && g.object_angvel.norm() < 0.1);
    for (c, p) in &g.nearest {
        let d = (p - c).norm();
        assert!((0.15..0.6).contains(&d), "{d} m");
        assert!((p.z - top).abs() < 1e-3, "{} against {top}", p.z);
    }
}

#[test]
fn critic_geometry_points_are_the_kinematic_surface_points() {
    // grasp run computes M3G's start points by forward kinematics: they must be the
    // simulator's collider centres (palm frame) within a millimetre.
    let sim = resting_box();
    let g = sim.critic_geometry().unwrap();
    let (q, _) = sim.joint_state();
    let kin = sim.robot.surface_points_palm(&q);
    let inv = g.palm.inverse();
    for (k, (c, _)) in g.nearest.iter().enumerate() {
        let d = (inv * c - kin[k]).norm();
        assert!(d < 1e-3, "point {k}: {d} m apart");
    }
}

#[test]
fn contact_force_of_a_resting_object_is_its_weight() {
    // The force calibration behind the tactile threshold: impulse / dt = m g.
    let sim = resting_box();
    let f = sim.pair_force(sim.table, sim.object_collider);
    assert!((f - 0.5 * 9.81).abs() < 0.05 * 4.905, "table force {f}");
    assert_eq!(sim.hand_object_force(), 0.0);
}

#[test]
fn the_deepest_contact_is_measured_at_the_current_pose_not_where_rapier_computed_it() {
    // rapier recycles the contacts of a pair that barely moved: their points keep the
    // separations of the step they were computed in. A resting box whose contacts were
    // computed at rest, then found 4 mm into the table, is 4 mm deep.
    let mut sim = resting_box();
    let rest = sim.deepest_object_contact().map_or(0.0, |c| c.depth);
    assert!(rest < 1e-3, "resting box {rest} m deep");
    let co = &mut sim.sets.colliders[sim.object_collider];
    let mut pose = *co.position();
    pose.translation.z -= 0.004;
    co.set_position(pose);
    let c = sim
        .deepest_object_contact()
        .expect("a contact with the table");
    assert_eq!(c.with, "table");
    assert!((c.depth - rest - 0.004).abs() < 5e-4, "{} m deep", c.depth);
}

#[test]
fn reset_writes_the_start_posture_and_placement() {
    let robot = Robot::builtin(Side::Left);
    let obj = ObjectSpec::default_box();
    let mut sim = HandSim::new(&robot, obj.clone(), SimConfig::default()).unwrap();
    let start = Posture::CShape.angles();
    let scene = Scene::above(&obj, start, 0.05, 0.4);
    sim.reset(&scene).unwrap();
    let (q, qd) = sim.joint_state();
    for k in 0..24 {
        assert!(
            (q[k] - start[k]).abs() < 1e-6,
            "{k}: {} vs {}",
            q[k],
            start[k]
        );
        assert_eq!(qd[k], 0.0);
    }
    // The TH/LF tip midpoint of the simulated bodies is at the grasp point.
    let tip = |f: usize| {
        let ji = robot.hand.distal[f];
        let mut full = robot.zero_q();
        robot.set_hand_q(&mut full, &start);
        let poses = robot.fk(&full);
        let off = poses[ji].inverse() * poses[robot.hand.tips[f]];
        (ji, off)
    };
    let mut mid = Vector3::zeros();
    for f in [3, 4] {
        let (link, off) = tip(f);
        let body = sim.link_body_pose(link).unwrap();
        mid += (body * off).translation.vector / 2.0;
    }
    let g = Vector3::from(scene.grasp_point);
    assert!((mid - g).norm() < 1e-4, "{mid} vs {g}");
    assert_eq!(sim.lift_position(), 0.0);
    assert!((sim.object_position().z - 0.04).abs() < 1e-6);
}

#[test]
fn nan_target_is_rejected_and_changes_nothing() {
    let robot = Robot::builtin(Side::Left);
    let mut sim = HandSim::new(&robot, ObjectSpec::default_box(), SimConfig::default()).unwrap();
    let before = sim.targets();
    let mut t = before;
    t[5] = f64::NAN;
    let e = sim.set_targets(&t).unwrap_err().to_string();
    assert!(e.contains("FFJ1"), "{e}");
    assert_eq!(sim.targets(), before);
}

#[test]
fn targets_are_clamped_and_coupled() {
    let robot = Robot::builtin(Side::Left);
    let mut sim = HandSim::new(&robot, ObjectSpec::default_box(), SimConfig::default()).unwrap();
    let mut t = [0.0; 24];
    t[3] = 5.0; // FFJ3 above its limit 1.5708
    t[4] = 1.0; // FFJ2
    t[5] = 0.2; // FFJ1 -> both 0.6
    sim.set_targets(&t).unwrap();
    let got = sim.targets();
    assert_eq!(got[3], robot.hand_limits()[3].1);
    assert!((got[4] - 0.6).abs() < 1e-12 && (got[5] - 0.6).abs() < 1e-12);
}
