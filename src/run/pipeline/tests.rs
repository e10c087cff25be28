//! Tests of `pipeline`.

use super::*;
use crate::robot::Side;

#[test]
fn cloud_surface_vectors_point_at_the_nearest_cloud_point_in_the_palm_frame() {
    // The hand root at 1 m height, turned 90 degrees about z; a cloud of two points:
    // one exactly at the thumb's distal point (its vector is zero), one 5 cm beside
    // the palm point along the palm's own x axis (the palm's vector is (0.05, 0, 0)).
    let robot = Robot::builtin(Side::Left);
    let q = crate::robot::Posture::Open.angles();
    let root = Isometry3::new(
        Vector3::new(0.2, 0.0, 1.0),
        Vector3::z() * std::f64::consts::FRAC_PI_2,
    );
    let palm = root * robot.hand_fk_palm(&q)[robot.hand.forearm].inverse();
    let pts = robot.surface_points_palm(&q);
    let thumb = palm * pts[4];
    let beside = palm * (pts[5] + Vector3::new(0.05, 0.0, 0.0));
    let v = cloud_surface_vectors(&robot, &root, &q, &[thumb, beside]);
    assert!(
        v[12..15].iter().all(|x| x.abs() < 1e-12),
        "{:?}",
        &v[12..15]
    );
    let p = &v[15..18];
    assert!(
        (p[0] - 0.05).abs() < 1e-9 && p[1].abs() < 1e-9 && p[2].abs() < 1e-9,
        "{p:?}"
    );
    // An empty cloud leaves every vector at zero.
    assert_eq!(
        cloud_surface_vectors(&robot, &root, &q, &[]),
        [0.0; N_SURFACE]
    );
}

#[test]
fn arm_base_pose_hand_computed() {
    let b = ArmBase {
        xyz: [1.0, 2.0, 0.5],
        yaw: std::f64::consts::FRAC_PI_2,
    };
    // Base x axis -> world y; the base origin sits at xyz.
    let p = b.pose() * Point3::new(1.0, 0.0, 0.0);
    assert!((p - Point3::new(1.0, 3.0, 0.5)).norm() < 1e-12);
}

