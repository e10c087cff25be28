//! Integration tests of the hardware layer: the safety wrapper around a fake backend with
//! a simulated clock, a logged attempt that builds observations with the simulator's
//! observation builder, and the point-cloud fixtures in `tests/data/clouds`.

use grasp::env::obs::{Modality, ObsLayout};
use grasp::hardware::calibration::{calibrate, TactileCalibration};
use grasp::hardware::log::{read_log, AttemptLog, LogRecord, OutcomeRecord, StepRecord};
use grasp::hardware::safety::{ClampReason, SafeHandArm, SafetyConfig};
use grasp::hardware::torque::TorqueMapper;
use grasp::hardware::{ArmMotion, HandArm, HwError, RawSensors};
use grasp::perception::pointcloud::{grasp_candidates, AntipodalConfig, CloudError, PointCloud};
use grasp::robot::{Robot, Side};
use nalgebra::Point3;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A scripted backend: a clock advanced by the test, readings stamped by the test.
#[derive(Default)]
struct FakeArm {
    clock: f64,
    reading: Option<RawSensors>,
    sent: Vec<[f64; 24]>,
    arm: Vec<ArmMotion>,
    stops: usize,
    fail_read: Option<String>,
}

impl FakeArm {
    fn with_reading(angles: [f64; 24]) -> Self {
        FakeArm {
            reading: Some(RawSensors {
                stamp: 0.0,
                joint_angles: angles,
                tactile_raw: [100.0; 5],
                tendon_raw: [1000.0; 20],
            }),
            ..Default::default()
        }
    }
}

impl HandArm for FakeArm {
    fn read(&mut self) -> Result<RawSensors, HwError> {
        if let Some(m) = &self.fail_read {
            return Err(HwError::Disconnected(m.clone()));
        }
        self.reading
            .ok_or_else(|| HwError::Disconnected("no data scripted".into()))
    }
    fn command_hand(&mut self, targets: &[f64; 24]) -> Result<(), HwError> {
        self.sent.push(*targets);
        Ok(())
    }
    fn move_arm(&mut self, motion: &ArmMotion) -> Result<(), HwError> {
        self.arm.push(*motion);
        Ok(())
    }
    fn stop(&mut self) -> Result<(), HwError> {
        self.stops += 1;
        Ok(())
    }
    fn now(&self) -> f64 {
        self.clock
    }
}

fn safe(backend: FakeArm) -> SafeHandArm<FakeArm> {
    let limits = Robot::builtin(Side::Left).hand_limits();
    SafeHandArm::new(
        backend,
        limits,
        SafetyConfig::default(),
        Arc::new(AtomicBool::new(false)),
    )
    .unwrap()
}

/// Mid-range angles of the builtin hand, so that +-0.3 rad steps stay inside the limits
/// for most joints.
fn mid_angles() -> [f64; 24] {
    Robot::builtin(Side::Left)
        .hand_limits()
        .map(|(lo, hi)| 0.5 * (lo + hi))
}

#[test]
fn commands_are_clamped_relative_to_the_measured_angles() {
    let q = mid_angles();
    let limits = Robot::builtin(Side::Left).hand_limits();
    let mut arm = safe(FakeArm::with_reading(q));
    // A command before any reading is refused and nothing is sent.
    assert!(matches!(
        arm.command_hand(&q),
        Err(HwError::InvalidCommand { .. })
    ));
    arm.read().unwrap();
    let mut t = q;
    let ffj3 = 3; // HAND_JOINTS[3] = FFJ3
    t[ffj3] = q[ffj3] + 1.0;
    t[0] = 100.0; // WRJ2 far beyond its upper limit
    arm.command_hand(&t).unwrap();
    let sent = arm.backend().sent[0];
    assert!((sent[ffj3] - (q[ffj3] + 0.3)).abs() < 1e-12);
    assert!(sent[0] <= limits[0].1 && sent[0] <= q[0] + 0.3 + 1e-12);
    for k in 0..24 {
        if k != 0 && k != ffj3 {
            assert_eq!(sent[k], q[k], "joint {k} changed");
        }
    }
    let ev = arm.last_clamp_events();
    assert_eq!(ev.len(), 2);
    assert_eq!(ev[0].joint, "WRJ2");
    assert_eq!(ev[1].joint, "FFJ3");
    assert_eq!(ev[1].reason, ClampReason::MaxStep);
    assert_eq!(ev[1].requested, q[ffj3] + 1.0);

    // NaN targets are rejected and never reach the backend.
    let mut bad = q;
    bad[10] = f64::NAN;
    let e = arm.command_hand(&bad).unwrap_err().to_string();
    assert!(e.contains("RFJ4"), "{e}");
    assert_eq!(arm.backend().sent.len(), 1);
}

