//! The object to grasp: a small set of primitives of the simulator's own, until the object
//! library provides shapes. One dynamic rigid body with one collider.

use rapier3d::prelude::{ColliderBuilder, SharedShape};
use serde::{Deserialize, Serialize};

/// Error of an invalid object description.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("object: field '{field}' = {value}: {message}")]
pub struct ObjectError {
    /// The field, e.g. `mass`.
    pub field: &'static str,
    /// The value found.
    pub value: f64,
    /// The allowed range.
    pub message: &'static str,
}

/// Shape of a primitive object, in its body frame (z up when resting).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum ObjectShape {
    /// A box with half extents (m).
    Box {
        /// Half extents x, y, z (m).
        half: [f64; 3],
    },
    /// An upright cylinder (axis along z).
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Half height (m).
        half_height: f64,
    },
}

impl ObjectShape {
    /// Volume (m^3).
    pub fn volume(&self) -> f64 {
        match *self {
            ObjectShape::Box { half } => 8.0 * half[0] * half[1] * half[2],
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => std::f64::consts::PI * radius * radius * 2.0 * half_height,
        }
    }

    /// Height of the body origin above a supporting plane when resting upright (m).
    pub fn rest_height(&self) -> f64 {
        match *self {
            ObjectShape::Box { half } => half[2],
            ObjectShape::Cylinder { half_height, .. } => half_height,
        }
    }

    /// The collision shape (rapier's cylinder runs along y; it is turned upright by the
    /// collider pose from [`ObjectShape::collider`]).
    pub fn shared_shape(&self) -> SharedShape {
        match *self {
            ObjectShape::Box { half } => {
                SharedShape::cuboid(half[0] as f32, half[1] as f32, half[2] as f32)
            }
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => SharedShape::cylinder(half_height as f32, radius as f32),
        }
    }

    /// A collider builder with the shape upright in the body frame.
    pub fn collider(&self) -> ColliderBuilder {
        let b = ColliderBuilder::new(self.shared_shape());
        match self {
            ObjectShape::Box { .. } => b,
            ObjectShape::Cylinder { .. } => b.rotation(rapier3d::math::Vector::new(
                std::f32::consts::FRAC_PI_2,
                0.0,
                0.0,
            )),
        }
    }
}

/// A primitive object with its mass and friction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// The shape.
    pub shape: ObjectShape,
    /// Mass (kg).
    pub mass: f64,
    /// Friction coefficient (combined with MIN against the hand and the table).
    pub friction: f64,
}

impl ObjectSpec {
    /// A box of `mass` kg with half extents `half`.
    pub fn cuboid(half: [f64; 3], mass: f64, friction: f64) -> Self {
        ObjectSpec {
            shape: ObjectShape::Box { half },
            mass,
            friction,
        }
    }

    /// The default test box: 5 x 5 x 8 cm, 100 g, friction 0.8.
    pub fn default_box() -> Self {
        Self::cuboid([0.025, 0.025, 0.04], 0.1, 0.8)
    }

    /// The default cylinder: radius 3 cm, height 10 cm, 150 g, friction 0.8.
    pub fn default_cylinder() -> Self {
        ObjectSpec {
            shape: ObjectShape::Cylinder {
                radius: 0.03,
                half_height: 0.05,
            },
            mass: 0.15,
            friction: 0.8,
        }
    }

    /// A spec of `mass` kg with the density `rho` (kg/m^3) of the shape.
    pub fn with_density(shape: ObjectShape, rho: f64, friction: f64) -> Self {
        ObjectSpec {
            shape,
            mass: rho * shape.volume(),
            friction,
        }
    }

    /// Checks sizes (1 mm .. 1 m), mass (1 g .. 20 kg) and friction ([0, 1]).
    pub fn validate(&self) -> Result<(), ObjectError> {
        let size = |field: &'static str, v: f64| {
            if v.is_finite() && (0.0005..=0.5).contains(&v) {
                Ok(())
            } else {
                Err(ObjectError {
                    field,
                    value: v,
                    message: "half size must be in [0.0005, 0.5] m",
                })
            }
        };
        match self.shape {
            ObjectShape::Box { half } => {
                size("half[0]", half[0])?;
                size("half[1]", half[1])?;
                size("half[2]", half[2])?;
            }
            ObjectShape::Cylinder {
                radius,
                half_height,
            } => {
                size("radius", radius)?;
                size("half_height", half_height)?;
            }
        }
        if !(self.mass.is_finite() && (0.001..=20.0).contains(&self.mass)) {
            return Err(ObjectError {
                field: "mass",
                value: self.mass,
                message: "must be in [0.001, 20] kg",
            });
        }
        if !(self.friction.is_finite() && (0.0..=1.0).contains(&self.friction)) {
            return Err(ObjectError {
                field: "friction",
                value: self.friction,
                message: "must be in [0, 1]",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_and_density() {
        let b = ObjectShape::Box {
            half: [0.01, 0.02, 0.03],
        };
        assert!((b.volume() - 8.0 * 6e-6).abs() < 1e-15);
        let s = ObjectSpec::with_density(b, 1000.0, 0.5);
        assert!((s.mass - 0.048).abs() < 1e-12);
        let c = ObjectShape::Cylinder {
            radius: 0.1,
            half_height: 0.5,
        };
        assert!((c.volume() - std::f64::consts::PI * 0.01).abs() < 1e-12);
    }

    #[test]
    fn validation_names_the_field() {
        let mut s = ObjectSpec::default_box();
        s.validate().unwrap();
        s.friction = 1.5;
        assert_eq!(s.validate().unwrap_err().field, "friction");
        s.friction = 0.5;
        s.mass = f64::NAN;
        assert_eq!(s.validate().unwrap_err().field, "mass");
    }
}
