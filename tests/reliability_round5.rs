//! The fifth hostile round on the command line (issue 66): nothing written through a link
//! or over an input, nothing lost to a signal or a full disk, bounded reads and sizes, no
//! grasp below the table. Each test fails on the build before its fix.

use std::path::{Path, PathBuf};

#[path = "common/cli.rs"]
mod cli;
use cli::*;

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// A folder `m/s` holding a copy of the U-channel mesh.
fn user_mesh_folder(dir: &Path) -> PathBuf {
    let set = dir.join("m/s");
    std::fs::create_dir_all(&set).unwrap();
    std::fs::copy(
        repo("assets/meshes/novel/u_channel.obj"),
        set.join("u_channel.obj"),
    )
    .unwrap();
    set
}

/// A hull cache beside a user mesh was written through a symbolic link (the file it
/// pointed to got hull JSON), and an edited cache with a valid key was trusted.
#[cfg(unix)]
#[test]
fn hull_caches_are_never_written_through_links_and_edited_ones_are_rebuilt() {
    let dir = tempfile::tempdir().unwrap();
    let set = user_mesh_folder(dir.path());
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, "keep\n").unwrap();
    let cache = set.join("u_channel.obj.hulls.json");
    std::os::unix::fs::symlink("../../victim.txt", &cache).unwrap();
    for args in [
        &["objects", "list", "--set", s(&set)][..],
        &["objects", "show", "u_channel", "--set", s(&set)],
    ] {
        let o = grasp(args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep\n");
        assert!(stderr(&o).contains("not a regular file"), "{}", stderr(&o));
    }
    assert!(std::fs::symlink_metadata(&cache)
        .unwrap()
        .file_type()
        .is_symlink());

    // A real cache, then edited: a point moved to 5 m, or all hulls but one removed.
    std::fs::remove_file(&cache).unwrap();
    let o = grasp(&["objects", "list", "--set", s(&set)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let good: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&cache).unwrap()).unwrap();
    assert!(good["hulls"].as_array().unwrap().len() >= 2);
    let moved = {
        let mut v = good.clone();
        v["hulls"][0]["points"][0] = serde_json::json!([5.0, 0.0, 0.0]);
        v
    };
    let cut = {
        let mut v = good.clone();
        v["hulls"].as_array_mut().unwrap().truncate(1);
        v
    };
    for edited in [moved, cut] {
        std::fs::write(&cache, edited.to_string()).unwrap();
        let o = grasp(&["objects", "show", "u_channel", "--set", s(&set)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("does not fit the mesh"),
            "{}",
            stderr(&o)
        );
        let back: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&cache).unwrap()).unwrap();
        assert_eq!(back, good, "the cache is rebuilt as it was");
    }
}

/// An output that is an input or another output was overwritten: `--from-json e.json
/// --csv e.json` turned the saved evaluation into a CSV, `objects export m.obj --out
/// m.obj` replaced the mesh, `--csv x.svg --plot x.svg` and `--csv rec/index.html
/// --record rec` wrote one file twice.
#[cfg(unix)]
#[test]
fn outputs_never_replace_inputs_or_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let saved = d.join("e.json");
    std::fs::write(&saved, "[]").unwrap();
    let hard = d.join("hard.json");
    std::fs::hard_link(&saved, &hard).unwrap();
    for out in [&saved, &hard] {
        let o = grasp(&["eval", "--from-json", s(&saved), "--csv", s(out)]);
        assert_fails(&o, &["--csv", "--from-json", "overwrite"]);
        assert_eq!(std::fs::read_to_string(&saved).unwrap(), "[]");
    }
    let mesh = d.join("m.obj");
    std::fs::copy(repo("tests/data/objects/cube.obj"), &mesh).unwrap();
    let before = std::fs::read(&mesh).unwrap();
    let o = grasp(&["objects", "export", s(&mesh), "--out", s(&mesh)]);
    assert_fails(&o, &["--out", "overwrite"]);
    assert_eq!(std::fs::read(&mesh).unwrap(), before);

    let svg = d.join("x.svg");
    let o = eval_one(&["--csv", s(&svg), "--plot", s(&svg)]);
    assert_fails(&o, &["--csv", "--plot", "same file"]);
    assert!(!stderr(&o).contains("evaluating"), "{}", stderr(&o));
    let rec = d.join("rec");
    let index = rec.join("index.html");
    let o = eval_one(&["--csv", s(&index), "--record", s(&rec)]);
    assert_fails(&o, &["--csv", "inside the folder of --record"]);
    assert!(!rec.exists());
    // A mesh of an --objects folder is an input too.
    let set = d.join("set");
    std::fs::create_dir(&set).unwrap();
    let cube = set.join("cube.obj");
    std::fs::copy(repo("tests/data/objects/cube.obj"), &cube).unwrap();
    let o = grasp(&[
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        s(&set),
        "--trials",
        "1",
        "--csv",
        s(&cube),
    ]);
    assert_fails(&o, &["--csv", "--objects", "overwrite"]);
    assert!(std::fs::read_to_string(&cube)
        .unwrap()
        .starts_with("# 5 cm cube"));
    // Other commands: the attempt log over the grasp file it reads.
    let g = d.join("g.toml");
    std::fs::copy(repo("tests/data/grasps/box_top_down.toml"), &g).unwrap();
    let o = grasp(&["run", "--grasp", s(&g), "--log", s(&g)]);
    assert_fails(&o, &["--log", "--grasp"]);
    assert!(std::fs::read_to_string(&g).unwrap().contains("center"));
    let o = grasp(&["pca", "fit", s(&g), "--out", s(&g)]);
    assert_fails(&o, &["--out", "DATASET"]);
}