#[test]
fn watchdog_trips_on_stale_data_and_stops_the_robot() {
    let mut arm = safe(FakeArm::with_reading(mid_angles()));
    arm.read().unwrap();
    // 0.08 s later the data (stamp 0) is still fresh.
    arm.backend_mut().clock = 0.08;
    arm.command_hand(&mid_angles()).unwrap();
    assert_eq!(arm.backend().stops, 0);
    // 0.15 s later with no new reading: stale -> timeout, stop, nothing sent.
    arm.backend_mut().clock = 0.15;
    match arm.command_hand(&mid_angles()) {
        Err(HwError::Timeout { waited_s, .. }) => assert!((waited_s - 0.15).abs() < 1e-12),
        other => panic!("expected a timeout, got {other:?}"),
    }
    assert_eq!(arm.backend().stops, 1);
    assert_eq!(arm.backend().sent.len(), 1);
    // The backend keeps returning the old stamp: the read trips too.
    assert!(matches!(arm.read(), Err(HwError::Timeout { .. })));
    assert_eq!(arm.backend().stops, 2);
    // Fresh data recovers.
    if let Some(r) = arm.backend_mut().reading.as_mut() {
        r.stamp = 0.149;
    }
    arm.read().unwrap();
    arm.command_hand(&mid_angles()).unwrap();
    assert_eq!(arm.backend().sent.len(), 2);
    assert_eq!(arm.stop_count(), 2);
}

#[test]
fn emergency_stop_flag_stops_everything() {
    let mut arm = safe(FakeArm::with_reading(mid_angles()));
    let estop = arm.estop_handle();
    arm.read().unwrap();
    estop.store(true, Ordering::SeqCst);
    assert!(matches!(
        arm.command_hand(&mid_angles()),
        Err(HwError::EmergencyStop)
    ));
    assert!(matches!(arm.read(), Err(HwError::EmergencyStop)));
    let lift = ArmMotion::Lift {
        height_m: 0.2,
        duration_s: 2.0,
    };
    assert!(matches!(arm.move_arm(&lift), Err(HwError::EmergencyStop)));
    let b = arm.into_inner();
    assert_eq!(b.stops, 3);
    assert!(b.sent.is_empty() && b.arm.is_empty());
}

#[test]
fn bad_readings_stop_the_robot() {
    let mut q = mid_angles();
    q[5] = 10.0; // FFJ1 far outside its limits
    let mut arm = safe(FakeArm::with_reading(q));
    match arm.read() {
        Err(HwError::LimitViolation { joint, value, .. }) => {
            assert_eq!(joint, "FFJ1");
            assert_eq!(value, 10.0);
        }
        other => panic!("expected a limit violation, got {other:?}"),
    }
    let mut q = mid_angles();
    q[7] = f64::NAN;
    arm.backend_mut().reading.as_mut().unwrap().joint_angles = q;
    let e = arm.read().unwrap_err().to_string();
    assert!(e.contains("joint_angles[7] (MFJ3)"), "{e}");
    arm.backend_mut().fail_read = Some("cable".into());
    assert!(matches!(arm.read(), Err(HwError::Disconnected(_))));
    assert_eq!(arm.backend().stops, 3);
    // Invalid arm motions are refused without stopping or sending.
    arm.backend_mut().fail_read = None;
    arm.backend_mut().reading.as_mut().unwrap().joint_angles = mid_angles();
    arm.read().unwrap();
    let bad = ArmMotion::Lift {
        height_m: f64::NAN,
        duration_s: 1.0,
    };
    assert!(matches!(
        arm.move_arm(&bad),
        Err(HwError::InvalidCommand { .. })
    ));
    arm.move_arm(&ArmMotion::Joints([0.0; 6])).unwrap();
    assert_eq!(arm.backend().arm.len(), 1);
}

