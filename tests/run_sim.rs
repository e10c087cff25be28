//! End-to-end tests of the sim backend behind the hardware interface: calibration from
//! raw readings, drift compensation, the watchdog on the simulated clock, clamping and
//! logging, and full `grasp run` attempts with the shipped policy.

use grasp::hardware::calibration::{TactileCalibration, DEFAULT_THRESHOLD_FRACTION};
use grasp::hardware::log::{read_log, LogRecord};
use grasp::hardware::safety::{ClampReason, SafeHandArm, SafetyConfig};
use grasp::hardware::torque::TorqueMapper;
use grasp::hardware::{HandArm, HwError};
use grasp::perception::pointcloud::{write_pcd, PcdData};
use grasp::robot::{Robot, Side};
use grasp::run::calibrate::calibrate_tactile;
use grasp::run::sim_backend::{SimBackendConfig, SimHandArm};
use grasp::sim::{ObjectSpec, SimConfig};
use nalgebra::Point3;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

const POLICY: &str = "assets/policies/quick_gru_m3_pca5";
/// The shipped M3G policy (surface vectors from the object's cloud).
const M3G_POLICY: &str = "assets/policies/ship_gru_m3g_pca5";
/// The main job's policy: M3 with the grip component (6 + 2 continuous actions).
const GRIP_POLICY: &str = "assets/policies/grip_gru_m3_pca5";

fn sim_arm(cfg: SimBackendConfig) -> SimHandArm {
    let robot = Robot::builtin(Side::Left);
    SimHandArm::new(&robot, ObjectSpec::default_box(), SimConfig::default(), cfg).unwrap()
}

fn safe(arm: SimHandArm) -> SafeHandArm<SimHandArm> {
    SafeHandArm::new(
        arm,
        Robot::builtin(Side::Left).hand_limits(),
        SafetyConfig::default(),
        Arc::new(AtomicBool::new(false)),
    )
    .unwrap()
}

fn grasp_cmd() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_grasp"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

/// Runs `grasp run --json` with `args` and returns (exit ok, stdout JSON or null, stderr).
fn run_json(args: &[&str]) -> (bool, serde_json::Value, String) {
    let out = grasp_cmd()
        .args(["run", "--backend", "sim", "--json"])
        .args(args)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let v = serde_json::from_str(&stdout).unwrap_or(serde_json::Value::Null);
    (out.status.success(), v, stderr)
}