/// `grasp train --out` into a checkpoint folder replaced its config.toml, and the
/// checkpoint no longer loaded; a folder of other files was trained into too.
#[test]
fn training_never_goes_into_a_checkpoint_or_a_foreign_folder() {
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("ck");
    std::fs::create_dir(&ck).unwrap();
    let src = repo("assets/policies/quick_gru_m3_pca5");
    for e in std::fs::read_dir(&src).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), ck.join(e.file_name())).unwrap();
    }
    let config = std::fs::read(ck.join("config.toml")).unwrap();
    let cfg = repo("configs/cartpole.toml");
    let o = grasp(&["train", "--config", s(&cfg), "--out", s(&ck)]);
    assert_fails(&o, &["is a checkpoint folder"]);
    assert_eq!(std::fs::read(ck.join("config.toml")).unwrap(), config);
    assert!(!ck.join(".lock").exists());
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    let o = grasp(&["train", "--config", s(&cfg), "--out", s(&other)]);
    assert_fails(&o, &["not empty and not a run folder", "notes.txt"]);
    assert_eq!(std::fs::read_dir(&other).unwrap().count(), 1);
    // The repository itself.
    let o = grasp(&["train", "--config", s(&cfg), "--out", "."]);
    assert_fails(&o, &["not a run folder"]);
    assert!(!repo("config.toml").exists() && !repo(".lock").exists());
    // A grid's output folder likewise: no reports among the user's files.
    for out in [&ck, &other] {
        let o = grasp(&[
            "experiment",
            "--grid",
            "configs/grids/tiny_grid.toml",
            "--out",
            s(out),
        ]);
        assert_fails(&o, &["--out", "run the grid into a new folder"]);
    }
    assert_eq!(std::fs::read_dir(&other).unwrap().count(), 1);
    assert!(!ck.join("summary.md").exists());
}

/// Every file input was read without bound: `--from-json /dev/zero` grew to gigabytes and
/// never ended; configs, clouds, grasps and datasets the same.
#[cfg(unix)]
#[test]
fn file_inputs_are_read_with_a_bound_and_only_when_regular() {
    for args in [
        &["eval", "--from-json", "/dev/zero"][..],
        &["train", "--config", "/dev/zero"],
        &["run", "--cloud", "/dev/zero"],
        &["run", "--grasp", "/dev/zero"],
        &["pca", "fit", "/dev/zero"],
        &["experiment", "--grid", "/dev/zero"],
    ] {
        let o = grasp(args);
        let e = stderr(&o);
        assert!(!o.status.success(), "{args:?}");
        assert!(!e.contains("panicked"), "{e}");
        assert!(
            e.contains("/dev/zero") && e.contains("not a regular file"),
            "{args:?}: {e}"
        );
    }
    // A FIFO is refused without being opened (opening it would block for good).
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("p.toml");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let o = grasp(&["train", "--config", s(&fifo)]);
    assert_fails(&o, &["p.toml", "FIFO, not a regular file"]);
}

