//! Tendon-force drift compensation and torque levels (Sec. V-C).
//!
//! The Shadow hand reports tendon forces, not joint torques, and they drift over time.
//! At the start of every grasp attempt, with the hand empty, the baseline `tau_j0` is
//! recorded (the mean of a few readings); during the attempt the mapped value
//! `tau_j - tau_j0` is turned into a level 0..5 by
//! [`torque_level`], the same function the simulator uses,
//! with the real robot's thresholds {-200, -100, 0, 100, 200}.

use crate::robot::joints::N_ACTUATORS;
use crate::util::levels::torque_level;

/// The paper's thresholds for the real robot's tendon readings.
pub const REAL_THRESHOLDS: [f64; 5] = [-200.0, -100.0, 0.0, 100.0, 200.0];
/// The paper's thresholds for the simulator's joint torques.
pub const SIM_THRESHOLDS: [f64; 5] = [-20.0, -10.0, 0.0, 10.0, 20.0];
/// Default number of empty-hand readings averaged into the baseline.
pub const DEFAULT_BASELINE_READINGS: usize = 5;

/// Error of the torque mapping.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TorqueError {
    /// The thresholds are not finite and strictly ascending.
    #[error("torque thresholds {0:?} must be finite and strictly ascending")]
    BadThresholds([f64; 5]),
    /// No baseline readings were given.
    #[error("the tendon baseline needs at least one reading")]
    NoReadings,
    /// A reading is NaN or infinite.
    #[error("tendon reading [{index}] = {value} is not finite")]
    NonFinite {
        /// Actuator index (paper actuator order).
        index: usize,
        /// The value.
        value: f64,
    },
    /// Mapping was asked for before a baseline was recorded for this attempt.
    #[error("no tendon baseline: record tau_j0 with the empty hand at the attempt start")]
    NoBaseline,
}

/// Maps raw tendon readings to drift-compensated values and levels.
#[derive(Debug, Clone, PartialEq)]
pub struct TorqueMapper {
    thresholds: [f64; 5],
    baseline: Option<[f64; N_ACTUATORS]>,
}

impl TorqueMapper {
    /// A mapper with these ascending thresholds and no baseline yet.
    pub fn new(thresholds: [f64; 5]) -> Result<Self, TorqueError> {
        let ok =
            thresholds.iter().all(|t| t.is_finite()) && thresholds.windows(2).all(|w| w[0] < w[1]);
        if !ok {
            return Err(TorqueError::BadThresholds(thresholds));
        }
        Ok(TorqueMapper {
            thresholds,
            baseline: None,
        })
    }

    /// A mapper with the real robot's thresholds [`REAL_THRESHOLDS`].
    pub fn real() -> Self {
        TorqueMapper {
            thresholds: REAL_THRESHOLDS,
            baseline: None,
        }
    }

    /// The thresholds in use.
    pub fn thresholds(&self) -> &[f64; 5] {
        &self.thresholds
    }

    /// The baseline `tau_j0`, if recorded.
    pub fn baseline(&self) -> Option<&[f64; N_ACTUATORS]> {
        self.baseline.as_ref()
    }

    /// Records `tau_j0` as the mean of `readings`, taken with the empty hand at the start
    /// of an attempt. Replaces any previous baseline.
    pub fn set_baseline<I>(&mut self, readings: I) -> Result<(), TorqueError>
    where
        I: IntoIterator<Item = [f64; N_ACTUATORS]>,
    {
        let mut sum = [0.0; N_ACTUATORS];
        let mut n = 0usize;
        for r in readings {
            check_finite(&r)?;
            for (s, v) in sum.iter_mut().zip(r) {
                *s += v;
            }
            n += 1;
        }
        if n == 0 {
            return Err(TorqueError::NoReadings);
        }
        self.baseline = Some(sum.map(|s| s / n as f64));
        Ok(())
    }

    /// Forgets the baseline (end of an attempt).
    pub fn clear_baseline(&mut self) {
        self.baseline = None;
    }

