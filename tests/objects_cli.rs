//! End-to-end tests of `grasp objects`: list, show, export, and their errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/objects")
        .join(name)
}

/// Runs `grasp` with a private hull cache folder.
fn grasp(cache: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grasp"))
        .args(args)
        .env("GRASP_CACHE_DIR", cache)
        .env_remove("GRASP_LOG")
        .output()
        .expect("run grasp")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts a clean failure: non-zero exit, every `needles` in stderr, no panic.
fn assert_fails(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure, got success: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "missing `{n}` in: {err}");
    }
}

#[test]
fn list_train_set_as_json() {
    let cache = tempfile::tempdir().unwrap();
    let o = grasp(
        cache.path(),
        &["objects", "list", "--set", "train", "--json"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 61);
    let kind = |k: &str| rows.iter().filter(|r| r["kind"] == k).count();
    assert_eq!(
        (
            kind("ycb-like"),
            kind("shapenet-like"),
            kind("primitive"),
            kind("egad")
        ),
        (11, 14, 5, 31)
    );
    for r in rows {
        let m = r["mass_g"].as_f64().unwrap();
        assert!((50.0..=600.0).contains(&m), "{r}");
        assert!(r["hulls"].as_u64().unwrap() >= 1, "{r}");
    }
    // Decompositions were cached in the private folder.
    assert!(cache.path().join("hulls/bottle_tall.hulls.json").is_file());
}

#[test]
fn list_names_as_text() {
    let cache = tempfile::tempdir().unwrap();
    let o = grasp(
        cache.path(),
        &["objects", "list", "--objects", "mug,box_sugar"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("mug") && out.contains("box_sugar"), "{out}");
    assert!(out.contains("9.0x4.5x17.5"), "{out}");
    assert!(out.contains("2 objects"), "{out}");
}

#[test]
fn show_text_and_json() {
    let cache = tempfile::tempdir().unwrap();
    let o = grasp(cache.path(), &["objects", "show", "bottle_tall"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    for k in ["size", "mass", "volume", "friction", "hulls", "bbox"] {
        assert!(out.contains(k), "{out}");
    }
    let o = grasp(
        cache.path(),
        &["--json", "objects", "show", "cylinder_wood"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["name"], "cylinder_wood");
    assert_eq!(v["primitive"]["type"], "cylinder");
    let mass = v["mass_kg"].as_f64().unwrap();
    let want = 600.0 * std::f64::consts::PI * 0.03 * 0.03 * 0.1;
    assert!((mass - want).abs() < 1e-9, "{mass}");
}

#[test]
fn export_writes_a_watertight_obj() {
    let cache = tempfile::tempdir().unwrap();
    let out = cache.path().join("out/egad.obj");
    let o = grasp(
        cache.path(),
        &[
            "objects",
            "export",
            "egad_c3_d2",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let mesh = grasp::objects::TriMesh::load(&out).unwrap();
    mesh.validate("export").unwrap();
    let bb = mesh.aabb().unwrap();
    assert!(bb.min[2].abs() < 1e-9, "{bb:?}");
}

#[test]
fn user_folder_caches_hulls_next_to_the_mesh() {
    let cache = tempfile::tempdir().unwrap();
    let dir = tempfile::tempdir().unwrap();
    for f in ["cube.obj", "l_block.obj"] {
        std::fs::copy(data(f), dir.path().join(f)).unwrap();
    }
    let d = dir.path().to_str().unwrap();
    let o = grasp(cache.path(), &["--json", "objects", "list", "--set", d]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(rows.as_array().unwrap().len(), 2);
    assert!(dir.path().join("l_block.obj.hulls.json").is_file());
    // A corrupt cache is rebuilt with a warning, not an error.
    std::fs::write(dir.path().join("l_block.obj.hulls.json"), "garbage").unwrap();
    let o = grasp(cache.path(), &["objects", "show", "l_block", "--set", d]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("corrupt hull cache"), "{}", stderr(&o));
}

#[test]
fn bad_meshes_fail_naming_the_file() {
    let cache = tempfile::tempdir().unwrap();
    for (file, what) in [
        ("empty.obj", "empty"),
        ("nan.obj", "NaN"),
        ("open_box.obj", "not watertight"),
        ("huge.obj", "too large"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::copy(data(file), dir.path().join(file)).unwrap();
        let o = grasp(
            cache.path(),
            &["objects", "list", "--set", dir.path().to_str().unwrap()],
        );
        assert_fails(&o, &[file, what]);
    }
    let o = grasp(
        cache.path(),
        &[
            "objects",
            "show",
            "/no/such/mesh.obj",
            "--set",
            "/no/such/mesh.obj",
        ],
    );
    assert_fails(&o, &["/no/such/mesh.obj"]);
}

#[test]
fn unknown_names_and_bad_manifests_fail_cleanly() {
    let cache = tempfile::tempdir().unwrap();
    let o = grasp(cache.path(), &["objects", "list", "--set", "trian"]);
    assert_fails(&o, &["train, unseen, all", "did you mean train"]);
    let o = grasp(cache.path(), &["objects", "show", "bottel_tall"]);
    assert_fails(&o, &["bottel_tall", "did you mean bottle_tall"]);

    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("set.toml");
    std::fs::write(
        &manifest,
        "[[object]]\nname = \"slippery\"\nshape = { type = \"sphere\", radius = 0.03 }\nfriction = 1.5\n",
    )
    .unwrap();
    let m = manifest.to_str().unwrap();
    let o = grasp(cache.path(), &["objects", "list", "--set", m]);
    assert_fails(&o, &["set.toml", "friction", "1.5"]);

    std::fs::write(
        &manifest,
        "[[object]]\nname = \"x\"\nshape = { type = \"cone\" }\n",
    )
    .unwrap();
    let o = grasp(cache.path(), &["objects", "list", "--set", m]);
    assert_fails(&o, &["set.toml", "line 3"]);
}

#[test]
fn export_to_an_unwritable_path_fails() {
    let cache = tempfile::tempdir().unwrap();
    let blocker = cache.path().join("file");
    std::fs::write(&blocker, "x").unwrap();
    let out = blocker.join("sub/x.obj");
    let o = grasp(
        cache.path(),
        &["objects", "export", "mug", "--out", out.to_str().unwrap()],
    );
    assert_fails(&o, &["x.obj"]);
}

#[test]
fn help_has_examples() {
    let cache = tempfile::tempdir().unwrap();
    let o = grasp(cache.path(), &["objects", "--help"]);
    assert!(o.status.success());
    assert!(stdout(&o).contains("grasp objects list --set train"));
}

#[test]
fn the_procedural_stream_lists_exports_and_checks_its_flags() {
    let cache = tempfile::tempdir().unwrap();
    let list = |seed: &str| {
        let o = grasp(
            cache.path(),
            &[
                "objects",
                "list",
                "--set",
                "procedural",
                "--count",
                "5",
                "--stream-seed",
                seed,
                "--json",
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let rows: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        rows.as_array().unwrap().clone()
    };
    let a = list("4");
    assert_eq!(a.len(), 5);
    assert_eq!(a[3]["name"], "proc-4-3");
    assert!(a.iter().all(|r| r["kind"] == "procedural"));
    for r in &a {
        let s: Vec<f64> = r["size_cm"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        // 3-12 cm across the grasp axis (rounded to 1 mm), at most 25 cm long.
        assert!((2.95..=12.05).contains(&s[0].min(s[1])), "{r}");
        assert!(s.iter().all(|&x| x <= 25.05), "{r}");
        assert!(
            (30.0..=600.0).contains(&r["mass_g"].as_f64().unwrap()),
            "{r}"
        );
    }
    // Reproducible from the seed; another seed, other objects.
    assert_eq!(a, list("4"));
    assert_ne!(a[0]["size_cm"], list("5")[0]["size_cm"]);
    // Any stream object by name.
    let out = cache.path().join("p.obj");
    let o = grasp(
        cache.path(),
        &[
            "objects",
            "export",
            "proc-4-3",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&out).unwrap().contains("proc-4-3"));
    let o = grasp(
        cache.path(),
        &["objects", "list", "--set", "train", "--count", "3"],
    );
    assert_fails(
        &o,
        &["--count and --stream-seed apply to --set procedural only"],
    );
    let o = grasp(
        cache.path(),
        &["objects", "list", "--set", "procedural", "--count", "0"],
    );
    assert_fails(&o, &["--count 0 must be in 1..=10000"]);
}

#[test]
fn validation_set_is_its_own_stream_seed_and_not_a_list_item() {
    // `validation`: objects 0..24 of stream seed 1000, disjoint from the `procedural` set
    // (stream seed 0) and from the built-in train and unseen names; like a set name, it
    // cannot be one item of a comma-separated list.
    let cache = tempfile::tempdir().unwrap();
    let o = grasp(
        cache.path(),
        &["objects", "list", "--set", "validation", "--json"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let names: Vec<String> = rows
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["name"].as_str().unwrap().to_string())
        .collect();
    let expected: Vec<String> = (0..24).map(|i| format!("proc-1000-{i}")).collect();
    assert_eq!(names, expected);
    let o = grasp(
        cache.path(),
        &["objects", "list", "--set", "box_sugar,validation"],
    );
    assert_fails(&o, &["validation"]);
}
