//! The procedural object stream: an endless sequence of graspable objects, each one
//! deterministic from `(stream seed, index)`, drawn from every generator family of
//! [`super::procedural::GENERATORS`] plus boxes and cylinders.
//!
//! # One object
//! [`stream_spec`] seeds a [`ChaCha8Rng`] with the stream seed and selects the index as
//! its stream (`set_stream`), then:
//! 1. picks a family uniformly (every generator, `box`, `cylinder`);
//! 2. draws every parameter of the generator uniformly in its declared range, and a fresh
//!    generator seed (boxes: three sides in 2-20 cm; cylinders: radius 1-6 cm, height
//!    2-25 cm);
//! 3. rejects the draw if it comes close to an object of the built-in unseen set
//!    ([`is_unseen_like`]) or the generator refuses the combination, and draws again;
//! 4. builds the shape at rest and scales it uniformly so that its narrowest horizontal
//!    width (the grasp axis of a top-down grasp) is a uniform draw in
//!    [`GRASP_WIDTH_M`], with no side longer than [`MAX_LENGTH_M`] (a draw that cannot
//!    meet both is rejected);
//! 5. draws a density log-uniformly in [`DENSITY_KG_M3`] (foam to dense wood and
//!    plastics), and the mass is that density times the scaled volume, clamped into
//!    [`MASS_KG`]; the friction is uniform in [`FRICTION`].
//!
//! Draws whose shape, once scaled, is thinner than [`MIN_THICKNESS_M`] along any axis are
//! rejected too (a 4 mm plate lying flat is not a grasping problem).
//!
//! Objects are named `proc-<seed>-<index>`; [`parse_name`] reads a name back, so any
//! stream object can be shown or exported by name.
//!
//! # Finite views
//! The `--objects procedural` set is the first [`DEFAULT_COUNT`] objects of stream seed 0,
//! and `--objects validation` the first [`VALIDATION_COUNT`] of stream seed
//! [`VALIDATION_SEED`], the set checkpoints are chosen on;
//! `grasp objects list --set procedural --count N --seed S` lists others. Training on the
//! stream (`objects = "procedural"` in a training config) draws a fresh index per object
//! from each episode's seed (see `env::stream`).

use super::build::{prepare, Prepared, ResolvedSpec};
use super::builtin::unseen_set;
use super::procedural::ParamDef;
use super::procedural::GENERATORS;
use super::spec::{ObjectKind, ObjectSpec, ShapeSpec};
use super::ObjectError;
use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// The set name of the stream in `--objects` and training configs.
pub const STREAM_SET: &str = "procedural";

/// Objects in the finite `procedural` set (stream seed 0).
pub const DEFAULT_COUNT: usize = 64;

/// The validation set's name in `--objects`: objects `0..VALIDATION_COUNT` of stream seed
/// [`VALIDATION_SEED`]. It is neither a training set nor a test set: checkpoints and
/// recipes are chosen on it, and the unseen objects and the novel meshes are kept for
/// the report. Its shapes are drawn away from the unseen set's as every stream object's
/// are, and training on the stream (stream seed 0 by default) never draws from this seed.
pub const VALIDATION_SET: &str = "validation";

/// The stream seed of the validation set.
pub const VALIDATION_SEED: u64 = 1000;

/// Objects in the validation set.
pub const VALIDATION_COUNT: usize = 24;

/// Range of the narrowest horizontal width (m): what a Shadow hand spans in a top-down
/// grasp.
pub const GRASP_WIDTH_M: (f64, f64) = (0.03, 0.12);

/// Longest side of a stream object (m).
pub const MAX_LENGTH_M: f64 = 0.25;

/// Mass range (kg).
pub const MASS_KG: (f64, f64) = (0.03, 0.6);

/// Density range (kg/m^3), drawn log-uniformly.
pub const DENSITY_KG_M3: (f64, f64) = (150.0, 1500.0);

/// Smallest extent of a stream object along any axis (m).
pub const MIN_THICKNESS_M: f64 = 0.015;

/// Friction range, drawn uniformly (combined with the hand's by the MIN rule).
pub const FRICTION: (f64, f64) = (0.5, 1.0);

