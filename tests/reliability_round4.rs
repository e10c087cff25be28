//! The fourth hostile round on the command line: the surfaces added since the third
//! (`eval --attempts`, `--perturb`, `--from-json`, `--labels`, `run --log`). Each test
//! fails on the build before its fix.

use std::path::Path;

#[path = "common/cli.rs"]
mod cli;
use cli::*;

/// `grasp run --log /dev/null` (no log wanted) ran the attempt, then failed with
/// "Invalid argument (os error 22)" when syncing the log, and the attempt's result was
/// lost.
#[cfg(unix)]
#[test]
fn an_attempt_logged_to_dev_null_keeps_its_result() {
    let o = grasp(&["run", "--backend", "sim", "--log", "/dev/null"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("on box_gelatin") && out.contains("/dev/null"),
        "{out}"
    );
}

/// `eval --perturb` with `[randomization]` ranges but without `enabled = true` evaluated
/// every agent unperturbed, and the JSON recorded the ranges as its conditions.
#[test]
fn perturbation_ranges_left_disabled_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("light.toml");
    std::fs::write(&p, "[randomization]\nfriction = [0.1, 0.2]\n").unwrap();
    let o = eval_one(&["--perturb", s(&p)]);
    assert_fails(
        &o,
        &[
            "light.toml",
            "randomization.enabled",
            "friction",
            "enabled = true",
        ],
    );
    assert!(!stderr(&o).contains("evaluating"), "{}", stderr(&o));
}

/// A saved evaluation of baseline 2 with two attempts per trial, as JSON.
fn saved_eval() -> serde_json::Value {
    let o = grasp(&[
        "--json",
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        "box_sugar",
        "--trials",
        "2",
        "--attempts",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `eval --from-json` read files that misled: an agent named twice was picked silently
/// by `--policy` (the other's different results ignored), an object listed twice counted
/// twice in the agent's mean, and an edited retry count printed "99 of 2 trials won at
/// the first (4950.0 %)".
#[test]
fn saved_evaluations_that_would_mislead_are_refused_or_recounted() {
    let dir = tempfile::tempdir().unwrap();
    let v = saved_eval();
    let file = |name: &str, v: &serde_json::Value| {
        let p = dir.path().join(name);
        std::fs::write(&p, serde_json::to_string(v).unwrap()).unwrap();
        p
    };
    // The same agent twice.
    let mut twice = v.clone();
    let again = twice[0].clone();
    twice.as_array_mut().unwrap().push(again);
    let p = file("twice.json", &twice);
    let o = grasp(&["eval", "--from-json", s(&p), "--policy", "baseline2"]);
    assert_fails(&o, &["twice.json", "holds 2 agents named 'Baseline 2'"]);
    // Shown whole, both are there.
    let o = grasp(&["eval", "--from-json", s(&p)]);
    assert!(o.status.success(), "{}", stderr(&o));
    // An object listed twice.
    let mut dup = v.clone();
    let obj = dup[0]["objects"][0].clone();
    dup[0]["objects"].as_array_mut().unwrap().push(obj);
    let p = file("dup.json", &dup);
    let o = grasp(&["eval", "--from-json", s(&p)]);
    assert_fails(&o, &["dup.json", "object 'box_sugar' is listed twice"]);
    // An edited retry count is recounted from the trials' attempts.
    let mut edited = v.clone();
    edited[0]["retries"]["first_attempt_successes"] = 99.into();
    let p = file("edited.json", &edited);
    let o = grasp(&["eval", "--from-json", s(&p)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let want = grasp(&["eval", "--from-json", s(&file("v.json", &v))]);
    assert_eq!(stdout(&o), stdout(&want));
    assert!(!stdout(&o).contains("99 of"), "{}", stdout(&o));
    // Attempts beyond those allowed.
    let mut beyond = v.clone();
    beyond[0]["objects"][0]["attempts"] = serde_json::json!([1, 7]);
    let p = file("beyond.json", &beyond);
    let o = grasp(&["eval", "--from-json", s(&p)]);
    assert_fails(
        &o,
        &[
            "beyond.json",
            "object 'box_sugar': the attempts per trial must be 2 numbers in 1..=2",
        ],
    );
}

/// `--labels "A, B"` named the second agent " B", so `--labels "A, A "` passed as two
/// names; a line break in a label split its `--csv` row in two.
#[test]
fn labels_are_trimmed_and_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let v = saved_eval();
    let mut two = v.clone();
    let mut other = v[0].clone();
    other["agent"] = "Other".into();
    two.as_array_mut().unwrap().push(other);
    let p = dir.path().join("two.json");
    std::fs::write(&p, serde_json::to_string(&two).unwrap()).unwrap();
    let o = grasp(&["eval", "--from-json", s(&p), "--labels", "A, A "]);
    assert_fails(&o, &["--labels: 'A' is given twice"]);
    let o = grasp(&["eval", "--from-json", s(&p), "--labels", "A,B\nC"]);
    assert_fails(&o, &["--labels: label 2", "control character"]);
    let csv = dir.path().join("t.csv");
    let o = grasp(&[
        "eval",
        "--from-json",
        s(&p),
        "--labels",
        "A, B",
        "--csv",
        s(&csv),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("\nB: mean success"), "{}", stdout(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.contains("\nB,box_sugar,2,"), "{text}");
}

/// A checkpoint whose `config.toml` was edited to `max_steps = 1000000` was evaluated: a
/// policy that never lifts (a young one, whose lift probability stays below 0.5) held
/// `grasp eval` of one trial for hours.
#[test]
fn an_edited_checkpoint_with_endless_episodes_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("ck");
    std::fs::create_dir(&ck).unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/policies/quick_gru_m3_pca5");
    for f in std::fs::read_dir(&src).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, ck.join(f.file_name().unwrap())).unwrap();
    }
    let cfg = ck.join("config.toml");
    let text = std::fs::read_to_string(&cfg).unwrap();
    assert!(text.contains("max_steps = 20\n"));
    std::fs::write(
        &cfg,
        text.replace("max_steps = 20\n", "max_steps = 1000000\n"),
    )
    .unwrap();
    let o = grasp(&[
        "eval",
        "--policy",
        s(&ck),
        "--objects",
        "box_sugar",
        "--trials",
        "1",
    ]);
    assert_fails(
        &o,
        &["config.toml", "max_steps: 1000000 must be in 1..=1000"],
    );
}
