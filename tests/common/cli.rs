//! Helpers of the command-line tests: run the `grasp` binary from the repository root and
//! check how it failed. Included with `#[path = "common/cli.rs"] mod cli;` (each test file
//! uses some of them).
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// The `grasp` binary with `args`, run from the repository root, `GRASP_LOG` unset.
pub fn cmd(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_grasp"));
    c.args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("GRASP_LOG");
    c
}

/// Runs `grasp` with `args` and waits for it.
pub fn grasp(args: &[&str]) -> Output {
    cmd(args).output().expect("run grasp")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Asserts a clean failure: exit status 1, every `needles` in stderr, no panic.
pub fn assert_fails(o: &Output, needles: &[&str]) {
    assert_fails_with(o, 1, needles);
}

/// Asserts a clean failure with status `code` (1 for our errors, 2 for the argument
/// parser's), every `needles` in stderr, no panic.
pub fn assert_fails_with(o: &Output, code: i32, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(code), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "missing `{n}` in: {err}");
    }
}

/// `grasp eval` of baseline 2 on one trial of one object, with `extra` flags.
pub fn eval_one(extra: &[&str]) -> Output {
    let mut a = vec![
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        "box_sugar",
        "--trials",
        "1",
    ];
    a.extend(extra);
    grasp(&a)
}

/// A path as the `&str` an argument list takes.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Starts `grasp` with `args`, waits until a line of its stderr contains `announced` (the
/// command has installed its signal handler by then), sends it SIGTERM and waits for it.
/// Returns its output (stdout; stderr is empty) and the stderr it wrote from that line
/// on, the line included.
#[cfg(unix)]
pub fn terminated_after(args: &[&str], announced: &str) -> (Output, String) {
    use std::io::{BufRead, BufReader, Read};
    use std::process::Stdio;
    let mut child = cmd(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start grasp");
    let mut err = BufReader::new(child.stderr.take().expect("piped stderr"));
    let mut line = String::new();
    while err.read_line(&mut line).expect("read stderr") > 0 && !line.contains(announced) {
        line.clear();
    }
    assert!(
        line.contains(announced),
        "no `{announced}` on stderr: {line}"
    );
    let st = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(st.success());
    let mut rest = line;
    err.read_to_string(&mut rest).expect("read stderr");
    (child.wait_with_output().expect("wait for grasp"), rest)
}
