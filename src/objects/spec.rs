//! Object specifications: what an object is made of, before it is built.
//!
//! A manifest is a TOML file with one `[[object]]` table per object:
//!
//! ```toml
//! [[object]]
//! name = "my_mug"
//! kind = "user"                       # optional, default "user"
//! shape = { type = "mesh", path = "mug.obj", scale = 0.001 }   # mm -> m
//! mass_kg = 0.3                       # or density_kg_m3, not both
//! friction = 0.8                      # optional, default 0.8
//!
//! [[object]]
//! name = "long_box"
//! shape = { type = "box", size = [0.04, 0.06, 0.2] }
//!
//! [[object]]
//! name = "bottle_3"
//! shape = { type = "procedural", generator = "bottle", seed = 3, params = { radius = 0.03 } }
//! ```
//!
//! Rules ([`ObjectSpec::validate`]):
//!
//! - `mass_kg` and `density_kg_m3` are mutually exclusive; with neither, the density is
//!   [`DEFAULT_DENSITY`] (500 kg/m^3, between wood and water). Masses must lie in
//!   0.001..=10 kg, densities in 1..=20000 kg/m^3.
//! - `friction` defaults to [`DEFAULT_FRICTION`] (0.8); user objects may use 0..=1,
//!   built-in objects 0.5..=1. Friction above 1 is always an error.
//! - primitive dimensions must be positive and within the object size limits (5 mm..1 m);
//!   a capsule's `height` is its total height and must be at least `2 radius`.
//! - relative mesh paths are resolved against the manifest's folder.

use super::ObjectError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The mass a user object may have (kg), given as `mass_kg` or as density times volume.
pub const MASS_RANGE_KG: (f64, f64) = (0.001, 10.0);

/// The thinnest side of a primitive shape (m): the simulator refuses thinner ones.
pub const MIN_SIDE_M: f64 = 0.001;

/// Density used when a spec gives neither mass nor density (kg/m^3).
pub const DEFAULT_DENSITY: f64 = 500.0;
/// Friction used when a spec gives none.
pub const DEFAULT_FRICTION: f64 = 0.8;
/// Friction range allowed for built-in objects.
pub const BUILTIN_FRICTION: (f64, f64) = (0.5, 1.0);

/// Category label of an object.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum ObjectKind {
    /// Everyday object with YCB-like dimensions and mass.
    YcbLike,
    /// Everyday object of a ShapeNet category.
    ShapenetLike,
    /// EGAD-like evolved shape on the complexity x difficulty grid.
    Egad,
    /// Box, cylinder, sphere or capsule.
    Primitive,
    /// A user's object.
    User,
    /// An object of the procedural training stream ([`super::stream`]).
    Procedural,
    /// A real household object: a scan or model of a real product at a real mass
    /// (`assets/meshes/real/`).
    Real,
}

impl ObjectKind {
    /// The label as written in manifests and printed by the CLI.
    pub fn label(&self) -> &'static str {
        match self {
            ObjectKind::YcbLike => "ycb-like",
            ObjectKind::ShapenetLike => "shapenet-like",
            ObjectKind::Egad => "egad",
            ObjectKind::Primitive => "primitive",
            ObjectKind::User => "user",
            ObjectKind::Procedural => "procedural",
            ObjectKind::Real => "real",
        }
    }
}

impl std::fmt::Display for ObjectKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

fn default_kind() -> ObjectKind {
    ObjectKind::User
}

fn default_friction() -> f64 {
    DEFAULT_FRICTION
}

fn default_scale() -> f64 {
    1.0
}

/// The geometry of an object. Primitives stand on the table with their axis along z.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// A box with full extents `size` = [x, y, z] in metres.
    Box {
        /// Full extents in metres.
        size: [f64; 3],
    },
    /// A cylinder standing on its base.
    Cylinder {
        /// Radius in metres.
        radius: f64,
        /// Height in metres.
        height: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius in metres.
        radius: f64,
    },
    /// A capsule standing upright.
    Capsule {
        /// Radius in metres.
        radius: f64,
        /// Total height in metres (at least `2 radius`).
        height: f64,
    },
    /// A closed OBJ or STL mesh file.
    Mesh {
        /// Path to the file (relative paths: against the manifest's folder).
        path: PathBuf,
        /// Factor applied to the file's coordinates to get metres (0.001 for mm).
        #[serde(default = "default_scale")]
        scale: f64,
    },
    /// A procedural shape (see [`super::procedural::GENERATORS`]).
    Procedural {
        /// Generator name.
        generator: String,
        /// Seed of the generator's random choices.
        #[serde(default)]
        seed: u64,
        /// Parameter overrides, by name.
        #[serde(default)]
        params: BTreeMap<String, f64>,
        /// Uniform factor applied to the generated shape (default 1).
        #[serde(default = "default_scale")]
        scale: f64,
    },
}

