//! Continuous-action CartPole: the classic cart-pole balancing task of Barto, Sutton and
//! Anderson (1983) with the dynamics of gymnasium's `CartPole-v1`, driven by a continuous
//! force.
//!
//! State (x, x_dot, theta, theta_dot); the action is one value a, the applied force is
//! `clip(a, -1, 1) * 10` N. Euler integration with tau = 0.02 s. The reward is +1 for every
//! step, including the one that ends the episode. The episode terminates when |x| > 2.4 m or
//! |theta| > 12 degrees, and is truncated after `max_steps` steps (500 as in `CartPole-v1`).
//! Each state component starts uniformly in [-0.05, 0.05]. A random policy balances for
//! about 20 steps.

use super::api::{Action, ActionSpec, Env, Step, StepInfo};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Gravity (m/s^2).
pub const GRAVITY: f64 = 9.8;
/// Mass of the cart (kg).
pub const MASS_CART: f64 = 1.0;
/// Mass of the pole (kg).
pub const MASS_POLE: f64 = 0.1;
/// Half the pole's length (m).
pub const HALF_LENGTH: f64 = 0.5;
/// Force for an action of magnitude 1 (N).
pub const FORCE_MAG: f64 = 10.0;
/// Integration step (s).
pub const TAU: f64 = 0.02;
/// Cart position limit (m).
pub const X_LIMIT: f64 = 2.4;
/// Pole angle limit (rad): 12 degrees.
pub const THETA_LIMIT: f64 = 12.0 * 2.0 * std::f64::consts::PI / 360.0;

/// One Euler step of the cart-pole dynamics from `state` = (x, x_dot, theta, theta_dot)
/// with the horizontal `force` (N) on the cart.
pub fn cartpole_dynamics(state: [f64; 4], force: f64) -> [f64; 4] {
    let [x, x_dot, theta, theta_dot] = state;
    let total_mass = MASS_CART + MASS_POLE;
    let polemass_length = MASS_POLE * HALF_LENGTH;
    let (sin, cos) = theta.sin_cos();
    let temp = (force + polemass_length * theta_dot * theta_dot * sin) / total_mass;
    let theta_acc = (GRAVITY * sin - cos * temp)
        / (HALF_LENGTH * (4.0 / 3.0 - MASS_POLE * cos * cos / total_mass));
    let x_acc = temp - polemass_length * theta_acc * cos / total_mass;
    [
        x + TAU * x_dot,
        x_dot + TAU * x_acc,
        theta + TAU * theta_dot,
        theta_dot + TAU * theta_acc,
    ]
}

/// The continuous-action CartPole environment.
#[derive(Debug, Clone)]
pub struct CartPole {
    state: [f64; 4],
    t: u32,
    max_steps: u32,
}

impl CartPole {
    /// A CartPole truncated after `max_steps` steps (at least 1).
    pub fn new(max_steps: u32) -> Self {
        Self {
            state: [0.0; 4],
            t: 0,
            max_steps: max_steps.max(1),
        }
    }

    /// The current state (x, x_dot, theta, theta_dot).
    pub fn state(&self) -> [f64; 4] {
        self.state
    }

    /// Sets the state (for tests and demonstrations); the step counter is kept.
    pub fn set_state(&mut self, state: [f64; 4]) {
        self.state = state;
    }

    fn obs(&self) -> Vec<f32> {
        self.state.iter().map(|&v| v as f32).collect()
    }
}

impl Default for CartPole {
    /// The `CartPole-v1` setting: truncation after 500 steps.
    fn default() -> Self {
        Self::new(500)
    }
}

impl Env for CartPole {
    fn obs_dim(&self) -> usize {
        4
    }

    fn action_spec(&self) -> ActionSpec {
        ActionSpec {
            continuous: 1,
            lift: false,
        }
    }

