//! `grasp robot mjcf`: the scene the MuJoCo backend simulates, written as MJCF in the
//! default build (no MuJoCo needed), and the errors of its flags and of
//! `--mujoco-settings`.

#[path = "common/cli.rs"]
mod cli;

use cli::{assert_fails, grasp, stdout};

#[test]
fn robot_mjcf_writes_the_hand_table_and_object() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scene.xml");
    let o = grasp(&[
        "robot",
        "mjcf",
        "--object",
        "box_gelatin",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", cli::stderr(&o));
    let xml = std::fs::read_to_string(&out).unwrap();
    assert!(xml.starts_with("<mujoco model="), "{}", &xml[..80]);
    assert!(xml.contains("integrator=\"implicitfast\"") && xml.contains("timestep=\"2e-3\""));
    // 24 hand actuators and the mount's three lift motors.
    assert_eq!(xml.matches("<position ").count(), 27);
    assert!(xml.contains("<body name=\"object\""));
    // Without an object: no object body and no pairs with the table.
    let o = grasp(&["robot", "mjcf", "--object", "none"]);
    assert!(o.status.success());
    let xml = stdout(&o);
    assert!(!xml.contains("<body name=\"object\"") && !xml.contains("<pair "));
}

#[test]
fn mjcf_and_settings_errors_name_the_flag() {
    let o = grasp(&["robot", "mjcf", "--object", "no_such_object_x"]);
    assert_fails(&o, &["no_such_object_x"]);
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("mj.toml");
    std::fs::write(&bad, "timestep = 0.5\n").unwrap();
    let o = grasp(&["robot", "mjcf", "--mujoco-settings", bad.to_str().unwrap()]);
    assert_fails(&o, &["--mujoco-settings", "mj.toml"]);
    let o = grasp(&[
        "run",
        "--backend",
        "sim",
        "--mujoco-settings",
        bad.to_str().unwrap(),
    ]);
    assert_fails(&o, &["--mujoco-settings is for --backend mujoco"]);
}
