//! The synergy maps of Sec. III and the target of eq. 2.
//!
//! With the mean posture `mu` and the component matrix `C` (n x 22, orthonormal rows):
//! - P: `eps = C (theta - mu)` ([`SynergyModel::project`]),
//! - P^-1: `theta = mu + C^T eps` ([`SynergyModel::reconstruct`]),
//! - eq. 2: `theta_target = P^-1(d_eps + P(theta_f))` ([`SynergyModel::target`]), then made
//!   feasible by [`project_feasible`].
//!
//! Because `C` has orthonormal rows, `P(P^-1(eps)) = eps` exactly (up to round-off), while
//! `P^-1(P(theta))` is the orthogonal projection of `theta - mu` onto the synergy span.
//! The batch versions write into caller-provided buffers and allocate nothing.

use crate::synergy::pca::SynergyModel;
use crate::synergy::N_FINGER_JOINTS;

const D: usize = N_FINGER_JOINTS;

/// Indices (in [`FINGER_JOINTS`](crate::robot::joints::FINGER_JOINTS)) of the J2 and J1
/// joints of the coupled fingers FF, MF, RF, LF
/// ([`COUPLED_FINGERS`](crate::robot::joints::COUPLED_FINGERS)); a unit test
/// derives them from the joint table with
/// [`finger_index`](crate::robot::joints::finger_index). A constant because eq. 2 runs
/// at every control step.
pub const COUPLED_PAIRS: [(usize, usize); 4] = [(2, 3), (6, 7), (10, 11), (15, 16)];

/// Makes a finger posture feasible for the simulated hand, in place:
/// 1. clamps every joint to its `limits` (lower, upper);
/// 2. for the coupled fingers FF, MF, RF and LF sets `J1 = J2 = (J1 + J2) / 2`: the
///    simulator couples J1 and J2 rigidly (one actuator drives `J0 = J1 + J2`), so a target
///    with `J1 != J2` cannot be reached; the mean keeps `J0` unchanged, and after step 1
///    `J0` lies in `[0, pi]` because J1 and J2 each lie in `[0, pi/2]`;
/// 3. clamps again, which matters only if the J1 and J2 limits of a finger differ.
///
/// Non-finite entries are not expected (the caller's inputs are finite); a NaN stays NaN.
pub fn project_feasible(theta: &mut [f64; D], limits: &[(f64, f64); D]) {
    clamp(theta, limits);
    for (j2, j1) in COUPLED_PAIRS {
        let avg = 0.5 * (theta[j2] + theta[j1]);
        theta[j2] = avg;
        theta[j1] = avg;
    }
    clamp(theta, limits);
}

fn clamp(theta: &mut [f64; D], limits: &[(f64, f64); D]) {
    for (t, &(lo, hi)) in theta.iter_mut().zip(limits) {
        *t = t.max(lo).min(hi);
    }
}

impl SynergyModel {
    /// P: the synergy coordinates `eps = C (theta - mean)` of posture `theta` (length n).
    pub fn project(&self, theta: &[f64; D]) -> Vec<f64> {
        let mut eps = vec![0.0; self.n_components()];
        self.project_into(theta, &mut eps);
        eps
    }

    /// P into a buffer: writes the n synergy coordinates of `theta` into `eps`.
    ///
    /// # Panics
    /// If `eps.len() != self.n_components()` (a programming error, not a data error).
    pub fn project_into(&self, theta: &[f64; D], eps: &mut [f64]) {
        assert_eq!(eps.len(), self.n_components(), "eps length must equal n");
        let mean = self.mean();
        let mut d = [0.0; D];
        for j in 0..D {
            d[j] = theta[j] - mean[j];
        }
        for (e, c) in eps.iter_mut().zip(self.components()) {
            *e = c.iter().zip(&d).map(|(a, b)| a * b).sum();
        }
    }

    /// P^-1: the posture `mean + C^T eps` for synergy coordinates `eps` (length n).
    ///
    /// # Panics
    /// If `eps.len() != self.n_components()`.
    pub fn reconstruct(&self, eps: &[f64]) -> [f64; D] {
        assert_eq!(eps.len(), self.n_components(), "eps length must equal n");
        let mut theta = *self.mean();
        for (&e, c) in eps.iter().zip(self.components()) {
            for (t, cj) in theta.iter_mut().zip(c) {
                *t += e * cj;
            }
        }
        theta
    }

    /// P over a batch: row i of `eps` (`eps[i*n..(i+1)*n]`) receives `P(thetas[i])`.
    ///
    /// # Panics
    /// If `eps.len() != thetas.len() * n`.
    pub fn project_batch(&self, thetas: &[[f64; D]], eps: &mut [f64]) {
        let n = self.n_components();
        assert_eq!(
            eps.len(),
            thetas.len() * n,
            "eps must hold n values per posture"
        );
        for (theta, e) in thetas.iter().zip(eps.chunks_exact_mut(n)) {
            self.project_into(theta, e);
        }
    }

