//! End-to-end checks of `--record` on `grasp rollout` and `grasp eval`, and of `grasp eval`
//! reading a checkpoint's own setup.

use std::path::Path;
use std::process::Command;

/// The policy shipped in assets/ (a checkpoint folder).
const SHIPPED_POLICY: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/assets/policies/quick_gru_m3_pca5"
);

fn grasp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .output()
        .expect("run grasp")
}

fn read_json(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(p).unwrap()).unwrap()
}

/// The recording JSON files of `dir`, sorted.
fn recordings(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    v.sort();
    v
}

fn check_recording(v: &serde_json::Value) {
    let hand = v["hand_geometry"].as_array().unwrap().len();
    assert!(hand > 20);
    assert_eq!(v["hand_tactile_fingers"].as_array().unwrap().len(), hand);
    assert!(!v["object_geometry"].as_array().unwrap().is_empty());
    let frames = v["frames"].as_array().unwrap();
    assert!(frames.len() > 10, "{}", frames.len());
    // The frames reach the end of the episode (the last control record, if any).
    let last_t = frames.last().unwrap()["t"].as_f64().unwrap();
    if let Some(c) = v["control"].as_array().and_then(|c| c.last()) {
        let dt = v["dt"].as_f64().unwrap() * v["frame_every"].as_f64().unwrap();
        assert!(last_t + dt >= c["t"].as_f64().unwrap() - 1e-9);
    }
    for f in frames {
        assert_eq!(f["hand"].as_array().unwrap().len(), hand);
        assert_eq!(f["object"].as_array().unwrap().len(), 7);
        assert_eq!(f["tactile"].as_array().unwrap().len(), 5);
        assert_eq!(f["torque_level"].as_array().unwrap().len(), 20);
    }
    // Frames every 4 physics steps from step 1.
    assert_eq!(frames[0]["physics_step"], 1);
    assert_eq!(frames[1]["physics_step"], 5);
    assert_eq!(frames[0]["stage"], "closing");
}

#[test]
fn rollout_records_json_html_and_index() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    let out = grasp(&[
        "--json",
        "rollout",
        "--policy",
        "random",
        "--objects",
        "box_sugar",
        "--episodes",
        "2",
        "--record",
        rec.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["episodes"].as_array().unwrap().len(), 2);
    let files = recordings(&rec);
    assert_eq!(files.len(), 2);
    for (i, f) in files.iter().enumerate() {
        let v = read_json(f);
        check_recording(&v);
        assert_eq!(v["agent"], "random");
        // The recorded outcome is the printed one.
        assert_eq!(
            v["summary"]["success"],
            summary["episodes"][i]["result"]["success"]
        );
        let steps = summary["episodes"][i]["result"]["steps"].as_u64().unwrap();
        assert_eq!(v["control"].as_array().unwrap().len() as u64, steps + 1);
        let html = std::fs::read_to_string(f.with_extension("html")).unwrap();
        assert!(html.contains("WebGLRenderer") && html.contains("\"frames\""));
    }
    let index = std::fs::read_to_string(rec.join("index.html")).unwrap();
    assert!(index.contains("random_box_sugar_000.html"));
    assert!(index.contains("random_box_sugar_001.html"));
}

#[test]
fn eval_records_the_same_outcomes_as_without() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    let args = [
        "--json",
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        "can_soup",
        "--trials",
        "1",
    ];
    let plain = grasp(&args);
    assert!(plain.status.success());
    let mut with = args.to_vec();
    with.extend(["--record", rec.to_str().unwrap(), "--record-every", "8"]);
    let recorded = grasp(&with);
    assert!(
        recorded.status.success(),
        "{}",
        String::from_utf8_lossy(&recorded.stderr)
    );
    let a: serde_json::Value = serde_json::from_slice(&plain.stdout).unwrap();
    let b: serde_json::Value = serde_json::from_slice(&recorded.stdout).unwrap();
    assert_eq!(a[0]["objects"], b[0]["objects"]);
    assert_eq!(a[0]["lifts"], b[0]["lifts"]);
    // Baseline 2 always lifts; its lift diagnostics are in the JSON.
    assert_eq!(a[0]["lifts"]["lifted"], 1);
    assert!(a[0]["lifts"]["mean_grip_effort"].as_f64().unwrap() >= 0.0);
    assert_eq!(b[0]["recordings"].as_array().unwrap().len(), 1);
    let files = recordings(&rec);
    assert_eq!(files.len(), 1);
    let v = read_json(&files[0]);
    assert_eq!(v["frame_every"], 8);
    assert_eq!(v["agent"], "Baseline 2");
    assert_eq!(v["frames"][1]["physics_step"], 9);
    let last = v["frames"].as_array().unwrap().last().unwrap().clone();
    assert_eq!(last["stage"], "lift");
}

