//! End-to-end tests of `grasp pca` on tiny inputs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn grasp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .output()
        .expect("the grasp binary runs")
}

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pca_ref_input.csv")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The first `rows` data lines of the fixture, with `edit(line_index, cells)` applied to
/// each data line's cells (index 0 = first data line = file line 2).
fn small_csv(
    dir: &Path,
    name: &str,
    rows: usize,
    edit: impl Fn(usize, &mut Vec<String>),
) -> PathBuf {
    let text = std::fs::read_to_string(fixture()).unwrap();
    let mut lines = text.lines();
    let mut out = String::from(lines.next().unwrap());
    out.push('\n');
    for (i, l) in lines.take(rows).enumerate() {
        let mut cells: Vec<String> = l.split(',').map(str::to_string).collect();
        edit(i, &mut cells);
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    let p = dir.join(name);
    std::fs::write(&p, out).unwrap();
    p
}

#[test]
fn fit_writes_a_model_and_prints_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let data = small_csv(dir.path(), "poses.csv", 40, |_, _| {});
    let model = dir.path().join("out/model.json");
    let o = grasp(&[
        "pca",
        "fit",
        data.to_str().unwrap(),
        "--components",
        "3",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("Fitted 3 synergies to 40 postures"), "{out}");
    for k in ["1*", "3*", " 4 ", "22 "] {
        assert!(out.contains(k), "row {k} missing:\n{out}");
    }
    assert!(
        out.contains("1.00000"),
        "cumulative ratio must reach 1:\n{out}"
    );
    assert!(stderr(&o).contains("ignored column(s)") && stderr(&o).contains("object"));
    assert!(
        out.contains("variance of each joint explained by the 3 kept components")
            && out.contains("THJ5"),
        "{out}"
    );
    let m = grasp::synergy::SynergyModel::load(&model).unwrap();
    assert_eq!(m.n_components(), 3);
    assert_eq!(m.n_samples(), 40);
}

#[test]
fn fit_json_parses() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.json");
    let o = grasp(&[
        "--json",
        "pca",
        "fit",
        fixture().to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("stdout is JSON");
    assert_eq!(v["n_components"], 5);
    assert_eq!(v["n_samples"], 200);
    assert_eq!(v["ignored_columns"][0], "object");
    let rows = v["components"].as_array().unwrap();
    assert_eq!(rows.len(), 22);
    let last = rows[21]["cumulative_ratio"].as_f64().unwrap();
    assert!((last - 1.0).abs() < 1e-12);
    let e1 = rows[0]["eigenvalue"].as_f64().unwrap();
    let e2 = rows[1]["eigenvalue"].as_f64().unwrap();
    assert!(e1 >= e2 && e2 > 0.0);
    assert_eq!(rows[4]["kept"], true);
    assert_eq!(rows[5]["kept"], false);
    let per_joint = v["per_joint_explained"].as_object().unwrap();
    assert_eq!(per_joint.len(), 22);
    assert!(per_joint
        .values()
        .all(|x| (0.0..=1.0 + 1e-9).contains(&x.as_f64().unwrap())));
    assert!(model.exists());
}

/// Runs `pca fit` on `path`, expects failure, and returns stderr.
fn fit_fails(path: &Path) -> String {
    let dir = path.parent().unwrap();
    let o = grasp(&[
        "pca",
        "fit",
        path.to_str().unwrap(),
        "--out",
        dir.join("never.json").to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(
        !o.status.success(),
        "expected failure for {}",
        path.display()
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains(path.file_name().unwrap().to_str().unwrap()),
        "{err}"
    );
    assert!(!dir.join("never.json").exists());
    err
}

#[test]
fn bad_csvs_fail_with_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();

    // Column 6 (lh_MFJ3) of data line 4 (file line 5) is not a number.
    let p = small_csv(d, "text.csv", 10, |i, c| {
        if i == 3 {
            c[5] = "abc".into()
        }
    });
    let err = fit_fails(&p);
    assert!(
        err.contains("line 5, column 6 (MFJ3)") && err.contains("'abc'"),
        "{err}"
    );

    let p = small_csv(d, "nan.csv", 10, |i, c| {
        if i == 7 {
            c[20] = "NaN".into()
        }
    });
    let err = fit_fails(&p);
    assert!(
        err.contains("line 9, column 21 (THJ2)") && err.contains("not finite"),
        "{err}"
    );

    // Missing column: drop lh_RFJ1 (column 12) from the header and every row.
    let p = small_csv(d, "missing.csv", 10, |_, c| {
        c.remove(11);
    });
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replacen("lh_RFJ1,", "", 1);
    std::fs::write(&p, text).unwrap();
    let err = fit_fails(&p);
    assert!(
        err.contains("missing finger joint column(s): RFJ1"),
        "{err}"
    );

    // Duplicate after prefix stripping: rename the extra "object" column to rh_ffj2.
    let p = small_csv(d, "dup.csv", 10, |_, c| {
        c[22] = "0.1".into();
    });
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replacen("object", "rh_ffj2", 1);
    std::fs::write(&p, text).unwrap();
    let err = fit_fails(&p);
    assert!(
        err.contains("FFJ2 appears twice") && err.contains("column 3") && err.contains("column 23"),
        "{err}"
    );

    let p = small_csv(d, "ragged.csv", 10, |i, c| {
        if i == 2 {
            c.pop();
        }
    });
    let err = fit_fails(&p);
    assert!(
        err.contains("line 4: 22 fields, but the header has 23"),
        "{err}"
    );

    let p = small_csv(d, "limits.csv", 10, |i, c| {
        if i == 0 {
            c[1] = "2.5".into()
        }
    });
    let err = fit_fails(&p);
    assert!(
        err.contains("line 2, column 2 (FFJ3)") && err.contains("outside"),
        "{err}"
    );

    let p = small_csv(d, "few.csv", 4, |_, _| {});
    let err = fit_fails(&p);
    assert!(
        err.contains("4 data row(s), fewer than the 5 required"),
        "{err}"
    );

    let p = d.join("empty.csv");
    std::fs::write(&p, "").unwrap();
    let err = fit_fails(&p);
    assert!(err.contains("empty"), "{err}");

    let p = d.join("absent.csv");
    let err = fit_fails(&p);
    assert!(err.contains("cannot read dataset"), "{err}");
}

#[test]
fn components_out_of_range_are_refused() {
    let o = grasp(&["pca", "fit", fixture().to_str().unwrap(), "-n", "23"]);
    assert!(!o.status.success());
    assert!(!stderr(&o).contains("panicked"));
    assert!(stderr(&o).contains("23"), "{}", stderr(&o));
}

#[test]
fn show_draws_three_rows_and_prints_ranges() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.json");
    let o = grasp(&[
        "pca",
        "fit",
        fixture().to_str().unwrap(),
        "-n",
        "3",
        "--out",
        model.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));

    let svg = dir.path().join("fig/postures.svg");
    let o = grasp(&[
        "pca",
        "show",
        model.to_str().unwrap(),
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"));
    for k in 1..=3 {
        assert!(
            text.contains(&format!("<g id=\"C{k}\">")),
            "row C{k} missing"
        );
    }
    assert!(!text.contains("<g id=\"C4\">"));

    let o = grasp(&["pca", "show", model.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("FFJ4") && out.contains("THJ1") && out.contains("C3 ("),
        "{out}"
    );

    let o = grasp(&["--json", "pca", "show", model.to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON");
    assert_eq!(v["components"].as_array().unwrap().len(), 3);
    let r = v["components"][0]["joint_ranges"]["FFJ3"]
        .as_array()
        .unwrap();
    assert!(r[0].as_f64().unwrap() <= r[1].as_f64().unwrap());
}

#[test]
fn show_rejects_bad_models() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{\"format_version\": 1,\n \"joints\": [}").unwrap();
    let o = grasp(&["pca", "show", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("bad.json, line 2"), "{err}");
    let o = grasp(&[
        "pca",
        "show",
        dir.path().join("none.json").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("none.json"));
}

#[test]
fn rank_deficient_data_is_refused() {
    // Every data line is one of two postures: the data vary along one direction only.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(fixture()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut out = format!("{}\n", lines[0]);
    for i in 0..30 {
        out.push_str(lines[1 + i % 2]);
        out.push('\n');
    }
    let data = dir.path().join("flat.csv");
    std::fs::write(&data, out).unwrap();
    let err = fit_fails(&data);
    assert!(
        err.contains("only 1 independent direction") && err.contains("ask for at most 1"),
        "{err}"
    );
}
