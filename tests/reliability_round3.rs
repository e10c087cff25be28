//! The third hostile round on the command line (issue 49): no evaluation thrown away by a
//! write bound to fail, no abort on a point cloud, no silent mix-ups. Each test fails on
//! the build before its fix.

use std::path::Path;
use std::process::{Command, Output};

fn grasp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("GRASP_LOG")
        .output()
        .expect("run grasp")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts a clean failure: exit status 1, every `needles` in stderr, no panic.
fn assert_fails(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "missing `{n}` in: {err}");
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Case 3: a point cloud whose header declares more points than the file can hold is an
/// error naming the file and line, not an aborted 96 GB allocation (exit 134).
#[test]
fn a_cloud_declaring_billions_of_points_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = "property float x\nproperty float y\nproperty float z\n";
    let files = [
        (
            "big.ply",
            format!("ply\nformat ascii 1.0\nelement vertex 4000000000\n{xyz}end_header\n0 0 0\n"),
            "line 3: element vertex 4000000000 cannot fit",
        ),
        (
            "big.pcd",
            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nPOINTS 4000000000\nDATA ascii\n0 0 0\n".to_string(),
            "line 6: POINTS 4000000000 cannot fit",
        ),
    ];
    for (name, text, want) in files {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        let o = grasp(&["run", "--backend", "sim", "--cloud", s(&p)]);
        assert_fails(&o, &[name, want]);
    }
}
