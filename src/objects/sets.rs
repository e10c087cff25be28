//! The `--objects` resolver: set names, folders, manifests, mesh files and name lists
//! into validated specs ([`resolve_specs`]) and built objects ([`load_objects`]). The
//! built-in sets are in [`super::builtin`], building a spec in [`super::build`]; both are
//! re-exported here.
//!
//! # The `--objects` argument ([`resolve_specs`])
//!
//! `train`, `unseen`, `all`; `procedural` (the first 64 objects of the procedural stream,
//! see [`super::stream`]); `validation` (24 objects of another stream seed, the set
//! checkpoints are chosen on); `real-validation` and `real` (household objects nobody here
//! made, at real masses: the validation set's real slice and the real report set, the
//! manifests in `assets/meshes/real/`, see [`REAL_SETS`]); a folder of `.obj`/`.stl` files (one object each, named by
//! the file stem, default density and friction); a manifest `.toml` (see [`super::spec`]);
//! a single `.obj`/`.stl` file; or a comma-separated list of built-in object names and
//! stream objects (`proc-<seed>-<index>`).

use super::spec::{load_manifest, ObjectSpec, ShapeSpec};
use super::{Object, ObjectError};
use std::path::{Path, PathBuf};

pub use super::build::{
    build, build_all, prepare, primitive_mesh, BuildContext, Prepared, ResolvedSpec,
    BUILTIN_MASS_RANGE, NEAR_CONVEX_RATIO,
};
pub use super::builtin::{builtin_object, builtin_set, train_set, unseen_set, BUILTIN_SETS};

/// Resolves an `--objects` argument and builds the objects.
pub fn load_objects(arg: &str, ctx: &BuildContext) -> Result<Vec<Object>, ObjectError> {
    build_all(&resolve_specs(arg)?, ctx)
}

/// The sets of real household objects: each name and its manifest under the project's
/// `assets/` folder. `real-validation` is the validation set's real slice (recipes and
/// checkpoints are chosen on it with `validation`); `real` is the real report set.
pub const REAL_SETS: [(&str, &str); 2] = [
    ("real-validation", "meshes/real/validation.toml"),
    ("real", "meshes/real/report.toml"),
];

/// The manifest of a shipped set, found from any working folder by the one rule for
/// shipped files ([`crate::util::assets::shipped`]).
fn shipped_asset(rel: &str) -> Result<PathBuf, ObjectError> {
    let path = Path::new("assets").join(rel);
    crate::util::assets::shipped(&path, "--objects").map_err(|e| ObjectError::Io {
        path: path.display().to_string(),
        error: std::io::Error::new(std::io::ErrorKind::NotFound, e.to_string()),
    })
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, &cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Up to five known names close to `name` (edit distance or substring).
pub fn suggest(name: &str) -> Vec<String> {
    let mut known: Vec<String> = BUILTIN_SETS.iter().map(|s| s.to_string()).collect();
    known.extend(REAL_SETS.iter().map(|(s, _)| s.to_string()));
    known.extend(
        builtin_set("all")
            .unwrap_or_default()
            .into_iter()
            .map(|s| s.name),
    );
    let lim = (name.chars().count() / 3).max(2);
    let mut scored: Vec<(usize, String)> = known
        .into_iter()
        .filter_map(|k| {
            let d = levenshtein(name, &k);
            let sub = name.len() >= 3 && (k.contains(name) || name.contains(&k));
            // A misspelt prefix: `bottel` for `bottle_tall`.
            let prefix: String = k.chars().take(name.chars().count()).collect();
            let sub = sub || (name.len() >= 4 && levenshtein(name, &prefix) <= 2);
            (d <= lim || sub).then_some((if sub { d.min(lim) } else { d }, k))
        })
        .collect();
    scored.sort();
    scored.into_iter().take(5).map(|(_, k)| k).collect()
}

fn unknown(name: &str) -> ObjectError {
    let sugg = suggest(name);
    let mut hint = format!(
        "known sets are {}, procedural, validation, {} (or a folder of .obj/.stl files, a manifest .toml, a mesh file, or a comma-separated list of built-in object names; `grasp objects list` shows them)",
        BUILTIN_SETS.join(", "),
        REAL_SETS.map(|(s, _)| s).join(", ")
    );
    if !sugg.is_empty() {
        hint.push_str(&format!("; did you mean {}?", sugg.join(", ")));
    }
    ObjectError::Unknown {
        name: name.to_string(),
        hint,
    }
}

fn is_mesh_file(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj") || e.eq_ignore_ascii_case("stl"))
}

fn mesh_spec(path: &Path) -> ObjectSpec {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "mesh".into());
    let name: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    ObjectSpec::new(
        name,
        ShapeSpec::Mesh {
            path: path.to_path_buf(),
            scale: 1.0,
        },
    )
}

