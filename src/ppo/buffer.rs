//! The rollout buffer: one rollout of `T` steps from `B` environments, time-major
//! (index `t * B + env`).

use candle_core::Tensor;

/// What one rollout collected.
#[derive(Debug, Clone)]
pub struct RolloutBuffer {
    /// Steps per environment T.
    pub num_steps: usize,
    /// Environments B.
    pub num_envs: usize,
    /// Observation length D.
    pub obs_dim: usize,
    /// Continuous action components C.
    pub act_dim: usize,
    /// Normalised observations, T * B * D.
    pub obs: Vec<f32>,
    /// 1.0 where the observation is the first of an episode, T * B.
    pub starts: Vec<f32>,
    /// Raw continuous actions, T * B * C.
    pub cont: Vec<f32>,
    /// Lift decisions 0/1, T * B.
    pub rho: Vec<f32>,
    /// Log-probabilities of the actions when sampled, T * B.
    pub log_probs: Vec<f32>,
    /// Values when sampled, T * B.
    pub values: Vec<f32>,
    /// (Scaled) rewards, T * B.
    pub rewards: Vec<f32>,
    /// Terminated flags, T * B.
    pub terminated: Vec<bool>,
    /// Truncated flags, T * B.
    pub truncated: Vec<bool>,
    /// Values of the final observations of truncated episodes (0 elsewhere), T * B.
    pub final_values: Vec<f32>,
    /// Values of the observations after the rollout, B.
    pub next_values: Vec<f32>,
    /// The recurrent state at the start of the rollout (B, hidden), for recurrent policies.
    pub initial_hidden: Option<Tensor>,
}

impl RolloutBuffer {
    /// An empty buffer with room for `num_steps` steps.
    pub fn new(num_steps: usize, num_envs: usize, obs_dim: usize, act_dim: usize) -> Self {
        let n = num_steps * num_envs;
        Self {
            num_steps,
            num_envs,
            obs_dim,
            act_dim,
            obs: Vec::with_capacity(n * obs_dim),
            starts: Vec::with_capacity(n),
            cont: Vec::with_capacity(n * act_dim),
            rho: Vec::with_capacity(n),
            log_probs: Vec::with_capacity(n),
            values: Vec::with_capacity(n),
            rewards: Vec::with_capacity(n),
            terminated: Vec::with_capacity(n),
            truncated: Vec::with_capacity(n),
            final_values: Vec::with_capacity(n),
            next_values: Vec::new(),
            initial_hidden: None,
        }
    }

    /// Number of transitions T * B.
    pub fn len(&self) -> usize {
        self.num_steps * self.num_envs
    }

    /// Whether the buffer holds no transitions.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Gathers the rows `idx` (flat indices) of a per-transition array with `width` values
    /// per transition.
    pub fn gather(src: &[f32], width: usize, idx: &[usize]) -> Vec<f32> {
        let mut out = Vec::with_capacity(idx.len() * width);
        for &i in idx {
            out.extend_from_slice(&src[i * width..(i + 1) * width]);
        }
        out
    }

    /// The flat indices, time-major, of whole sequences of environments `envs`:
    /// `t * B + envs[j]` for t in 0..T, j in 0..envs.len().
    pub fn sequence_indices(&self, envs: &[usize]) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.num_steps * envs.len());
        for t in 0..self.num_steps {
            for &e in envs {
                out.push(t * self.num_envs + e);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sequence_indices_keep_time_order() {
        let b = RolloutBuffer::new(3, 4, 1, 1);
        assert_eq!(b.sequence_indices(&[2, 0]), vec![2, 0, 6, 4, 10, 8]);
        let src = [0.0, 1.0, 10.0, 11.0, 20.0, 21.0];
        assert_eq!(
            RolloutBuffer::gather(&src, 2, &[2, 0]),
            vec![20.0, 21.0, 0.0, 1.0]
        );
    }
}
