//! End-to-end tests of `grasp robot` and of the URDF loader on bad input.

use std::path::PathBuf;
use std::process::Command;

fn grasp(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .output()
        .expect("run grasp");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn data(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/robots")
        .join(name)
        .display()
        .to_string()
}

#[test]
fn show_prints_the_joint_table_and_tips() {
    let (ok, out, err) = grasp(&["robot", "show"]);
    assert!(ok, "{err}");
    assert!(out.contains("lh_FFJ3"), "{out}");
    assert!(out.contains("20 actuators"), "{out}");
    assert!(out.contains("FFJ0   drives FFJ2 + FFJ1"), "{out}");
    // Left hand, zero posture: FF tip at (-0.033, 0, 0.191).
    assert!(out.contains("FF  ( -0.0330,   0.0000,   0.1910)"), "{out}");
}

#[test]
fn show_json_right_hand_c_shape() {
    let (ok, out, err) = grasp(&[
        "robot", "show", "--hand", "right", "--q", "c-shape", "--json",
    ]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("valid JSON");
    assert_eq!(v["side"], "right");
    assert_eq!(v["joints"].as_array().unwrap().len(), 24);
    assert_eq!(v["actuators"].as_array().unwrap().len(), 20);
    let th = &v["fingertips_palm_frame"][4];
    assert_eq!(th["finger"], "TH");
}

#[test]
fn maker_style_urdf_loads_with_mesh_fallback_and_fails_when_strict() {
    let path = data("maker_style_rh.urdf");
    let (ok, out, err) = grasp(&["robot", "show", "--urdf", &path]);
    assert!(ok, "{err}");
    assert!(out.contains("rh_FFJ3"), "{out}");
    assert!(
        err.contains("not found, using a primitive approximation"),
        "{err}"
    );
    // Same fingertip as our own right hand: the kinematics agree.
    assert!(out.contains("FF  (  0.0330,   0.0000,   0.1910)"), "{out}");
    let (ok, _, err) = grasp(&["robot", "show", "--urdf", &path, "--strict"]);
    assert!(!ok);
    assert!(err.contains("mesh"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_urdfs_get_clear_errors_without_panics() {
    for (file, needle) in [
        ("malformed.urdf", "malformed URDF"),
        ("missing_joint.urdf", "missing joint FFJ3"),
        (
            "nan_origin.urdf",
            "joint 'rh_FFJ2': origin has a non-finite number",
        ),
        ("bad_limits.urdf", "lower limit"),
        ("two_roots.urdf", "roots"),
    ] {
        let path = data(file);
        let (ok, _, err) = grasp(&["robot", "show", "--urdf", &path]);
        assert!(!ok, "{file} should fail");
        assert!(err.contains(needle), "{file}: {err}");
        assert!(
            err.contains(file),
            "{file}: error must name the file: {err}"
        );
        assert!(!err.contains("panicked"), "{file}: {err}");
    }
    let (ok, _, err) = grasp(&["robot", "show", "--urdf", "/nonexistent/x.urdf"]);
    assert!(!ok && err.contains("/nonexistent/x.urdf"), "{err}");
}

#[test]
fn bad_hand_side_and_posture_are_errors() {
    let (ok, _, err) = grasp(&["robot", "show", "--hand", "middle"]);
    assert!(!ok && err.contains("middle"), "{err}");
    let (ok, _, err) = grasp(&["robot", "show", "--q", "fist"]);
    assert!(!ok && err.contains("unknown posture 'fist'"), "{err}");
}

#[test]
fn ik_round_trips() {
    let (ok, out, err) = grasp(&["robot", "ik", "--xyz", "0.6", "0.2", "0.4", "--json"]);
    assert!(ok, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["position_error_m"].as_f64().unwrap() < 1e-6);
    let (ok, _, err) = grasp(&["robot", "ik", "--xyz", "5", "0", "0"]);
    assert!(!ok && err.contains("no IK solution"), "{err}");
}