fn check_unique(specs: &[ResolvedSpec], source: &str) -> Result<(), ObjectError> {
    let mut seen: std::collections::HashMap<&str, &ResolvedSpec> = Default::default();
    let file = |s: &ResolvedSpec| match &s.spec.shape {
        ShapeSpec::Mesh { path, .. } => Some(path.display().to_string()),
        _ => None,
    };
    for s in specs {
        if let Some(first) = seen.insert(s.spec.name.as_str(), s) {
            let detail = match (file(first), file(s)) {
                (Some(a), Some(b)) if a != b => format!(": {a} and {b} both give it"),
                _ => String::new(),
            };
            return Err(ObjectError::DuplicateName {
                name: s.spec.name.clone(),
                source_name: source.to_string(),
                detail,
            });
        }
    }
    Ok(())
}

/// The files an `--objects`-style argument reads: the manifest or mesh file it names and
/// the mesh files of its objects (none for built-in sets and names): no output may
/// replace them. An argument that does not resolve gives none (its error comes later).
pub fn files_read(arg: &str) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    let p = std::path::Path::new(arg);
    if p.is_file() {
        files.push(p.to_path_buf());
    }
    if let Ok(specs) = resolve_specs(arg) {
        for s in specs {
            if let crate::objects::ShapeSpec::Mesh { path, .. } = s.spec.shape {
                files.push(path);
            }
        }
    }
    files
}

