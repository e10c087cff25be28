//! The stage-1 closing trajectory T (Sec. IV-B): a smooth path from the start posture to a
//! power grasp that the hand follows until a fingertip touches.
//!
//! - [`ClosingSpace::Joint`]: every joint interpolates from `start` to `closed` with the
//!   smoothstep profile of [`closing_target`]. The fingers then leave the synergy span, so
//!   the first eq.-2 step (which projects onto the span) jumps: with the shipped model the
//!   span is 0.34-0.98 rad (L2) away along the path, and the thumb opens by 0.2-0.3 rad.
//! - [`ClosingSpace::Synergy`]: the fingers interpolate in synergy coordinates,
//!   `T(s) = P^-1((1 - a) P(start) + a P(closed))` with `a = s^2 (3 - 2 s)`, made feasible
//!   for the joint limits and the J1 = J2 coupling; the wrist as in joint space. The
//!   episode starts from `T(0)`, the start posture's feasible projection onto the span, so
//!   stage 1 and stage 2 act in one space.

use crate::synergy::map::project_feasible;
use crate::synergy::SynergyModel;
use serde::{Deserialize, Serialize};

/// Where the closing trajectory T interpolates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClosingSpace {
    /// Joint space (the setting of every checkpoint trained before this option existed).
    #[default]
    Joint,
    /// Synergy space, from the start posture's projection onto the span.
    Synergy,
}

/// The smoothstep fraction `a = s^2 (3 - 2 s)` of T at update `i` of `n`,
/// `s = min(i / n, 1)`.
fn fraction(i: usize, n: usize) -> f64 {
    let s = (i as f64 / n.max(1) as f64).min(1.0);
    s * s * (3.0 - 2.0 * s)
}

/// Target of joint `j` at update `i` of `n` along the joint-space closing trajectory from
/// `start` to `closed`: `start + a (closed - start)`, held at `closed` for `i > n`.
pub fn closing_target(start: &[f64; 24], closed: &[f64; 24], j: usize, i: usize, n: usize) -> f64 {
    start[j] + fraction(i, n) * (closed[j] - start[j])
}

/// The closing trajectory T of one setup.
#[derive(Debug, Clone)]
pub struct ClosingPath {
    start: [f64; 24],
    closed: [f64; 24],
    synergy: Option<SynergyPath>,
}

#[derive(Debug, Clone)]
struct SynergyPath {
    model: SynergyModel,
    eps_start: Vec<f64>,
    eps_closed: Vec<f64>,
    limits: [(f64, f64); 22],
}

impl ClosingPath {
    /// T from `start` to `closed` (24 hand joints, paper order) in `space`; `model` and the
    /// 22 finger `limits` serve the synergy space.
    pub fn new(
        space: ClosingSpace,
        start: &[f64; 24],
        closed: &[f64; 24],
        model: &SynergyModel,
        limits: &[(f64, f64); 22],
    ) -> ClosingPath {
        let fingers = |q: &[f64; 24]| -> [f64; 22] { std::array::from_fn(|k| q[k + 2]) };
        let synergy = (space == ClosingSpace::Synergy).then(|| SynergyPath {
            model: model.clone(),
            eps_start: model.project(&fingers(start)),
            eps_closed: model.project(&fingers(closed)),
            limits: *limits,
        });
        ClosingPath {
            start: *start,
            closed: *closed,
            synergy,
        }
    }

    /// The 24 targets at update `i` of `n` (`i = 0`: the posture an episode starts in).
    pub fn target(&self, i: usize, n: usize) -> [f64; 24] {
        let mut t: [f64; 24] =
            std::array::from_fn(|j| closing_target(&self.start, &self.closed, j, i, n));
        if let Some(p) = &self.synergy {
            let a = fraction(i, n);
            let eps: Vec<f64> = p
                .eps_start
                .iter()
                .zip(&p.eps_closed)
                .map(|(e0, e1)| e0 + a * (e1 - e0))
                .collect();
            let mut f = p.model.reconstruct(&eps);
            project_feasible(&mut f, &p.limits);
            t[2..].copy_from_slice(&f);
        }
        t
    }

    /// The posture an episode starts in: `start`, or its feasible projection onto the
    /// synergy span.
    pub fn start(&self) -> [f64; 24] {
        self.target(0, 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closing_target_is_a_smoothstep_hand_computed() {
        let start = [0.0; 24];
        let mut closed = [0.0; 24];
        closed[3] = 2.0;
        // s = 1/2: a = 0.25 * 2 = 0.5 -> 1.0; s = 1/4: a = 0.0625 * 2.5 = 0.15625 -> 0.3125.
        assert!((closing_target(&start, &closed, 3, 2, 4) - 1.0).abs() < 1e-12);
        assert!((closing_target(&start, &closed, 3, 1, 4) - 0.3125).abs() < 1e-12);
        assert_eq!(closing_target(&start, &closed, 3, 0, 4), 0.0);
        // Held at the end.
        assert_eq!(closing_target(&start, &closed, 3, 9, 4), 2.0);
        assert_eq!(closing_target(&start, &closed, 5, 2, 4), 0.0);
    }

    #[test]
    fn synergy_path_stays_on_the_span_and_joint_path_does_not() {
        let model = crate::synergy::default_model().truncated(5).unwrap();
        let robot = crate::robot::Robot::builtin(crate::robot::Side::Left);
        let limits = robot.finger_limits();
        let start = crate::robot::Posture::Open.angles();
        let closed = crate::sim::script::power_grasp();
        let off_span = |t: &[f64; 24]| {
            let f: [f64; 22] = std::array::from_fn(|k| t[k + 2]);
            let mut back = model.reconstruct(&model.project(&f));
            project_feasible(&mut back, &limits);
            back.iter()
                .zip(&f)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt()
        };
        let syn = ClosingPath::new(ClosingSpace::Synergy, &start, &closed, &model, &limits);
        let joint = ClosingPath::new(ClosingSpace::Joint, &start, &closed, &model, &limits);
        for i in 0..=10 {
            // Measured: the synergy path is 0.155 rad (L2) off the span at its start (the
            // joint limits clamp the projected open hand) and on it from update 3; the
            // joint-space path is 0.35-0.98 rad off it throughout.
            let (s, j) = (off_span(&syn.target(i, 10)), off_span(&joint.target(i, 10)));
            assert!(s < 0.2 && (i < 3 || s < 0.01), "update {i}: {s}");
            assert!(j > 0.3, "update {i}: {j}");
        }
        // Both start where they say, and the wrist follows the same path.
        assert_eq!(joint.start(), start);
        assert_eq!(syn.start()[..2], start[..2]);
        assert_eq!(syn.target(10, 10)[..2], closed[..2]);
    }
}