    /// P^-1 over a batch: `thetas[i]` receives `P^-1(eps[i*n..(i+1)*n])`.
    ///
    /// # Panics
    /// If `eps.len() != thetas.len() * n`.
    pub fn reconstruct_batch(&self, eps: &[f64], thetas: &mut [[f64; D]]) {
        let n = self.n_components();
        assert_eq!(
            eps.len(),
            thetas.len() * n,
            "eps must hold n values per posture"
        );
        for (theta, e) in thetas.iter_mut().zip(eps.chunks_exact(n)) {
            *theta = self.reconstruct(e);
        }
    }

    /// Eq. 2: the finger target `P^-1(d_eps + P(theta_f))`, made feasible with
    /// [`project_feasible`] for `limits`. `d_eps` has length n.
    ///
    /// With `d_eps = 0` this returns `theta_f` itself when `theta_f - mean` lies in the
    /// synergy span and `theta_f` is feasible; otherwise it returns the feasible projection
    /// of `theta_f` onto the span.
    ///
    /// # Panics
    /// If `d_eps.len() != self.n_components()`.
    pub fn target(&self, theta_f: &[f64; D], d_eps: &[f64], limits: &[(f64, f64); D]) -> [f64; D] {
        let n = self.n_components();
        assert_eq!(d_eps.len(), n, "d_eps length must equal n");
        let mut eps = [0.0; D];
        self.project_into(theta_f, &mut eps[..n]);
        for (e, d) in eps.iter_mut().zip(d_eps) {
            *e += d;
        }
        let mut t = self.reconstruct(&eps[..n]);
        project_feasible(&mut t, limits);
        t
    }

    /// Eq. 2 over a batch: `out[i] = target(theta_f[i], d_eps[i*n..(i+1)*n], limits)`.
    ///
    /// # Panics
    /// If `d_eps.len() != theta_f.len() * n` or `out.len() != theta_f.len()`.
    pub fn target_batch(
        &self,
        theta_f: &[[f64; D]],
        d_eps: &[f64],
        limits: &[(f64, f64); D],
        out: &mut [[f64; D]],
    ) {
        let n = self.n_components();
        assert_eq!(
            d_eps.len(),
            theta_f.len() * n,
            "d_eps must hold n values per posture"
        );
        assert_eq!(
            out.len(),
            theta_f.len(),
            "out must hold one posture per input"
        );
        for ((theta, d), o) in theta_f
            .iter()
            .zip(d_eps.chunks_exact(n))
            .zip(out.iter_mut())
        {
            *o = self.target(theta, d, limits);
        }
    }
}

#[cfg(test)]
#[allow(clippy::approx_constant)] // the published joint limits (0.7854, 1.0472, ...)
mod tests {
    use super::*;
    use crate::robot::joints::{finger_index, COUPLED_FINGERS};
    use crate::robot::Side;
    use crate::synergy::finger_limits;
    use crate::synergy::pca::tests::{base_posture, directions, known_rows};
    use approx::assert_relative_eq;

    fn model() -> SynergyModel {
        SynergyModel::fit(&known_rows(), 2).unwrap()
    }

    #[test]
    fn projection_of_known_directions() {
        let m = model();
        let (u, v) = directions();
        let mut theta = base_posture();
        for j in 0..22 {
            theta[j] += 0.2 * u[j] - 0.05 * v[j];
        }
        let eps = m.project(&theta);
        assert_relative_eq!(eps[0], 0.2, epsilon = 1e-12);
        assert_relative_eq!(eps[1], -0.05, epsilon = 1e-12);
        assert_eq!(m.project(m.mean()), vec![0.0, 0.0]);
    }

    #[test]
    fn p_of_p_inverse_is_identity() {
        let m = model();
        for eps in [[0.0, 0.0], [0.3, -0.2], [-1.5, 2.5]] {
            let back = m.project(&m.reconstruct(&eps));
            assert_relative_eq!(back[0], eps[0], epsilon = 1e-12);
            assert_relative_eq!(back[1], eps[1], epsilon = 1e-12);
        }
    }

    #[test]
    fn p_inverse_of_p_projects_onto_the_span() {
        let m = model();
        let (u, _) = directions();
        let mut theta = base_posture();
        theta[0] += 0.1; // FFJ4: orthogonal to u and v
        theta[1] += 0.05; // FFJ3: has a component along u
        let r = m.reconstruct(&m.project(&theta));
        let expected_u = 0.05 * u[1];
        for j in 0..22 {
            let want = base_posture()[j] + expected_u * u[j];
            assert_relative_eq!(r[j], want, epsilon = 1e-12);
        }
    }

