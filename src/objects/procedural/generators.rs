//! The catalogue of procedural generators: each one's name, what it makes, its parameters
//! with defaults and ranges, and its builder.

use super::*;

/// Every generator, by name.
pub const GENERATORS: &[GeneratorDef] = &[
    GeneratorDef {
        name: "egad",
        doc: "EGAD-like evolved shape: superquadric core, extra ellipsoid lobes and low-frequency noise growing with complexity; size and aspect ratio set by difficulty",
        params: &[
            p("complexity", 3.0, 0.0, 6.0, "shape complexity level: lobes = 1 + c/2, noise terms = c"),
            p("difficulty", 2.0, 0.0, 4.0, "grasp difficulty level: smaller, more elongated and flatter"),
            p("size", 1.0, 0.5, 1.5, "overall scale factor"),
        ],
        build: build_egad,
    },
    GeneratorDef {
        name: "superquadric",
        doc: "superellipsoid |x/rx|^e + |y/ry|^e + |z/rz|^e = 1 with optional bumps (fruit, soap, remote controls)",
        params: &[
            p("rx", 0.035, 0.005, 0.15, "semi-axis along x (m)"),
            p("ry", 0.035, 0.005, 0.15, "semi-axis along y (m)"),
            p("rz", 0.035, 0.005, 0.15, "semi-axis along z (m)"),
            p("exponent", 2.0, 1.0, 10.0, "2 = ellipsoid, larger = boxier"),
            p("bump", 0.0, 0.0, 0.3, "relative amplitude of the seeded surface bumps"),
            p("bump_freq", 2.0, 1.0, 6.0, "spatial frequency of the bumps"),
        ],
        build: build_superquadric,
    },
    GeneratorDef {
        name: "can",
        doc: "closed cylinder with bevelled edges (tin cans, soda cans); convex",
        params: &[
            p("radius", 0.033, 0.01, 0.08, "radius (m)"),
            p("height", 0.1, 0.01, 0.3, "height (m)"),
            p("bevel", 0.003, 0.0, 0.01, "edge bevel (m)"),
        ],
        build: build_can,
    },
    GeneratorDef {
        name: "bottle",
        doc: "bottle or jar: body (optionally waisted), rounded shoulder, neck and lip",
        params: &[
            p("radius", 0.035, 0.01, 0.08, "body radius (m)"),
            p("height", 0.22, 0.04, 0.3, "total height (m)"),
            p("neck_radius", 0.013, 0.004, 0.075, "neck radius (m)"),
            p("neck_height", 0.05, 0.005, 0.15, "neck length (m)"),
            p("shoulder", 0.04, 0.003, 0.15, "height of the shoulder transition (m)"),
            p("waist", 0.0, 0.0, 0.3, "relative inward waist in the middle of the body"),
        ],
        build: build_bottle,
    },
    GeneratorDef {
        name: "vessel",
        doc: "thick-walled open vessel (bowls, cups); collision from convex wall sectors",
        params: &[
            p("radius_top", 0.055, 0.02, 0.08, "outer rim radius (m)"),
            p("radius_bottom", 0.035, 0.01, 0.08, "outer base radius (m)"),
            p("height", 0.06, 0.02, 0.2, "height (m)"),
            p("wall", 0.005, 0.002, 0.02, "wall and floor thickness (m)"),
            p("curve", 1.0, 0.0, 1.0, "0 = straight tapered wall, 1 = rounded bowl"),
        ],
        build: build_vessel,
    },
    GeneratorDef {
        name: "mug",
        doc: "mug: straight vessel plus a D-shaped handle, all convex parts",
        params: &[
            p("radius", 0.04, 0.02, 0.06, "outer radius (m)"),
            p("height", 0.09, 0.04, 0.15, "height (m)"),
            p("wall", 0.005, 0.002, 0.01, "wall thickness (m)"),
            p("handle_reach", 0.028, 0.015, 0.05, "how far the handle sticks out (m)"),
            p("handle_thickness", 0.008, 0.004, 0.015, "handle tube radius (m)"),
        ],
        build: build_mug,
    },
    GeneratorDef {
        name: "banana",
        doc: "curved tapered tube lying on the table, closed by cones; convex segments",
        params: &[
            p("length", 0.18, 0.08, 0.25, "chord length (m)"),
            p("radius", 0.018, 0.008, 0.03, "largest tube radius (m)"),
            p("bend", 0.9, 0.2, 1.6, "bend angle of the centre line (rad)"),
        ],
        build: build_banana,
    },
    GeneratorDef {
        name: "hammer",
        doc: "tool lying on its side: cylindrical handle plus a box head",
        params: &[
            p("handle_length", 0.2, 0.08, 0.26, "handle length (m)"),
            p("handle_radius", 0.012, 0.006, 0.02, "handle radius (m)"),
            p("head_length", 0.1, 0.04, 0.14, "head length across the handle (m)"),
            p("head_size", 0.025, 0.012, 0.04, "head cross-section side (m)"),
            p("flat", 0.0, 0.0, 1.0, "1 = flat blade head (spatula-like) instead of a block"),
        ],
        build: build_hammer,
    },
    GeneratorDef {
        name: "vase",
        doc: "solid vase: wavy surface of revolution narrowing to a neck",
        params: &[
            p("radius", 0.04, 0.015, 0.06, "base body radius (m)"),
            p("height", 0.18, 0.05, 0.3, "height (m)"),
            p("waves", 1.5, 0.5, 4.0, "number of bulges along the height"),
            p("amplitude", 0.2, 0.0, 0.4, "relative bulge amplitude"),
            p("neck", 0.6, 0.3, 1.0, "top radius relative to the base"),
        ],
        build: build_vase,
    },
    GeneratorDef {
        name: "camera",
        doc: "box body with a cylindrical lens and a viewfinder bump",
        params: &[
            p("width", 0.11, 0.04, 0.15, "body width along x (m)"),
            p("depth", 0.045, 0.02, 0.08, "body depth along y (m)"),
            p("height", 0.07, 0.03, 0.12, "body height (m)"),
            p("lens_radius", 0.025, 0.01, 0.04, "lens radius (m)"),
            p("lens_length", 0.035, 0.01, 0.07, "lens length (m)"),
        ],
        build: build_camera,
    },
    GeneratorDef {
        name: "teapot",
        doc: "round body, lid knob, spout and handle, all convex parts",
        params: &[
            p("radius", 0.055, 0.03, 0.07, "body radius (m)"),
            p("height", 0.09, 0.05, 0.14, "body height (m)"),
        ],
        build: build_teapot,
    },
    GeneratorDef {
        name: "flashlight",
        doc: "standing cylinder with a wider head (torch, spray can)",
        params: &[
            p("radius", 0.016, 0.008, 0.04, "handle radius (m)"),
            p("length", 0.2, 0.06, 0.3, "total length (m)"),
            p("head_radius", 0.026, 0.01, 0.06, "head radius (m)"),
            p("head_length", 0.05, 0.01, 0.1, "head length (m)"),
        ],
        build: build_flashlight,
    },
    GeneratorDef {
        name: "prism",
        doc: "regular polygonal prism standing on a face; convex",
        params: &[
            p("sides", 6.0, 3.0, 12.0, "number of sides (rounded)"),
            p("radius", 0.035, 0.01, 0.07, "circumradius (m)"),
            p("height", 0.08, 0.01, 0.25, "height (m)"),
        ],
        build: build_prism,
    },
    GeneratorDef {
        name: "star",
        doc: "extruded star: polygon core plus triangular spikes (convex parts)",
        params: &[
            p("points", 5.0, 3.0, 8.0, "number of spikes (rounded)"),
            p("outer", 0.05, 0.02, 0.07, "spike tip radius (m)"),
            p("inner", 0.022, 0.008, 0.05, "inner radius (m)"),
            p("height", 0.035, 0.01, 0.1, "thickness (m)"),
        ],
        build: build_star,
    },
    GeneratorDef {
        name: "torus",
        doc: "ring lying flat; convex ring segments",
        params: &[
            p("major", 0.045, 0.02, 0.06, "radius of the centre circle (m)"),
            p("minor", 0.014, 0.005, 0.03, "tube radius (m)"),
        ],
        build: build_torus,
    },
    GeneratorDef {
        name: "egg",
        doc: "egg lying on its side; convex",
        params: &[
            p("radius", 0.024, 0.01, 0.05, "largest radius (m)"),
            p("length", 0.065, 0.03, 0.12, "length (m)"),
            p("pointiness", 0.2, 0.0, 0.4, "asymmetry between the ends"),
        ],
        build: build_egg,
    },
    GeneratorDef {
        name: "pear",
        doc: "pear standing on a flattened base: round body and a narrower top",
        params: &[
            p("radius", 0.033, 0.015, 0.05, "body radius (m)"),
            p("height", 0.1, 0.05, 0.15, "height (m)"),
            p("neck", 0.55, 0.3, 0.9, "top radius relative to the body"),
        ],
        build: build_pear,
    },
    GeneratorDef {
        name: "dumbbell",
        doc: "two discs joined by a bar, standing upright (convex parts)",
        params: &[
            p("end_radius", 0.03, 0.015, 0.06, "disc radius (m)"),
            p("end_length", 0.025, 0.01, 0.05, "disc thickness (m)"),
            p("bar_radius", 0.013, 0.006, 0.03, "bar radius (m)"),
            p("length", 0.15, 0.06, 0.25, "total length (m)"),
        ],
        build: build_dumbbell,
    },
    GeneratorDef {
        name: "goblet",
        doc: "wine-glass silhouette (solid): foot, thin stem, cup",
        params: &[
            p("cup_radius", 0.035, 0.02, 0.05, "cup radius (m)"),
            p("height", 0.16, 0.08, 0.25, "height (m)"),
            p("stem_radius", 0.007, 0.004, 0.015, "stem radius (m)"),
        ],
        build: build_goblet,
    },
    GeneratorDef {
        name: "frustum",
        doc: "truncated cone standing on its base; convex",
        params: &[
            p("radius_bottom", 0.04, 0.01, 0.07, "base radius (m)"),
            p("radius_top", 0.015, 0.003, 0.07, "top radius (m)"),
            p("height", 0.1, 0.02, 0.25, "height (m)"),
        ],
        build: build_frustum,
    },
    GeneratorDef {
        name: "block",
        doc: "flat block made of boxes: 0 = L, 1 = T, 2 = plus (convex parts)",
        params: &[
            p("layout", 0.0, 0.0, 2.0, "0 = L, 1 = T, 2 = plus (rounded)"),
            p("arm", 0.05, 0.02, 0.08, "arm length from the centre (m)"),
            p("thickness", 0.025, 0.01, 0.05, "arm width (m)"),
            p("height", 0.04, 0.01, 0.1, "block height (m)"),
        ],
        build: build_block,
    },
    GeneratorDef {
        name: "extrusion",
        doc: "random polygon (seeded angles and radii, possibly non-convex) extruded along z: wedges, kites, irregular prisms",
        params: &[
            p("sides", 5.0, 3.0, 8.0, "polygon vertices"),
            p("radius", 0.035, 0.01, 0.07, "largest vertex distance from the centre (m)"),
            p("height", 0.06, 0.01, 0.25, "extrusion length (m)"),
            p("irregularity", 0.5, 0.0, 0.9, "0 = regular polygon; larger = jittered angles, radii down to (1 - irregularity) radius"),
        ],
        build: crate::objects::random_shapes::build_extrusion,
    },
    GeneratorDef {
        name: "stack",
        doc: "vertical stack of seeded boxes and cylinders standing face to face, optionally with a side arm",
        params: &[
            p("parts", 3.0, 2.0, 4.0, "number of stacked parts"),
            p("width", 0.06, 0.03, 0.1, "largest part width (m)"),
            p("height", 0.12, 0.04, 0.2, "nominal total height (m)"),
            p("arm", 0.0, 0.0, 1.0, ">= 0.5: a box arm on the side of the first box"),
        ],
        build: crate::objects::random_shapes::build_stack,
    },
];