/// `[policy]` widths each within their bound aborted the process with a 103 GB
/// allocation, and `num_envs` x `num_steps` with a 721 GB one, leaving a run folder.
#[test]
fn network_and_rollout_sizes_are_bounded_together() {
    let dir = tempfile::tempdir().unwrap();
    let base = repo("configs/quick.toml");
    for (extra, needles) in [
        (
            "[policy]\nembed_dim = 65536\ngru_hidden = 65536\nmlp_hidden = 65536\n",
            &[
                "policy.embed_dim/gru_hidden/mlp_hidden",
                "million parameters",
            ][..],
        ),
        (
            "num_envs = 1024\n[ppo]\nnum_steps = 1048576\nnum_minibatches = 4\n",
            &["ppo.num_steps", "transitions per rollout", "GB"],
        ),
        ("[policy]\nembed_dim = 0\n", &["policy.embed_dim"]),
        // A long history multiplies the observation: within the bound of a few hundred
        // values, not of this one's.
        (
            "num_envs = 1024\n[ppo]\nnum_steps = 1024\nnum_minibatches = 4\n[env]\nhistory = 64\n",
            &["ppo.num_steps", "transitions per rollout", "GB"],
        ),
    ] {
        let cfg = dir.path().join("big.toml");
        std::fs::write(&cfg, format!("base = \"{}\"\n{extra}", s(&base))).unwrap();
        let run = dir.path().join("run");
        let o = grasp(&["train", "--config", s(&cfg), "--out", s(&run)]);
        assert_fails(&o, needles);
        assert!(!run.exists(), "a run folder was left");
    }
}

/// `--budget-minutes 1e18` panicked converting to a Duration; a grid's `minutes =
/// 1e308` wrote `time_budget_minutes = inf` into every checkpoint's config.toml.
#[test]
fn minutes_are_bounded_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = grasp(&[
        "experiment",
        "--grid",
        "configs/grids/tiny_grid.toml",
        "--out",
        s(&out),
        "--budget-minutes",
        "1e18",
    ]);
    assert_fails(&o, &["--budget-minutes 1e18", "at most 525960"]);
    let grid = std::fs::read_to_string(repo("configs/grids/tiny_grid.toml"))
        .unwrap()
        .replace("minutes = 5.0", "minutes = 1e308")
        .replace("\"../", &format!("\"{}/", s(&repo("configs"))));
    let g = dir.path().join("g.toml");
    std::fs::write(&g, grid).unwrap();
    let o = grasp(&["experiment", "--grid", s(&g), "--out", s(&out)]);
    assert_fails(&o, &["budget.minutes", "at most 525960"]);
    assert!(!out.exists());
    let o = grasp(&[
        "train",
        "--config",
        "configs/cartpole.toml",
        "--time-budget-minutes",
        "1e18",
        "--out",
        s(&out),
    ]);
    assert_fails(&o, &["--time-budget-minutes 1e18", "at most 525960"]);
}

/// A point cloud of the given points as an ASCII PCD file.
fn cloud(dir: &Path, name: &str, points: &[[f64; 3]]) -> PathBuf {
    let p = dir.join(name);
    let pts: Vec<nalgebra::Point3<f64>> = points.iter().map(|&q| q.into()).collect();
    grasp::perception::pointcloud::write_pcd(
        &p,
        &pts,
        grasp::perception::pointcloud::PcdData::Ascii,
    )
    .unwrap();
    p
}

/// A cube's surface samples, 4 cm across, its bottom at z = `z0`.
fn cube_points(z0: f64) -> Vec<[f64; 3]> {
    let mut v = Vec::new();
    for i in 0..9 {
        for j in 0..9 {
            let (a, b) = (-0.02 + 0.005 * i as f64, -0.02 + 0.005 * j as f64);
            v.push([a, b, z0 + 0.04]);
            v.push([a, -0.02, z0 + 0.005 * j as f64 * 0.888]);
            v.push([-0.02, a, z0 + 0.005 * j as f64 * 0.888]);
        }
    }
    v
}