#[test]
fn config_and_grasp_file_errors_name_the_field() {
    let bad = PipelineConfig {
        preshape: "fist".into(),
        ..PipelineConfig::default()
    };
    assert!(bad.validate().unwrap_err().to_string().contains("preshape"));
    let bad = PipelineConfig {
        control_period_s: 0.0,
        ..PipelineConfig::default()
    };
    assert!(bad
        .validate()
        .unwrap_err()
        .to_string()
        .contains("control_period_s"));
    let bad = PipelineConfig {
        torque_thresholds: [0.0, 0.0, 1.0, 2.0, 3.0],
        ..PipelineConfig::default()
    };
    assert!(bad.validate().is_err());
    // Bounded above too: refused before the arm moves, not at the first wait.
    let bad = PipelineConfig {
        lift_duration_s: 1e300,
        ..PipelineConfig::default()
    };
    let e = bad.validate().unwrap_err().to_string();
    assert!(e.contains("lift_duration_s") && e.contains("1e300"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.toml");
    std::fs::write(&p, "center = [0, 0, 0.05]\nclosing = [1, 0, \"x\"]\n").unwrap();
    let e = load_grasp_file(&p).unwrap_err().to_string();
    assert!(e.contains("g.toml") && e.contains("line 2"), "{e}");
    std::fs::write(&p, "center = [0, 0, 0.05]\nclosing = [0, 1, 0]\n").unwrap();
    let g = load_grasp_file(&p).unwrap();
    assert_eq!(g.approach, -Vector3::z());
}

/// A scripted hand: it takes every target at once, its clock advances by the waits,
/// and fingertip FF reads far above its range from the `touch_after`-th hand command
/// on; it holds the object after any lift.
struct ScriptedArm {
    t: f64,
    q: [f64; N_JOINTS],
    commands: Vec<[f64; N_JOINTS]>,
    touch_after: usize,
    lifted: bool,
}

impl HandArm for ScriptedArm {
    fn read(&mut self) -> Result<RawSensors, crate::hardware::HwError> {
        let mut tactile_raw = [0.0; 5];
        if self.commands.len() >= self.touch_after {
            tactile_raw[0] = 1000.0;
        }
        Ok(RawSensors {
            stamp: self.t,
            joint_angles: self.q,
            tactile_raw,
            tendon_raw: [0.0; N_ACTUATORS],
        })
    }
    fn command_hand(&mut self, targets: &[f64; N_JOINTS]) -> Result<(), crate::hardware::HwError> {
        self.q = *targets;
        self.commands.push(*targets);
        Ok(())
    }
    fn move_arm(&mut self, motion: &ArmMotion) -> Result<(), crate::hardware::HwError> {
        self.lifted |= matches!(motion, ArmMotion::Lift { .. });
        Ok(())
    }
    fn stop(&mut self) -> Result<(), crate::hardware::HwError> {
        Ok(())
    }
    fn now(&self) -> f64 {
        self.t
    }
    fn wait(&mut self, seconds: f64) -> Result<(), crate::hardware::HwError> {
        self.t += seconds;
        Ok(())
    }
    fn lift_outcome(&self) -> Option<bool> {
        self.lifted.then_some(true)
    }
}

/// The hand commands of a baseline attempt on a [`ScriptedArm`] whose FF touches at
/// its `touch_after`-th command, and the attempt's outcome.
fn baseline_commands(
    stop_on_touch: bool,
    touch_after: usize,
) -> (Vec<[f64; N_JOINTS]>, AttemptOutcome) {
    let robot = Robot::builtin(Side::Left);
    let cfg = PipelineConfig {
        safety: SafetyConfig {
            max_step_rad: 10.0,
            ..SafetyConfig::default()
        },
        ..PipelineConfig::default()
    };
    let preshape = cfg.preshape_angles(&EnvConfig::default()).unwrap();
    let arm = ScriptedArm {
        t: 0.0,
        q: preshape,
        commands: Vec::new(),
        touch_after,
        lifted: false,
    };
    let mut arm = SafeHandArm::new(
        arm,
        robot.hand_limits(),
        cfg.safety,
        std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false)),
    )
    .unwrap();
    let plan = GraspPlan {
        center: [0.0, 0.0, 0.05],
        approach: [0.0, 0.0, -1.0],
        closing: [1.0, 0.0, 0.0],
        score: None,
        candidates: 0,
        skipped: 0,
        fallback: false,
        preshape,
        pregrasp_q: ur10e::HOME,
        grasp_q: ur10e::HOME,
    };
    let cal = TactileCalibration::new([0.0; 5], [100.0; 5], 0.003).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut log = AttemptLog::open(&dir.path().join("a.jsonl")).unwrap();
    let mut c = Controller::Baseline { stop_on_touch };
    let out = run_attempt_with(&mut arm, &robot, &plan, &mut c, &cal, &cfg, &mut log).unwrap();
    // Every closing update and the lift decision are logged, then the outcome.
    assert_eq!(log.lines_written(), out.stage1_updates as u64 + 2);
    (arm.backend().commands.clone(), out)
}

#[test]
fn baseline2_freezes_a_finger_at_its_calibrated_touch_and_baseline1_does_not() {
    let env = EnvConfig::default();
    let n = (env.closing_time / env.closing_period).round() as usize;
    let settle = (BASELINE_SETTLE_S / env.closing_period).round() as usize;
    let (b2, out) = baseline_commands(true, 3);
    assert_eq!(b2.len(), n + settle);
    assert!(out.success && out.lifted && out.touched, "{out:?}");
    assert_eq!(out.policy_steps, 0);
    assert_eq!(out.judged_by, "simulator");
    // FF (joints 2..6) touched after the 3rd command: it keeps that command's
    // targets; MF goes on closing to the power grasp.
    let closed = script::power_grasp();
    for c in &b2[3..] {
        assert_eq!(&c[2..6], &b2[2][2..6]);
    }
    assert_ne!(&b2[3][6..10], &b2.last().unwrap()[6..10]);
    assert!((b2.last().unwrap()[7] - closed[7]).abs() < 1e-12);
    // Baseline 1 closes FF too, along the same trajectory.
    let (b1, _) = baseline_commands(false, 3);
    assert_eq!(b1.len(), b2.len());
    assert_eq!(b1[..3], b2[..3]);
    assert!((b1.last().unwrap()[3] - closed[3]).abs() < 1e-12);
    assert_ne!(&b1[3][2..6], &b2[3][2..6]);
    // No touch: baseline 2 closes every finger like baseline 1.
    let (never, out) = baseline_commands(true, usize::MAX);
    assert_eq!(never, b1);
    assert!(!out.touched);
}
