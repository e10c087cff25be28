//! The built-in object sets (`train`, `unseen`, `all`) as specs.
//!
//! `train` mirrors the paper's 61 training objects (Sec. IV-A, Fig. 4). Its caption lists
//! 11 YCB, 14 ShapeNet, 5 primitive shapes (4 boxes, 1 cylinder) and 31 EGAD objects; the
//! text counts the primitives among 19 ShapeNet objects. The mapping used here:
//!
//! | paper                         | here                                   | count |
//! |-------------------------------|----------------------------------------|-------|
//! | YCB                           | `ycb-like` everyday shapes, YCB sizes and masses | 11 |
//! | ShapeNet (without primitives) | `shapenet-like` everyday shapes        | 14 |
//! | primitive shapes              | `primitive`: 4 boxes, 1 cylinder       | 5 |
//! | EGAD                          | `egad` grid `egad_c{0..5}_d{0..4}` plus `egad_c6_d2` | 31 |
//!
//! The EGAD-like grid covers complexity levels 0-5 by difficulty levels 0-4 (30 cells)
//! plus one object at the highest complexity level, 6, middle difficulty.
//!
//! `unseen` (19 objects) holds shape families absent from `train` (prisms, a cone frustum,
//! a star, a ring, a dumbbell, a goblet, an egg, a pear, flat blocks, a spatula, a sphere
//! and a capsule) and five EGAD-like shapes from other seeds and sizes. `all` is both.
//!
//! # Masses and friction of built-ins
//!
//! YCB-like objects use the real YCB object's mass; other kinds use a density per object
//! (apparent density: hollow bottles count as light solids; EGAD-like shapes use
//! 350 kg/m^3, a 3-D print with sparse infill). Built-in masses are then clamped into
//! [`BUILTIN_MASS_RANGE`](super::build::BUILTIN_MASS_RANGE) (50..600 g) so that every object suits the hand. Friction is
//! 0.8 (YCB-like), 0.75 (ShapeNet-like), 0.9 (EGAD-like, rough prints), 0.7 (primitives).

use super::spec::{ObjectKind, ObjectSpec, ShapeSpec};
use std::collections::BTreeMap;

/// The built-in set names.
pub const BUILTIN_SETS: [&str; 3] = ["train", "unseen", "all"];