/// `run --center=0,0,-0.5` planned and executed an arm solution half a metre under the
/// table top, and so did a cloud shifted down; degenerate clouds (one point 3,000 times,
/// collinear points, 5e-8 m across) were planned and reported SUCCESS.
#[test]
fn no_grasp_below_the_table_or_on_a_degenerate_cloud() {
    let o = grasp(&["run", "--center=0,0,-0.5", "--closing", "1,0,0"]);
    assert_fails(&o, &["below the table top"]);
    assert!(!stdout(&o).contains("FAILURE"), "{}", stdout(&o));
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let below = cloud(d, "below.pcd", &cube_points(-0.5));
    let same = cloud(d, "same.pcd", &vec![[0.0, 0.0, 0.03]; 3000]);
    let line: Vec<[f64; 3]> = (0..200).map(|i| [i as f64 * 0.001, 0.0, 0.03]).collect();
    let line = cloud(d, "line.pcd", &line);
    let tiny: Vec<[f64; 3]> = cube_points(0.0)
        .iter()
        .map(|p| [p[0] * 1e-6, p[1] * 1e-6, p[2] * 1e-6])
        .collect();
    let tiny = cloud(d, "tiny.pcd", &tiny);
    for (c, why) in [
        (&below, "below the table top"),
        (&same, "spans only 0 m"),
        (&line, "lies on a line"),
        (&tiny, "spans only"),
    ] {
        let o = grasp(&["run", "--cloud", s(c)]);
        assert_fails(&o, &[why]);
        assert!(!stdout(&o).contains("SUCCESS"), "{}", stdout(&o));
    }
    // A calibration no sensor can have reported SUCCESS with no fingertip in contact.
    let cal = d.join("cal.json");
    std::fs::write(
        &cal,
        r#"{"lower": [300, 300, 300, 300, 300], "upper": [1e300, 1400, 1400, 1400, 1400], "threshold_fraction": 0.003}"#,
    )
    .unwrap();
    let o = grasp(&["run", "--calibration", s(&cal)]);
    assert_fails(&o, &["cal.json", "upper[0] (FF)", "1e300", "raw reading"]);
}

/// `eval --record` on a full disk exited 1 with nothing printed: the whole evaluation
/// was lost (here a recording's file name is taken by a folder, so its write fails).
#[test]
fn a_recording_that_cannot_be_written_keeps_the_results() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec");
    std::fs::create_dir_all(rec.join("Baseline_2_box_sugar_000.json")).unwrap();
    let o = eval_one(&["--record", s(&rec)]);
    assert_fails(&o, &["episodes could not be recorded", "the results above"]);
    assert!(stdout(&o).contains("mean success"), "{}", stdout(&o));
    assert!(rec.join("index.html").is_file());
    // `rollout --record` likewise.
    let rec = dir.path().join("rec2");
    std::fs::create_dir_all(rec.join("baseline2_box_sugar_000.json")).unwrap();
    let o = grasp(&[
        "rollout",
        "--policy",
        "baseline2",
        "--objects",
        "box_sugar",
        "--episodes",
        "1",
        "--record",
        s(&rec),
    ]);
    assert_fails(&o, &["episodes could not be recorded", "the results above"]);
    assert!(stdout(&o).contains("/1 successes"), "{}", stdout(&o));
    assert!(rec.join("index.html").is_file());
}

/// SIGTERM during `grasp eval` lost everything: nothing printed, no CSV, no index.
#[cfg(unix)]
#[test]
fn an_interrupted_evaluation_prints_and_writes_what_finished() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("a.csv");
    // The handler is installed before the first agent is announced.
    let (o, rest) = terminated_after(
        &[
            "eval",
            "--policy",
            "baseline2",
            "--objects",
            "train",
            "--trials",
            "3",
            "--threads",
            "1",
            "--csv",
            s(&csv),
        ],
        "evaluating",
    );
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(130), "{rest}");
    assert!(!rest.contains("panicked"), "{rest}");
    if rest.contains("before any trial finished") {
        assert!(!csv.exists());
    } else {
        assert!(out.contains("interrupted (SIGINT or SIGTERM)"), "{out}");
        assert!(csv.is_file(), "{rest}");
    }
}