    #[test]
    fn eq2_with_zero_increment_returns_a_feasible_theta_in_the_span() {
        let m = model();
        let limits = finger_limits(Side::Left);
        let (u, v) = directions();
        let mut theta = base_posture();
        for j in 0..22 {
            theta[j] += 0.1 * u[j] + 0.04 * v[j];
        }
        let mut check = theta;
        project_feasible(&mut check, &limits);
        assert_eq!(check, theta, "test posture must be feasible");
        let t = m.target(&theta, &[0.0, 0.0], &limits);
        for j in 0..22 {
            assert_relative_eq!(t[j], theta[j], epsilon = 1e-12);
        }
    }

    #[test]
    fn eq2_adds_the_increment_in_synergy_space() {
        let m = model();
        let limits = finger_limits(Side::Left);
        let (u, _) = directions();
        let theta = base_posture();
        let t = m.target(&theta, &[0.1, 0.0], &limits);
        for j in 0..22 {
            assert_relative_eq!(t[j], theta[j] + 0.1 * u[j], epsilon = 1e-12);
        }
        let eps = m.project(&t);
        assert_relative_eq!(eps[0], 0.1, epsilon = 1e-12);
    }

    #[test]
    fn feasibility_clamps_then_couples() {
        let limits = finger_limits(Side::Left);
        let mut t = [0.0; 22];
        t[0] = 0.5; // FFJ4 above 0.3491
        t[1] = -1.0; // FFJ3 below -0.2618
        t[2] = 1.0; // FFJ2
        t[3] = 0.2; // FFJ1: coupled -> both 0.6
        t[6] = 2.0; // MFJ2 clamps to 1.5708 first
        t[7] = 0.0; // MFJ1: -> both 0.7854
        t[14] = -0.4; // LFJ3 -> -0.2618
        t[15] = -0.3; // LFJ2 clamps to 0 -> pair (0 + 0.1) / 2 = 0.05
        t[16] = 0.1; // LFJ1
        t[19] = 0.5; // THJ3 -> 0.2094 (not coupled)
        t[20] = 0.3; // THJ2 stays
        t[21] = 0.9; // THJ1 stays: the thumb is not coupled
        project_feasible(&mut t, &limits);
        assert_eq!(t[0], 0.3491);
        assert_eq!(t[1], -0.2618);
        assert_relative_eq!(t[2], 0.6, epsilon = 1e-15);
        assert_relative_eq!(t[3], 0.6, epsilon = 1e-15);
        assert_relative_eq!(t[6], 0.7854, epsilon = 1e-15);
        assert_relative_eq!(t[7], 0.7854, epsilon = 1e-15);
        assert_eq!(t[14], -0.2618);
        assert_relative_eq!(t[15], 0.05, epsilon = 1e-15);
        assert_relative_eq!(t[16], 0.05, epsilon = 1e-15);
        assert_eq!(t[19], 0.2094);
        assert_eq!(t[20], 0.3);
        assert_eq!(t[21], 0.9);
        // RF untouched (zeros are feasible).
        assert_eq!(&t[8..12], &[0.0; 4]);
    }

    #[test]
    fn eq2_result_is_always_feasible() {
        let m = model();
        let limits = finger_limits(Side::Left);
        let t = m.target(&base_posture(), &[40.0, -30.0], &limits);
        for (j, (&v, &(lo, hi))) in t.iter().zip(&limits).enumerate() {
            assert!(v >= lo && v <= hi, "joint {j}: {v}");
        }
        for (j2, j1) in COUPLED_PAIRS {
            assert_eq!(t[j2], t[j1]);
        }
    }

    #[test]
    fn batches_match_single_calls() {
        let m = model();
        let limits = finger_limits(Side::Left);
        let rows = known_rows();
        let mut eps = vec![0.0; rows.len() * 2];
        m.project_batch(&rows, &mut eps);
        for (i, r) in rows.iter().enumerate() {
            assert_eq!(&eps[2 * i..2 * i + 2], m.project(r).as_slice());
        }
        let mut back = vec![[0.0; 22]; rows.len()];
        m.reconstruct_batch(&eps, &mut back);
        for (i, b) in back.iter().enumerate() {
            assert_eq!(*b, m.reconstruct(&eps[2 * i..2 * i + 2]));
        }
        let d: Vec<f64> = (0..rows.len() * 2).map(|i| 0.01 * i as f64).collect();
        let mut out = vec![[0.0; 22]; rows.len()];
        m.target_batch(&rows, &d, &limits, &mut out);
        for (i, o) in out.iter().enumerate() {
            assert_eq!(*o, m.target(&rows[i], &d[2 * i..2 * i + 2], &limits));
        }
    }

    #[test]
    fn coupled_pairs_are_j2_j1_of_ff_mf_rf_lf() {
        for ((j2, j1), f) in COUPLED_PAIRS.iter().zip(COUPLED_FINGERS) {
            assert_eq!(Some(*j2), finger_index(&format!("{f}J2")));
            assert_eq!(Some(*j1), finger_index(&format!("{f}J1")));
        }
    }
}