/// Draws rejected before an object falls back to a plain box.
const MAX_DRAWS: usize = 32;

/// A parameter within this fraction of its range from an unseen object's counts as close.
const UNSEEN_TOLERANCE: f64 = 0.15;

/// Every family the stream draws from: the generators, then `box` and `cylinder`.
pub fn families() -> Vec<&'static str> {
    let mut f: Vec<&'static str> = GENERATORS.iter().map(|g| g.name).collect();
    f.extend(["box", "cylinder"]);
    f
}

/// The name of object `index` of stream `seed`.
pub fn name(seed: u64, index: u64) -> String {
    format!("proc-{seed}-{index}")
}

/// `(seed, index)` of a stream object's name, `None` for any other name.
pub fn parse_name(name: &str) -> Option<(u64, u64)> {
    let rest = name.strip_prefix("proc-")?;
    let (s, i) = rest.split_once('-')?;
    Some((s.parse().ok()?, i.parse().ok()?))
}

fn source(seed: u64) -> String {
    format!("procedural stream (seed {seed})")
}

/// Whether `shape` is close to an object of the built-in unseen set: the same generator
/// with every parameter within 15 % of its range of the unseen object's (defaults where a
/// spec does not set one), whatever the generator seed and scale; or a near-spherical
/// superquadric (exponent <= 2.5, axes within 15 % of each other) when the unseen set
/// holds a sphere.
pub fn is_unseen_like(shape: &ShapeSpec, unseen: &[ObjectSpec]) -> bool {
    let ShapeSpec::Procedural {
        generator, params, ..
    } = shape
    else {
        return false;
    };
    let Some(def) = super::procedural::find_generator(generator) else {
        return false;
    };
    let value =
        |p: &BTreeMap<String, f64>, pd: &ParamDef| p.get(pd.name).copied().unwrap_or(pd.default);
    let close_to = |other: &BTreeMap<String, f64>| {
        def.params.iter().all(|pd| {
            (value(params, pd) - value(other, pd)).abs() <= UNSEEN_TOLERANCE * (pd.max - pd.min)
        })
    };
    let has_sphere = unseen
        .iter()
        .any(|u| matches!(u.shape, ShapeSpec::Sphere { .. }));
    if has_sphere && generator == "superquadric" {
        let g = |n: &str| {
            def.params
                .iter()
                .find(|pd| pd.name == n)
                .map_or(f64::NAN, |pd| value(params, pd))
        };
        let axes = [g("rx"), g("ry"), g("rz")];
        let (lo, hi) = axes
            .iter()
            .fold((f64::MAX, 0.0f64), |(lo, hi), &a| (lo.min(a), hi.max(a)));
        if g("exponent") <= 2.5 && hi <= (1.0 + UNSEEN_TOLERANCE) * lo {
            return true;
        }
    }
    unseen.iter().any(|u| match &u.shape {
        ShapeSpec::Procedural {
            generator: g,
            params: p,
            ..
        } => g == generator && close_to(p),
        _ => false,
    })
}

/// One draw of family and shape parameters (unscaled).
fn draw_shape(rng: &mut ChaCha8Rng) -> ShapeSpec {
    let fams = families();
    let family = fams[rng.random_range(0..fams.len())];
    match family {
        "box" => ShapeSpec::Box {
            size: [0; 3].map(|_| rng.random_range(0.02..=0.2)),
        },
        "cylinder" => ShapeSpec::Cylinder {
            radius: rng.random_range(0.01..=0.06),
            height: rng.random_range(0.02..=0.25),
        },
        generator => {
            let def = super::procedural::find_generator(generator).unwrap_or(&GENERATORS[0]);
            let params = def
                .params
                .iter()
                .map(|pd| (pd.name.to_string(), rng.random_range(pd.min..=pd.max)))
                .collect();
            ShapeSpec::Procedural {
                generator: def.name.to_string(),
                seed: rng.next_u64(),
                params,
                scale: 1.0,
            }
        }
    }
}

