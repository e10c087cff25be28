//! The action distribution: a diagonal Gaussian over the continuous components with a
//! learned, state-independent log standard deviation, and (when the action has a lift
//! decision) a Bernoulli over rho with probability sigmoid(beta(O)).
//!
//! Joint log-probability, exactly SPEC eq. 3:
//! `log pi(a|O) = log pi(rho|O) + (1 - rho) [ log N(cont | mu, sigma) ]`: once the hand lifts,
//! the continuous increments are not executed and do not count.
//!
//! Entropy: `H = H_Bernoulli(p) + (1 - p) H_Gaussian`, with p = sigmoid(beta). This is the
//! exact entropy of the distribution eq. 3 defines (the action is rho = 1 alone with
//! probability p, or rho = 0 together with a Gaussian sample with probability 1 - p), so it
//! is the quantity whose gradient the entropy bonus should follow. Without a lift decision
//! both reduce to the plain Gaussian.
//!
//! Sampling uses a caller-supplied seeded RNG (candle's CPU device cannot be seeded): for
//! each row, `continuous` standard normal draws, then, with a lift head, one uniform draw.

use candle_core::{Result, Tensor, D};
use rand::Rng;
use rand_distr::StandardNormal;

/// ln(2 pi) / 2.
pub const HALF_LN_2PI: f64 = 0.918_938_533_204_672_8;

/// Numerically stable softplus: ln(1 + e^x) = max(x, 0) + ln(1 + e^-|x|).
pub fn softplus(x: &Tensor) -> Result<Tensor> {
    x.relu()? + (x.abs()?.neg()?.exp()? + 1.0)?.log()?
}

/// Numerically stable softplus on a scalar.
pub fn softplus_f32(x: f32) -> f32 {
    x.max(0.0) + (-x.abs()).exp().ln_1p()
}

/// Actions sampled for a batch, flat.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledActions {
    /// Continuous components, `n * continuous` values, row-major.
    pub cont: Vec<f32>,
    /// The lift decisions as 0.0 / 1.0, `n` values (all 0.0 without a lift head).
    pub rho: Vec<f32>,
}

/// The policy's action distribution for a batch of N observations.
#[derive(Debug, Clone)]
pub struct ActionDist {
    /// Gaussian means, shape (N, C).
    pub mean: Tensor,
    /// Log standard deviations, shape (C), shared by every row.
    pub log_std: Tensor,
    /// Lift logits beta, shape (N), when the action has a lift decision.
    pub lift_logit: Option<Tensor>,
}

impl ActionDist {
    /// Sum over components of the Gaussian log-density of `cont` (N, C); shape (N).
    pub fn gaussian_log_prob(&self, cont: &Tensor) -> Result<Tensor> {
        let std = self.log_std.exp()?;
        let z = cont.sub(&self.mean)?.broadcast_div(&std)?;
        let per = (z.sqr()? * -0.5)?.broadcast_sub(&self.log_std)?;
        let c = self.mean.dim(D::Minus1)? as f64;
        per.sum(D::Minus1)? - c * HALF_LN_2PI
    }

    /// Entropy of the Gaussian part, shape (N).
    pub fn gaussian_entropy(&self) -> Result<Tensor> {
        let n = self.mean.dim(0)?;
        let c = self.mean.dim(D::Minus1)? as f64;
        let h = (self.log_std.sum_all()? + c * (0.5 + HALF_LN_2PI))?;
        h.broadcast_as(n)?.contiguous()
    }

    /// Joint log-probability of eq. 3 for continuous actions `cont` (N, C) and lift
    /// decisions `rho` (N) in {0, 1}; `rho` is ignored without a lift head. Shape (N).
    pub fn log_prob(&self, cont: &Tensor, rho: Option<&Tensor>) -> Result<Tensor> {
        let lg = self.gaussian_log_prob(cont)?;
        match (&self.lift_logit, rho) {
            (Some(beta), Some(rho)) => {
                // log p = -softplus(-beta), log(1 - p) = -softplus(beta)
                let log_p = softplus(&beta.neg()?)?.neg()?;
                let log_q = softplus(beta)?.neg()?;
                let not_rho = rho.affine(-1.0, 1.0)?;
                let lr = ((rho * log_p)? + (&not_rho * log_q)?)?;
                lr + (not_rho * lg)?
            }
            (Some(_), None) => Err(candle_core::Error::Msg(
                "the policy has a lift head: log_prob needs the lift decisions".into(),
            )),
            (None, _) => Ok(lg),
        }
    }