    fn reset(&mut self, seed: u64) -> Vec<f32> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for s in &mut self.state {
            *s = rng.random_range(-0.05..0.05);
        }
        self.t = 0;
        self.obs()
    }

    fn step(&mut self, a: &Action) -> Step {
        let raw = f64::from(a.cont.first().copied().unwrap_or(0.0));
        // NaN actions push with zero force rather than poisoning the state.
        let u = if raw.is_nan() {
            0.0
        } else {
            raw.clamp(-1.0, 1.0)
        };
        self.state = cartpole_dynamics(self.state, u * FORCE_MAG);
        self.t += 1;
        let [x, _, theta, _] = self.state;
        let terminated = x.abs() > X_LIMIT || theta.abs() > THETA_LIMIT;
        Step {
            obs: self.obs(),
            reward: 1.0,
            terminated,
            truncated: !terminated && self.t >= self.max_steps,
            info: StepInfo::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn push_from_rest_matches_hand_computation() {
        // temp = 10 / 1.1 = 9.090909; theta_acc = -temp / (0.5 (4/3 - 0.1/1.1)) = -14.634146;
        // x_acc = temp - 0.05 theta_acc / 1.1 = 9.756098; velocities gain tau * acc.
        let s = cartpole_dynamics([0.0; 4], 10.0);
        assert_relative_eq!(s[0], 0.0);
        assert_relative_eq!(s[1], 0.195_121_95, epsilon = 1e-7);
        assert_relative_eq!(s[2], 0.0);
        assert_relative_eq!(s[3], -0.292_682_93, epsilon = 1e-7);
    }

    #[test]
    fn tilted_pole_step_matches_hand_computation() {
        // theta = 0.1, theta_dot = 0.5, x_dot = 0.2, no force:
        // temp = 0.05 * 0.25 * sin(0.1) / 1.1 = 0.00113446
        // theta_acc = (9.8 sin 0.1 - cos 0.1 temp) / (0.5 (4/3 - 0.1 cos^2 0.1 / 1.1))
        //           = (0.978367 - 0.00112880) / (0.5 * 1.243330) = 1.571970
        // x_acc = temp - 0.05 * theta_acc * cos 0.1 / 1.1 = 0.00113447 - 0.0710962 = -0.0699617
        let s = cartpole_dynamics([1.0, 0.2, 0.1, 0.5], 0.0);
        assert_relative_eq!(s[0], 1.004, epsilon = 1e-12);
        assert_relative_eq!(s[1], 0.2 - 0.02 * 0.069_961_7, epsilon = 1e-7);
        assert_relative_eq!(s[2], 0.11, epsilon = 1e-12);
        assert_relative_eq!(s[3], 0.5 + 0.02 * 1.571_970, epsilon = 1e-6);
    }

    #[test]
    fn action_is_clipped_and_termination_and_truncation_happen() {
        let mut a = CartPole::new(3);
        a.reset(1);
        a.set_state([0.0; 4]);
        let s = a.step(&Action {
            cont: vec![5.0],
            lift: false,
        });
        assert_relative_eq!(f64::from(s.obs[1]), 0.195_121_95, epsilon = 1e-6);
        assert_eq!(s.reward, 1.0);
        assert!(!s.terminated && !s.truncated);
        let zero = Action {
            cont: vec![0.0],
            lift: false,
        };
        a.step(&zero);
        let s = a.step(&zero);
        assert!(s.truncated && !s.terminated);

        let mut b = CartPole::new(500);
        b.reset(2);
        b.set_state([0.0, 0.0, 0.25, 0.0]);
        let s = b.step(&zero);
        assert!(s.terminated && !s.truncated);
    }

    #[test]
    fn reset_is_seeded_and_small() {
        let mut a = CartPole::default();
        let o1 = a.reset(42);
        let o2 = a.reset(42);
        let o3 = a.reset(43);
        assert_eq!(o1, o2);
        assert_ne!(o1, o3);
        assert!(o1.iter().all(|v| v.abs() <= 0.05));
    }
}