/// `shape` scaled uniformly by `s`.
fn scaled(shape: ShapeSpec, s: f64) -> ShapeSpec {
    match shape {
        ShapeSpec::Box { size } => ShapeSpec::Box {
            size: size.map(|x| x * s),
        },
        ShapeSpec::Cylinder { radius, height } => ShapeSpec::Cylinder {
            radius: radius * s,
            height: height * s,
        },
        ShapeSpec::Procedural {
            generator,
            seed,
            params,
            scale,
        } => ShapeSpec::Procedural {
            generator,
            seed,
            params,
            scale: scale * s,
        },
        other => other,
    }
}

fn resolved(spec: ObjectSpec, seed: u64) -> ResolvedSpec {
    ResolvedSpec {
        spec,
        builtin: false,
        source: source(seed),
    }
}

/// `spec` prepared (at rest) with its extents (m), `None` if it does not build.
fn prepared(spec: &ObjectSpec, seed: u64) -> Option<(Prepared, [f64; 3])> {
    let p = prepare(&resolved(spec.clone(), seed)).ok()?;
    let e = p.mesh.aabb()?.extents();
    Some((p, e))
}

/// Whether extents `e` (m) meet the stream's size rules.
fn fits(e: [f64; 3]) -> bool {
    let tol = 1e-9;
    let narrow = e[0].min(e[1]);
    (GRASP_WIDTH_M.0 - tol..=GRASP_WIDTH_M.1 + tol).contains(&narrow)
        && e.iter()
            .all(|&x| x <= MAX_LENGTH_M + tol && x >= MIN_THICKNESS_M - tol)
}

/// Object `index` of stream `seed` (see the module docs). Never fails: after
/// `MAX_DRAWS` rejected draws it is a 5 x 5 x 8 cm box.
pub fn stream_spec(seed: u64, index: u64) -> ResolvedSpec {
    draw_object(seed, index).0
}

/// Object `index` of stream `seed`, prepared: the geometry [`stream_spec`] already built
/// to check the object's size, so building it costs no second preparation.
pub fn stream_prepared(seed: u64, index: u64) -> Result<Prepared, ObjectError> {
    match draw_object(seed, index) {
        (_, Some(p)) => Ok(p),
        (fallback, None) => prepare(&fallback),
    }
}

/// The spec of object `index` of stream `seed` and, unless it is the fallback box, its
/// preparation.
fn draw_object(seed: u64, index: u64) -> (ResolvedSpec, Option<Prepared>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    let unseen = unseen_set();
    let name = name(seed, index);
    let density = |rng: &mut ChaCha8Rng| {
        let (lo, hi) = (DENSITY_KG_M3.0.ln(), DENSITY_KG_M3.1.ln());
        rng.random_range(lo..=hi).exp()
    };
    for _ in 0..MAX_DRAWS {
        let shape = draw_shape(&mut rng);
        let width = rng.random_range(GRASP_WIDTH_M.0..=GRASP_WIDTH_M.1);
        let (rho, friction) = (density(&mut rng), rng.random_range(FRICTION.0..=FRICTION.1));
        if is_unseen_like(&shape, &unseen) {
            continue;
        }
        let spec = ObjectSpec {
            name: name.clone(),
            kind: ObjectKind::Procedural,
            shape,
            mass_kg: Some(MASS_KG.0),
            density_kg_m3: None,
            friction,
        };
        let Some((p, e)) = prepared(&spec, seed) else {
            continue;
        };
        let s = width / e[0].min(e[1]);
        if !(s.is_finite() && s > 0.0) {
            continue;
        }
        let mass = (rho * p.volume_m3 * s.powi(3)).clamp(MASS_KG.0, MASS_KG.1);
        let out = ObjectSpec {
            shape: scaled(spec.shape, s),
            mass_kg: Some(mass),
            ..spec
        };
        // The scaled shape is built again and checked: its rest face can differ from the
        // unscaled one's where two faces are nearly equally stable.
        match prepared(&out, seed) {
            Some((p, e)) if fits(e) => return (resolved(out, seed), Some(p)),
            _ => continue,
        }
    }
    let fallback = resolved(
        ObjectSpec {
            name,
            kind: ObjectKind::Procedural,
            shape: ShapeSpec::Box {
                size: [0.05, 0.05, 0.08],
            },
            mass_kg: Some(0.15),
            density_kg_m3: None,
            friction: 0.8,
        },
        seed,
    );
    (fallback, None)
}

