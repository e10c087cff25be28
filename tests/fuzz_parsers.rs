//! Property tests of every parser of user input: arbitrary bytes and randomly mutated
//! valid inputs never panic, and a rejected input gets an error that names its file.
//!
//! Each property runs `PROPTEST_CASES` cases (default: the count given per target below,
//! a few thousand for the cheap parsers, the whole file in well under a minute in the dev
//! profile). For a longer run:
//!
//! ```text
//! PROPTEST_CASES=200000 cargo test --release --test fuzz_parsers
//! ```
//!
//! The rosbridge message decoder is fuzzed in `tests/ros_backend.rs` (feature `ros`).

use grasp::objects::TriMesh;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::path::{Path, PathBuf};

/// Cases per property: `PROPTEST_CASES` when set, else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn runner(default: u32) -> TestRunner {
    TestRunner::new(Config {
        cases: cases(default),
        failure_persistence: None,
        ..Config::default()
    })
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn read(p: &str) -> Vec<u8> {
    std::fs::read(repo(p)).unwrap_or_else(|e| panic!("{p}: {e}"))
}

/// One edit of a byte string: overwrite, insert, delete or truncate at a position (taken
/// modulo the length, so every edit applies to any input).
#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Insert(usize, u8),
    Delete(usize),
    Truncate(usize),
    /// Copy a byte from one place to another (keeps the input's own vocabulary: digits,
    /// quotes, brackets).
    Copy(usize, usize),
}

/// Bytes that matter to the text formats here.
fn interesting_byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        any::<u8>(),
        prop::sample::select(b"0123456789-+.eE,;:=[]{}\"'#\n\r\t <>/nN\\x".to_vec()),
    ]
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), interesting_byte()).prop_map(|(p, b)| Edit::Set(p, b)),
        2 => (any::<usize>(), interesting_byte()).prop_map(|(p, b)| Edit::Insert(p, b)),
        2 => any::<usize>().prop_map(Edit::Delete),
        1 => any::<usize>().prop_map(Edit::Truncate),
        2 => (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::Copy(a, b)),
    ]
}

/// 1 to 8 edits.
fn edits() -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(edit(), 1..8)
}

/// `seed` with `edits` applied, positions limited to the first `window` bytes.
fn mutate(seed: &[u8], edits: &[Edit], window: usize) -> Vec<u8> {
    let mut v = seed.to_vec();
    for e in edits {
        // Positions within the window and the current length (at least 1).
        let n = v.len().min(window).max(1);
        let len = v.len();
        match *e {
            Edit::Set(p, b) if len > 0 => v[p % n] = b,
            Edit::Insert(p, b) => v.insert((p % n).min(len), b),
            Edit::Delete(p) if len > 0 => {
                v.remove(p % n);
            }
            Edit::Truncate(p) => v.truncate(p % (len + 1)),
            Edit::Copy(a, b) if len > 0 => v[b % n] = v[a % n],
            _ => {}
        }
    }
    v
}

/// Arbitrary bytes, biased towards the formats' own characters.
fn junk() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(interesting_byte(), 0..400)
}

/// Checks one parser on mutated `seed`s (edits in the first `window` bytes) and on junk:
/// `parse` must not panic; an error's text must contain `name` (the file it names).
fn check<T, E: std::fmt::Display>(
    label: &str,
    default_cases: u32,
    seed: &[u8],
    window: usize,
    name: &str,
    parse: impl Fn(&[u8]) -> Result<T, E>,
) {
    let judge = |bytes: &[u8]| -> Result<(), TestCaseError> {
        if let Err(e) = parse(bytes) {
            let text = e.to_string();
            prop_assert!(
                text.contains(name),
                "{label}: the error does not name {name}: {text}"
            );
        }
        Ok(())
    };
    // The seed itself must parse: otherwise the mutations test nothing.
    assert!(
        parse(seed).is_ok(),
        "{label}: the seed does not parse: {}",
        parse(seed).err().unwrap()
    );
    runner(default_cases)
        .run(&edits(), |e| judge(&mutate(seed, &e, window)))
        .unwrap_or_else(|e| panic!("{label} (mutated): {e}"));
    runner(default_cases / 2)
        .run(&junk(), |b| judge(&b))
        .unwrap_or_else(|e| panic!("{label} (junk): {e}"));
}

