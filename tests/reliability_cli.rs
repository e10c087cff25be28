//! The command line under hostile but realistic use (issue 21): closed pipes, absurd
//! sizes, special files as outputs, object lists in another order, `--out -`, and error
//! messages that say each cause once.

use std::process::{Command, Output, Stdio};

#[path = "common/cli.rs"]
mod cli;
use cli::*;

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

    let fifo = dir.path().join("fifo.obj");
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

// ---------------------------------------------------------------------------------------
// Issue 31: reliability, round 2.

fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A manifest: a good box and `bad` (a TOML `[[object]]` table).
fn manifest(dir: &std::path::Path, bad: &str) -> String {
    let m = write(
        dir,
        "set.toml",
        &format!(
            "[[object]]\nname = \"good\"\nshape = {{ type = \"box\", size = [0.05, 0.05, 0.1] }}\n\
             mass_kg = 0.2\n\n{bad}"
        ),
    );
    m.to_str().unwrap().to_string()
}

#[test]
fn objects_are_validated_before_any_episode() {
    let dir = tempfile::tempdir().unwrap();
    // A box 0.1 mm thick: refused by the manifest check, naming file, line and field.
    let m = manifest(
        dir.path(),
        "[[object]]\nname = \"sheet\"\nshape = { type = \"box\", size = [0.05, 0.05, 0.0001] }\n",
    );
    for args in [
        &["objects", "list", "--set", &m][..],
        &[
            "eval",
            "--policy",
            "baseline2",
            "--objects",
            &m,
            "--trials",
            "1",
        ],
        &["rollout", "--policy", "baseline2", "--objects", &m],
    ] {
        let o = grasp(args);
        assert_fails(
            &o,
            &[
                "set.toml",
                "sheet",
                "shape.size[2]",
                "0.0001 must be in [0.001, 1] m",
            ],
        );
    }
    // A flat mesh the manifest accepts but the simulator would refuse at every reset:
    // refused before the first episode, naming the set and the object.
    write(
        dir.path(),
        "flat.obj",
        "v 0 0 0\nv 0.05 0 0\nv 0.05 0.05 0\nv 0 0.05 0\nv 0 0 0.0002\nv 0.05 0 0.0002\n\
         v 0.05 0.05 0.0002\nv 0 0.05 0.0002\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\n\
         f 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n",
    );
    let m = manifest(
        dir.path(),
        "[[object]]\nname = \"flat\"\nshape = { type = \"mesh\", path = \"flat.obj\" }\n\
         mass_kg = 0.1\n",
    );
    let o = grasp(&[
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        &m,
        "--trials",
        "1",
    ]);
    assert_fails(
        &o,
        &["set.toml", "object 'flat' cannot be simulated", "half[2]"],
    );
    // A density times a large volume: the mass is held to mass_kg's bound.
    let m = manifest(
        dir.path(),
        "[[object]]\nname = \"crate\"\nshape = { type = \"box\", size = [0.9, 0.9, 0.9] }\n\
         density_kg_m3 = 500\n",
    );
    let o = grasp(&["objects", "list", "--set", &m]);
    assert_fails(&o, &["crate", "density_kg_m3", "364.5 kg", "0.001..=10 kg"]);
}