#[test]
fn calibration_thresholds_lie_between_still_and_pressed_readings() {
    let mut arm = sim_arm(SimBackendConfig::default());
    let r = calibrate_tactile(&mut arm, 10, 0.02, DEFAULT_THRESHOLD_FRACTION, |a, f| {
        (0..3)
            .map(|_| a.read_pressed(f, 10.0).map_err(Into::into))
            .collect()
    })
    .unwrap();
    let raw = SimBackendConfig::default().raw;
    for k in 0..5 {
        // Lower = mean of still readings ~ the offset; upper ~ offset + gain * 10 N.
        assert!(
            (r.calibration.lower[k] - raw.tactile_offset[k]).abs() < 0.5,
            "{k}"
        );
        let expect_upper = raw.tactile_offset[k] + 10.0 * raw.tactile_gain[k];
        assert!((r.calibration.upper[k] - expect_upper).abs() < 2.0, "{k}");
        // No still reading counts as a contact, every pressed one does.
        assert!(r.still_max[k] < r.thresholds[k], "{k}: {r:?}");
        assert!(r.thresholds[k] < r.pressed_max[k], "{k}");
    }
    // The same through the CLI, saved and loaded back.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tactile.json");
    let o = grasp_cmd()
        .args(["calibrate", "--backend", "sim", "--json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = TactileCalibration::load(&out).unwrap();
    assert!((c.threshold_fraction - 0.003).abs() < 1e-15);
    for k in 0..5 {
        assert!(c.lower[k] < c.threshold(k) && c.threshold(k) < c.upper[k]);
    }
}

/// Levels of the same squeeze on two simulated hands whose tendon offsets differ by a
/// drift of `rate * clock_start` units.
fn squeeze_levels(clock_start: f64, compensate: Option<&TorqueMapper>) -> Vec<[u8; 20]> {
    let mut cfg = SimBackendConfig::default();
    cfg.raw.clock_start_s = clock_start;
    cfg.raw.tendon_drift_walk = 0.0;
    cfg.raw.tendon_drift_rate = 2.0;
    let mut arm = sim_arm(cfg);
    let mut mapper = TorqueMapper::real();
    let base: Vec<[f64; 20]> = (0..5)
        .map(|_| {
            arm.wait(0.02).unwrap();
            arm.read().unwrap().tendon_raw
        })
        .collect();
    mapper.set_baseline(base).unwrap();
    let m = compensate.unwrap_or(&mapper);
    let q0 = arm.read().unwrap().joint_angles;
    let mut levels = Vec::new();
    for step in 1..=6 {
        // Fingers and wrist pushed away from their measured angles: large PD efforts.
        let mut t = q0;
        for (k, v) in t.iter_mut().enumerate() {
            *v += if k % 2 == 0 { 0.05 } else { -0.05 } * step as f64;
        }
        arm.command_hand(&t).unwrap();
        arm.wait(0.01).unwrap();
        levels.push(m.levels(&arm.read().unwrap().tendon_raw).unwrap());
    }
    levels
}

#[test]
fn drift_compensation_keeps_levels_under_a_drifting_tendon_offset() {
    // One hour of drift at 2 units/s: 7200 units, 36 times the widest threshold.
    let a = squeeze_levels(0.0, None);
    let b = squeeze_levels(3600.0, None);
    assert_eq!(a, b);
    // The levels are not trivially constant.
    let all: std::collections::BTreeSet<u8> = a.iter().flatten().copied().collect();
    assert!(all.len() >= 3, "{all:?}");
    // Without compensation (the baseline of the drift-free hand), the drift would show.
    let mut stale = TorqueMapper::real();
    let mut arm = sim_arm(SimBackendConfig::default());
    stale
        .set_baseline([arm.read().unwrap().tendon_raw])
        .unwrap();
    let c = squeeze_levels(3600.0, Some(&stale));
    assert_ne!(a, c);
    assert!(c.iter().flatten().all(|&l| l == 5));
}

#[test]
fn watchdog_stops_the_robot_within_its_timeout_when_readings_stop() {
    let mut arm = sim_arm(SimBackendConfig::default());
    arm.inject_sensor_dropout(0.3);
    let mut safe = safe(arm);
    let mut last_fresh = 0.0;
    let mut err = None;
    for _ in 0..100 {
        match safe.read() {
            Ok(r) => {
                last_fresh = r.stamp;
                let hold = r.joint_angles;
                if let Err(e) = safe.command_hand(&hold).and_then(|_| safe.wait(0.02)) {
                    err = Some(e);
                    break;
                }
            }
            Err(e) => {
                err = Some(e);
                break;
            }
        }
    }
    assert!(
        matches!(err, Some(HwError::Timeout { .. })),
        "expected a watchdog timeout, got {err:?}"
    );
    let stops = safe.backend().stop_times().to_vec();
    assert_eq!(stops.len(), 1, "{stops:?}");
    // The data stopped after the reading at `last_fresh` (<= 0.3 s); the stop came after
    // the 0.1 s timeout and at most one watchdog slice (half the timeout) later.
    assert!(
        last_fresh <= 0.3 + 1e-9 && last_fresh > 0.25,
        "{last_fresh}"
    );
    let delay = stops[0] - last_fresh;
    assert!(
        delay > 0.1 && delay <= 0.15 + 1e-9,
        "stopped {delay} s after the data"
    );
}

#[test]
fn out_of_range_commands_are_clamped_and_the_clamped_targets_are_sent() {
    let mut safe = safe(sim_arm(SimBackendConfig::default()));
    let q = safe.read().unwrap().joint_angles;
    let mut t = q;
    t[3] = 5.0; // FFJ3 far above: limited to measured + 0.3 (max step)
    t[14] = -0.5; // LFJ5 below its lower limit 0: the limit wins
    safe.command_hand(&t).unwrap();
    let ev = safe.last_clamp_events().to_vec();
    let ff = ev.iter().find(|e| e.joint == "FFJ3").unwrap();
    assert_eq!(ff.reason, ClampReason::MaxStep);
    assert!((ff.applied - (q[3] + 0.3)).abs() < 1e-12);
    let lf = ev.iter().find(|e| e.joint == "LFJ5").unwrap();
    assert_eq!((lf.reason, lf.applied), (ClampReason::JointLimit, 0.0));
    // The simulator received the clamped targets, not the requested ones.
    let sent = safe.backend().sim().targets();
    assert!((sent[3] - ff.applied).abs() < 1e-12);
    assert_eq!(sent[14], 0.0);
    // NaN is refused and nothing is sent.
    t[5] = f64::NAN;
    assert!(safe.command_hand(&t).is_err());
}

#[test]
fn a_full_run_from_the_simulated_cameras_grasps_the_box_and_logs_every_step() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("attempt.jsonl");
    let cloud = dir.path().join("cloud.pcd");
    let (ok, v, err) = run_json(&[
        "--policy",
        POLICY,
        "--object",
        "box",
        "--seed",
        "1",
        "--log",
        log.to_str().unwrap(),
        "--save-cloud",
        cloud.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let out = &v["outcome"];
    assert_eq!(out["success"], true, "{v:#}");
    assert_eq!(out["judged_by"], "simulator");
    assert_eq!(out["touched"], true);
    assert_eq!(out["lifted"], true);
    assert!(v["plan"]["candidates"].as_u64().unwrap() > 10);
    // The log: one line per step, the outcome last, clamp events recorded with the
    // targets that were actually sent.
    let recs = read_log(&log).unwrap();
    assert_eq!(recs.len() as u64, out["log_lines"].as_u64().unwrap());
    let Some(LogRecord::Outcome(o)) = recs.last() else {
        panic!("no outcome line")
    };
    assert!(o.success);
    let steps: Vec<_> = recs
        .iter()
        .filter_map(|r| match r {
            LogRecord::Step(s) => Some(s),
            _ => None,
        })
        .collect();
    assert!(
        steps.iter().any(|s| s.action.len() == 8),
        "policy steps logged"
    );
    let clamped: Vec<_> = steps
        .iter()
        .filter(|s| !s.clamp_events.is_empty())
        .collect();
    assert_eq!(
        clamped.len() as u64,
        out["clamped_commands"].as_u64().unwrap()
    );
    for s in &clamped {
        for e in &s.clamp_events {
            let k = grasp::robot::joints::hand_index(&e.joint).unwrap();
            assert_eq!(s.targets[k], e.applied);
            assert_ne!(e.requested, e.applied);
        }
    }
    // The same attempt planned on the saved cloud file.
    let (ok, v, err) = run_json(&[
        "--policy",
        POLICY,
        "--object",
        "box",
        "--seed",
        "1",
        "--cloud",
        cloud.to_str().unwrap(),
        "--log",
        dir.path().join("b.jsonl").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert_eq!(v["outcome"]["success"], true, "{v:#}");
}

#[test]
fn the_success_is_not_hard_wired_zero_friction_and_an_empty_grasp_fail() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("a.jsonl");
    let log = log.to_str().unwrap();
    // Frictionless fingers (MIN combine rule: the hand's 0 wins).
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/sim.toml"))
            .unwrap()
            .replace("hand = 1.0", "hand = 0.0");
    let cfg = dir.path().join("slippery.toml");
    std::fs::write(&cfg, text).unwrap();
    let grasp = "tests/data/grasps/box_top_down.toml";
    let (ok, v, err) = run_json(&["--object", "box", "--grasp", grasp, "--log", log]);
    assert!(ok, "{err}");
    assert_eq!(v["outcome"]["success"], true, "{v:#}");
    let (ok, v, err) = run_json(&[
        "--object",
        "box",
        "--grasp",
        grasp,
        "--log",
        log,
        "--sim-config",
        cfg.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert_eq!(v["outcome"]["success"], false, "{v:#}");
    // A grasp 25 cm beside the object closes on nothing.
    let (ok, v, err) = run_json(&[
        "--object",
        "box",
        "--center",
        "0.25,0.0,0.057",
        "--closing",
        "1,0,0",
        "--log",
        log,
    ]);
    assert!(ok, "{err}");
    assert_eq!(v["outcome"]["success"], false, "{v:#}");
    assert_eq!(v["outcome"]["touched"], false, "{v:#}");
}

#[test]
fn the_spatula_is_planned_across_its_handle_and_lifted() {
    // The cameras see the spatula (lying flat along x) from four sides: the plan closes
    // across its handle (the object's y axis), and the long grip policy lifts it.
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("spatula.jsonl");
    let (ok, v, err) = run_json(&[
        "--policy",
        "assets/policies/grip_long_gru_m3_pca5",
        "--object",
        "spatula",
        "--seed",
        "1",
        "--log",
        log.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let closing_y = v["plan"]["closing"][1].as_f64().unwrap();
    assert!(closing_y.abs() > 0.95, "{v:#}");
    assert_eq!(v["outcome"]["success"], true, "{v:#}");
}

#[test]
fn a_cloud_without_an_antipodal_pair_is_grasped_across_its_narrow_axis() {
    // The top face of a 10 x 3 cm plate, 2 cm above the table: every normal points up, so
    // no pair of points is antipodal; the plan falls back to closing across the cloud's
    // narrow axis (y), at its centroid.
    let dir = tempfile::tempdir().unwrap();
    let pts: Vec<Point3<f64>> = (0..=20)
        .flat_map(|i| {
            (0..=6).map(move |j| {
                Point3::new(
                    -0.05 + 0.005 * f64::from(i),
                    -0.015 + 0.005 * f64::from(j),
                    0.02,
                )
            })
        })
        .collect();
    let cloud = dir.path().join("plate.pcd");
    write_pcd(&cloud, &pts, PcdData::Ascii).unwrap();
    let log = dir.path().join("plate.jsonl");
    let (ok, v, err) = run_json(&[
        "--policy",
        POLICY,
        "--object",
        "box",
        "--cloud",
        cloud.to_str().unwrap(),
        "--log",
        log.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert_eq!(v["plan"]["fallback"], true, "{v:#}");
    assert!(v["plan"]["score"].is_null(), "{v:#}");
    let c = &v["plan"]["closing"];
    assert!(c[1].as_f64().unwrap() > 0.99, "{v:#}");
    let center = &v["plan"]["center"];
    for (k, want) in [(0, 0.0), (1, 0.0), (2, 0.02)] {
        assert!((center[k].as_f64().unwrap() - want).abs() < 1e-6, "{v:#}");
    }
}

#[test]
fn the_m3g_policy_grasps_on_the_cameras_cloud_and_refuses_a_grasp_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("m3g.jsonl");
    let log = log.to_str().unwrap();
    let (ok, v, err) = run_json(&[
        "--policy", M3G_POLICY, "--object", "box", "--seed", "1", "--log", log,
    ]);
    assert!(ok, "{err}");
    assert_eq!(v["outcome"]["success"], true, "{v:#}");
    assert_eq!(v["outcome"]["lifted"], true, "{v:#}");
    // A grasp given by its centre has no cloud to measure the surface in.
    let (ok, _, err) = run_json(&[
        "--policy",
        M3G_POLICY,
        "--object",
        "box",
        "--center",
        "0.0,0.0,0.057",
        "--closing",
        "1,0,0",
        "--log",
        log,
    ]);
    assert!(!ok);
    assert!(err.contains("M3G") && err.contains("--cloud"), "{err}");
}

/// A copy of the grip policy in `copy` (created), its config's `grip_scale = 0.5` line
/// replaced by `grip_line`.
fn grip_policy_copy(copy: &Path, grip_line: &str) -> PathBuf {
    std::fs::create_dir(copy).unwrap();
    for f in ["checkpoint.safetensors", "synergy.json"] {
        std::fs::copy(Path::new(GRIP_POLICY).join(f), copy.join(f)).unwrap();
    }
    let cfg = std::fs::read_to_string(Path::new(GRIP_POLICY).join("config.toml")).unwrap();
    let edited = cfg.replace("grip_scale = 0.5", grip_line);
    assert_ne!(
        edited, cfg,
        "{GRIP_POLICY}/config.toml has no `grip_scale = 0.5`"
    );
    std::fs::write(copy.join("config.toml"), edited).unwrap();
    copy.to_path_buf()
}

#[test]
fn the_grip_policy_grasps_and_a_config_without_its_grip_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("grip.jsonl");
    let log = log.to_str().unwrap();
    for object in ["box", "cylinder_wood"] {
        let (ok, v, err) = run_json(&[
            "--policy",
            GRIP_POLICY,
            "--object",
            object,
            "--seed",
            "1",
            "--log",
            log,
        ]);
        assert!(ok, "{err}");
        assert_eq!(v["outcome"]["success"], true, "{object}: {v:#}");
    }
    // The same network beside a config without the grip: 5 synergies and the wrist give 7
    // continuous actions, the network has 8.
    let copy = grip_policy_copy(&dir.path().join("policy"), "grip_scale = 0.0");
    let (ok, _, err) = run_json(&[
        "--policy",
        copy.to_str().unwrap(),
        "--object",
        "box",
        "--log",
        log,
    ]);
    assert!(!ok);
    assert!(
        err.contains("5 synergy components (7 continuous actions)") && err.contains("acts in 8"),
        "{err}"
    );
}

#[test]
fn grasp_run_ramps_the_grip_as_the_checkpoint_config_says() {
    // The grip policy (grip_scale 0.5) with `grip_ramp` set in a copy of its config: a ramp
    // of 1.0 caps nothing (w <= 0.5 < k), so the run is the original's line for line; a
    // ramp of 0.01 caps the grip from the first command, so the commands differ.
    let dir = tempfile::tempdir().unwrap();
    let run_log = |policy: &str, name: &str| {
        let log = dir.path().join(name);
        let (ok, _, err) = run_json(&[
            "--policy",
            policy,
            "--object",
            "box",
            "--seed",
            "1",
            "--log",
            log.to_str().unwrap(),
        ]);
        assert!(ok, "{name}: {err}");
        std::fs::read_to_string(log).unwrap()
    };
    let original = run_log(GRIP_POLICY, "original.jsonl");
    for (ramp, same) in [("1.0", true), ("0.01", false)] {
        let copy = grip_policy_copy(
            &dir.path().join(format!("ramp_{ramp}")),
            &format!("grip_scale = 0.5\ngrip_ramp = {ramp}"),
        );
        let log = run_log(copy.to_str().unwrap(), &format!("ramp_{ramp}.jsonl"));
        assert_eq!(log == original, same, "grip_ramp = {ramp}");
    }
    // `grasp eval` says how each checkpoint's grip acts.
    let ramped = dir.path().join("ramp_0.01");
    let out = grasp_cmd()
        .args([
            "eval",
            "--objects",
            "box_sugar",
            "--trials",
            "1",
            "--policy",
        ])
        .arg(format!("{GRIP_POLICY},{},baseline1", ramped.display()))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("evaluating {GRIP_POLICY} (grip 0.5) on 1 objects"))
            && err.contains("(grip 0.5, ramped by 0.01 per step) on 1 objects")
            && err.contains("evaluating Baseline 1 on 1 objects"),
        "{err}"
    );
}

#[test]
fn the_default_policy_is_found_from_any_working_directory() {
    // `grasp run` without --policy, started in an empty folder: the default policy is a
    // path relative to the repository, found under the crate's source folder when the
    // working directory does not hold it (grasp::util::assets).
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_grasp"))
        .current_dir(dir.path())
        .args([
            "run",
            "--backend",
            "sim",
            "--json",
            "--object",
            "box",
            "--seed",
            "1",
        ])
        .args(["--log", "attempt.jsonl"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["policy"], "assets/policies/fig5_gru_m3_pca8", "{v:#}");
    assert!(dir.path().join("attempt.jsonl").exists());
}

#[test]
fn bad_inputs_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad_cal = dir.path().join("cal.json");
    std::fs::write(
        &bad_cal,
        r#"{"lower": [1, 2, 3], "upper": [9, 9, 9, 9, 9], "threshold_fraction": 0.003}"#,
    )
    .unwrap();
    let bad_cal = bad_cal.to_str().unwrap().to_string();
    let log = dir.path().join("a.jsonl").to_str().unwrap().to_string();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--grasp", "tests/data/grasps/missing.toml"],
            "missing.toml",
        ),
        (
            vec!["--grasp", "tests/data/grasps/unknown_field.toml"],
            "unknown field `width`",
        ),
        (
            vec!["--grasp", "tests/data/grasps/short_center.json"],
            "short_center.json",
        ),
        (
            vec!["--grasp", "tests/data/grasps/parallel.toml"],
            "parallel to the approach",
        ),
        (
            vec!["--cloud", "tests/data/clouds/missing.pcd"],
            "missing.pcd",
        ),
        (
            vec!["--cloud", "tests/data/clouds/bad_value.ply"],
            "bad_value.ply",
        ),
        (vec!["--calibration", &bad_cal], "cal.json"),
        (
            vec!["--policy", "tests/data/no_such_policy"],
            "no_such_policy",
        ),
        (vec!["--policy", "tests/data/grasps"], "checkpoint"),
        (vec!["--object", "no_such_object"], "no_such_object"),
        (
            vec!["--center", "0,0", "--closing", "1,0,0"],
            "three numbers",
        ),
    ];
    for (args, needle) in cases {
        let out = grasp_cmd()
            .args(["run", "--backend", "sim", "--log", &log])
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    // calibrate: too few still readings.
    let out = grasp_cmd()
        .args(["calibrate", "--backend", "sim", "--still", "9", "--out"])
        .arg(dir.path().join("c.json"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("at least 10"));
}

#[cfg(not(feature = "ros"))]
#[test]
fn the_ros_backend_without_the_feature_says_how_to_build_it() {
    for sub in [
        vec!["run", "--backend", "ros"],
        vec!["calibrate", "--backend", "ros", "--out", "x.json"],
    ] {
        let out = grasp_cmd().args(&sub).output().unwrap();
        assert!(!out.status.success());
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains("--features ros"), "{e}");
    }
}

#[test]
fn a_failed_attempt_is_retried_on_where_the_object_lies() {
    // The paper's policy fails its first two grasps of the egg (seed 2); the egg settles
    // where each attempt left it, the cameras look again, and the third plan (another
    // grasp than those tried) lifts it.
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("egg.jsonl");
    let (ok, v, err) = run_json(&[
        "--policy",
        POLICY,
        "--object",
        "egg",
        "--seed",
        "2",
        "--attempts",
        "3",
        "--log",
        log.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let attempts = v["attempts"].as_array().expect("one report per attempt");
    let won: Vec<bool> = attempts
        .iter()
        .map(|a| a["outcome"]["success"].as_bool().unwrap())
        .collect();
    assert_eq!(won, [false, false, true], "{v:#}");
    assert_eq!(v["success"], true);
    let centre = |k: usize| -> Vec<f64> {
        serde_json::from_value(attempts[k]["plan"]["center"].clone()).unwrap()
    };
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let d: f64 = (0..3).map(|c| (centre(i)[c] - centre(j)[c]).powi(2)).sum();
        assert!(
            d.sqrt() > 0.01,
            "attempts {i} and {j} at {:?} {:?}",
            centre(i),
            centre(j)
        );
    }
    // One attempt (the default) keeps the one-report JSON; a given grasp has nothing to
    // plan again; the count is checked.
    let (ok, v, err) = run_json(&[
        "--policy",
        POLICY,
        "--object",
        "egg",
        "--seed",
        "2",
        "--log",
        log.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert_eq!(v["outcome"]["success"], false, "{v:#}");
    let (ok, _, err) = run_json(&[
        "--center",
        "0,0,0.03",
        "--closing",
        "1,0,0",
        "--attempts",
        "2",
    ]);
    assert!(
        !ok && err.contains("drop --grasp, --cloud and --center"),
        "{err}"
    );
    let (ok, _, err) = run_json(&["--attempts", "0"]);
    assert!(
        !ok && err.contains("--attempts 0 must be in 1..=10"),
        "{err}"
    );
}
