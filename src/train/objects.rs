//! Built-in object sets for training.

use crate::sim::{ObjectShape, ObjectSpec};

/// The `"primitives"` set: eight boxes and cylinders of varied sizes (2-7 cm across,
/// 6-10 cm tall), masses (80-200 g) and frictions (0.55-0.95), all graspable by the hand.
pub fn primitives() -> Vec<(String, ObjectSpec)> {
    let cyl = |radius: f64, half_height: f64, mass: f64, friction: f64| {
        let mut s = ObjectSpec::default_cylinder();
        s.shape = ObjectShape::Cylinder {
            radius,
            half_height,
        };
        s.mass = mass;
        s.friction = friction;
        s
    };
    vec![
        (
            "box_small".into(),
            ObjectSpec::cuboid([0.02, 0.02, 0.03], 0.08, 0.9),
        ),
        (
            "box_medium".into(),
            ObjectSpec::cuboid([0.025, 0.025, 0.04], 0.1, 0.8),
        ),
        (
            "box_flat".into(),
            ObjectSpec::cuboid([0.035, 0.025, 0.03], 0.15, 0.7),
        ),
        (
            "box_tall".into(),
            ObjectSpec::cuboid([0.02, 0.02, 0.05], 0.12, 0.6),
        ),
        ("cylinder_thin".into(), cyl(0.02, 0.05, 0.1, 0.85)),
        ("cylinder_medium".into(), cyl(0.03, 0.05, 0.15, 0.75)),
        ("cylinder_wide".into(), cyl(0.035, 0.04, 0.2, 0.55)),
        ("cylinder_short".into(), cyl(0.025, 0.03, 0.09, 0.95)),
    ]
}

/// The object set called `name`: `primitives`, or anything `--objects` accepts (`train`,
/// `unseen`, a folder, a manifest, names), converted for the simulator. Errors name the
/// unknown set or the object that cannot be simulated (and the set: the manifest, the
/// folder), checked for every object before any episode runs.
pub fn object_set(name: &str) -> Result<Vec<(String, ObjectSpec)>, String> {
    if name == "primitives" {
        return Ok(primitives());
    }
    let ctx = crate::objects::sets::BuildContext::from_env();
    let objects = crate::objects::sets::load_objects(name, &ctx).map_err(|e| e.to_string())?;
    // Every object is checked before any episode runs: one the simulator refuses would
    // otherwise fail each of its episodes.
    objects
        .iter()
        .map(|o| {
            ObjectSpec::simulable(o)
                .map(|s| (o.name.clone(), s))
                .map_err(|e| format!("{e} (in `{name}`)"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_are_valid_varied_and_uniquely_named() {
        let set = primitives();
        assert_eq!(set.len(), 8);
        let mut names: Vec<&str> = set.iter().map(|(n, _)| n.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), 8);
        for (name, s) in &set {
            s.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!((0.5..=1.0).contains(&s.friction), "{name}");
        }
        let boxes = set
            .iter()
            .filter(|(_, s)| matches!(s.shape, ObjectShape::Box { .. }))
            .count();
        assert_eq!(boxes, 4);
        assert!(object_set("primitives").is_ok() && object_set("no_such_set_xyz").is_err());
    }
}