/// [`check`] for a parser that reads a file: each input is written to `path` first, and
/// errors must name its file name.
fn check_file<T, E: std::fmt::Display>(
    label: &str,
    default_cases: u32,
    seed: &[u8],
    path: &Path,
    parse: impl Fn(&Path) -> Result<T, E>,
) {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    check(label, default_cases, seed, usize::MAX, &name, |b| {
        std::fs::write(path, b).unwrap();
        parse(path)
    });
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn pose_csv() {
    let full = read("assets/synergy/poses.csv");
    let seed: Vec<u8> = text(&full)
        .lines()
        .take(6)
        .flat_map(|l| format!("{l}\n").into_bytes())
        .collect();
    let limits = grasp::synergy::finger_limits(grasp::robot::Side::Left);
    let opts = grasp::synergy::dataset::LoadOptions::default();
    check("pose CSV", 3000, &seed, usize::MAX, "poses.csv", |b| {
        grasp::synergy::dataset::Dataset::parse(Path::new("poses.csv"), &text(b), &limits, &opts)
    });
}

#[test]
fn train_configs() {
    for cfg in ["configs/base.toml", "configs/cartpole.toml"] {
        let seed = read(cfg);
        check(cfg, 1500, &seed, usize::MAX, "train.toml", |b| {
            grasp::train::TrainConfig::parse(Path::new("train.toml"), &text(b))
        });
    }
    // A config inheriting from another (`base = "base.toml"`), read from its file.
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(repo("configs/base.toml"), dir.path().join("base.toml")).unwrap();
    let path = dir.path().join("quick.toml");
    let seed = read("configs/quick.toml");
    check_file(
        "quick.toml",
        1000,
        &seed,
        &path,
        grasp::train::TrainConfig::load,
    );
}

/// The resolved config of the stream recipe spells out every key of every section
/// (`[env.randomization]`, `[env.stream]`, `[env.curriculum]`, `[env.action]`, `[ppo]`,
/// `[policy]`), so mutations reach each of them.
#[test]
fn resolved_configs_with_every_section() {
    let cfg = grasp::train::TrainConfig::load(&repo("configs/stream.toml")).unwrap();
    let seed = cfg.to_toml_string().unwrap();
    for section in ["[env.randomization]", "[env.stream]", "[env.curriculum]"] {
        assert!(seed.contains(section), "{section} missing from {seed}");
    }
    check(
        "resolved stream.toml",
        1500,
        seed.as_bytes(),
        usize::MAX,
        "train.toml",
        |b| grasp::train::TrainConfig::parse(Path::new("train.toml"), &text(b)),
    );
}

#[test]
fn sim_config() {
    let seed = read("configs/sim.toml");
    // Range errors name the field ("sim config: field 'dt' = ..."), syntax errors the
    // file; the commands add the file to both.
    check("sim config", 2000, &seed, usize::MAX, "sim", |b| {
        grasp::sim::SimConfig::parse(Path::new("sim.toml"), &text(b))
    });
}

#[test]
fn experiment_grids() {
    let seed = read("configs/grids/tiny_grid.toml");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.toml");
    check_file("grid", 1500, &seed, &path, |p| {
        grasp::experiment::GridConfig::load(p).map_err(|e| e.to_string())
    });
}

#[test]
fn obj_meshes() {
    let seed = read("tests/data/objects/cube.obj");
    check("OBJ", 3000, &seed, usize::MAX, "m.obj", |b| {
        TriMesh::from_obj_bytes(Path::new("m.obj"), b).and_then(|m| {
            m.validate("m.obj")?;
            m.check_closed("m.obj")?;
            m.check_size("m.obj")?;
            Ok(m)
        })
    });
}

#[test]
fn stl_meshes() {
    let seed = read("tests/data/objects/cube_ascii.stl");
    check("ASCII STL", 2000, &seed, usize::MAX, "m.stl", |b| {
        TriMesh::from_stl_bytes(Path::new("m.stl"), b)
    });
    // Binary STL: an 80-byte header, a triangle count, 50 bytes per triangle.
    let m = TriMesh::from_stl_bytes(Path::new("c.stl"), &seed).unwrap();
    let mut bin = vec![0u8; 80];
    bin.extend((m.triangles.len() as u32).to_le_bytes());
    for t in &m.triangles {
        bin.extend([0u8; 12]);
        for &i in t {
            for x in m.vertices[i as usize] {
                bin.extend((x as f32).to_le_bytes());
            }
        }
        bin.extend([0u8; 2]);
    }
    check("binary STL", 2000, &bin, usize::MAX, "b.stl", |b| {
        TriMesh::from_stl_bytes(Path::new("b.stl"), b)
    });
}

#[test]
fn object_manifests() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo("tests/data/objects/cube.obj"),
        dir.path().join("cube.obj"),
    )
    .unwrap();
    let seed = b"[[object]]\nname = \"my_cube\"\nshape = { type = \"mesh\", path = \
                 \"cube.obj\", scale = 0.05 }\nmass_kg = 0.2\nfriction = 0.8\n\n\
                 [[object]]\nname = \"long_box\"\nshape = { type = \"box\", size = \
                 [0.04, 0.06, 0.2] }\n\n[[object]]\nname = \"bottle_3\"\nshape = { type = \
                 \"procedural\", generator = \"bottle\", seed = 3, params = { radius = 0.03 } }\n";
    let path = dir.path().join("manifest.toml");
    check_file(
        "manifest",
        1500,
        seed,
        &path,
        grasp::objects::spec::load_manifest,
    );
}

