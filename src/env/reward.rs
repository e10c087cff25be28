//! The reward of the grasping MDP (Sec. IV-D).
//!
//! Eq. 4: `R = r_b` at the final step (1 if the object was picked up, else 0) and
//! `R = 0.03 r_c` at every earlier step.
//! Eq. 5: `r_c = sum_i (theta_target_i - theta_i) M_i`, with the mask `M` = 1 on the key
//! closing joints FFJ3, MFJ3, RFJ3, LFJ3, THJ5. `theta_target` is the feasible finger
//! target actually commanded (eq. 2 after clamping to limits and coupling) and `theta`
//! the measured finger angles when the action was chosen, both in radians.

use crate::robot::joints::{finger_index, KEY_CLOSING_JOINTS};
use serde::{Deserialize, Serialize};

/// Weight of the closing reward in eq. 4.
pub const CLOSING_WEIGHT: f64 = 0.03;

/// Indices of the key closing joints in the 22-joint finger vector.
pub fn key_closing_indices() -> [usize; 5] {
    KEY_CLOSING_JOINTS.map(|k| finger_index(k).unwrap_or_default())
}

/// Eq. 5: the hand-closing reward `r_c`.
pub fn closing_reward(target: &[f64; 22], theta: &[f64; 22]) -> f64 {
    key_closing_indices()
        .iter()
        .map(|&i| target[i] - theta[i])
        .sum()
}

/// Eq. 4: the step reward. `final_success` is `Some(r_b)` at the final (lift) step.
pub fn step_reward(target: &[f64; 22], theta: &[f64; 22], final_success: Option<bool>) -> f64 {
    match final_success {
        Some(ok) => f64::from(u8::from(ok)),
        None => CLOSING_WEIGHT * closing_reward(target, theta),
    }
}

/// Shaped reward terms beyond the paper, all off by default (eq. 4-5 unchanged).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RewardConfig {
    /// Penalty per metre the object's origin moves during a (non-final) stage-2 step:
    /// `R -= displacement_weight * |p_after - p_before|`. A hand that pushes the object
    /// away while adjusting its fingers pays for it (0: the paper's reward).
    pub displacement_weight: f64,
}

impl Default for RewardConfig {
    fn default() -> Self {
        RewardConfig {
            displacement_weight: 0.0,
        }
    }
}

impl RewardConfig {
    /// Checks the ranges: `(field, message)` on error.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        crate::util::num::within(
            "reward.displacement_weight",
            self.displacement_weight,
            0.0,
            1000.0,
            " per metre",
        )
    }
}

/// The shaped displacement penalty for an object that moved `moved` metres in one step.
pub fn displacement_penalty(cfg: &RewardConfig, moved: f64) -> f64 {
    cfg.displacement_weight * moved
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closing_reward_sums_only_the_masked_joints() {
        let theta = [0.0; 22];
        let mut target = [0.0; 22];
        // FFJ3 (index 1) +0.2, MFJ3 (5) +0.1, THJ5 (17) -0.05, FFJ4 (0) +1.0 (masked out).
        target[1] = 0.2;
        target[5] = 0.1;
        target[17] = -0.05;
        target[0] = 1.0;
        let rc = closing_reward(&target, &theta);
        assert!((rc - 0.25).abs() < 1e-12, "{rc}");
        assert!((step_reward(&target, &theta, None) - 0.0075).abs() < 1e-12);
    }

    #[test]
    fn final_step_reward_is_binary() {
        let z = [0.0; 22];
        let mut t = z;
        t[1] = 1.0;
        assert_eq!(step_reward(&t, &z, Some(true)), 1.0);
        assert_eq!(step_reward(&t, &z, Some(false)), 0.0);
    }

    #[test]
    fn displacement_penalty_is_linear_in_the_distance_and_off_by_default() {
        let cfg = RewardConfig {
            displacement_weight: 10.0,
        };
        // 1 cm of push costs 0.1 with weight 10; nothing with the default.
        assert!((displacement_penalty(&cfg, 0.01) - 0.1).abs() < 1e-12);
        assert_eq!(displacement_penalty(&RewardConfig::default(), 0.01), 0.0);
        assert!(cfg.validate().is_ok());
        for bad in [-1.0, f64::NAN, 2000.0] {
            let e = RewardConfig {
                displacement_weight: bad,
            }
            .validate()
            .unwrap_err();
            assert_eq!(e.0, "reward.displacement_weight");
        }
    }

    #[test]
    fn key_indices_are_the_j3s_and_thj5() {
        assert_eq!(key_closing_indices(), [1, 5, 9, 14, 17]);
    }
}
