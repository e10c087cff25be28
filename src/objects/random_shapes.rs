//! Generators whose shape comes mostly from the seed: extrusions of random polygons and
//! stacks of primitives. Both are assemblies of convex parts ([`Assembly`]) that touch
//! face to face or share a centre line, so the visual mesh's volume is the solid's.
//!
//! They widen the procedural training stream ([`super::stream`]) beyond the hand-made
//! families of [`super::procedural`]: wedges, kites, irregular and non-convex prisms,
//! and totem-like unions of boxes and cylinders.

use super::shape_kit::{box_points, cylinder_points, Assembly, Generated, Params};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::f64::consts::TAU;

/// Vertices of a random polygon around the origin, counter-clockwise: `n` angles spread
/// around the circle (jittered by `irregularity` of their spacing), each at a radius in
/// `radius * [1 - irregularity, 1]`. Star-shaped from the origin by construction.
pub fn random_polygon(
    rng: &mut ChaCha8Rng,
    n: usize,
    radius: f64,
    irregularity: f64,
) -> Vec<[f64; 2]> {
    let step = TAU / n as f64;
    let phase = rng.random_range(0.0..TAU);
    (0..n)
        .map(|k| {
            let a = phase + step * (k as f64 + 0.45 * irregularity * rng.random_range(-1.0..1.0));
            let r = radius * (1.0 - irregularity * rng.random_range(0.0..1.0));
            [r * a.cos(), r * a.sin()]
        })
        .collect()
}

/// A random polygon (see [`random_polygon`]) extruded along z; each fan triangle from the
/// centre is one convex wedge part, so non-convex outlines stay exact.
pub(super) fn build_extrusion(rng: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let n = p.get("sides").round() as usize;
    let (r, h, irr) = (p.get("radius"), p.get("height"), p.get("irregularity"));
    let poly = random_polygon(rng, n, r, irr);
    let mut asm = Assembly::new();
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        // Skip slivers: a fan triangle thinner than 1 mm has no 3-D hull worth keeping.
        let cross = a[0] * b[1] - a[1] * b[0];
        if cross <= 1e-3 * r * r {
            continue;
        }
        let pts: Vec<[f64; 3]> = [[0.0, 0.0], a, b]
            .iter()
            .flat_map(|q| [[q[0], q[1], 0.0], [q[0], q[1], h]])
            .collect();
        asm.add(&pts)?;
    }
    Ok(asm.finish())
}

/// A vertical stack of `parts` boxes and cylinders of random widths, each standing on the
/// previous one's top face, with an optional box arm on the side of one part.
pub(super) fn build_stack(rng: &mut ChaCha8Rng, p: &Params) -> Result<Generated, String> {
    let parts = p.get("parts").round() as usize;
    let (w, h) = (p.get("width"), p.get("height"));
    let mut asm = Assembly::new();
    let mut z = 0.0;
    let mut boxes: Vec<([f64; 3], [f64; 3])> = Vec::new();
    for _ in 0..parts {
        let half_w = 0.5 * w * rng.random_range(0.5..1.0);
        let half_d = half_w * rng.random_range(0.6..1.0);
        let part_h = h / parts as f64 * rng.random_range(0.6..1.4);
        if rng.random_bool(0.5) {
            let c = [0.0, 0.0, z + 0.5 * part_h];
            let half = [half_w, half_d, 0.5 * part_h];
            asm.add(&box_points(c, half))?;
            boxes.push((c, half));
        } else {
            asm.add(&cylinder_points(
                [0.0, 0.0, z],
                [0.0, 0.0, z + part_h],
                half_w,
                24,
            ))?;
        }
        z += part_h;
    }
    if p.get("arm") >= 0.5 {
        if let Some(&(c, half)) = boxes.first() {
            // An arm on the +x face of the first box, face to face with it.
            let len = w * rng.random_range(0.3..0.8);
            let arm_half = [0.5 * len, 0.5 * half[1], 0.6 * half[2]];
            let centre = [c[0] + half[0] + arm_half[0], c[1], c[2]];
            asm.add(&box_points(centre, arm_half))?;
        }
    }
    Ok(asm.finish())
}

#[cfg(test)]
mod tests {
    use crate::objects::procedural::generate;
    use std::collections::BTreeMap;

    fn params(p: &[(&str, f64)]) -> BTreeMap<String, f64> {
        p.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    #[test]
    fn a_regular_extrusion_has_the_polygon_area_times_height() {
        // Irregularity 0: a regular hexagon of circumradius 3 cm, 5 cm tall:
        // area = 3 sqrt(3) / 2 r^2 = 2.598 * 9e-4 = 2.338e-3 m^2, volume 1.169e-4 m^3.
        let g = generate(
            "extrusion",
            3,
            &params(&[
                ("sides", 6.0),
                ("radius", 0.03),
                ("height", 0.05),
                ("irregularity", 0.0),
            ]),
            "t",
            "test",
        )
        .unwrap();
        g.mesh.validate("t").unwrap();
        let v = g.mesh.mass_properties().volume;
        let exact = 1.5 * 3f64.sqrt() * 0.03 * 0.03 * 0.05;
        assert!((v - exact).abs() / exact < 1e-6, "{v} vs {exact}");
        assert_eq!(g.parts.unwrap().len(), 6);
    }

    #[test]
    fn irregular_extrusions_differ_by_seed_and_repeat_by_seed() {
        let p = params(&[("sides", 5.0), ("irregularity", 0.8)]);
        let a = generate("extrusion", 1, &p, "t", "test").unwrap();
        let b = generate("extrusion", 1, &p, "t", "test").unwrap();
        let c = generate("extrusion", 2, &p, "t", "test").unwrap();
        assert_eq!(a.mesh.vertices, b.mesh.vertices);
        assert_ne!(a.mesh.vertices, c.mesh.vertices);
    }

    #[test]
    fn a_stack_is_as_tall_as_its_parts_and_stands_on_z0() {
        for seed in 0..10 {
            let g = generate("stack", seed, &params(&[("arm", 1.0)]), "t", "test").unwrap();
            g.mesh.validate("t").unwrap();
            let bb = g.mesh.aabb().unwrap();
            assert!(bb.min[2].abs() < 1e-12, "seed {seed}: {:?}", bb.min);
            // 3 parts (default) of 0.6-1.4 x height / 3 each.
            let h = bb.max[2];
            assert!((0.6 * 0.12..=1.4 * 0.12 + 1e-12).contains(&h), "{h}");
        }
    }
}
