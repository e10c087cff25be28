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

/// `grasp eval` of baseline 2 on one trial of one object, with `extra` flags.
fn eval_one(extra: &[&str]) -> Output {
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

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Case 1: every output path of `eval` is checked before the first episode, with one rule
/// (missing folders are created; a folder where a file goes, or a file where a folder
/// goes, is refused), and the results are printed before any file is written.
#[test]
fn eval_outputs_are_checked_before_the_first_episode() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = d.join("a");
    std::fs::write(&file, "x").unwrap();
    let cases: [(Vec<String>, Vec<String>); 4] = [
        (
            vec!["--csv".into(), s(d).into()],
            vec![format!("--csv {}", s(d)), "is a directory".into()],
        ),
        (
            vec!["--plot".into(), format!("{}/x.svg", s(&file))],
            vec!["x.svg".into(), "a is a file, not a folder".into()],
        ),
        (
            vec!["--record".into(), s(&file).into()],
            vec![
                format!("--record {}", s(&file)),
                "is a file, not a folder".into(),
            ],
        ),
        (
            vec!["--labels".into(), "A,A".into()],
            vec!["--labels: 'A' is given twice".into()],
        ),
    ];
    for (flags, needles) in cases {
        let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
        let o = eval_one(&flags);
        let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
        assert_fails(&o, &needles);
        assert!(
            !stderr(&o).contains("evaluating"),
            "{flags:?}: {}",
            stderr(&o)
        );
        assert!(o.stdout.is_empty(), "{flags:?}");
    }
    // Missing folders are created for every output, --plot included; the results are
    // printed as well.
    let csv = d.join("new/t.csv");
    let svg = d.join("plots/p.svg");
    let o = eval_one(&["--json", "--csv", s(&csv), "--plot", s(&svg)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v[0]["objects"][0]["trials"], 1, "{v:#}");
    assert!(csv.is_file() && svg.is_file());
}

/// Case 10: `--trials` is bounded like `objects list --count`.
#[test]
fn eval_trials_are_bounded() {
    let o = grasp(&[
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        "box_sugar",
        "--trials",
        "100000000000",
    ]);
    assert_fails(&o, &["--trials 100000000000 must be in 1..=10000"]);
    assert!(!stderr(&o).contains("evaluating"), "{}", stderr(&o));
}

/// A copy of the shipped policy in `dir` without its synergy.json.
fn policy_copy(dir: &Path) -> std::path::PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/policies/quick_gru_m3_pca5");
    let dst = dir.join("policy");
    std::fs::create_dir_all(&dst).unwrap();
    for f in ["checkpoint.safetensors", "config.toml"] {
        std::fs::copy(src.join(f), dst.join(f)).unwrap();
    }
    dst
}

/// Case 8: a checkpoint without synergy.json says which model it falls back to; a
/// synergy.json with a meaningless mean or projection range is refused on load.
#[test]
fn synergy_models_are_validated_and_fallbacks_named() {
    let dir = tempfile::tempdir().unwrap();
    let pol = policy_copy(dir.path());
    let o = grasp(&[
        "eval",
        "--policy",
        s(&pol),
        "--objects",
        "box_sugar",
        "--trials",
        "1",
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains(&format!(
            "warning: {} has no synergy.json; its policy acts in the shipped synergy model",
            s(&pol)
        )),
        "{err}"
    );
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/policies/quick_gru_m3_pca5/synergy.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(shipped).unwrap()).unwrap();
    v["mean"][0] = 1e308.into();
    std::fs::write(pol.join("synergy.json"), v.to_string()).unwrap();
    let o = grasp(&[
        "eval",
        "--policy",
        s(&pol),
        "--objects",
        "box_sugar",
        "--trials",
        "1",
    ]);
    assert_fails(
        &o,
        &[
            "synergy.json",
            "mean[0] (FFJ4) = 1e308 rad is not a joint angle",
        ],
    );
    assert!(!stderr(&o).contains("evaluating"), "{}", stderr(&o));
}

/// Case 7: `--from-json` pairs agents trial by trial only when they started from the
/// same placement and seed, and says why it does not; an agent with no trials is refused
/// (it printed "mean success 0.0 %").
#[test]
fn saved_evaluations_pair_only_the_same_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let saved = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/results/recipe_2026_12/eval_unseen_20.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(saved).unwrap()).unwrap();
    v[2]["pregrasp"] =
        serde_json::json!({"placement": "antipodal", "planned": 380, "default_placement": 0});
    v[3]["seed"] = 7.into();
    let merged = write(dir.path(), "merged.json", &v.to_string());
    let o = grasp(&["eval", "--from-json", s(&merged)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let first = "runs/ship_new/checkpoints/latest";
    assert!(
        out.contains(&format!(
            "{first} vs Baseline 1: not compared trial by trial: their hands started from \
             different placements (top-down and antipodal)"
        )) && out.contains(&format!(
            "{first} vs Baseline 2: not compared trial by trial: their start poses came from \
             different seeds (not recorded and 7)"
        )),
        "{out}"
    );
    assert!(
        !out.contains(&format!("{first} vs Baseline 1 on identical start poses")),
        "{out}"
    );
    // The agents that share both are still compared.
    assert!(
        out.contains(&format!(
            "{first} vs runs/ship_mlp/checkpoints/best on identical start poses"
        )),
        "{out}"
    );
    v[4]["objects"][0]["trials"] = 0.into();
    v[4]["objects"][0]["successes"] = 0.into();
    v[4]["objects"][0]["outcomes"] = serde_json::json!([]);
    let empty = write(dir.path(), "empty.json", &v.to_string());
    let o = grasp(&["eval", "--from-json", s(&empty)]);
    assert_fails(&o, &["empty.json", "no trials"]);
}

/// Case 2: `--record` never overwrites one agent's episodes with another's (two
/// checkpoints of one folder name are refused unless `--labels` names them apart, and the
/// labels name the files), nor a folder that already holds recordings.
#[test]
fn recordings_are_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/policies/quick_gru_m3_pca5");
    let mut ck = Vec::new();
    for run in ["a", "b"] {
        let d = dir.path().join(run).join("t1/checkpoints/latest");
        std::fs::create_dir_all(&d).unwrap();
        for f in ["checkpoint.safetensors", "config.toml", "synergy.json"] {
            std::fs::copy(src.join(f), d.join(f)).unwrap();
        }
        ck.push(d.to_str().unwrap().to_string());
    }
    let rec = dir.path().join("rec");
    let policies = ck.join(",");
    let eval = |extra: &[&str]| {
        let mut a = vec![
            "eval",
            "--policy",
            &policies,
            "--objects",
            "box_sugar",
            "--trials",
            "1",
            "--record",
            s(&rec),
        ];
        a.extend(extra);
        grasp(&a)
    };
    let o = eval(&[]);
    assert_fails(
        &o,
        &[
            "would both be recorded as 't1_latest_<object>_<trial>'",
            "--labels",
        ],
    );
    assert!(
        !stderr(&o).contains("evaluating") && !rec.exists(),
        "{}",
        stderr(&o)
    );
    let o = eval(&["--labels", "first,second"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(&rec)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json"))
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["first_box_sugar_000.json", "second_box_sugar_000.json"]
    );
    // A second recording into the same folder is refused before any episode.
    let o = eval(&["--labels", "third,fourth"]);
    assert_fails(&o, &["already holds recordings", "index.html"]);
    assert!(!stderr(&o).contains("evaluating"), "{}", stderr(&o));
}