    /// The drift-compensated values `tau_j - tau_j0`.
    pub fn mapped(&self, raw: &[f64; N_ACTUATORS]) -> Result<[f64; N_ACTUATORS], TorqueError> {
        let b = self.baseline.as_ref().ok_or(TorqueError::NoBaseline)?;
        check_finite(raw)?;
        Ok(std::array::from_fn(|k| raw[k] - b[k]))
    }

    /// The levels 0..5 of the drift-compensated values.
    pub fn levels(&self, raw: &[f64; N_ACTUATORS]) -> Result<[u8; N_ACTUATORS], TorqueError> {
        let m = self.mapped(raw)?;
        Ok(m.map(|v| torque_level(v, &self.thresholds)))
    }
}

fn check_finite(r: &[f64; N_ACTUATORS]) -> Result<(), TorqueError> {
    match r.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(TorqueError::NonFinite {
            index,
            value: r[index],
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn baseline_is_the_mean_and_levels_are_hand_computed() {
        let mut m = TorqueMapper::real();
        assert_eq!(m.levels(&[0.0; 20]), Err(TorqueError::NoBaseline));
        let mut a = [1000.0; 20];
        a[0] = 990.0;
        let mut b = [1000.0; 20];
        b[0] = 1010.0;
        m.set_baseline([a, b]).unwrap();
        assert_eq!(m.baseline().unwrap()[0], 1000.0);
        let mut raw = [1000.0; 20];
        // mapped: -250 -> 0, -200 -> 1, -150 -> 1, -1 -> 2, 0 -> 3, 99 -> 3, 100 -> 4, 250 -> 5
        let vals = [-250.0, -200.0, -150.0, -1.0, 0.0, 99.0, 100.0, 250.0];
        for (k, v) in vals.iter().enumerate() {
            raw[k] = 1000.0 + v;
        }
        let lv = m.levels(&raw).unwrap();
        assert_eq!(&lv[..8], &[0, 1, 1, 2, 3, 3, 4, 5]);
        assert!(lv[8..].iter().all(|&l| l == 3));
        assert_eq!(m.mapped(&raw).unwrap()[0], -250.0);
    }

    #[test]
    fn constant_drift_does_not_change_levels() {
        let base: [f64; 20] = std::array::from_fn(|k| 50.0 * k as f64 - 300.0);
        let during: [f64; 20] = std::array::from_fn(|k| base[k] + 37.0 * k as f64 - 260.0);
        let mut m0 = TorqueMapper::real();
        m0.set_baseline([base; 3]).unwrap();
        let l0 = m0.levels(&during).unwrap();
        for drift in [-5000.0, -123.4, 0.5, 777.0] {
            let mut m = TorqueMapper::real();
            m.set_baseline([base.map(|v| v + drift); 3]).unwrap();
            assert_eq!(m.levels(&during.map(|v| v + drift)).unwrap(), l0);
        }
        // The levels are not trivially constant: they span several values.
        assert!(l0.contains(&0) && l0.contains(&5));
    }

    #[test]
    fn bad_inputs() {
        assert!(TorqueMapper::new([0.0, 1.0, 1.0, 2.0, 3.0]).is_err());
        assert!(TorqueMapper::new([0.0, 1.0, f64::NAN, 2.0, 3.0]).is_err());
        assert!(TorqueMapper::new(SIM_THRESHOLDS).is_ok());
        let mut m = TorqueMapper::real();
        assert_eq!(
            m.set_baseline(std::iter::empty()),
            Err(TorqueError::NoReadings)
        );
        let mut r = [0.0; 20];
        r[7] = f64::NAN;
        assert!(matches!(
            m.set_baseline([r]),
            Err(TorqueError::NonFinite { index: 7, .. })
        ));
        m.set_baseline([[0.0; 20]]).unwrap();
        assert!(matches!(
            m.levels(&r),
            Err(TorqueError::NonFinite { index: 7, .. })
        ));
        m.clear_baseline();
        assert_eq!(m.mapped(&[0.0; 20]), Err(TorqueError::NoBaseline));
    }
}
