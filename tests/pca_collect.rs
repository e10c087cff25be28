//! End-to-end tests of `grasp pca collect` and of the shipped synergy model.

use grasp::robot::Side;
use grasp::synergy::{finger_limits, SynergyModel, PAPER_COMPONENTS};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn grasp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .output()
        .expect("the grasp binary runs")
}

fn collect(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "pca",
        "collect",
        "--samples",
        "24",
        "--seed",
        "1",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = grasp(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

#[test]
fn collect_writes_a_dataset_that_fit_accepts_and_is_reproducible() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.csv");
    let b = dir.path().join("b.csv");
    collect(&a, &["--threads", "2"]);
    collect(&b, &["--threads", "1"]);
    let text = std::fs::read_to_string(&a).unwrap();
    // Same seed, different thread counts: the same bytes.
    assert_eq!(text, std::fs::read_to_string(&b).unwrap());

    // Header: 22 lh_ joints and grasp_type; 24 rows of 23 cells.
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header.len(), 23);
    assert_eq!(header[0], "lh_FFJ4");
    assert_eq!(header[22], "grasp_type");
    let limits = finger_limits(Side::Left);
    let mut rows = 0;
    let mut types = std::collections::BTreeSet::new();
    for l in lines {
        let cells: Vec<&str> = l.split(',').collect();
        assert_eq!(cells.len(), 23, "{l}");
        for (j, c) in cells[..22].iter().enumerate() {
            let v: f64 = c.parse().unwrap();
            let (lo, hi) = limits[j];
            assert!(
                v >= lo && v <= hi,
                "{} = {v} outside [{lo}, {hi}]",
                header[j]
            );
        }
        types.insert(cells[22].to_string());
        rows += 1;
    }
    assert_eq!(rows, 24);
    // Samples cycle through the grasp types.
    assert!(types.len() >= 20, "{types:?}");

    // `pca fit` accepts it (the grasp_type column is ignored).
    let model = dir.path().join("model.json");
    let o = grasp(&[
        "pca",
        "fit",
        a.to_str().unwrap(),
        "--components",
        "3",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(SynergyModel::load(&model).unwrap().n_samples(), 24);

    // Another seed gives other postures.
    let c = dir.path().join("c.csv");
    let o = grasp(&[
        "pca",
        "collect",
        "--samples",
        "24",
        "--seed",
        "2",
        "--out",
        c.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert_ne!(text, std::fs::read_to_string(&c).unwrap());
}

#[test]
fn collect_json_reports_the_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.csv");
    let o = grasp(&[
        "--json",
        "pca",
        "collect",
        "--samples",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["samples"], 3);
    assert!(v["stats"]["attempts"].as_u64().unwrap() >= 3);
}

#[test]
fn collect_bad_inputs_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.csv");
    let o = grasp(&[
        "pca",
        "collect",
        "--samples",
        "0",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--samples"));
    let missing = dir.path().join("missing.toml");
    let o = grasp(&[
        "pca",
        "collect",
        "--samples",
        "1",
        "--sim-config",
        missing.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("missing.toml"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists());
}

fn shipped() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/synergy/model.json")
}

#[test]
fn the_shipped_model_has_ten_plausible_components() {
    let m = SynergyModel::load(&shipped()).unwrap();
    assert!(m.n_components() >= 10);
    let r = m.explained_variance_ratio();
    assert!(r[0] > 0.3, "first component explains {}", r[0]);
    assert!(m.cumulative_ratio()[9] > 0.9);
    assert!(m.n_samples() >= 1000);
    // The embedded copy is the same model.
    assert_eq!(grasp::synergy::default_model(), m);
    // The trainer's choices of n are truncations.
    for n in PAPER_COMPONENTS {
        let t = m.truncated(n).unwrap();
        assert_eq!(t.n_components(), n);
        assert_eq!(t.components(), &m.components()[..n]);
    }
}

#[test]
fn the_shipped_dataset_refits_to_the_shipped_model() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/synergy/poses.csv");
    let d = grasp::synergy::Dataset::load(
        &data,
        &finger_limits(Side::Left),
        &grasp::synergy::LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(d.extras, vec!["grasp_type"]);
    let m = SynergyModel::fit(&d.rows, 10).unwrap();
    let shipped = SynergyModel::load(&shipped()).unwrap();
    for (a, b) in m.eigenvalues().iter().zip(shipped.eigenvalues()) {
        assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-12), "{a} vs {b}");
    }
}