#[test]
fn a_tilted_compound_object_is_never_below_the_table() {
    // proc-3-2 (10 convex parts) ends this lift tilted; its compound bounding box
    // reached 2.7 cm under the table top.
    let o = grasp(&["--json", "sim", "--object", "proc-3-2", "--close", "--lift"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let lift = &v["lift"];
    let z = lift["object_lowest_z"].as_f64().unwrap();
    assert!(z > -0.003, "object_lowest_z {z} is below the table: {lift}");
}

#[test]
fn benchmarks_refuse_figures_that_measure_nothing() {
    let o = grasp(&[
        "bench",
        "sim",
        "--seconds",
        "1e-9",
        "--envs",
        "2",
        "--threads",
        "1",
    ]);
    assert_fails(&o, &["no episode finished in --seconds 1e-9"]);
    let o = grasp(&["bench", "sim", "--seconds", &format!("{}", 1e300)]);
    assert_fails(&o, &["--seconds 1e300 must be in (0, 3600]"]);
    assert!(stderr(&o).len() < 200, "{}", stderr(&o));
    let o = grasp(&["bench", "env", "--envs", "100000"]);
    assert_fails(&o, &["--envs 100000 must be in 1..=1024"]);
    let o = grasp(&[
        "bench",
        "env",
        "--seconds",
        "1e-9",
        "--envs",
        "1",
        "--threads",
        "1",
        "--objects",
        "box_sugar",
    ]);
    assert_fails(
        &o,
        &["built-in: no environment step finished in --seconds 1e-9"],
    );
    let o = grasp(&[
        "bench",
        "env",
        "--compare",
        "/nonexistent/b.toml",
        "--seconds",
        "1",
    ]);
    assert_fails(&o, &["/nonexistent/b.toml"]);
    // Physics that breaks at once: every episode fails, no throughput is printed.
    let dir = tempfile::tempdir().unwrap();
    let sim =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/sim.toml")).unwrap();
    let broken = write(dir.path(), "broken.toml", &broken_sim(&sim));
    let o = grasp(&[
        "bench",
        "sim",
        "--config",
        broken.to_str().unwrap(),
        "--seconds",
        "0.5",
        "--envs",
        "2",
        "--threads",
        "1",
    ]);
    assert_fails(&o, &["broken.toml", "ended in a physics failure"]);
}

/// `configs/sim.toml` with a speed limit no motion stays under: the failure detection
/// declares every episode broken at its first step.
fn broken_sim(sim: &str) -> String {
    sim.lines()
        .map(|l| {
            if l.starts_with("max_speed") {
                "max_speed = 1e-6".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn sizes_and_integers_out_of_range_are_clean_errors() {
    for n in ["18446744073709551615", "1000000000"] {
        let o = grasp(&["objects", "list", "--set", "procedural", "--count", n]);
        assert_fails(&o, &["--count", "must be in 1..=10000"]);
    }
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let cfg = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/cartpole.toml");
    for args in [
        &["--seed", "18446744073709551615", "train", "--config", cfg][..],
        &[
            "train",
            "--config",
            cfg,
            "--total-timesteps",
            "18446744073709551615",
        ],
    ] {
        let mut a = args.to_vec();
        a.extend(["--out", run.to_str().unwrap()]);
        let o = grasp(&a);
        assert_fails(&o, &["must be at most 9223372036854775807"]);
        assert!(!run.exists(), "a run folder was left");
    }
}

#[test]
fn object_names_sets_and_exports_follow_one_rule() {
    let dir = tempfile::tempdir().unwrap();
    // A stream object is not in the unseen set.
    let o = grasp(&["objects", "show", "proc-0-100", "--set", "unseen"]);
    assert_fails(&o, &["no object `proc-0-100` in set `unseen`"]);
    // A set inside a name list is named as a set.
    let o = grasp(&[
        "eval",
        "--policy",
        "baseline2",
        "--objects",
        "procedural,box_sugar",
    ]);
    assert_fails(&o, &["`procedural` is an object set, not an object name"]);
    // `procedural` is stream seed 0 everywhere; --seed seeds episodes, not objects.
    let o = grasp(&[
        "--seed",
        "3",
        "objects",
        "list",
        "--set",
        "procedural",
        "--count",
        "2",
    ]);
    assert_fails(&o, &["--stream-seed"]);
    let o = grasp(&[
        "--json",
        "objects",
        "list",
        "--set",
        "procedural",
        "--count",
        "2",
        "--stream-seed",
        "3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("proc-3-1"));
    // .stl gets STL, another extension is refused.
    let stl = dir.path().join("p.stl");
    let o = grasp(&[
        "objects",
        "export",
        "box_sugar",
        "--out",
        stl.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&stl).unwrap();
    let mut cur = std::io::Cursor::new(&bytes);
    let mesh = stl_io::read_stl(&mut cur).expect("an STL file");
    assert!(mesh.faces.len() >= 12);
    let o = grasp(&["objects", "show", stl.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bad = dir.path().join("p.ply");
    let o = grasp(&[
        "objects",
        "export",
        "box_sugar",
        "--out",
        bad.to_str().unwrap(),
    ]);
    assert_fails(&o, &["must end in .obj or .stl"]);
    assert!(!bad.exists());
}

#[test]
fn lift_statistics_of_no_lift_are_plain_zeros() {
    let s = grasp::eval::LiftStats::of(std::iter::empty());
    for v in [s.mean_grip_effort, s.mean_grip_held, s.mean_grip_dropped] {
        assert!(v == 0.0 && v.is_sign_positive(), "{v}");
    }
    assert_eq!(format!("{:.2}", s.mean_grip_dropped), "0.00");
}

/// A copy of the shipped policy whose config.toml names `sim_config`.
fn policy_trained_with(dir: &std::path::Path, sim_config: &str) -> std::path::PathBuf {
    let src =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/policies/quick_gru_m3_pca5");
    let dst = dir.join("policy");
    std::fs::create_dir_all(&dst).unwrap();
    for e in std::fs::read_dir(&src).unwrap() {
        let e = e.unwrap();
        if e.path().is_file() {
            std::fs::copy(e.path(), dst.join(e.file_name())).unwrap();
        }
    }
    let cfg = std::fs::read_to_string(dst.join("config.toml")).unwrap();
    let line = "sim_config = \"configs/sim.toml\"";
    assert!(cfg.contains(line));
    let cfg = cfg.replace(line, &format!("sim_config = \"{sim_config}\""));
    std::fs::write(dst.join("config.toml"), cfg).unwrap();
    dst
}

#[test]
fn eval_uses_the_simulator_config_a_checkpoint_was_trained_with() {
    let dir = tempfile::tempdir().unwrap();
    let eval = |p: &std::path::Path, extra: &[&str]| {
        let mut a = vec![
            "eval",
            "--policy",
            p.to_str().unwrap(),
            "--objects",
            "box_sugar",
            "--trials",
            "1",
        ];
        a.extend(extra);
        let o = grasp(&a);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    // Trained with another simulator config: evaluated in it, and told so.
    let sim = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/configs/levers/sim_rapier_rows.toml"
    );
    let p = policy_trained_with(dir.path(), sim);
    let err = eval(&p, &[]);
    assert!(
        err.contains("simulator config: ") && err.contains("sim_rapier_rows.toml"),
        "{err}"
    );
    // --sim-config chooses another, with a warning.
    let err = eval(&p, &["--sim-config", "configs/sim.toml"]);
    assert!(
        err.contains("warning: checkpoint") && err.contains("sim_rapier_rows.toml"),
        "{err}"
    );
    // A file that cannot be read here: a warning naming it.
    let other = dir.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    let p = policy_trained_with(&other, "/nonexistent/trained_sim.toml");
    let err = eval(&p, &[]);
    assert!(
        err.contains("/nonexistent/trained_sim.toml") && err.contains("cannot be read"),
        "{err}"
    );
}