fn params(p: &[(&str, f64)]) -> BTreeMap<String, f64> {
    p.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

fn friction_of(kind: ObjectKind) -> f64 {
    match kind {
        ObjectKind::YcbLike => 0.8,
        ObjectKind::ShapenetLike => 0.75,
        ObjectKind::Egad => 0.9,
        ObjectKind::Primitive => 0.7,
        ObjectKind::User | ObjectKind::Procedural | ObjectKind::Real => {
            super::spec::DEFAULT_FRICTION
        }
    }
}

enum M {
    Kg(f64),
    Density(f64),
}

fn spec(name: &str, kind: ObjectKind, shape: ShapeSpec, m: M) -> ObjectSpec {
    let (mass_kg, density_kg_m3) = match m {
        M::Kg(x) => (Some(x), None),
        M::Density(d) => (None, Some(d)),
    };
    ObjectSpec {
        name: name.to_string(),
        kind,
        shape,
        mass_kg,
        density_kg_m3,
        friction: friction_of(kind),
    }
}

fn gen(
    name: &str,
    kind: ObjectKind,
    generator: &str,
    seed: u64,
    p: &[(&str, f64)],
    m: M,
) -> ObjectSpec {
    spec(
        name,
        kind,
        ShapeSpec::Procedural {
            generator: generator.to_string(),
            seed,
            params: params(p),
            scale: 1.0,
        },
        m,
    )
}

fn egad(name: &str, c: u32, d: u32, seed: u64, size: f64) -> ObjectSpec {
    gen(
        name,
        ObjectKind::Egad,
        "egad",
        seed,
        &[
            ("complexity", c as f64),
            ("difficulty", d as f64),
            ("size", size),
        ],
        M::Density(350.0),
    )
}

/// The 61 training objects (see the module docs for the mapping to the paper).
pub fn train_set() -> Vec<ObjectSpec> {
    use ObjectKind::{Primitive as P, ShapenetLike as S, YcbLike as Y};
    let bx = |n: &str, s: [f64; 3], d: f64| spec(n, P, ShapeSpec::Box { size: s }, M::Density(d));
    let mut v = vec![
        bx("box_cracker", [0.16, 0.06, 0.21], 200.0),
        bx("box_sugar", [0.09, 0.045, 0.175], 700.0),
        bx("box_pudding", [0.11, 0.09, 0.035], 550.0),
        bx("box_gelatin", [0.09, 0.07, 0.03], 500.0),
        spec(
            "cylinder_wood",
            P,
            ShapeSpec::Cylinder {
                radius: 0.03,
                height: 0.1,
            },
            M::Density(600.0),
        ),
        // YCB-like, with the YCB objects' masses.
        gen(
            "can_soup",
            Y,
            "can",
            0,
            &[("radius", 0.0335), ("height", 0.102)],
            M::Kg(0.349),
        ),
        gen(
            "can_tuna",
            Y,
            "can",
            0,
            &[("radius", 0.043), ("height", 0.033)],
            M::Kg(0.171),
        ),
        gen(
            "can_chips",
            Y,
            "can",
            0,
            &[("radius", 0.0375), ("height", 0.25)],
            M::Kg(0.205),
        ),
        gen(
            "bottle_mustard",
            Y,
            "bottle",
            0,
            &[
                ("radius", 0.03),
                ("height", 0.19),
                ("neck_radius", 0.011),
                ("neck_height", 0.03),
                ("shoulder", 0.05),
            ],
            M::Kg(0.45),
        ),
        gen(
            "mug",
            Y,
            "mug",
            0,
            &[("radius", 0.04), ("height", 0.08)],
            M::Kg(0.118),
        ),
        gen(
            "bowl",
            Y,
            "vessel",
            0,
            &[
                ("radius_top", 0.058),
                ("radius_bottom", 0.035),
                ("height", 0.055),
                ("wall", 0.006),
                ("curve", 1.0),
            ],
            M::Kg(0.147),
        ),
        gen("banana", Y, "banana", 0, &[], M::Kg(0.066)),
        gen(
            "apple",
            Y,
            "superquadric",
            21,
            &[
                ("rx", 0.037),
                ("ry", 0.037),
                ("rz", 0.035),
                ("bump", 0.04),
                ("bump_freq", 1.5),
            ],
            M::Kg(0.068),
        ),
        gen(
            "lemon",
            Y,
            "superquadric",
            22,
            &[("rx", 0.034), ("ry", 0.026), ("rz", 0.026), ("bump", 0.03)],
            M::Kg(0.06),
        ),
        gen("hammer", Y, "hammer", 0, &[], M::Kg(0.5)),
        gen(
            "cup_stacking",
            Y,
            "vessel",
            0,
            &[
                ("radius_top", 0.04),
                ("radius_bottom", 0.032),
                ("height", 0.07),
                ("wall", 0.003),
                ("curve", 0.0),
            ],
            M::Kg(0.06),
        ),
        // ShapeNet-like, apparent densities.
        gen(
            "bottle_tall",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.035),
                ("height", 0.26),
                ("neck_radius", 0.013),
                ("neck_height", 0.06),
                ("shoulder", 0.05),
            ],
            M::Density(250.0),
        ),
        gen(
            "bottle_wine",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.037),
                ("height", 0.29),
                ("neck_radius", 0.014),
                ("neck_height", 0.08),
                ("shoulder", 0.06),
            ],
            M::Density(300.0),
        ),
        gen(
            "bottle_water",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.032),
                ("height", 0.21),
                ("neck_radius", 0.014),
                ("neck_height", 0.02),
                ("shoulder", 0.04),
                ("waist", 0.15),
            ],
            M::Density(300.0),
        ),
        gen(
            "bottle_flask",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.05),
                ("height", 0.14),
                ("neck_radius", 0.012),
                ("neck_height", 0.03),
                ("shoulder", 0.04),
            ],
            M::Density(250.0),
        ),
        gen(
            "jar_round",
            S,
            "bottle",
            0,
            &[
                ("radius", 0.045),
                ("height", 0.12),
                ("neck_radius", 0.04),
                ("neck_height", 0.02),
                ("shoulder", 0.01),
            ],
            M::Density(350.0),
        ),
        gen(
            "can_soda",
            S,
            "can",
            0,
            &[("radius", 0.033), ("height", 0.122), ("bevel", 0.006)],
            M::Density(800.0),
        ),
        gen(
            "mug_tall",
            S,
            "mug",
            0,
            &[("radius", 0.038), ("height", 0.11), ("handle_reach", 0.03)],
            M::Density(1800.0),
        ),
        gen(
            "mug_short",
            S,
            "mug",
            0,
            &[("radius", 0.045), ("height", 0.07)],
            M::Density(1800.0),
        ),
        gen(
            "bowl_deep",
            S,
            "vessel",
            0,
            &[
                ("radius_top", 0.055),
                ("radius_bottom", 0.038),
                ("height", 0.07),
                ("wall", 0.005),
                ("curve", 0.5),
            ],
            M::Density(1500.0),
        ),
        gen("vase", S, "vase", 5, &[], M::Density(300.0)),
        gen(
            "remote",
            S,
            "superquadric",
            0,
            &[
                ("rx", 0.025),
                ("ry", 0.09),
                ("rz", 0.012),
                ("exponent", 6.0),
            ],
            M::Density(600.0),
        ),
        gen("camera", S, "camera", 0, &[], M::Density(500.0)),
        gen("flashlight", S, "flashlight", 0, &[], M::Density(900.0)),
        gen("teapot", S, "teapot", 0, &[], M::Density(400.0)),
    ];
    for c in 0..=5u32 {
        for d in 0..=4u32 {
            v.push(egad(
                &format!("egad_c{c}_d{d}"),
                c,
                d,
                1000 + 10 * c as u64 + d as u64,
                1.0,
            ));
        }
    }
    v.push(egad("egad_c6_d2", 6, 2, 1062, 1.0));
    v
}

