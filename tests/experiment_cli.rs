//! End-to-end check of `grasp experiment` on the tiny grid: every run trains, the
//! reports are written, a second call skips finished runs, and an unfinished run resumes.

use std::process::Command;

fn grasp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run grasp")
}

fn ok(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn statuses(v: &serde_json::Value) -> Vec<String> {
    v["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["status"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn tiny_grid_trains_reports_skips_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("tiny");
    let out = out_dir.to_str().unwrap();
    let grid = "configs/grids/tiny_grid.toml";
    let v = ok(&grasp(&[
        "--json",
        "experiment",
        "--grid",
        grid,
        "--out",
        out,
    ]));
    assert_eq!(statuses(&v), ["finished"; 4]);
    let variants = v["summary"]["variants"].as_array().unwrap();
    assert_eq!(variants.len(), 2);
    for var in variants {
        assert_eq!(var["finished"], 2);
        assert_eq!(var["transitions"], 32.0);
        // Mean and std of the final success across the two seeds, in [0, 1].
        let fs = var["final_success"].as_array().unwrap();
        assert!((0.0..=1.0).contains(&fs[0].as_f64().unwrap()));
        assert!(var["eval_success"].is_array());
    }
    for f in ["summary.md", "summary.csv", "runs.csv", "policy.svg"] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
    let svg = std::fs::read_to_string(out_dir.join("policy.svg")).unwrap();
    assert!(svg.contains("GRU-M3PCA5") && svg.contains("MLP-M3PCA5"));
    let runs = std::fs::read_to_string(out_dir.join("runs.csv")).unwrap();
    assert_eq!(runs.lines().count(), 5);
    assert!(runs.contains("mlp_m3_pca5,2,done,32,"));
    let run = out_dir.join("gru_m3_pca5/seed2");
    assert!(run.join("done.json").is_file() && run.join("eval.json").is_file());
    // The second evaluated set has its own cache; each set is pooled over the two seeds
    // (2 trials each), the MLP paired with the reference GRU.
    assert!(run.join("eval_ball_tennis.json").is_file());
    let pooled = v["summary"]["pooled"].as_array().unwrap();
    assert_eq!(pooled.len(), 2);
    for (set, name) in pooled.iter().zip(["bottle_tall", "ball_tennis"]) {
        assert_eq!(set["objects"], name);
        assert_eq!(set["reference"], "gru_m3_pca5");
        let rows = set["rows"].as_array().unwrap();
        assert_eq!(rows[0]["trials"], 4);
        assert!(rows[0]["vs_reference"].is_null());
        let vs = rows[1]["vs_reference"].as_array().expect("MLP vs GRU");
        let won = vs[0].as_u64().unwrap() + vs[1].as_u64().unwrap();
        assert!(won <= 4);
    }
    let md = std::fs::read_to_string(out_dir.join("summary.md")).unwrap();
    assert!(
        md.contains("### policy on ball_tennis (reference gru_m3_pca5)"),
        "{md}"
    );
    assert!(out_dir.join("pooled.csv").is_file());

    // Without --resume an existing grid is refused.
    let again = grasp(&["experiment", "--grid", grid, "--out", out]);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("--resume"));

    // A run that lost its done marker (killed after its last checkpoint) resumes; the
    // others are skipped.
    std::fs::remove_file(run.join("done.json")).unwrap();
    let v = ok(&grasp(&[
        "--json",
        "experiment",
        "--grid",
        grid,
        "--out",
        out,
        "--resume",
    ]));
    assert_eq!(statuses(&v), ["skipped", "finished", "skipped", "skipped"]);
    assert!(run.join("done.json").is_file());
    let metrics = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
    assert_eq!(metrics.lines().count(), 3, "no update is repeated");
}

#[test]
fn bad_grid_is_reported_with_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.toml");
    std::fs::write(
        &p,
        "name = \"g\"\nseeds = [1]\nablation = []\nparallel = \"x\"\n",
    )
    .unwrap();
    let out = grasp(&["experiment", "--grid", p.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("g.toml") && err.contains("line 4"), "{err}");
    let missing = grasp(&["experiment", "--grid", "no/such/grid.toml"]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/grid.toml"));
}
