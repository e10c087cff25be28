//! Running statistics for observation normalisation and reward scaling (the algorithms of
//! gymnasium's `NormalizeObservation` and `NormalizeReward`, which CleanRL uses).

/// Added to variances before taking square roots.
pub const NORM_EPS: f64 = 1e-8;

/// Running mean and variance of vectors, merged batch by batch with Chan et al.'s parallel
/// algorithm. Starts at mean 0, variance 1, count 1e-4 (as gymnasium).
#[derive(Debug, Clone, PartialEq)]
pub struct RunningMeanStd {
    /// Per-component mean.
    pub mean: Vec<f64>,
    /// Per-component (population) variance.
    pub var: Vec<f64>,
    /// Number of samples seen (plus the 1e-4 prior).
    pub count: f64,
}

impl RunningMeanStd {
    /// Fresh statistics for vectors of length `dim`.
    pub fn new(dim: usize) -> Self {
        Self {
            mean: vec![0.0; dim],
            var: vec![1.0; dim],
            count: 1e-4,
        }
    }

    /// Vector length.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Merges a batch of row-major vectors (`rows.len()` a multiple of `dim`).
    pub fn update(&mut self, rows: &[f32]) {
        let d = self.dim();
        if d == 0 || rows.is_empty() {
            return;
        }
        let n = rows.len() / d;
        let nf = n as f64;
        let mut bm = vec![0f64; d];
        for r in rows.chunks_exact(d) {
            for (m, &x) in bm.iter_mut().zip(r) {
                *m += f64::from(x);
            }
        }
        for m in &mut bm {
            *m /= nf;
        }
        let mut bv = vec![0f64; d];
        for r in rows.chunks_exact(d) {
            for ((v, &x), m) in bv.iter_mut().zip(r).zip(&bm) {
                let dx = f64::from(x) - m;
                *v += dx * dx;
            }
        }
        for v in &mut bv {
            *v /= nf;
        }
        let tot = self.count + nf;
        for k in 0..d {
            let delta = bm[k] - self.mean[k];
            let m_a = self.var[k] * self.count;
            let m_b = bv[k] * nf;
            let m2 = m_a + m_b + delta * delta * self.count * nf / tot;
            self.mean[k] += delta * nf / tot;
            self.var[k] = m2 / tot;
        }
        self.count = tot;
    }

    /// `clip((x - mean) / sqrt(var + eps), -clip, clip)` for row-major vectors.
    pub fn normalize(&self, rows: &[f32], clip: f64) -> Vec<f32> {
        let d = self.dim();
        rows.iter()
            .enumerate()
            .map(|(i, &x)| {
                let k = i % d;
                let z = (f64::from(x) - self.mean[k]) / (self.var[k] + NORM_EPS).sqrt();
                z.clamp(-clip, clip) as f32
            })
            .collect()
    }
}

/// Scales rewards by the running standard deviation of each environment's discounted
/// return: `acc = gamma * acc + r`, statistics updated with `acc`, reward
/// `clip(r / sqrt(var + eps))`, and `acc` reset to 0 when the episode ends.
#[derive(Debug, Clone, PartialEq)]
pub struct RewardScaler {
    /// Statistics of the discounted returns.
    pub rms: RunningMeanStd,
    /// Discounted return accumulated so far, per environment.
    pub acc: Vec<f64>,
    /// Discount.
    pub gamma: f64,
}

impl RewardScaler {
    /// A scaler for `num_envs` environments.
    pub fn new(num_envs: usize, gamma: f64) -> Self {
        Self {
            rms: RunningMeanStd::new(1),
            acc: vec![0.0; num_envs],
            gamma,
        }
    }

    /// Scales one step's rewards in place; `ended[i]` marks episodes that ended on it.
    pub fn scale(&mut self, rewards: &mut [f32], ended: &[bool], clip: f64) {
        for (a, &r) in self.acc.iter_mut().zip(rewards.iter()) {
            *a = *a * self.gamma + f64::from(r);
        }
        let accs: Vec<f32> = self.acc.iter().map(|&a| a as f32).collect();
        self.rms.update(&accs);
        let s = (self.rms.var[0] + NORM_EPS).sqrt();
        for r in rewards.iter_mut() {
            *r = (f64::from(*r) / s).clamp(-clip, clip) as f32;
        }
        for (a, &e) in self.acc.iter_mut().zip(ended) {
            if e {
                *a = 0.0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batch_updates_match_direct_statistics() {
        let mut r = RunningMeanStd::new(2);
        r.update(&[1.0, 10.0, 3.0, 10.0]);
        r.update(&[5.0, 10.0]);
        // data (1,3,5) and (10,10,10); the 1e-4 prior at (0, var 1) barely moves them.
        assert!((r.mean[0] - 3.0).abs() < 1e-3, "{r:?}");
        assert!((r.var[0] - 8.0 / 3.0).abs() < 1e-3, "{r:?}");
        assert!((r.mean[1] - 10.0).abs() < 1e-3);
        assert!(r.var[1] < 0.05);
        assert!((r.count - 3.0001).abs() < 1e-9);
        let z = r.normalize(&[3.0, 1000.0], 10.0);
        assert!(z[0].abs() < 1e-3);
        assert_eq!(z[1], 10.0);
    }

    #[test]
    fn reward_scaler_by_hand() {
        let mut s = RewardScaler::new(1, 0.5);
        let mut r = [2.0f32];
        s.scale(&mut r, &[false], 10.0);
        // acc = 2; with the prior: var = (1e-4 + 4e-4 / 1.0001) / 1.0001 ~ 5e-4, so the
        // scaled reward 2 / 0.0224 ~ 89 is clipped to 10.
        assert!((s.rms.var[0] - 5e-4).abs() < 1e-6, "{s:?}");
        assert_eq!(r[0], 10.0);
        let mut r = [2.0f32];
        s.scale(&mut r, &[true], 10.0);
        assert_eq!(s.acc[0], 0.0);
        // acc was 0.5 * 2 + 2 = 3 before the reset: mean of {2, 3}, var ~0.25
        assert!((s.rms.mean[0] - 2.5).abs() < 1e-3);
        assert!((s.rms.var[0] - 0.25).abs() < 1e-3);
        assert!(
            (f64::from(r[0]) - 2.0 / 0.25f64.sqrt()).abs() < 1e-2,
            "{r:?}"
        );
    }
}