/// One object: name, category, geometry, mass and friction.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Unique name: letters, digits, `_`, `-`, `.`.
    pub name: String,
    /// Category label (default `user`).
    #[serde(default = "default_kind")]
    pub kind: ObjectKind,
    /// Geometry.
    pub shape: ShapeSpec,
    /// Total mass in kg (exclusive with `density_kg_m3`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_kg: Option<f64>,
    /// Density in kg/m^3 (exclusive with `mass_kg`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density_kg_m3: Option<f64>,
    /// Friction coefficient (default 0.8).
    #[serde(default = "default_friction")]
    pub friction: f64,
}

/// A manifest file: a list of `[[object]]` tables.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The objects.
    #[serde(default)]
    pub object: Vec<ObjectSpec>,
}

/// How the mass of an object is determined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MassSpec {
    /// A fixed total mass in kg.
    Mass(f64),
    /// A density in kg/m^3.
    Density(f64),
}

impl ObjectSpec {
    /// A spec with default kind, mass and friction.
    pub fn new(name: impl Into<String>, shape: ShapeSpec) -> Self {
        ObjectSpec {
            name: name.into(),
            kind: ObjectKind::User,
            shape,
            mass_kg: None,
            density_kg_m3: None,
            friction: DEFAULT_FRICTION,
        }
    }

    /// The mass rule after applying the default (see the module docs). Call
    /// [`ObjectSpec::validate`] first.
    pub fn mass_spec(&self) -> MassSpec {
        match (self.mass_kg, self.density_kg_m3) {
            (Some(m), _) => MassSpec::Mass(m),
            (None, Some(d)) => MassSpec::Density(d),
            (None, None) => MassSpec::Density(DEFAULT_DENSITY),
        }
    }

