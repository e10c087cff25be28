//! The third hostile round on the command line (issue 49): no evaluation thrown away by a
//! write bound to fail, no abort on a point cloud, no silent mix-ups. Each test fails on
//! the build before its fix.

use std::path::Path;

#[path = "common/cli.rs"]
mod cli;
use cli::*;

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
    let cases: [(Vec<String>, Vec<String>); 5] = [
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
        // A folder no file can be created in (as an unprivileged user's read-only one).
        (
            vec!["--csv".into(), "/proc/t.csv".into()],
            vec!["--csv /proc/t.csv: cannot create files in /proc".into()],
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

/// The `global_step` of the last row of `run`'s metrics.csv.
fn last_global_step(run: &Path) -> u64 {
    let text = std::fs::read_to_string(run.join("metrics.csv")).unwrap();
    let rows = grasp::train::metrics::parse_csv(Path::new("metrics.csv"), &text).unwrap();
    rows.last().unwrap().global_step
}

/// Case 4: a run's length is counted in transitions, so a resume with another
/// `--num-envs` stops at `--total-timesteps` instead of counting updates of the old
/// batch size (0 new updates, or 43 % over the target).
#[test]
fn resume_with_another_num_envs_counts_transitions() {
    let tmp = tempfile::tempdir().unwrap();
    // 2 cart-poles x 32 steps: 64 transitions per update.
    let cfg = write(
        tmp.path(),
        "cp.toml",
        "name = \"cp\"\nseed = 5\ntotal_timesteps = 192\nnum_envs = 2\nthreads = 1\n\
         checkpoint_every = 1\nplot_every = 10\nbest_window = 2\n[ppo]\nnum_steps = 32\n\
         num_minibatches = 2\nupdate_epochs = 1\n[policy]\nkind = \"mlp\"\nmlp_hidden = 8\n\
         [env]\nkind = \"cartpole\"\ncartpole_max_steps = 50\n",
    );
    let run = tmp.path().join("run");
    let train = |extra: &[&str]| {
        let mut a = vec!["train", "--config", s(&cfg), "--out", s(&run)];
        a.extend(extra);
        let o = grasp(&a);
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    train(&[]);
    assert_eq!(last_global_step(&run), 192);
    // 4 envs: 128 per update; 192 + 128 = 320 (before: 320 / 128 = 2 updates < 3 done,
    // nothing trained).
    let out = train(&["--resume", "--num-envs", "4", "--total-timesteps", "320"]);
    assert!(out.contains("4 updates (1 new)"), "{out}");
    assert_eq!(last_global_step(&run), 320);
    // 1 env: 32 per update; one update reaches 352 (before: 352 / 32 = 11 updates, 7 new,
    // 544 transitions).
    let out = train(&["--resume", "--num-envs", "1", "--total-timesteps", "352"]);
    assert!(out.contains("5 updates (1 new)"), "{out}");
    assert_eq!(last_global_step(&run), 352);
}

/// Case 5: a resume that changes the training objects needs --allow-env-change, as a
/// change of `[env]` does; nothing is rewritten when it is refused.
#[test]
fn resume_with_other_objects_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("model.json");
    grasp::synergy::default_model().save(&model).unwrap();
    let cfg = write(
        tmp.path(),
        "g.toml",
        &format!(
            "base = \"{}\"\nname = \"g\"\ntotal_timesteps = 16\nnum_envs = 2\nthreads = 2\n\
             synergy = \"{}\"\n[ppo]\nnum_steps = 8\nnum_minibatches = 2\nupdate_epochs = 1\n\
             [policy]\nembed_dim = 16\ngru_hidden = 16\n",
            concat!(env!("CARGO_MANIFEST_DIR"), "/configs/base.toml"),
            s(&model)
        ),
    );
    let run = tmp.path().join("run");
    let base = ["train", "--config", s(&cfg), "--out", s(&run)];
    let o = grasp(&[&base[..], &["--objects", "box_sugar"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let saved = std::fs::read_to_string(run.join("config.toml")).unwrap();
    let o = grasp(
        &[
            &base[..],
            &["--resume", "--objects", "unseen", "--total-timesteps", "32"],
        ]
        .concat(),
    );
    assert_fails(
        &o,
        &["objects ('box_sugar', now 'unseen')", "--allow-env-change"],
    );
    assert_eq!(
        std::fs::read_to_string(run.join("config.toml")).unwrap(),
        saved
    );
}

/// Case 9: `--objects` with the cart-pole is refused, naming the setting (it was
/// accepted and ignored).
#[test]
fn objects_for_the_cartpole_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = write(
        tmp.path(),
        "cp.toml",
        "name = \"cp\"\ntotal_timesteps = 64\nnum_envs = 2\n[ppo]\nnum_steps = 32\n\
         num_minibatches = 2\n[policy]\nkind = \"mlp\"\n[env]\nkind = \"cartpole\"\n",
    );
    let run = tmp.path().join("run");
    let o = grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&run),
        "--objects",
        "unseen",
    ]);
    assert_fails(&o, &["--objects unseen", "cp.toml trains the cart-pole"]);
    assert!(!run.exists());
}

/// A training object folder that cannot be built is named as the objects, not as "invalid
/// config config.toml".
#[test]
fn a_broken_training_object_folder_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("model.json");
    grasp::synergy::default_model().save(&model).unwrap();
    let objects = tmp.path().join("objs");
    std::fs::create_dir(&objects).unwrap();
    write(&objects, "broken.obj", "v 0 0\nf 1 2 3\n");
    let cfg = write(
        tmp.path(),
        "g.toml",
        &format!(
            "base = \"{}\"\nname = \"g\"\ntotal_timesteps = 16\nnum_envs = 2\nthreads = 2\n\
             synergy = \"{}\"\n[ppo]\nnum_steps = 8\nnum_minibatches = 2\n",
            concat!(env!("CARGO_MANIFEST_DIR"), "/configs/base.toml"),
            s(&model)
        ),
    );
    let o = grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&tmp.path().join("run")),
        "--objects",
        s(&objects),
    ]);
    assert_fails(&o, &[&format!("`{}`", s(&objects)), "broken.obj"]);
    assert!(!stderr(&o).contains("config.toml"), "{}", stderr(&o));
}