#[test]
fn urdf() {
    let seed = read("assets/robots/shadow_hand_left.urdf");
    check("URDF", 600, &seed, usize::MAX, "hand.urdf", |b| {
        grasp::robot::Robot::from_str(
            &text(b),
            Path::new("hand.urdf"),
            grasp::robot::MeshPolicy::Fallback,
        )
    });
}

#[test]
fn checkpoints() {
    let src = repo("assets/policies/quick_gru_m3_pca5");
    let seed = std::fs::read(src.join("checkpoint.safetensors")).unwrap();
    // The header (8-byte length, JSON with the metadata) and the first tensor bytes.
    let header = 8 + u64::from_le_bytes(seed[..8].try_into().unwrap()) as usize;
    let dir = tempfile::tempdir().unwrap();
    for f in ["config.toml", "synergy.json"] {
        std::fs::copy(src.join(f), dir.path().join(f)).unwrap();
    }
    let file = dir.path().join("checkpoint.safetensors");
    check(
        "checkpoint",
        400,
        &seed,
        header + 64,
        "checkpoint.safetensors",
        |b| {
            std::fs::write(&file, b).unwrap();
            grasp::ppo::load_policy(dir.path())
        },
    );
    // config.toml beside a checkpoint, as eval reads it.
    std::fs::write(&file, &seed).unwrap();
    let cfg = std::fs::read(src.join("config.toml")).unwrap();
    let cfg_path = dir.path().join("config.toml");
    check_file("checkpoint config.toml", 1500, &cfg, &cfg_path, |_| {
        grasp::checkpoint::checkpoint_setup(dir.path())
    });
}

#[test]
fn calibration_json() {
    let seed = br#"{"lower": [0.1, 0.2, 0.3, 0.4, 0.5], "upper": [10.0, 11.0, 12.0, 13.0, 14.0], "threshold_fraction": 0.003}"#;
    check("calibration", 3000, seed, usize::MAX, "cal.json", |b| {
        grasp::hardware::calibration::TactileCalibration::parse(Path::new("cal.json"), &text(b))
    });
}

#[test]
fn point_clouds() {
    for (f, name) in [
        ("tests/data/clouds/tetra_ascii.pcd", "c.pcd"),
        ("tests/data/clouds/cube_binary.pcd", "c.pcd"),
    ] {
        let seed = read(f);
        check(f, 2000, &seed, usize::MAX, name, |b| {
            grasp::perception::pointcloud::parse_pcd(Path::new(name), b)
        });
    }
    for (f, name) in [
        ("tests/data/clouds/tetra_ascii.ply", "c.ply"),
        ("tests/data/clouds/cube_binary_le.ply", "c.ply"),
    ] {
        let seed = read(f);
        check(f, 2000, &seed, usize::MAX, name, |b| {
            grasp::perception::pointcloud::parse_ply(Path::new(name), b)
        });
    }
}

#[test]
fn synergy_models_and_metrics() {
    let seed = read("assets/synergy/model.json");
    check(
        "synergy model",
        1500,
        &seed,
        usize::MAX,
        "model.json",
        |b| grasp::synergy::SynergyModel::from_json(Path::new("model.json"), &text(b)),
    );
    let full = read("assets/policies/quick_gru_m3_pca5/metrics.csv");
    let seed: Vec<u8> = text(&full)
        .lines()
        .take(5)
        .flat_map(|l| format!("{l}\n").into_bytes())
        .collect();
    check("metrics.csv", 2000, &seed, usize::MAX, "metrics.csv", |b| {
        grasp::train::metrics::parse_csv(Path::new("metrics.csv"), &text(b))
    });
    // The same rows written with today's header (the physics_failures column).
    let rows = grasp::train::metrics::parse_csv(Path::new("metrics.csv"), &text(&seed)).unwrap();
    let seed = grasp::train::metrics::to_csv(&rows).into_bytes();
    check(
        "metrics.csv (v2)",
        2000,
        &seed,
        usize::MAX,
        "metrics.csv",
        |b| grasp::train::metrics::parse_csv(Path::new("metrics.csv"), &text(b)),
    );
}

#[test]
fn grasp_files() {
    let dir = tempfile::tempdir().unwrap();
    for f in ["box_top_down.json", "box_top_down.toml"] {
        let seed = read(&format!("tests/data/grasps/{f}"));
        let path = dir.path().join(f);
        check_file(f, 1500, &seed, &path, grasp::run::pipeline::load_grasp_file);
    }
}
