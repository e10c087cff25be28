//! `grasp run --objects`: Table I through the robot path, end to end in the release-built
//! binary: the JSON has `grasp eval --json`'s shape (read back by `grasp eval
//! --from-json`, plotted), the same seed gives the same table, attempt logs only with
//! --log, and the flags that do not fit are clear errors.

#[path = "common/cli.rs"]
mod cli;

use cli::{assert_fails, assert_fails_with, grasp, s, stderr, stdout};

const POLICY: &str = "assets/policies/fig5_gru_m3_pca8";

/// `grasp --seed SEED run --backend sim --objects box_sugar --trials 1 --policy
/// baseline2,POLICY --json` with `extra` flags: its JSON.
fn table(seed: &str, extra: &[&str]) -> serde_json::Value {
    let policies = format!("baseline2,{POLICY}");
    let mut args = vec![
        "--seed",
        seed,
        "run",
        "--backend",
        "sim",
        "--objects",
        "box_sugar",
        "--trials",
        "1",
        "--policy",
        &policies,
        "--json",
    ];
    args.extend(extra);
    let o = grasp(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&stdout(&o)).expect("the table's JSON")
}

/// `v` without its wall-clock fields.
fn timeless(mut v: serde_json::Value) -> serde_json::Value {
    for agent in v.as_array_mut().expect("a list of agents") {
        let a = agent.as_object_mut().unwrap();
        a.remove("wall_s");
        a.remove("control_steps_per_s");
    }
    v
}

#[test]
fn the_table_has_grasp_evals_shape_and_the_same_seed_gives_the_same_table() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("attempts.jsonl");
    let j = table("0", &["--log", s(&log)]);
    let agents = j.as_array().unwrap();
    assert_eq!(agents.len(), 2);
    assert_eq!(agents[0]["agent"], "Baseline 2");
    assert_eq!(agents[1]["agent"], POLICY);
    for a in agents {
        assert_eq!(a["backend"], "sim");
        assert!(a["trial_errors"].is_array());
        assert_eq!(a["seed"], 0);
        let o = &a["objects"][0];
        assert_eq!(o["object"], "box_sugar");
        assert_eq!(o["trials"], 1);
        assert_eq!(o["outcomes"].as_array().unwrap().len(), 1);
        assert!(o["ci95"].is_array() && o["rate"].is_number());
        assert!(a["physics_failures"].is_number() && a["lifts"].is_object());
    }
    // One attempt per trial in the log, each ending in its outcome line.
    let text = std::fs::read_to_string(&log).unwrap();
    let outcomes = text.lines().filter(|l| l.contains("\"outcome\"")).count();
    assert_eq!(outcomes, 2, "{text}");

    // `grasp eval --from-json` reads it back, compares the agents and plots them.
    let file = dir.path().join("table.json");
    std::fs::write(&file, serde_json::to_string_pretty(&j).unwrap()).unwrap();
    let svg = dir.path().join("table.svg");
    let o = grasp(&["eval", "--from-json", s(&file), "--plot", s(&svg)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("Baseline 2") && out.contains("box_sugar"),
        "{out}"
    );
    assert!(out.contains("on identical start poses"), "{out}");
    assert!(svg.is_file());
    let o = grasp(&["eval", "--from-json", s(&file), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let back: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        back[0]["objects"][0]["outcomes"],
        j[0]["objects"][0]["outcomes"]
    );

    // The same seed on one worker thread: the same table, wall clocks aside; no log
    // without --log.
    let again = table("0", &["--threads", "1"]);
    assert_eq!(timeless(again), timeless(j));
}

#[test]
fn flags_that_do_not_fit_a_table_are_clear_errors() {
    let o = grasp(&["run", "--objects", "box_sugar", "--object", "box"]);
    assert_fails_with(&o, 2, &["--object"]);
    let o = grasp(&["run", "--objects", "box_sugar", "--attempts", "2"]);
    assert_fails(&o, &["--attempts 2", "--objects"]);
    let o = grasp(&["run", "--objects", "box_sugar", "--trials", "0"]);
    assert_fails(&o, &["--trials 0"]);
    let o = grasp(&[
        "run",
        "--objects",
        "box_sugar",
        "--policy",
        "baseline1,,baseline2",
    ]);
    assert_fails(&o, &["--policy", "empty"]);
    let o = grasp(&[
        "run",
        "--objects",
        "box_sugar",
        "--policy",
        "no/such/policy",
    ]);
    assert_fails(&o, &["no/such/policy"]);
    let o = grasp(&["run", "--objects", "box_sugar", "--backend", "ros"]);
    assert_fails(&o, &["--objects", "simulated"]);
    let o = grasp(&["run", "--trials", "3"]);
    assert_fails_with(&o, 2, &["--objects"]);
    if cfg!(feature = "mujoco") {
        // The backend is part of this build: its own tests cover it (and these commands
        // would write into the repository).
        return;
    }
    for args in [
        &["run", "--backend", "mujoco", "--objects", "box_sugar"][..],
        &["run", "--backend", "mujoco"][..],
        &["calibrate", "--backend", "mujoco", "--out", "x.json"][..],
    ] {
        let o = grasp(args);
        assert_fails(
            &o,
            &[
                "mujoco backend is not part of this build",
                "--features mujoco",
            ],
        );
    }
}

/// A signal stops starting trials: the table of the trials that finished is printed, each
/// agent marked interrupted, and the exit status is 130 (or, stopped before any trial
/// finished, nothing is printed).
#[cfg(unix)]
#[test]
fn an_interrupted_table_prints_what_finished() {
    // The handler is installed before the table is announced.
    let (o, rest) = cli::terminated_after(
        &[
            "run",
            "--backend",
            "sim",
            "--objects",
            "box_sugar,box_gelatin,can_soup",
            "--trials",
            "20",
            "--threads",
            "1",
            "--policy",
            "baseline2",
        ],
        "running 1 agents",
    );
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(130), "{rest}");
    assert!(!rest.contains("panicked"), "{rest}");
    if rest.contains("before any trial finished") {
        assert!(out.is_empty(), "{out}");
    } else {
        assert!(
            out.contains("Baseline 2: interrupted (SIGINT or SIGTERM): only the trials"),
            "{out}"
        );
        assert!(rest.contains("the results above are of the trials that finished"));
    }
}