/// One short attempt as the real-robot runner will do it: calibrate, record tau_j0,
/// read, map, build the observation with the simulator's builder, command, log.
#[test]
fn logged_attempt_with_calibrated_observations() {
    let dir = tempfile::tempdir().unwrap();
    let cal_path = dir.path().join("tactile.json");
    let still = vec![[100.0, 110.0, 120.0, 130.0, 140.0]; 10];
    let presses = (0..5).map(|f| {
        let mut r = [0.0; 5];
        r[f] = 1100.0 + 10.0 * f as f64;
        (f, r)
    });
    calibrate(still, presses, 0.003)
        .unwrap()
        .save(&cal_path)
        .unwrap();
    let cal = TactileCalibration::load(&cal_path).unwrap();
    // FF threshold: 100 + 0.003 * 1000 = 103.
    assert!((cal.threshold(0) - 103.0).abs() < 1e-9);

    let mut arm = safe(FakeArm::with_reading(mid_angles()));
    let mut torque = TorqueMapper::real();
    let empty: Vec<[f64; 20]> = (0..3).map(|_| arm.read().unwrap().tendon_raw).collect();
    torque.set_baseline(empty).unwrap();

    let layout = ObsLayout::new(Modality::M3, 5, 3);
    let log_path = dir.path().join("attempt.jsonl");
    let mut log = AttemptLog::open(&log_path).unwrap();
    let mut prev_action = vec![0.0f32; 7];
    for step in 0..3u64 {
        let t = 0.05 * step as f64;
        {
            let b = arm.backend_mut();
            b.clock = t;
            let r = b.reading.as_mut().unwrap();
            r.stamp = t;
            r.tactile_raw[0] = 100.0 + 2.0 * step as f64; // 100, 102, 104: contact at 104
            r.tendon_raw[3] = 1000.0 + 120.0 * step as f64; // mapped 0, 120, 240
        }
        let r = arm.read().unwrap();
        let tactile = cal.contacts(&r.tactile_raw);
        let levels = torque.levels(&r.tendon_raw).unwrap();
        let sensed = grasp::env::obs::Sensing {
            tactile,
            torque_levels: levels,
            joint_angles: r.joint_angles,
            surface: [0.0; grasp::env::obs::N_SURFACE],
        };
        let frame = layout.frame(&prev_action, &sensed);
        assert_eq!(frame.len(), layout.frame_len());
        let mut targets = r.joint_angles;
        targets[3] += 0.5; // asks for more than the 0.3 rad step
        arm.command_hand(&targets).unwrap();
        let applied = *arm.backend().sent.last().unwrap();
        log.step(StepRecord {
            step,
            time_s: t,
            joint_angles: r.joint_angles,
            tactile_raw: r.tactile_raw,
            tendon_raw: r.tendon_raw,
            tactile,
            torque_mapped: torque.mapped(&r.tendon_raw).unwrap(),
            torque_levels: levels,
            action: prev_action.iter().map(|&a| f64::from(a)).collect(),
            targets: applied,
            clamp_events: arm.last_clamp_events().to_vec(),
        })
        .unwrap();
        prev_action = vec![0.1 * step as f32; 7];
    }
    log.outcome(OutcomeRecord {
        time_s: 0.1,
        steps: 3,
        success: false,
        reason: "test".into(),
    })
    .unwrap();

    let recs = read_log(&log_path).unwrap();
    assert_eq!(recs.len(), 4);
    let steps: Vec<&StepRecord> = recs
        .iter()
        .filter_map(|r| match r {
            LogRecord::Step(s) => Some(s.as_ref()),
            LogRecord::Outcome(_) => None,
        })
        .collect();
    assert_eq!(
        steps.iter().map(|s| s.tactile[0]).collect::<Vec<_>>(),
        [false, false, true]
    );
    // Levels with thresholds {-200,-100,0,100,200}: 0 -> 3, 120 -> 4, 240 -> 5.
    assert_eq!(
        steps.iter().map(|s| s.torque_levels[3]).collect::<Vec<_>>(),
        [3, 4, 5]
    );
    assert!(steps.iter().all(|s| s.clamp_events.len() == 1
        && s.clamp_events[0].joint == "FFJ3"
        && (s.targets[3] - s.joint_angles[3] - 0.3).abs() < 1e-12));
    assert!(matches!(&recs[3], LogRecord::Outcome(o) if o.steps == 3));
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/clouds")
        .join(name)
}

#[test]
fn fixture_clouds_load_in_every_format() {
    for name in ["tetra_ascii.pcd", "tetra_ascii.ply"] {
        let c = PointCloud::load(&fixture(name)).unwrap();
        assert_eq!(c.points.len(), 4, "{name}");
        assert_eq!(c.dropped_non_finite, 1, "{name}");
        assert_eq!(c.points[1], Point3::new(0.1, 0.0, 0.0));
    }
    let pcd = PointCloud::load(&fixture("cube_binary.pcd")).unwrap();
    let ply = PointCloud::load(&fixture("cube_binary_le.ply")).unwrap();
    assert_eq!(pcd.points.len(), 1200);
    assert_eq!(ply.points.len(), 1200);
    // The PCD stores f32, the PLY f64: the same points to f32 precision.
    for (a, b) in pcd.points.iter().zip(&ply.points) {
        assert!((a - b).norm() < 1e-7);
    }
    let c = pcd.centroid();
    assert!((c - Point3::new(0.5, 0.0, 0.03)).norm() < 0.005, "{c}");
}

#[test]
fn best_grasp_on_the_cube_fixture() {
    let cloud = PointCloud::load(&fixture("cube_binary.pcd")).unwrap();
    let g = grasp_candidates(&cloud.points, &AntipodalConfig::default()).unwrap();
    let best = g[0];
    assert!((best.width - 0.06).abs() < 0.005, "width {}", best.width);
    assert!((best.grasp.center - Point3::new(0.5, 0.0, 0.03)).norm() < 0.01);
    assert!(best.grasp.approach.z < -0.98);
}

#[test]
fn bad_fixture_clouds_give_clear_errors() {
    let cases = [
        ("bad_missing_z.pcd", "no 'z' field"),
        ("bad_count.pcd", "POINTS 3 but the data has 2"),
        ("bad_value.ply", "line 9: vertex 1, property y: 'five'"),
        ("all_nan.pcd", "empty (2 non-finite points dropped)"),
        ("truncated_binary.pcd", "binary data has 14 bytes"),
        ("does_not_exist.ply", "cannot read point cloud"),
    ];
    for (name, want) in cases {
        let e = PointCloud::load(&fixture(name)).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains(name) && msg.contains(want), "{name}: {msg}");
        if name == "all_nan.pcd" {
            assert!(matches!(e, CloudError::Empty { dropped: 2, .. }));
        }
    }
}