/// Objects `0..count` of stream `seed`.
pub fn stream_specs(seed: u64, count: usize) -> Vec<ResolvedSpec> {
    use rayon::prelude::*;
    (0..count as u64)
        .into_par_iter()
        .map(|i| stream_spec(seed, i))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn names_round_trip_and_other_names_do_not_parse() {
        assert_eq!(parse_name(&name(7, 123)), Some((7, 123)));
        assert_eq!(parse_name("proc-7"), None);
        assert_eq!(parse_name("egg"), None);
        assert_eq!(parse_name("proc-x-1"), None);
    }

    #[test]
    fn objects_repeat_by_seed_and_index_and_differ_otherwise() {
        assert_eq!(stream_spec(3, 10), stream_spec(3, 10));
        assert_ne!(stream_spec(3, 10).spec.shape, stream_spec(3, 11).spec.shape);
        assert_ne!(stream_spec(3, 10).spec.shape, stream_spec(4, 10).spec.shape);
    }

    #[test]
    fn every_unseen_object_would_be_rejected_and_no_stream_object_is_unseen_like() {
        let unseen = unseen_set();
        // The rejection rule recognises each procedural unseen object itself, and a
        // ball-like superquadric (the unseen set holds a tennis ball).
        for u in unseen
            .iter()
            .filter(|u| matches!(u.shape, ShapeSpec::Procedural { .. }))
        {
            assert!(is_unseen_like(&u.shape, &unseen), "{}", u.name);
        }
        let ball = ShapeSpec::Procedural {
            generator: "superquadric".into(),
            seed: 1,
            params: [
                ("rx", 0.03),
                ("ry", 0.031),
                ("rz", 0.032),
                ("exponent", 2.2),
            ]
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect(),
            scale: 2.0,
        };
        assert!(is_unseen_like(&ball, &unseen));
        let names: HashSet<String> = unseen.iter().map(|u| u.name.clone()).collect();
        for s in stream_specs(1, 300) {
            assert!(!is_unseen_like(&s.spec.shape, &unseen), "{}", s.spec.name);
            assert!(!names.contains(&s.spec.name));
        }
    }

    #[test]
    fn stream_objects_are_graspable_sized_light_and_from_every_family() {
        let specs = stream_specs(0, 400);
        let mut seen = HashSet::new();
        for rs in &specs {
            let p = prepare(rs).unwrap_or_else(|e| panic!("{}: {e}", rs.spec.name));
            let name = &rs.spec.name;
            p.mesh.validate(name).unwrap();
            let e = p.mesh.aabb().unwrap().extents();
            let narrow = e[0].min(e[1]);
            assert!(
                (GRASP_WIDTH_M.0 - 1e-6..=GRASP_WIDTH_M.1 + 1e-6).contains(&narrow),
                "{name}: narrowest width {narrow}"
            );
            assert!(e.iter().all(|&x| x <= MAX_LENGTH_M + 1e-6), "{name}: {e:?}");
            assert!(
                e.iter().all(|&x| x >= MIN_THICKNESS_M - 1e-6),
                "{name}: {e:?}"
            );
            assert!((MASS_KG.0..=MASS_KG.1).contains(&p.mass_kg), "{name}");
            assert!((FRICTION.0..=FRICTION.1).contains(&rs.spec.friction));
            seen.insert(match &rs.spec.shape {
                ShapeSpec::Procedural { generator, .. } => generator.clone(),
                ShapeSpec::Box { .. } => "box".into(),
                ShapeSpec::Cylinder { .. } => "cylinder".into(),
                other => panic!("{name}: unexpected shape {other:?}"),
            });
        }
        let all: HashSet<String> = families().iter().map(|f| f.to_string()).collect();
        assert_eq!(
            seen,
            all,
            "families never drawn: {:?}",
            all.difference(&seen)
        );
    }
}
