//! Orthogonal weight initialisation (Saxe et al. 2014), as `torch.nn.init.orthogonal_`.
//!
//! A Gaussian matrix drawn from a seeded RNG is QR-factorised with faer; Q, with its columns'
//! signs fixed by the signs of R's diagonal, times `gain` is the weight. For a `rows x cols`
//! weight with `rows >= cols` the columns are orthonormal (W^T W = gain^2 I), otherwise the
//! rows are (W W^T = gain^2 I).

use faer::Mat;
use rand::Rng;
use rand_distr::StandardNormal;

/// A `rows x cols` orthogonal matrix scaled by `gain`, row-major, drawn from `rng`.
pub fn orthogonal<R: Rng + ?Sized>(rows: usize, cols: usize, gain: f64, rng: &mut R) -> Vec<f32> {
    if rows == 0 || cols == 0 {
        return Vec::new();
    }
    // Factorise the tall orientation: (big x small).
    let (big, small) = if rows >= cols {
        (rows, cols)
    } else {
        (cols, rows)
    };
    let mut draws = Vec::with_capacity(big * small);
    for _ in 0..big * small {
        draws.push(rng.sample::<f64, _>(StandardNormal));
    }
    let a = Mat::<f64>::from_fn(big, small, |i, j| draws[i * small + j]);
    let qr = a.qr();
    let q = qr.compute_thin_Q();
    let r = qr.thin_R();
    let mut out = vec![0.0f32; rows * cols];
    for j in 0..small {
        let s = if r[(j, j)] < 0.0 { -gain } else { gain };
        for i in 0..big {
            let v = (q[(i, j)] * s) as f32;
            if rows >= cols {
                out[i * cols + j] = v;
            } else {
                // transpose back: W = Q^T
                out[j * cols + i] = v;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn gram(w: &[f32], rows: usize, cols: usize, by_rows: bool) -> Vec<f64> {
        let n = if by_rows { rows } else { cols };
        let mut g = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                let mut s = 0.0;
                if by_rows {
                    for k in 0..cols {
                        s += f64::from(w[a * cols + k]) * f64::from(w[b * cols + k]);
                    }
                } else {
                    for k in 0..rows {
                        s += f64::from(w[k * cols + a]) * f64::from(w[k * cols + b]);
                    }
                }
                g[a * n + b] = s;
            }
        }
        g
    }

    #[test]
    fn tall_and_wide_matrices_are_orthogonal_with_gain() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for &(rows, cols, by_rows) in &[(8usize, 3usize, false), (3, 8, true), (5, 5, true)] {
            let gain = 2f64.sqrt();
            let w = orthogonal(rows, cols, gain, &mut rng);
            assert_eq!(w.len(), rows * cols);
            let n = if by_rows { rows } else { cols };
            let g = gram(&w, rows, cols, by_rows);
            for a in 0..n {
                for b in 0..n {
                    let want = if a == b { 2.0 } else { 0.0 };
                    assert!((g[a * n + b] - want).abs() < 1e-5, "{rows}x{cols}: {g:?}");
                }
            }
        }
    }

    #[test]
    fn same_seed_same_matrix() {
        let a = orthogonal(4, 6, 0.01, &mut ChaCha8Rng::seed_from_u64(9));
        let b = orthogonal(4, 6, 0.01, &mut ChaCha8Rng::seed_from_u64(9));
        let c = orthogonal(4, 6, 0.01, &mut ChaCha8Rng::seed_from_u64(10));
        assert_eq!(a, b);
        assert_ne!(a, c);
    }
}