/// Resolves an `--objects` argument (see the module docs) into validated specs.
pub fn resolve_specs(arg: &str) -> Result<Vec<ResolvedSpec>, ObjectError> {
    let arg = arg.trim();
    if arg.is_empty() {
        return Err(unknown(arg));
    }
    let builtin = |s: ObjectSpec| ResolvedSpec {
        spec: s,
        builtin: true,
        source: "built-in".into(),
    };
    if let Some(set) = builtin_set(arg) {
        return Ok(set.into_iter().map(builtin).collect());
    }
    if arg == super::stream::STREAM_SET {
        return Ok(super::stream::stream_specs(0, super::stream::DEFAULT_COUNT));
    }
    if arg == super::stream::VALIDATION_SET {
        return Ok(super::stream::stream_specs(
            super::stream::VALIDATION_SEED,
            super::stream::VALIDATION_COUNT,
        ));
    }
    if let Some((_, rel)) = REAL_SETS.iter().find(|(name, _)| *name == arg) {
        let manifest = shipped_asset(rel)?;
        return resolve_specs(&manifest.to_string_lossy());
    }
    let path = Path::new(arg);
    let src = path.display().to_string();
    let looks_like_path = arg.contains('/')
        || arg.contains('\\')
        || is_mesh_file(path)
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if path.is_dir() {
        let entries = std::fs::read_dir(path).map_err(|error| ObjectError::Io {
            path: src.clone(),
            error,
        })?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_mesh_file(p))
            .collect();
        files.sort();
        let specs: Vec<ResolvedSpec> = files
            .iter()
            .map(|f| ResolvedSpec {
                spec: mesh_spec(f),
                builtin: false,
                source: src.clone(),
            })
            .collect();
        if specs.is_empty() {
            return Err(ObjectError::EmptySet {
                source_name: format!("folder {src} (no .obj or .stl files)"),
            });
        }
        check_unique(&specs, &src)?;
        return Ok(specs);
    }
    if path.is_file() {
        if is_mesh_file(path) {
            return Ok(vec![ResolvedSpec {
                spec: mesh_spec(path),
                builtin: false,
                source: src,
            }]);
        }
        let specs: Vec<ResolvedSpec> = load_manifest(path)?
            .into_iter()
            .map(|s| ResolvedSpec {
                spec: s,
                builtin: false,
                source: src.clone(),
            })
            .collect();
        if specs.is_empty() {
            return Err(ObjectError::EmptySet {
                source_name: format!("manifest {src} (no [[object]] tables)"),
            });
        }
        check_unique(&specs, &src)?;
        return Ok(specs);
    }
    if looks_like_path {
        return Err(ObjectError::Io {
            path: src,
            error: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file or folder"),
        });
    }
    let all = builtin_set("all").unwrap_or_default();
    let mut out = Vec::new();
    for name in arg.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if BUILTIN_SETS.contains(&name)
            || REAL_SETS.iter().any(|(s, _)| *s == name)
            || name == super::stream::STREAM_SET
            || name == super::stream::VALIDATION_SET
        {
            return Err(ObjectError::SetInList {
                name: name.to_string(),
            });
        }
        if let Some((seed, index)) = super::stream::parse_name(name) {
            out.push(super::stream::stream_spec(seed, index));
            continue;
        }
        let s = all
            .iter()
            .find(|s| s.name == name)
            .ok_or_else(|| unknown(name))?;
        out.push(builtin(s.clone()));
    }
    if out.is_empty() {
        return Err(unknown(arg));
    }
    check_unique(&out, "the name list")?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::decomp::DecompParams;
    use crate::objects::spec::ObjectKind;
    use crate::objects::HullSource;
    use approx::assert_relative_eq;
    use std::collections::HashSet;

    fn prepared(set: &str) -> Vec<Prepared> {
        resolve_specs(set)
            .unwrap()
            .iter()
            .map(|s| prepare(s).unwrap_or_else(|e| panic!("{e}")))
            .collect()
    }

    #[test]
    fn set_counts_match_the_paper() {
        let train = train_set();
        assert_eq!(train.len(), 61);
        let count = |k: ObjectKind| train.iter().filter(|s| s.kind == k).count();
        assert_eq!(count(ObjectKind::YcbLike), 11);
        assert_eq!(count(ObjectKind::ShapenetLike), 14);
        assert_eq!(count(ObjectKind::Primitive), 5);
        assert_eq!(count(ObjectKind::Egad), 31);
        let boxes = train
            .iter()
            .filter(|s| matches!(s.shape, ShapeSpec::Box { .. }))
            .count();
        let cyl = train
            .iter()
            .filter(|s| matches!(s.shape, ShapeSpec::Cylinder { .. }))
            .count();
        assert_eq!((boxes, cyl), (4, 1));
        let unseen = unseen_set();
        assert!(unseen.len() >= 14);
        let names: HashSet<_> = train.iter().map(|s| s.name.clone()).collect();
        assert!(unseen.iter().all(|s| !names.contains(&s.name)));
        let all = builtin_set("all").unwrap();
        let unique: HashSet<_> = all.iter().map(|s| &s.name).collect();
        assert_eq!(unique.len(), all.len());
    }

    #[test]
    fn unseen_uses_other_families_and_seeds() {
        let family = |s: &ObjectSpec| match &s.shape {
            ShapeSpec::Procedural {
                generator,
                seed,
                params,
                ..
            } => format!("{generator}:{seed}:{params:?}"),
            other => format!("{other:?}"),
        };
        let train: HashSet<String> = train_set().iter().map(family).collect();
        for s in unseen_set() {
            assert!(
                !train.contains(&family(&s)),
                "{} duplicates a train shape",
                s.name
            );
        }
    }

    #[test]
    fn every_builtin_is_watertight_graspable_and_light() {
        for p in prepared("all") {
            let name = &p.spec.spec.name;
            p.mesh.validate(name).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                (0.05..=0.6).contains(&p.mass_kg),
                "{name}: mass {} kg",
                p.mass_kg
            );
            let e = p.mesh.aabb().unwrap().extents();
            let min_xy = e[0].min(e[1]);
            assert!(
                (0.02..=0.12).contains(&min_xy),
                "{name}: narrowest horizontal width {min_xy} m"
            );
            assert!(e.iter().all(|&x| x <= 0.30), "{name}: extents {e:?}");
            assert!(e[2] >= 0.01, "{name}: height {}", e[2]);
            // Object frame: bottom centre of the bounding box at the origin.
            let bb = p.mesh.aabb().unwrap();
            assert!(bb.min[2].abs() < 1e-12, "{name}");
            assert!((bb.min[0] + bb.max[0]).abs() < 1e-9, "{name}");
            assert!((bb.min[1] + bb.max[1]).abs() < 1e-9, "{name}");
            assert!(p.com[2] > 0.0 && p.com[2] < bb.max[2], "{name}");
            assert!((0.5..=1.0).contains(&p.spec.spec.friction), "{name}");
        }
    }

    #[test]
    fn builtins_are_deterministic() {
        let a = prepared("egad_c4_d1,banana,vase");
        let b = prepared("egad_c4_d1,banana,vase");
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.mesh, y.mesh);
            assert_eq!(x.mass_kg, y.mass_kg);
        }
    }

    #[test]
    fn primitive_mass_properties_are_exact() {
        let p = &prepared("box_sugar")[0];
        let prim = p.primitive.unwrap();
        assert_relative_eq!(p.volume_m3, 0.09 * 0.045 * 0.175, epsilon = 1e-12);
        assert_relative_eq!(p.mass_kg, 700.0 * p.volume_m3, epsilon = 1e-12);
        assert_relative_eq!(p.com[2], 0.0875, epsilon = 1e-12);
        assert_relative_eq!(
            p.inertia[0][0],
            p.mass_kg * (0.045f64.powi(2) + 0.175f64.powi(2)) / 12.0,
            epsilon = 1e-12
        );
        assert_eq!(prim.half_height_total(), 0.0875);
    }

    #[test]
    fn resolver_errors_are_helpful() {
        let e = resolve_specs("trian").unwrap_err().to_string();
        assert!(
            e.contains("train, unseen, all") && e.contains("did you mean train"),
            "{e}"
        );
        let e = resolve_specs("bottle_tal,mug").unwrap_err().to_string();
        assert!(e.contains("bottle_tall"), "{e}");
        let e = resolve_specs("no/such/dir").unwrap_err().to_string();
        assert!(e.contains("no/such/dir"), "{e}");
        let e = resolve_specs("mug,mug").unwrap_err().to_string();
        assert!(e.contains("duplicate"), "{e}");
        assert_eq!(resolve_specs("mug, banana").unwrap().len(), 2);
    }

    #[test]
    fn real_sets_load_from_the_shipped_manifests_at_real_masses() {
        let mut names = HashSet::new();
        for (set, min_count) in [("real-validation", 11), ("real", 12)] {
            let specs = resolve_specs(set).unwrap_or_else(|e| panic!("{set}: {e}"));
            assert!(specs.len() >= min_count, "{set}: {} objects", specs.len());
            for rs in &specs {
                let s = &rs.spec;
                // One object in one set only: the report set shares nothing with validation.
                assert!(names.insert(s.name.clone()), "{set}: {} twice", s.name);
                let m = s
                    .mass_kg
                    .unwrap_or_else(|| panic!("{}: no real mass", s.name));
                assert!((0.02..=1.0).contains(&m), "{}: {m} kg", s.name);
                assert!(s.friction <= 1.0);
                let p = prepare(rs).unwrap_or_else(|e| panic!("{}: {e}", s.name));
                let e = p.mesh.aabb().unwrap().extents();
                assert!(e[0].min(e[1]) <= 0.12, "{}: {e:?}", s.name);
                assert!(e.iter().all(|&x| x <= 0.3), "{}: {e:?}", s.name);
            }
        }
        // In a name list a set name is refused, as the other sets' are.
        assert!(resolve_specs("mug,real").is_err());
    }

    #[test]
    fn levenshtein_distance() {
        assert_eq!(levenshtein("kitten", "sitting"), 3);
        assert_eq!(levenshtein("", "abc"), 3);
        assert_eq!(levenshtein("mug", "mug"), 0);
    }

    #[test]
    fn vhacd_cache_is_reused_and_rebuilt_when_stale_or_corrupt() {
        use crate::objects::CacheStatus;
        let dir = tempfile::tempdir().unwrap();
        let ctx = BuildContext::with_cache_dir(dir.path());
        let spec = &resolve_specs("bottle_water").unwrap()[0];
        let file = dir.path().join("hulls/bottle_water.hulls.json");
        let a = build(spec, &ctx).unwrap();
        assert_eq!(a.hull_source, HullSource::Vhacd(CacheStatus::Built));
        assert!(file.is_file());
        let b = build(spec, &ctx).unwrap();
        assert_eq!(b.hull_source, HullSource::Vhacd(CacheStatus::Hit));
        assert_eq!(a.hulls, b.hulls);
        // Corrupt file: rebuilt, same result (VHACD is deterministic), file repaired.
        std::fs::write(&file, b"{ this is not json").unwrap();
        let c = build(spec, &ctx).unwrap();
        assert_eq!(c.hull_source, HullSource::Vhacd(CacheStatus::Rebuilt));
        assert_eq!(a.hulls, c.hulls);
        assert_eq!(
            build(spec, &ctx).unwrap().hull_source,
            HullSource::Vhacd(CacheStatus::Hit)
        );
        // Stale file (other parameters): rebuilt.
        let ctx2 = BuildContext {
            decomp: DecompParams {
                max_hulls: 4,
                ..ctx.decomp
            },
            ..ctx.clone()
        };
        let d = build(spec, &ctx2).unwrap();
        assert_eq!(d.hull_source, HullSource::Vhacd(CacheStatus::Rebuilt));
        assert!(d.hulls.len() <= 4);
    }

    #[test]
    fn vhacd_hulls_cover_the_object() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = BuildContext::with_cache_dir(dir.path());
        for name in ["bottle_tall", "egad_c5_d2", "vase"] {
            let o = build(&resolve_specs(name).unwrap()[0], &ctx).unwrap();
            assert!(matches!(o.hull_source, HullSource::Vhacd(_)), "{name}");
            assert!(o.hulls.len() <= ctx.decomp.max_hulls as usize, "{name}");
            let hull_vol: f64 = o
                .hulls
                .iter()
                .map(|h| h.mesh().unwrap().signed_volume())
                .sum();
            let ratio = hull_vol / o.volume_m3;
            assert!(
                (0.9..1.35).contains(&ratio),
                "{name}: hull/mesh volume {ratio}"
            );
            let pts: Vec<[f64; 3]> = o.hulls.iter().flat_map(|h| h.points.clone()).collect();
            let hb = crate::objects::Aabb::of_points(&pts).unwrap();
            for k in 0..3 {
                assert!((hb.min[k] - o.bbox.min[k]).abs() < 0.006, "{name} {hb:?}");
                assert!((hb.max[k] - o.bbox.max[k]).abs() < 0.006, "{name} {hb:?}");
            }
        }
    }

    #[test]
    fn shared_shapes_match_the_object() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = BuildContext::with_cache_dir(dir.path());
        for name in [
            "cylinder_wood",
            "capsule_pill",
            "mug",
            "egad_c0_d0",
            "box_gelatin",
        ] {
            let o = build(&resolve_specs(name).unwrap()[0], &ctx).unwrap();
            let shape = o.to_shared_shape().unwrap();
            let aabb = shape.compute_local_aabb();
            let (lo, hi) = (aabb.mins, aabb.maxs);
            let got = [[lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]];
            for k in 0..3 {
                assert!(
                    (got[0][k] as f64 - o.bbox.min[k]).abs() < 2e-3,
                    "{name} {got:?} {:?}",
                    o.bbox
                );
                assert!(
                    (got[1][k] as f64 - o.bbox.max[k]).abs() < 2e-3,
                    "{name} {got:?} {:?}",
                    o.bbox
                );
            }
            let d = o.collider_desc();
            assert_eq!(d.hulls.len(), o.hulls.len());
            assert_eq!(d.primitive.is_some(), o.primitive.is_some());
            assert_eq!(d.mass_kg, o.mass_kg);
        }
    }

    #[test]
    fn user_mesh_folder_and_manifest() {
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/objects");
        let dir = tempfile::tempdir().unwrap();
        for f in ["cube.obj", "cube_ascii.stl", "l_block.obj"] {
            std::fs::copy(data.join(f), dir.path().join(f)).unwrap();
        }
        let ctx = BuildContext::with_cache_dir(dir.path().join("cache"));
        let objs = load_objects(&dir.path().display().to_string(), &ctx).unwrap();
        let names: Vec<&str> = objs.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["cube", "cube_ascii", "l_block"]);
        let cube = &objs[0];
        assert_relative_eq!(
            cube.mass_kg,
            0.05f64.powi(3) * super::super::spec::DEFAULT_DENSITY,
            max_relative = 1e-6
        );
        assert_eq!(cube.hull_source, HullSource::Convex);
        assert_relative_eq!(cube.com[2], 0.025, epsilon = 1e-9);
        assert!(matches!(objs[2].hull_source, HullSource::Vhacd(_)));
        assert!(dir.path().join("l_block.obj.hulls.json").is_file());

        let manifest = dir.path().join("set.toml");
        std::fs::write(
            &manifest,
            "[[object]]\nname = \"small\"\nshape = { type = \"mesh\", path = \"cube.obj\", scale = 0.5 }\nmass_kg = 0.2\nfriction = 0.3\n\
             [[object]]\nname = \"b3\"\nshape = { type = \"procedural\", generator = \"bottle\", seed = 3 }\n",
        )
        .unwrap();
        let objs = load_objects(&manifest.display().to_string(), &ctx).unwrap();
        assert_eq!(objs.len(), 2);
        assert_relative_eq!(objs[0].size()[0], 0.025, epsilon = 1e-9);
        assert_eq!(objs[0].mass_kg, 0.2);
        assert_eq!(objs[0].friction, 0.3);
        assert_eq!(objs[1].kind, ObjectKind::User);
    }
}