    /// Checks every field; `source` (manifest path or "built-in") names the origin in
    /// errors; `builtin` selects the stricter friction range.
    pub fn validate(&self, source: &str, builtin: bool) -> Result<(), ObjectError> {
        let err = |field: &str, message: String| ObjectError::InvalidSpec {
            source_name: source.to_string(),
            object: if self.name.is_empty() {
                "<unnamed>".into()
            } else {
                self.name.clone()
            },
            field: field.to_string(),
            message,
        };
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
        {
            return Err(err(
                "name",
                format!(
                    "`{}`: use letters, digits, `_`, `-` or `.` (no spaces or commas)",
                    self.name
                ),
            ));
        }
        let (fmin, fmax) = if builtin {
            BUILTIN_FRICTION
        } else {
            (0.0, 1.0)
        };
        if !(self.friction.is_finite() && self.friction >= fmin && self.friction <= fmax) {
            return Err(err(
                "friction",
                format!(
                    "{} is outside {fmin}..={fmax}",
                    crate::util::num::short(self.friction)
                ),
            ));
        }
        match (self.mass_kg, self.density_kg_m3) {
            (Some(_), Some(_)) => {
                return Err(err(
                    "mass_kg",
                    "give either mass_kg or density_kg_m3, not both".into(),
                ))
            }
            (Some(m), None)
                if !(m.is_finite() && (MASS_RANGE_KG.0..=MASS_RANGE_KG.1).contains(&m)) =>
            {
                return Err(err(
                    "mass_kg",
                    format!("{} is outside 0.001..=10 kg", crate::util::num::short(m)),
                ))
            }
            (None, Some(d)) if !(d.is_finite() && (1.0..=20000.0).contains(&d)) => {
                return Err(err(
                    "density_kg_m3",
                    format!("{} is outside 1..=20000 kg/m^3", crate::util::num::short(d)),
                ))
            }
            _ => {}
        }
        // At least 1 mm: the simulator refuses thinner sides (half sizes below 0.5 mm).
        let dim = |field: &str, v: f64| -> Result<(), ObjectError> {
            if (MIN_SIDE_M..=super::mesh::MAX_EXTENT_M).contains(&v) {
                Ok(())
            } else {
                Err(err(
                    field,
                    format!("{} must be in [0.001, 1] m", crate::util::num::short(v)),
                ))
            }
        };
        match &self.shape {
            ShapeSpec::Box { size } => {
                for (k, &v) in size.iter().enumerate() {
                    dim(&format!("shape.size[{k}]"), v)?;
                }
            }
            ShapeSpec::Cylinder { radius, height } => {
                dim("shape.radius", 2.0 * radius)?;
                dim("shape.height", *height)?;
            }
            ShapeSpec::Sphere { radius } => dim("shape.radius", 2.0 * radius)?,
            ShapeSpec::Capsule { radius, height } => {
                dim("shape.radius", 2.0 * radius)?;
                dim("shape.height", *height)?;
                if *height < 2.0 * radius {
                    return Err(err(
                        "shape.height",
                        format!(
                            "capsule height {height} is below 2 radius ({})",
                            2.0 * radius
                        ),
                    ));
                }
            }
            ShapeSpec::Mesh { scale, path } => {
                if !(scale.is_finite() && *scale > 0.0) {
                    return Err(err(
                        "shape.scale",
                        format!("{} must be positive", crate::util::num::short(*scale)),
                    ));
                }
                if path.as_os_str().is_empty() {
                    return Err(err("shape.path", "empty path".into()));
                }
            }
            ShapeSpec::Procedural {
                generator, scale, ..
            } => {
                if !(scale.is_finite() && (0.05..=20.0).contains(scale)) {
                    return Err(err(
                        "shape.scale",
                        format!("{} is outside 0.05..=20", crate::util::num::short(*scale)),
                    ));
                }
                if super::procedural::find_generator(generator).is_none() {
                    let known: Vec<_> = super::procedural::GENERATORS
                        .iter()
                        .map(|g| g.name)
                        .collect();
                    return Err(err(
                        "shape.generator",
                        format!(
                            "unknown generator `{generator}`; known: {}",
                            known.join(", ")
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Resolves a relative mesh path against `base` (the manifest's folder).
    pub fn resolve_paths(&mut self, base: &Path) {
        if let ShapeSpec::Mesh { path, .. } = &mut self.shape {
            if path.is_relative() {
                *path = base.join(&*path);
            }
        }
    }
}

/// Reads a manifest, validates every object and resolves relative mesh paths.
pub fn load_manifest(path: &Path) -> Result<Vec<ObjectSpec>, ObjectError> {
    let m: Manifest = crate::util::config::load_toml(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let src = path.display().to_string();
    let mut out = Vec::with_capacity(m.object.len());
    for mut spec in m.object {
        spec.validate(&src, false)?;
        spec.resolve_paths(base);
        out.push(spec);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::config::parse_toml;

    fn parse(src: &str) -> Result<Vec<ObjectSpec>, String> {
        let m: Manifest = parse_toml(Path::new("m.toml"), src).map_err(|e| e.to_string())?;
        for s in &m.object {
            s.validate("m.toml", false).map_err(|e| e.to_string())?;
        }
        Ok(m.object)
    }

    #[test]
    fn manifest_parses_all_shapes() {
        let specs = parse(
            r#"
[[object]]
name = "b"
shape = { type = "box", size = [0.1, 0.05, 0.2] }
mass_kg = 0.2
[[object]]
name = "c"
kind = "ycb-like"
shape = { type = "cylinder", radius = 0.03, height = 0.1 }
density_kg_m3 = 700
friction = 0.6
[[object]]
name = "s"
shape = { type = "sphere", radius = 0.03 }
[[object]]
name = "k"
shape = { type = "capsule", radius = 0.02, height = 0.1 }
[[object]]
name = "m"
shape = { type = "mesh", path = "cube.obj", scale = 0.001 }
[[object]]
name = "p"
shape = { type = "procedural", generator = "bottle", seed = 4, params = { radius = 0.03 } }
"#,
        )
        .unwrap();
        assert_eq!(specs.len(), 6);
        assert_eq!(specs[1].kind, ObjectKind::YcbLike);
        assert_eq!(specs[2].mass_spec(), MassSpec::Density(DEFAULT_DENSITY));
        assert_eq!(specs[0].mass_spec(), MassSpec::Mass(0.2));
        assert_eq!(specs[3].friction, DEFAULT_FRICTION);
    }

    #[test]
    fn invalid_specs_name_the_field() {
        let both = "[[object]]\nname = \"x\"\nshape = { type = \"sphere\", radius = 0.03 }\nmass_kg = 0.1\ndensity_kg_m3 = 300\n";
        assert!(parse(both).unwrap_err().contains("not both"));
        let fr = "[[object]]\nname = \"x\"\nshape = { type = \"sphere\", radius = 0.03 }\nfriction = 1.2\n";
        let e = parse(fr).unwrap_err();
        assert!(e.contains("friction") && e.contains("m.toml"), "{e}");
        let typo = "[[object]]\nname = \"x\"\nshape = { type = \"sphere\", radius = 0.03 }\nfrictoin = 0.5\n";
        let e = parse(typo).unwrap_err();
        assert!(e.contains("frictoin") && e.contains("line 4"), "{e}");
        let shape_typo = "[[object]]\nname = \"x\"\nshape = { type = \"sphere\", radus = 0.03 }\n";
        assert!(parse(shape_typo).unwrap_err().contains("radus"));
        let cap = "[[object]]\nname = \"x\"\nshape = { type = \"capsule\", radius = 0.03, height = 0.05 }\n";
        assert!(parse(cap).unwrap_err().contains("below 2 radius"));
        let neg = "[[object]]\nname = \"x\"\nshape = { type = \"box\", size = [0.1, -0.1, 0.1] }\n";
        assert!(parse(neg).unwrap_err().contains("shape.size[1]"));
        let name = "[[object]]\nname = \"a b\"\nshape = { type = \"sphere\", radius = 0.03 }\n";
        assert!(parse(name).unwrap_err().contains("name"));
        let nan = "[[object]]\nname = \"x\"\nshape = { type = \"sphere\", radius = nan }\n";
        assert!(parse(nan).unwrap_err().contains("shape.radius"));
    }

    #[test]
    fn builtin_friction_is_stricter() {
        let mut s = ObjectSpec::new("x", ShapeSpec::Sphere { radius: 0.03 });
        s.friction = 0.3;
        assert!(s.validate("user.toml", false).is_ok());
        assert!(s.validate("built-in", true).is_err());
    }
}
