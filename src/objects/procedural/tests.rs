//! Tests of `procedural`.

use super::*;
use crate::objects::shape_kit::icosphere;
use approx::assert_relative_eq;

#[test]
fn icosphere_approximates_the_unit_sphere() {
    let m = icosphere(4);
    m.validate("icosphere").unwrap();
    let props = m.mass_properties();
    let exact = 4.0 / 3.0 * PI;
    assert!(
        (props.volume - exact).abs() / exact < 0.01,
        "{}",
        props.volume
    );
    // Sphere of radius 1, unit density: I = 2/5 m r^2 with m = V.
    let want = 0.4 * props.volume;
    for k in 0..3 {
        assert!(props.centroid[k].abs() < 1e-9);
        assert!((props.inertia_unit_density[k][k] - want).abs() / want < 0.01);
    }
    assert!(props.inertia_unit_density[0][1].abs() < 1e-6);
}

#[test]
fn revolve_cylinder_volume() {
    let m = revolve(&[[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [0.0, 2.0]], 256).unwrap();
    m.validate("cyl").unwrap();
    // Inscribed 256-gon area: n/2 sin(2 pi / n).
    let area = 128.0 * (TAU / 256.0).sin();
    assert_relative_eq!(m.signed_volume(), 2.0 * area, epsilon = 1e-9);
    assert!(revolve(&[[0.5, 0.0], [1.0, 0.0], [0.0, 1.0]], 8).is_err());
}

#[test]
fn superquadric_and_ellipsoid_rays() {
    assert_relative_eq!(superquadric_ray([1.0, 0.0, 0.0], [2.0, 3.0, 4.0], 2.0), 2.0);
    assert_relative_eq!(
        ellipsoid_ray([0.0, 0.0, 1.0], [0.0, 0.0, 0.5], [1.0, 1.0, 1.0]),
        1.5,
        epsilon = 1e-12
    );
}

#[test]
fn every_generator_with_defaults_is_watertight() {
    for g in GENERATORS {
        let out = generate(g.name, 7, &BTreeMap::new(), g.name, "test")
            .unwrap_or_else(|e| panic!("{}: {e}", g.name));
        out.mesh.validate(g.name).unwrap_or_else(|e| panic!("{e}"));
        if let Some(parts) = &out.parts {
            assert!(!parts.is_empty() && parts.len() <= 24, "{}", g.name);
        }
    }
}

#[test]
fn same_seed_same_mesh_other_seed_other_mesh() {
    let params = BTreeMap::from([("complexity".to_string(), 5.0)]);
    let a = generate("egad", 11, &params, "a", "t").unwrap().mesh;
    let b = generate("egad", 11, &params, "b", "t").unwrap().mesh;
    let c = generate("egad", 12, &params, "c", "t").unwrap().mesh;
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn bad_generator_params_are_named() {
    let e = generate("nope", 0, &BTreeMap::new(), "x", "m.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unknown generator") && e.contains("bottle"),
        "{e}"
    );
    let p = BTreeMap::from([("radius".to_string(), 5.0)]);
    let e = generate("can", 0, &p, "x", "m.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("shape.params.radius") && e.contains("m.toml"),
        "{e}"
    );
    let p = BTreeMap::from([("radios".to_string(), 0.03)]);
    let e = generate("can", 0, &p, "x", "m.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("radios") && e.contains("known: radius"), "{e}");
    let p = BTreeMap::from([("neck_radius".to_string(), 0.05)]);
    let e = generate("bottle", 0, &p, "x", "m.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("neck_radius must be smaller"), "{e}");
}
