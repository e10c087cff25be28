//! Adam (Kingma and Ba 2015, PyTorch's formulation, no weight decay) with inspectable
//! moments so checkpoints can save and restore them, and global gradient-norm clipping.

use crate::policy::Params;
use candle_core::backprop::GradStore;
use candle_core::{Result, Tensor, Var};

/// The global L2 norm of all parameters' gradients, summed in name order. Parameters
/// without a gradient count as zero.
pub fn global_grad_norm(params: &Params, grads: &GradStore) -> Result<f64> {
    let mut sq = 0f64;
    for v in params.vars().values() {
        if let Some(g) = grads.get(v) {
            sq += f64::from(g.sqr()?.sum_all()?.to_scalar::<f32>()?);
        }
    }
    Ok(sq.sqrt())
}

/// The factor `min(1, max_norm / (norm + 1e-6))` that clips a gradient of global norm
/// `norm` to `max_norm` (as `torch.nn.utils.clip_grad_norm_`).
pub fn clip_factor(norm: f64, max_norm: f64) -> f64 {
    (max_norm / (norm + 1e-6)).min(1.0)
}

/// Adam over a fixed, name-ordered list of parameters.
#[derive(Debug)]
pub struct Adam {
    names: Vec<String>,
    vars: Vec<Var>,
    exp_avg: Vec<Tensor>,
    exp_avg_sq: Vec<Tensor>,
    step: u64,
    /// Learning rate.
    pub lr: f64,
    /// First-moment decay (0.9).
    pub beta1: f64,
    /// Second-moment decay (0.999).
    pub beta2: f64,
    /// Denominator epsilon.
    pub eps: f64,
}

impl Adam {
    /// Adam over every parameter of `params` with zero moments.
    pub fn new(params: &Params, lr: f64, eps: f64) -> Result<Self> {
        let mut names = Vec::new();
        let mut vars = Vec::new();
        let mut exp_avg = Vec::new();
        let mut exp_avg_sq = Vec::new();
        for (n, v) in params.vars() {
            names.push(n.clone());
            vars.push(v.clone());
            exp_avg.push(v.as_tensor().zeros_like()?);
            exp_avg_sq.push(v.as_tensor().zeros_like()?);
        }
        Ok(Self {
            names,
            vars,
            exp_avg,
            exp_avg_sq,
            step: 0,
            lr,
            beta1: 0.9,
            beta2: 0.999,
            eps,
        })
    }

    /// Number of steps taken.
    pub fn step_count(&self) -> u64 {
        self.step
    }

    /// One update with the gradients multiplied by `grad_scale` (the clipping factor).
    pub fn step(&mut self, grads: &GradStore, grad_scale: f64) -> Result<()> {
        self.step += 1;
        let t = self.step as i32;
        let bc1 = 1.0 - self.beta1.powi(t);
        let bc2 = 1.0 - self.beta2.powi(t);
        for i in 0..self.vars.len() {
            let Some(g) = grads.get(&self.vars[i]) else {
                continue;
            };
            let g = (g * grad_scale)?;
            let m = ((&self.exp_avg[i] * self.beta1)? + (&g * (1.0 - self.beta1))?)?;
            let v = ((&self.exp_avg_sq[i] * self.beta2)? + (g.sqr()? * (1.0 - self.beta2))?)?;
            let denom = ((&v / bc2)?.sqrt()? + self.eps)?;
            let upd = ((&m / denom)? * (self.lr / bc1))?;
            let theta = self.vars[i].as_tensor().sub(&upd)?;
            self.vars[i].set(&theta)?;
            self.exp_avg[i] = m;
            self.exp_avg_sq[i] = v;
        }
        Ok(())
    }

    /// The moments by parameter name: (name, first moment, second moment).
    pub fn moments(&self) -> impl Iterator<Item = (&str, &Tensor, &Tensor)> {
        self.names
            .iter()
            .zip(&self.exp_avg)
            .zip(&self.exp_avg_sq)
            .map(|((n, m), v)| (n.as_str(), m, v))
    }

    /// Replaces the moments of parameter `name` and is the caller's responsibility to give
    /// tensors of the parameter's shape. Returns false when there is no such parameter.
    pub fn set_moments(&mut self, name: &str, m: Tensor, v: Tensor) -> bool {
        match self.names.iter().position(|n| n == name) {
            Some(i) => {
                self.exp_avg[i] = m;
                self.exp_avg_sq[i] = v;
                true
            }
            None => false,
        }
    }

    /// Sets the step counter (for resuming).
    pub fn set_step_count(&mut self, step: u64) {
        self.step = step;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::api::ActionSpec;
    use crate::policy::{build_policy, PolicyConfig, PolicyKind};
    use candle_core::{Device, Tensor};

    #[test]
    fn clip_factor_by_hand() {
        assert_eq!(clip_factor(0.25, 0.5), 1.0);
        assert!((clip_factor(2.0, 0.5) - 0.5 / (2.0 + 1e-6)).abs() < 1e-12);
    }

    #[test]
    fn adam_first_step_moves_by_lr_and_norm_is_global() {
        let cfg = PolicyConfig {
            kind: PolicyKind::Mlp,
            mlp_hidden: 4,
            ..PolicyConfig::default()
        };
        let spec = ActionSpec {
            continuous: 1,
            lift: false,
        };
        let p = build_policy(&cfg, 2, spec, 0).unwrap();
        let ls = p.params().vars()["actor.log_std"].clone();
        let b = p.params().vars()["critic.out.bias"].clone();
        // loss = 3 * log_std + 4 * bias: gradient 3 and 4, global norm 5.
        let loss = ((ls.as_tensor() * 3.0).unwrap().sum_all().unwrap()
            + (b.as_tensor() * 4.0).unwrap().sum_all().unwrap())
        .unwrap();
        let grads = loss.backward().unwrap();
        let norm = global_grad_norm(p.params(), &grads).unwrap();
        assert!((norm - 5.0).abs() < 1e-6, "{norm}");
        let mut opt = Adam::new(p.params(), 0.1, 1e-8).unwrap();
        opt.step(&grads, clip_factor(norm, 0.5)).unwrap();
        // Adam's first step is lr * sign(g) whatever the scale.
        let l = ls.as_tensor().to_vec1::<f32>().unwrap()[0];
        assert!((l + 0.1).abs() < 1e-5, "{l}");
        let bb = b.as_tensor().to_vec1::<f32>().unwrap()[0];
        assert!((bb + 0.1).abs() < 1e-5, "{bb}");
        let (_, m, v) = opt
            .moments()
            .find(|(n, _, _)| *n == "actor.log_std")
            .unwrap();
        // g = 3 * 0.1 (clipped): m = 0.1 * 0.3, v = 0.001 * 0.09
        assert!((m.to_vec1::<f32>().unwrap()[0] - 0.03).abs() < 1e-6);
        assert!((v.to_vec1::<f32>().unwrap()[0] - 9e-5).abs() < 1e-8);
        assert_eq!(opt.step_count(), 1);
        let z = Tensor::zeros(1, candle_core::DType::F32, &Device::Cpu).unwrap();
        assert!(opt.set_moments("actor.log_std", z.clone(), z.clone()));
        assert!(!opt.set_moments("nope", z.clone(), z));
    }
}
