//! Generalised advantage estimation (Schulman et al. 2016) with the time-limit distinction of
//! Pardo et al. (2018).
//!
//! For each environment, backwards over the rollout:
//!
//! - `r'_t = r_t + gamma * V(final_obs_t)` when step t was truncated (a time limit, not a
//!   terminal state): the value of the state the episode was cut in is folded into the reward
//!   (the CleanRL/SB3 way of bootstrapping on truncation); `r'_t = r_t` otherwise;
//! - `nonterminal_t = 0` when the episode ended at t (terminated or truncated), else 1;
//! - `delta_t = r'_t + gamma * V_{t+1} * nonterminal_t - V_t`, with `V_{t+1}` the next
//!   rollout value, or the value of the observation after the rollout for the last step;
//! - `A_t = delta_t + gamma * lambda * nonterminal_t * A_{t+1}`, returns `R_t = A_t + V_t`.
//!
//! A terminated step gets no bootstrap at all.

/// The inputs of [`compute_gae`]; every per-step slice is time-major, `T * num_envs` long
/// (index `t * num_envs + env`).
#[derive(Debug, Clone, Copy)]
pub struct GaeInput<'a> {
    /// Number of environments B.
    pub num_envs: usize,
    /// Rewards r_t.
    pub rewards: &'a [f32],
    /// Values V(o_t) computed during the rollout.
    pub values: &'a [f32],
    /// The episode reached a terminal state at step t.
    pub terminated: &'a [bool],
    /// The episode was truncated at step t.
    pub truncated: &'a [bool],
    /// V(final observation) for truncated steps (ignored elsewhere).
    pub final_values: &'a [f32],
    /// V of the observation after the last step, one per environment.
    pub next_values: &'a [f32],
    /// Discount gamma.
    pub gamma: f64,
    /// GAE lambda.
    pub lambda: f64,
}

/// Advantages and returns (`advantages + values`), time-major. Computed in f64.
///
/// # Panics
/// When the slices' lengths disagree (an internal invariant of the rollout buffer).
pub fn compute_gae(inp: &GaeInput<'_>) -> (Vec<f32>, Vec<f32>) {
    let b = inp.num_envs;
    let n = inp.rewards.len();
    assert!(
        b > 0 && n.is_multiple_of(b),
        "rollout length {n} is not a multiple of {b}"
    );
    for len in [
        inp.values.len(),
        inp.terminated.len(),
        inp.truncated.len(),
        inp.final_values.len(),
    ] {
        assert_eq!(len, n, "GAE inputs have different lengths");
    }
    assert_eq!(inp.next_values.len(), b, "one next value per environment");
    let t_len = n / b;
    let (g, l) = (inp.gamma, inp.lambda);
    let mut adv = vec![0f32; n];
    let mut ret = vec![0f32; n];
    for e in 0..b {
        let mut last = 0f64;
        for t in (0..t_len).rev() {
            let i = t * b + e;
            let mut r = f64::from(inp.rewards[i]);
            if inp.truncated[i] && !inp.terminated[i] {
                r += g * f64::from(inp.final_values[i]);
            }
            let ended = inp.terminated[i] || inp.truncated[i];
            let nonterminal = if ended { 0.0 } else { 1.0 };
            let next_v = if t + 1 == t_len {
                f64::from(inp.next_values[e])
            } else {
                f64::from(inp.values[i + b])
            };
            let v = f64::from(inp.values[i]);
            let delta = r + g * next_v * nonterminal - v;
            last = delta + g * l * nonterminal * last;
            adv[i] = last as f32;
            ret[i] = (last + v) as f32;
        }
    }
    (adv, ret)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_steps_with_truncation_and_termination_by_hand() {
        // gamma = lambda = 0.5. Env 0: step 0 plain, step 1 truncated with V(final) = 4,
        // step 2 terminated (the next value 10 must be ignored).
        //   t2: delta = 1 - 3 = -2                    A2 = -2
        //   t1: r' = 1 + 0.5*4 = 3, delta = 3 - 2 = 1 A1 = 1 (episode ended: no carry)
        //   t0: delta = 1 + 0.5*2 - 1 = 1             A0 = 1 + 0.25*1 = 1.25
        // Env 1: nothing ends, rewards (0, 0, 1), values 0, next value 4:
        //   t2: delta = 1 + 0.5*4 = 3 -> A2 = 3; A1 = 0.25*3 = 0.75; A0 = 0.1875.
        let inp = GaeInput {
            num_envs: 2,
            rewards: &[1.0, 0.0, 1.0, 0.0, 1.0, 1.0],
            values: &[1.0, 0.0, 2.0, 0.0, 3.0, 0.0],
            terminated: &[false, false, false, false, true, false],
            truncated: &[false, false, true, false, false, false],
            final_values: &[0.0, 0.0, 4.0, 0.0, 99.0, 0.0],
            next_values: &[10.0, 4.0],
            gamma: 0.5,
            lambda: 0.5,
        };
        let (adv, ret) = compute_gae(&inp);
        let want_adv = [1.25, 0.1875, 1.0, 0.75, -2.0, 3.0];
        let want_ret = [2.25, 0.1875, 3.0, 0.75, 1.0, 3.0];
        for i in 0..6 {
            assert!((adv[i] - want_adv[i]).abs() < 1e-6, "{adv:?}");
            assert!((ret[i] - want_ret[i]).abs() < 1e-6, "{ret:?}");
        }
    }

    #[test]
    fn lambda_one_gives_discounted_returns() {
        // One env, no ends, values zero: returns are discounted reward-to-go + bootstrap.
        let inp = GaeInput {
            num_envs: 1,
            rewards: &[1.0, 1.0],
            values: &[0.0, 0.0],
            terminated: &[false, false],
            truncated: &[false, false],
            final_values: &[0.0, 0.0],
            next_values: &[2.0],
            gamma: 0.9,
            lambda: 1.0,
        };
        let (_, ret) = compute_gae(&inp);
        assert!((ret[1] - (1.0 + 0.9 * 2.0)).abs() < 1e-6);
        assert!((ret[0] - (1.0 + 0.9 * 2.8)).abs() < 1e-6);
    }
}
