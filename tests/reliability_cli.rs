//! The command line under hostile but realistic use (issue 21): closed pipes, absurd
//! sizes, special files as outputs, object lists in another order, `--out -`, and error
//! messages that say each cause once.

use std::process::{Command, Output, Stdio};

fn cmd(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_grasp"));
    c.args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("GRASP_LOG");
    c
}

fn grasp(args: &[&str]) -> Output {
    cmd(args).output().expect("run grasp")
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

#[test]
fn a_closed_stdout_ends_quietly() {
    for args in [
        &["objects", "list", "--set", "train"][..],
        &["robot", "show"],
        &["--json", "objects", "list", "--set", "train"],
        &["sim", "--close", "--lift"],
    ] {
        let mut child = cmd(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn grasp");
        // Close the reading end before the first line is printed, as `| head -0` would.
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = stderr(&out);
        assert!(
            !err.contains("panicked") && !err.contains("Broken pipe"),
            "{args:?}: {err}"
        );
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
    }
}

#[test]
fn thread_counts_follow_one_rule() {
    for n in ["0", "100000"] {
        let started = std::time::Instant::now();
        for args in [
            &[
                "eval",
                "--policy",
                "baseline2",
                "--objects",
                "box_sugar",
                "--trials",
                "1",
            ][..],
            &["rollout", "--policy", "baseline2", "--objects", "box_sugar"],
        ] {
            let mut a = args.to_vec();
            a.extend(["--threads", n]);
            let o = grasp(&a);
            assert_fails(&o, &[&format!("--threads {n} must be in 1..=256")]);
        }
        assert!(started.elapsed().as_secs() < 60);
    }
}

fn export_box(out: &std::path::Path) -> Output {
    grasp(&[
        "objects",
        "export",
        "box_sugar",
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn outputs_follow_symlinks_and_refuse_special_files() {
    let dir = tempfile::tempdir().unwrap();
    let real = dir.path().join("real.obj");
    let link = dir.path().join("link.obj");
    std::fs::write(&real, "old").unwrap();
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let o = export_box(&link);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(&real).unwrap().contains("\nv "));

    let fifo = dir.path().join("fifo");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let o = export_box(&fifo);
    assert_fails(&o, &["fifo", "FIFO, not a regular file"]);
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    assert!(!String::from_utf8_lossy(&o.stdout).contains("wrote"));
}

#[test]
fn export_to_dash_writes_stdout() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(["objects", "export", "box_sugar", "--out", "-"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.starts_with("# grasp object box_sugar"), "{text}");
    assert!(text.contains("\nv ") && text.contains("\nf "));
    assert!(!dir.path().join("-").exists());
}

#[test]
fn an_io_error_is_said_once() {
    let o = grasp(&[
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        "box_sugar",
        "--sim-config",
        "/nonexistent/sim.toml",
    ]);
    assert_fails(&o, &["/nonexistent/sim.toml"]);
    let err = stderr(&o);
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
}

/// Per object: (mean steps, outcomes) of a `--json eval` of baseline 2.
fn per_object(objects: &str) -> Vec<(String, f64, Vec<bool>)> {
    let o = grasp(&[
        "--json",
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        objects,
        "--trials",
        "2",
        "--seed",
        "4",
        "--threads",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut rows: Vec<(String, f64, Vec<bool>)> = v[0]["objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            (
                o["object"].as_str().unwrap().to_string(),
                o["mean_steps"].as_f64().unwrap(),
                o["outcomes"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|b| b.as_bool().unwrap())
                    .collect(),
            )
        })
        .collect();
    rows.sort_by(|a, b| a.0.cmp(&b.0));
    rows
}

#[test]
fn start_poses_do_not_depend_on_the_object_order() {
    let a = per_object("box_sugar,can_soup");
    let b = per_object("can_soup,box_sugar");
    assert_eq!(a, b);
    // And an object alone sees the same trials as in a list.
    let alone = per_object("can_soup");
    assert_eq!(alone[0], a[1]);
}
