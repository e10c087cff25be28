//! Letting the object come to rest after a failed grasp: the hand opens where it is and
//! the physics runs until the object lies still on the table, clear of the hand. Both
//! retries use it: `grasp eval --attempts` ([`crate::env::grasp::GraspEnv::prepare_retry`])
//! and `grasp run --attempts` (the sim backend).

use super::HandSim;

/// Longest wait for the object to come to rest (s).
pub const SETTLE_MAX_S: f64 = 2.0;

/// Shortest wait (s): the fingers open before the object is judged at rest.
pub const SETTLE_MIN_S: f64 = 0.25;

/// The object is at rest below this linear speed (m/s) ...
pub const REST_SPEED: f64 = 0.005;

/// ... and this angular speed (rad/s).
pub const REST_SPIN: f64 = 0.05;

/// The object lies on the table when its lowest point is within this of the table top (m).
pub const ON_TABLE_M: f64 = 0.01;

/// Why the object did not settle on the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Unsettled {
    /// A target was refused or the physics failed while waiting.
    #[error("the physics failed while the object settled")]
    PhysicsFailure,
    /// The object still moved, or still touched the hand, after [`SETTLE_MAX_S`].
    #[error("the object did not come to rest clear of the hand within 2 s")]
    NotAtRest,
    /// The object came to rest off the table top.
    #[error("the object left the table")]
    OffTable,
}

impl HandSim {
    /// Opens the hand to `open` where it is and runs the physics (at least
    /// [`SETTLE_MIN_S`], at most [`SETTLE_MAX_S`]) until the object is at rest, clear of
    /// the hand, and lies on the table top.
    pub fn settle_object(&mut self, open: &[f64; 24]) -> Result<(), Unsettled> {
        let dt = self.config().dt;
        let (min, max) = (
            (SETTLE_MIN_S / dt).round() as usize,
            (SETTLE_MAX_S / dt).round() as usize,
        );
        self.set_targets(open)
            .map_err(|_| Unsettled::PhysicsFailure)?;
        let mut settled = false;
        for k in 0..max {
            if !self.step_physics() {
                return Err(Unsettled::PhysicsFailure);
            }
            if k + 1 >= min {
                let (v, w) = self.object_speed();
                if v < REST_SPEED && w < REST_SPIN && self.hand_object_force() == 0.0 {
                    settled = true;
                    break;
                }
            }
        }
        if !settled {
            return Err(Unsettled::NotAtRest);
        }
        if self.object_lowest_z().abs() > ON_TABLE_M {
            return Err(Unsettled::OffTable);
        }
        Ok(())
    }
}