    /// Entropy `H_Bernoulli(p) + (1 - p) H_Gaussian` (or the Gaussian's alone without a
    /// lift head), shape (N).
    pub fn entropy(&self) -> Result<Tensor> {
        let hg = self.gaussian_entropy()?;
        match &self.lift_logit {
            Some(beta) => {
                let p = candle_nn::ops::sigmoid(beta)?;
                let q = p.affine(-1.0, 1.0)?;
                // H_b = -p log p - (1-p) log(1-p) = p softplus(-beta) + (1-p) softplus(beta)
                let hb = ((&p * softplus(&beta.neg()?)?)? + (&q * softplus(beta)?)?)?;
                hb + (q * hg)?
            }
            None => Ok(hg),
        }
    }

    /// Draws one action per row with `rng`.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Result<SampledActions> {
        let mean = self.mean.to_vec2::<f32>()?;
        let std: Vec<f32> = self
            .log_std
            .to_vec1::<f32>()?
            .iter()
            .map(|l| l.exp())
            .collect();
        let beta = match &self.lift_logit {
            Some(b) => Some(b.to_vec1::<f32>()?),
            None => None,
        };
        let mut cont = Vec::with_capacity(mean.len() * std.len());
        let mut rho = Vec::with_capacity(mean.len());
        for (i, row) in mean.iter().enumerate() {
            for (m, s) in row.iter().zip(&std) {
                let e: f32 = rng.sample(StandardNormal);
                cont.push(m + s * e);
            }
            let r = match &beta {
                Some(b) => {
                    let p = 1.0 / (1.0 + (-b[i]).exp());
                    let u: f32 = rng.random();
                    if u < p {
                        1.0
                    } else {
                        0.0
                    }
                }
                None => 0.0,
            };
            rho.push(r);
        }
        Ok(SampledActions { cont, rho })
    }

    /// The most likely action of each row: the Gaussian mean, and rho = 1 when p > 0.5.
    pub fn mode(&self) -> Result<SampledActions> {
        let cont = self.mean.flatten_all()?.to_vec1::<f32>()?;
        let n = self.mean.dim(0)?;
        let rho = match &self.lift_logit {
            Some(b) => b
                .to_vec1::<f32>()?
                .iter()
                .map(|&x| if x > 0.0 { 1.0 } else { 0.0 })
                .collect(),
            None => vec![0.0; n],
        };
        Ok(SampledActions { cont, rho })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn t1(v: &[f32]) -> Tensor {
        Tensor::new(v, &Device::Cpu).unwrap()
    }
    fn t2(v: &[f32], c: usize) -> Tensor {
        Tensor::from_vec(v.to_vec(), (v.len() / c, c), &Device::Cpu).unwrap()
    }
    fn vals(t: &Tensor) -> Vec<f32> {
        t.to_vec1::<f32>().unwrap()
    }
    const L2PI: f32 = 1.837_877_1; // ln(2 pi)

    #[test]
    fn gaussian_log_prob_by_hand() {
        // mean 0, std 1, x = 1 in each of 2 dims: 2 (-0.5 - 0.5 ln 2pi)
        let d = ActionDist {
            mean: t2(&[0.0, 0.0], 2),
            log_std: t1(&[0.0, 0.0]),
            lift_logit: None,
        };
        let lp = vals(&d.log_prob(&t2(&[1.0, 1.0], 2), None).unwrap());
        assert!((lp[0] - 2.0 * (-0.5 - 0.5 * L2PI)).abs() < 1e-5, "{lp:?}");
        // mean 1, std e (log_std 1), x = 1 + e: -0.5 - 1 - 0.5 ln 2pi
        let e = std::f32::consts::E;
        let d = ActionDist {
            mean: t2(&[1.0], 1),
            log_std: t1(&[1.0]),
            lift_logit: None,
        };
        let lp = vals(&d.log_prob(&t2(&[1.0 + e], 1), None).unwrap());
        assert!((lp[0] - (-1.5 - 0.5 * L2PI)).abs() < 1e-5, "{lp:?}");
        // entropy of N(., e^1): 0.5 + 0.5 ln 2pi + 1
        let h = vals(&d.entropy().unwrap());
        assert!((h[0] - (1.5 + 0.5 * L2PI)).abs() < 1e-5, "{h:?}");
    }

    #[test]
    fn lift_masks_the_gaussian_eq3() {
        // beta = 0 -> p = 0.5; two rows, rho = 1 then rho = 0, Gaussian as above (x = 1).
        let d = ActionDist {
            mean: t2(&[0.0, 0.0], 1),
            log_std: t1(&[0.0]),
            lift_logit: Some(t1(&[0.0, 0.0])),
        };
        let lp = vals(
            &d.log_prob(&t2(&[1.0, 1.0], 1), Some(&t1(&[1.0, 0.0])))
                .unwrap(),
        );
        let ln_half = 0.5f32.ln();
        assert!((lp[0] - ln_half).abs() < 1e-6, "{lp:?}");
        assert!(
            (lp[1] - (ln_half - 0.5 - 0.5 * L2PI)).abs() < 1e-5,
            "{lp:?}"
        );
        // entropy: ln 2 + 0.5 (0.5 + 0.5 ln 2pi)
        let h = vals(&d.entropy().unwrap());
        let want = 2f32.ln() + 0.5 * (0.5 + 0.5 * L2PI);
        assert!((h[0] - want).abs() < 1e-5, "{h:?}");
    }

    #[test]
    fn bernoulli_log_prob_and_entropy_for_skewed_p() {
        // beta = ln 3 -> p = 0.75.
        let beta = 3f32.ln();
        let d = ActionDist {
            mean: t2(&[0.0], 1),
            log_std: t1(&[0.0]),
            lift_logit: Some(t1(&[beta])),
        };
        let lp = vals(&d.log_prob(&t2(&[0.0], 1), Some(&t1(&[1.0]))).unwrap());
        assert!((lp[0] - 0.75f32.ln()).abs() < 1e-6);
        let lp0 = vals(&d.log_prob(&t2(&[0.0], 1), Some(&t1(&[0.0]))).unwrap());
        assert!((lp0[0] - (0.25f32.ln() - 0.5 * L2PI)).abs() < 1e-5);
        let hb = -(0.75f32 * 0.75f32.ln() + 0.25 * 0.25f32.ln());
        let h = vals(&d.entropy().unwrap());
        assert!((h[0] - (hb + 0.25 * (0.5 + 0.5 * L2PI))).abs() < 1e-5);
        // extreme logits stay finite
        let d = ActionDist {
            mean: t2(&[0.0], 1),
            log_std: t1(&[0.0]),
            lift_logit: Some(t1(&[200.0])),
        };
        let lp = vals(&d.log_prob(&t2(&[0.0], 1), Some(&t1(&[0.0]))).unwrap());
        assert!((lp[0] - (-200.0 - 0.5 * L2PI)).abs() < 1e-3, "{lp:?}");
        assert!(vals(&d.entropy().unwrap())[0].is_finite());
    }

    #[test]
    fn log_prob_without_rho_is_an_error_when_lifting() {
        let d = ActionDist {
            mean: t2(&[0.0], 1),
            log_std: t1(&[0.0]),
            lift_logit: Some(t1(&[0.0])),
        };
        assert!(d.log_prob(&t2(&[0.0], 1), None).is_err());
    }

    #[test]
    fn sampling_is_seeded_and_has_the_right_moments() {
        let d = ActionDist {
            mean: t2(&vec![2.0; 4000], 1),
            log_std: t1(&[0.5f32.ln()]),
            lift_logit: Some(t1(&vec![3f32.ln(); 4000])),
        };
        let a = d.sample(&mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        let b = d.sample(&mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(a, b);
        let n = a.cont.len() as f32;
        let m = a.cont.iter().sum::<f32>() / n;
        let v = a.cont.iter().map(|x| (x - m).powi(2)).sum::<f32>() / n;
        assert!((m - 2.0).abs() < 0.05, "{m}");
        assert!((v - 0.25).abs() < 0.03, "{v}");
        let p = a.rho.iter().sum::<f32>() / n;
        assert!((p - 0.75).abs() < 0.03, "{p}");
        let mode = d.mode().unwrap();
        assert!(mode.rho.iter().all(|&r| r == 1.0));
        assert!(mode.cont.iter().all(|&c| c == 2.0));
    }

    #[test]
    fn softplus_scalar_and_tensor_agree() {
        for x in [-50.0f32, -1.0, 0.0, 2.0, 80.0] {
            let t = vals(&softplus(&t1(&[x])).unwrap())[0];
            assert!((t - softplus_f32(x)).abs() < 1e-5);
            assert!((softplus_f32(x) - (1.0 + x.exp()).ln()).abs() < 1e-4 || x > 50.0);
        }
    }
}