/// The unclear errors of the round: each is one line naming the value and what is valid.
#[test]
fn unclear_errors_name_the_value_and_what_is_valid() {
    let dir = tempfile::tempdir().unwrap();
    // Negative numbers reach their own checks instead of clap's generic usage error.
    let o = grasp(&["sim", "--mass", "-1"]);
    assert_fails(&o, &["--mass"]);
    assert!(
        !stderr(&o).contains("unexpected argument"),
        "{}",
        stderr(&o)
    );
    let o = eval_one(&["--difficulty", "-0.5"]);
    assert_fails(&o, &["--difficulty must be in [0, 1], got -0.5"]);
    // Large numbers in scientific notation, not 300 digits.
    let o = eval_one(&["--difficulty", "1e300"]);
    assert_fails(&o, &["--difficulty must be in [0, 1], got 1e300\n"]);
    let cfg = write(
        dir.path(),
        "cp.toml",
        "name = \"cp\"\ntotal_timesteps = 64\nnum_envs = 2\n[ppo]\nnum_steps = 32\n\
         num_minibatches = 2\n[policy]\nkind = \"mlp\"\n[env]\nkind = \"cartpole\"\n",
    );
    let o = grasp(&[
        "train",
        "--config",
        s(&cfg),
        "--out",
        s(&dir.path().join("r")),
        "--time-budget-minutes",
        "-1e300",
    ]);
    assert_fails(
        &o,
        &["--time-budget-minutes -1e300 must be a positive number of minutes"],
    );
    // A zero closing direction is called zero.
    let o = grasp(&["run", "--center", "0,0,0.05", "--closing", "0,0,0"]);
    assert_fails(&o, &["closing direction is zero"]);
    // A cloud too small to fit normals to, and a PLY version that does not exist.
    let small = write(
        dir.path(),
        "small.pcd",
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nPOINTS 3\nDATA ascii\n\
         0 0 0\n0.01 0 0\n0 0.01 0\n",
    );
    let log = dir.path().join("attempt.jsonl");
    let o = grasp(&["run", "--cloud", s(&small), "--log", s(&log)]);
    assert_fails(
        &o,
        &["the point cloud has only 3 points: at least 15 are needed"],
    );
    // The run failed before its first step: no empty log is left behind.
    assert!(!log.exists(), "an empty attempt log was left at {log:?}");
    let ply = write(
        dir.path(),
        "v9.ply",
        "ply\nformat ascii 9.0\nelement vertex 1\nproperty float x\nproperty float y\n\
         property float z\nend_header\n0 0 0\n",
    );
    let o = grasp(&["run", "--cloud", s(&ply)]);
    assert_fails(
        &o,
        &["v9.ply", "line 2: unsupported PLY version '9.0' (1.0)"],
    );
}
