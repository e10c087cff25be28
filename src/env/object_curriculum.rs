//! An object curriculum (beyond the paper): each episode's training object is drawn in
//! proportion to its recent failure rate, so that the budget goes where the policy fails.
//!
//! Object `k`'s weight is `floor + (f_k + 1) / (n_k + 2)`, where `n_k` of its last
//! `window` episodes (physics failures excluded) ended with `f_k` failures: the failure
//! rate with a uniform prior (an object not yet tried weighs `floor + 0.5`), plus a floor
//! that keeps every object in the draw. Each environment keeps its own windows, as for
//! eq. 6's curriculum, so runs stay reproducible whatever the thread schedule. Off by
//! default; evaluation always turns it off.

use rand::Rng;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// Object curriculum settings (`[env.object_curriculum]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObjectCurriculumConfig {
    /// Draw objects by their recent failure rate (false: uniformly, as the paper).
    pub enabled: bool,
    /// Recent episodes per object in its failure rate.
    pub window: usize,
    /// Weight every object keeps on top of its failure rate.
    pub floor: f64,
}

impl Default for ObjectCurriculumConfig {
    fn default() -> Self {
        ObjectCurriculumConfig {
            enabled: false,
            window: 8,
            floor: 0.1,
        }
    }
}

/// Longest per-object window accepted.
pub const MAX_OBJECT_WINDOW: usize = 10_000;

impl ObjectCurriculumConfig {
    /// Checks the values; `Err` names the field relative to `[env]`, as
    /// [`super::randomize::Randomization::validate`] does (`object_curriculum.window`).
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        if !(1..=MAX_OBJECT_WINDOW).contains(&self.window) {
            return Err((
                "object_curriculum.window",
                format!("{} must be in 1..={MAX_OBJECT_WINDOW}", self.window),
            ));
        }
        if !(self.floor > 0.0 && self.floor <= 10.0) {
            return Err((
                "object_curriculum.floor",
                format!("{} must be in (0, 10]", crate::util::num::short(self.floor)),
            ));
        }
        Ok(())
    }
}

/// The recent outcomes of each object of a fixed set.
#[derive(Debug, Clone)]
pub struct ObjectCurriculum {
    cfg: ObjectCurriculumConfig,
    outcomes: Vec<VecDeque<bool>>,
}

impl ObjectCurriculum {
    /// No outcomes yet for `objects` objects.
    pub fn new(cfg: ObjectCurriculumConfig, objects: usize) -> ObjectCurriculum {
        ObjectCurriculum {
            cfg,
            outcomes: vec![VecDeque::new(); objects],
        }
    }

    /// Object `k`'s weight (see the module docs); 0 for an index outside the set.
    pub fn weight(&self, k: usize) -> f64 {
        self.outcomes.get(k).map_or(0.0, |o| {
            let failures = o.iter().filter(|s| !**s).count() as f64;
            self.cfg.floor + (failures + 1.0) / (o.len() as f64 + 2.0)
        })
    }

    /// Draws an object index in proportion to the weights (one uniform draw from `rng`).
    pub fn sample<R: Rng>(&self, rng: &mut R) -> usize {
        let total: f64 = (0..self.outcomes.len()).map(|k| self.weight(k)).sum();
        let mut u = rng.random::<f64>() * total;
        for k in 0..self.outcomes.len() {
            u -= self.weight(k);
            if u < 0.0 {
                return k;
            }
        }
        self.outcomes.len().saturating_sub(1)
    }

    /// Records an episode of object `k` (ignored outside the set).
    pub fn record(&mut self, k: usize, success: bool) {
        let window = self.cfg.window;
        if let Some(o) = self.outcomes.get_mut(k) {
            o.push_back(success);
            while o.len() > window {
                o.pop_front();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn cfg(window: usize, floor: f64) -> ObjectCurriculumConfig {
        ObjectCurriculumConfig {
            enabled: true,
            window,
            floor,
        }
    }

    #[test]
    fn weights_are_the_failure_rate_with_a_prior_plus_the_floor() {
        let mut c = ObjectCurriculum::new(cfg(4, 0.1), 3);
        // Nothing tried: 0.1 + 1/2.
        assert!((c.weight(0) - 0.6).abs() < 1e-12);
        // Two failures and a success: 0.1 + (2 + 1) / (3 + 2) = 0.7.
        for s in [false, false, true] {
            c.record(0, s);
        }
        assert!((c.weight(0) - 0.7).abs() < 1e-12);
        // Four successes: 0.1 + 1 / 6.
        for _ in 0..4 {
            c.record(1, true);
        }
        assert!((c.weight(1) - (0.1 + 1.0 / 6.0)).abs() < 1e-12);
        // The window keeps the last 4: two more successes leave F S S S -> 0.1 + 2/6.
        for _ in 0..2 {
            c.record(0, true);
        }
        assert!((c.weight(0) - (0.1 + 2.0 / 6.0)).abs() < 1e-12);
        assert_eq!(c.weight(7), 0.0);
        c.record(7, false);
    }

    #[test]
    fn draws_follow_the_weights() {
        let mut c = ObjectCurriculum::new(cfg(10, 0.1), 2);
        for _ in 0..10 {
            c.record(0, false); // weight 0.1 + 11/12
            c.record(1, true); // weight 0.1 + 1/12
        }
        let (w0, w1) = (c.weight(0), c.weight(1));
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let n = 20_000;
        let hits = (0..n).filter(|_| c.sample(&mut rng) == 0).count() as f64;
        let expected = w0 / (w0 + w1);
        assert!(
            (hits / n as f64 - expected).abs() < 0.01,
            "{hits} vs {expected}"
        );
    }

    #[test]
    fn bad_settings_are_named() {
        assert_eq!(
            cfg(0, 0.1).validate().unwrap_err().0,
            "object_curriculum.window"
        );
        assert_eq!(
            cfg(4, 0.0).validate().unwrap_err().0,
            "object_curriculum.floor"
        );
        assert_eq!(
            cfg(4, f64::NAN).validate().unwrap_err().0,
            "object_curriculum.floor"
        );
        assert!(ObjectCurriculumConfig::default().validate().is_ok());
    }
}
