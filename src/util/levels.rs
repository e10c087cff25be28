//! The paper's torque levels (Sec. V-C): a torque reading mapped to one of six levels by
//! ascending thresholds. The simulator, the environment's observations and the real
//! robot's tendon readings all use [`torque_level`].

/// Maps a reading to a level: the number of thresholds less than or equal to `value`.
///
/// With the paper's simulation thresholds `[-20, -10, 0, 10, 20]` the levels are 0..=5:
/// -25 -> 0, -20 -> 1, -5 -> 2, 0 -> 3, 15 -> 4, 20 -> 5. The thresholds must be ascending
/// for the levels to be monotonic. A NaN reading compares false with every threshold and
/// gives level 0.
pub fn torque_level(value: f64, thresholds: &[f64]) -> u8 {
    thresholds.iter().filter(|t| **t <= value).count() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIM: [f64; 5] = [-20.0, -10.0, 0.0, 10.0, 20.0];
    const REAL: [f64; 5] = [-200.0, -100.0, 0.0, 100.0, 200.0];

    #[test]
    fn sim_levels_hand_computed() {
        assert_eq!(torque_level(-35.0, &SIM), 0);
        assert_eq!(torque_level(-25.0, &SIM), 0);
        assert_eq!(torque_level(-20.0, &SIM), 1);
        assert_eq!(torque_level(-15.0, &SIM), 1);
        assert_eq!(torque_level(-10.0, &SIM), 2);
        assert_eq!(torque_level(-5.0, &SIM), 2);
        assert_eq!(torque_level(-0.5, &SIM), 2);
        assert_eq!(torque_level(0.0, &SIM), 3);
        assert_eq!(torque_level(9.99, &SIM), 3);
        assert_eq!(torque_level(10.0, &SIM), 4);
        assert_eq!(torque_level(15.0, &SIM), 4);
        assert_eq!(torque_level(19.0, &SIM), 4);
        assert_eq!(torque_level(20.0, &SIM), 5);
        assert_eq!(torque_level(1e9, &SIM), 5);
        assert_eq!(torque_level(f64::INFINITY, &SIM), 5);
        assert_eq!(torque_level(f64::NEG_INFINITY, &SIM), 0);
    }

    #[test]
    fn nan_is_level_zero() {
        assert_eq!(torque_level(f64::NAN, &SIM), 0);
        assert_eq!(torque_level(f64::NAN, &REAL), 0);
    }

    #[test]
    fn real_thresholds_and_other_lengths() {
        assert_eq!(torque_level(-150.0, &REAL), 1);
        assert_eq!(torque_level(99.0, &REAL), 3);
        assert_eq!(torque_level(250.0, &REAL), 5);
        // No thresholds: one level. Three thresholds: levels 0..=3.
        assert_eq!(torque_level(7.0, &[]), 0);
        assert_eq!(torque_level(0.5, &[0.0, 1.0, 2.0]), 1);
        assert_eq!(torque_level(2.0, &[0.0, 1.0, 2.0]), 3);
    }
}
