//! `grasp eval --perturb FILE` (issue 50, the sensing study): every agent evaluated in the
//! same perturbed conditions, recorded in the JSON, reproducible, and a bad file refused
//! with its name and field.

use std::process::{Command, Output};

fn grasp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("GRASP_LOG")
        .output()
        .expect("run grasp")
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("eval --json prints JSON")
}

#[test]
fn perturbed_evaluation_is_recorded_paired_and_reproducible() {
    let args = [
        "--seed",
        "4",
        "--json",
        "eval",
        "--policy",
        "baseline1,baseline2",
        "--objects",
        "ball_tennis",
        "--trials",
        "3",
        "--threads",
        "1",
        "--perturb",
        "configs/sensing/conditions.toml",
    ];
    let a = json(&grasp(&args));
    let agents = a.as_array().expect("a list of agents");
    assert_eq!(agents.len(), 2);
    for r in agents {
        let c = &r["conditions"];
        assert_eq!(c["placement"]["offset"], 0.01, "{c}");
        assert_eq!(c["randomization"]["enabled"], true, "{c}");
    }
    // The same seed and conditions give the same trials.
    let b = json(&grasp(&args));
    let outcomes = |v: &serde_json::Value| {
        v.as_array()
            .unwrap()
            .iter()
            .map(|r| r["objects"][0]["outcomes"].clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(outcomes(&a), outcomes(&b));
    // Without --perturb the JSON carries no conditions.
    let plain = json(&grasp(&args[..args.len() - 2]));
    assert!(plain[0].get("conditions").is_none(), "{plain}");
}

#[test]
fn a_bad_conditions_file_names_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("far.toml");
    std::fs::write(&f, "[placement]\noffset = 0.3\n").unwrap();
    let o = grasp(&[
        "eval",
        "--policy",
        "baseline1",
        "--objects",
        "ball_tennis",
        "--trials",
        "1",
        "--perturb",
        f.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("far.toml") && err.contains("placement.offset"),
        "{err}"
    );
}