/// Objects `sugar` and `box_sugar` with labels `P_box,P` said "recorded 4 episodes" but
/// kept 3 file pairs: both agents' recordings were named `P_box_sugar_000`.
#[test]
fn recordings_that_would_share_a_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let set = dir.path().join("set");
    std::fs::create_dir(&set).unwrap();
    for n in ["sugar.obj", "box_sugar.obj"] {
        std::fs::copy(repo("tests/data/objects/cube.obj"), set.join(n)).unwrap();
    }
    let rec = dir.path().join("rec");
    let o = grasp(&[
        "eval",
        "--policy",
        "baseline2,baseline2",
        "--labels",
        "P_box,P",
        "--objects",
        s(&set),
        "--trials",
        "1",
        "--record",
        s(&rec),
    ]);
    assert_fails(
        &o,
        &["'P_box' on object 'sugar'", "'P' on object 'box_sugar'"],
    );
    assert!(!stderr(&o).contains("evaluating"), "{}", stderr(&o));
    assert!(!rec.exists());
}

/// `--from-json` accepted `thumb_contact_rate: 7.0` (printed 700.0 %) and
/// `physics_failures: 99` of 2 trials.
#[test]
fn saved_rates_and_counts_must_fit_their_trials() {
    let dir = tempfile::tempdir().unwrap();
    let src = repo("docs/results/delay_2026_12/novel_top-down_seed0.json");
    let good: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&src).unwrap()).unwrap();
    let o = grasp(&["eval", "--from-json", s(&src)]);
    assert!(o.status.success(), "{}", stderr(&o));
    for (edit, needle) in [
        (
            serde_json::json!({"lifts": {"thumb_contact_rate": 7.0}}),
            "thumb_contact_rate` 7 must be a rate in [0, 1]",
        ),
        (
            serde_json::json!({"physics_failures": 99_999}),
            "`physics_failures` is 99999, more than its",
        ),
    ] {
        let mut v = good.clone();
        for (k, x) in edit.as_object().unwrap() {
            match x {
                serde_json::Value::Object(inner) => {
                    for (k2, y) in inner {
                        v[0][k][k2] = y.clone();
                    }
                }
                _ => v[0][k] = x.clone(),
            }
        }
        let f = dir.path().join("e.json");
        std::fs::write(&f, v.to_string()).unwrap();
        let o = grasp(&["eval", "--from-json", s(&f)]);
        assert_fails(&o, &["e.json", needle]);
    }
}

/// Unclear errors: OBJ vertices counted from 0, a face index 0 as "index out of bounds",
/// a wrong STL triangle count as "failed to fill whole buffer", 300-digit numbers,
/// "could not convert slice to array", "File exists (os error 17)", `[policy]` keys
/// under `ppo`, a duplicate object name without its files.
#[test]
fn errors_name_the_line_the_count_and_the_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = grasp(&["objects", "show", "tests/data/objects/nan.obj"]);
    assert_fails(&o, &["nan.obj", "line 5", "vertex 4"]);
    let zero = d.join("zero.obj");
    std::fs::write(
        &zero,
        "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 0 2 3\n",
    )
    .unwrap();
    let o = grasp(&["objects", "show", s(&zero)]);
    assert_fails(&o, &["zero.obj", "line 5", "face index 0", "count from 1"]);
    let stl = d.join("bad.stl");
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&12u32.to_le_bytes());
    bytes.extend_from_slice(&[0u8; 50 * 3]);
    std::fs::write(&stl, bytes).unwrap();
    let o = grasp(&["objects", "show", s(&stl)]);
    assert_fails(
        &o,
        &["bad.stl", "gives 12 triangles", "684 bytes", "234 bytes"],
    );
    let o = grasp(&["run", "--center", "0,0", "--closing", "1,0,0"]);
    assert_fails(&o, &["--center takes three numbers x,y,z, got 2"]);
    let o = grasp(&["run", "--center", "1e300,0,0.05", "--closing", "1,0,0"]);
    assert_fails(&o, &["1e300"]);
    assert!(!stderr(&o).contains("00000000000"), "{}", stderr(&o));
    let file = d.join("f");
    std::fs::write(&file, "x").unwrap();
    let log = file.join("a.jsonl");
    let o = grasp(&["run", "--log", s(&log)]);
    assert_fails(&o, &["is a file, not a folder"]);
    assert!(!stderr(&o).contains("os error 17"), "{}", stderr(&o));
    let set = d.join("set");
    std::fs::create_dir(&set).unwrap();
    for n in ["a b.obj", "a_b.obj"] {
        std::fs::copy(repo("tests/data/objects/cube.obj"), set.join(n)).unwrap();
    }
    let o = grasp(&["objects", "list", "--set", s(&set)]);
    assert_fails(
        &o,
        &["duplicate object name `a_b`", "a b.obj and", "a_b.obj both"],
    );
}