/// The held-out objects: families and sizes absent from [`train_set`].
pub fn unseen_set() -> Vec<ObjectSpec> {
    use ObjectKind::{Primitive as P, ShapenetLike as S, YcbLike as Y};
    vec![
        gen(
            "prism_hex",
            S,
            "prism",
            0,
            &[("sides", 6.0), ("radius", 0.035), ("height", 0.09)],
            M::Density(600.0),
        ),
        gen(
            "prism_tri",
            S,
            "prism",
            0,
            &[("sides", 3.0), ("radius", 0.045), ("height", 0.06)],
            M::Density(600.0),
        ),
        gen("frustum_cone", S, "frustum", 0, &[], M::Density(500.0)),
        gen("star_5", S, "star", 0, &[], M::Density(500.0)),
        gen("torus_ring", S, "torus", 0, &[], M::Density(700.0)),
        gen("dumbbell", S, "dumbbell", 0, &[], M::Density(1500.0)),
        gen("goblet", S, "goblet", 0, &[], M::Density(400.0)),
        gen(
            "block_l",
            S,
            "block",
            0,
            &[("layout", 0.0)],
            M::Density(600.0),
        ),
        gen(
            "block_cross",
            S,
            "block",
            0,
            &[("layout", 2.0), ("arm", 0.045)],
            M::Density(600.0),
        ),
        gen(
            "spatula",
            S,
            "hammer",
            0,
            &[("flat", 1.0), ("head_length", 0.07), ("head_size", 0.035)],
            M::Kg(0.1),
        ),
        gen("egg", Y, "egg", 0, &[], M::Kg(0.06)),
        gen("pear", Y, "pear", 0, &[], M::Kg(0.15)),
        spec(
            "ball_tennis",
            P,
            ShapeSpec::Sphere { radius: 0.033 },
            M::Kg(0.058),
        ),
        spec(
            "capsule_pill",
            P,
            ShapeSpec::Capsule {
                radius: 0.02,
                height: 0.11,
            },
            M::Density(800.0),
        ),
        egad("egad_u1_c1_d3", 1, 3, 9001, 1.1),
        egad("egad_u2_c2_d1", 2, 1, 9002, 0.8),
        egad("egad_u3_c3_d4", 3, 4, 9003, 1.2),
        egad("egad_u4_c5_d0", 5, 0, 9004, 0.9),
        egad("egad_u5_c6_d3", 6, 3, 9005, 1.0),
    ]
}

/// The specs of a built-in set (`train`, `unseen`, `all`).
pub fn builtin_set(name: &str) -> Option<Vec<ObjectSpec>> {
    match name {
        "train" => Some(train_set()),
        "unseen" => Some(unseen_set()),
        "all" => {
            let mut v = train_set();
            v.extend(unseen_set());
            Some(v)
        }
        _ => None,
    }
}

/// The built-in object called `name`.
pub fn builtin_object(name: &str) -> Option<ObjectSpec> {
    builtin_set("all")?.into_iter().find(|s| s.name == name)
}