#[test]
fn record_every_zero_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = grasp(&[
        "rollout",
        "--objects",
        "box_sugar",
        "--episodes",
        "1",
        "--record",
        dir.path().to_str().unwrap(),
        "--record-every",
        "0",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--record-every"));
}

#[test]
fn eval_takes_the_setup_from_the_checkpoint() {
    let policy = SHIPPED_POLICY;
    // No --modality/--components needed: the checkpoint's config.toml says M3, 5.
    let out = grasp(&[
        "--json",
        "eval",
        "--policy",
        policy,
        "--objects",
        "box_sugar",
        "--trials",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A contradicting flag is an error naming the checkpoint's value.
    for (flag, value, expect) in [
        ("--modality", "M1", "modality M3"),
        ("--components", "3", "5 synergy components"),
    ] {
        let out = grasp(&[
            "eval",
            "--policy",
            policy,
            "--objects",
            "box_sugar",
            "--trials",
            "1",
            flag,
            value,
        ]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expect) && err.contains("config.toml"), "{err}");
    }
    // Agreeing flags are fine.
    let out = grasp(&[
        "eval",
        "--policy",
        policy,
        "--objects",
        "box_sugar",
        "--trials",
        "1",
        "--modality",
        "M3",
        "--components",
        "5",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn eval_reports_a_malformed_checkpoint_config() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(SHIPPED_POLICY);
    for f in ["checkpoint.safetensors", "synergy.json"] {
        std::fs::copy(src.join(f), dir.path().join(f)).unwrap();
    }
    std::fs::write(dir.path().join("config.toml"), "name = \"x\"\nbogus = 3\n").unwrap();
    let out = grasp(&[
        "eval",
        "--policy",
        dir.path().to_str().unwrap(),
        "--objects",
        "box_sugar",
        "--trials",
        "1",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("config.toml") && err.contains("bogus"),
        "{err}"
    );
}

#[test]
fn stochastic_eval_samples_reproducibly() {
    let policy = SHIPPED_POLICY;
    let run = || {
        let out = grasp(&[
            "--json",
            "eval",
            "--policy",
            policy,
            "--stochastic",
            "--objects",
            "box_sugar,can_soup",
            "--trials",
            "2",
            "--seed",
            "5",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice::<serde_json::Value>(&out.stdout).expect("JSON")
    };
    let (a, b) = (run(), run());
    let text = a.to_string();
    assert!(text.contains("(sampled)"), "{text}");
    let outcomes = |v: &serde_json::Value| -> Vec<(String, u64, f64)> {
        v[0]["objects"]
            .as_array()
            .expect("objects")
            .iter()
            .map(|o| {
                (
                    o["object"].as_str().unwrap().to_string(),
                    o["successes"].as_u64().unwrap(),
                    o["mean_steps"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    assert_eq!(outcomes(&a).len(), 2);
    assert_eq!(outcomes(&a), outcomes(&b));
}

#[test]
fn eval_pairs_the_first_agent_with_the_others() {
    let args = [
        "eval",
        "--policy",
        "baseline1,baseline2",
        "--objects",
        "can_soup,box_sugar",
        "--trials",
        "2",
    ];
    let json = grasp(&[&["--json"], &args[..]].concat());
    assert!(
        json.status.success(),
        "{}",
        String::from_utf8_lossy(&json.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).expect("JSON");
    // Each object lists its trials' outcomes; count the pairs by hand.
    let outcomes = |a: usize| -> Vec<bool> {
        v[a]["objects"]
            .as_array()
            .expect("objects")
            .iter()
            .flat_map(|o| {
                let t = o["outcomes"].as_array().expect("outcomes");
                assert_eq!(t.len(), 2);
                t.iter().map(|x| x.as_bool().unwrap()).collect::<Vec<_>>()
            })
            .collect()
    };
    let (a, b) = (outcomes(0), outcomes(1));
    let count = |x: bool, y: bool| a.iter().zip(&b).filter(|p| *p.0 == x && *p.1 == y).count();
    let md = grasp(&[&args[..], &["--markdown"]].concat());
    assert!(md.status.success());
    let text = String::from_utf8_lossy(&md.stdout);
    let expect = format!(
        "Baseline 1 vs Baseline 2 on identical start poses: only the first won {} trials, only the second {}, both {}, neither {} (exact McNemar p",
        count(true, false),
        count(false, true),
        count(true, true),
        count(false, false)
    );
    assert!(text.contains(&expect), "{text}");
}
