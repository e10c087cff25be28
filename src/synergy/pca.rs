//! Principal component analysis of finger postures: the synergy model.
//!
//! [`SynergyModel::fit`] centres the data, forms the sample covariance with the `n - 1`
//! denominator (so eigenvalues equal scikit-learn's `PCA.explained_variance_`), and takes
//! its eigendecomposition with faer (sequentially, so it never competes with other thread
//! pools). Eigenvalues are sorted in descending order. Each component's sign is fixed so
//! that its entry of largest magnitude is positive (the lowest joint index wins an exact
//! tie), which makes the model independent of the eigensolver's arbitrary signs.
//!
//! The model keeps the whole spectrum (all 22 eigenvalues and variance ratios, for the
//! scree table) but only the first `n` components. It is saved as a versioned JSON file.

use crate::robot::joints::FINGER_JOINTS;
use crate::synergy::N_FINGER_JOINTS;
use crate::util::fsx::{write_atomic, WriteError};
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors};
use faer::{Accum, Mat, Par};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The numbers of components compared in the paper (Sec. V-B); 5 worked best.
pub const PAPER_COMPONENTS: [usize; 4] = [3, 5, 8, 10];

/// The model file format version written by [`SynergyModel::save`].
pub const MODEL_FORMAT_VERSION: u32 = 1;

/// How far `C C^T` may deviate from the identity in a loaded model.
pub const ORTHONORMAL_TOLERANCE: f64 = 1e-6;

/// Error while fitting, loading or saving a synergy model.
#[derive(Debug, thiserror::Error)]
pub enum SynergyError {
    /// The number of components is not in `1..=22`.
    #[error("invalid number of components {n}: expected 1 to 22")]
    InvalidComponents {
        /// The number asked for.
        n: usize,
    },
    /// A truncation asked for more components than the model has (or for none).
    #[error("cannot keep {requested} component(s) of a model with {available}: expected 1 to {available}")]
    TooFewComponents {
        /// Components asked for.
        requested: usize,
        /// Components in the model.
        available: usize,
    },
    /// Too few samples for the requested fit.
    #[error("{samples} sample(s) cannot fit {n} component(s): need at least {required}")]
    TooFewSamples {
        /// Samples given.
        samples: usize,
        /// Components asked for.
        n: usize,
        /// Samples required (`max(2, n)`).
        required: usize,
    },
    /// A sample holds NaN or an infinity.
    #[error("sample {row}, joint {joint}: value {value} is not finite")]
    NonFiniteSample {
        /// 0-based sample index.
        row: usize,
        /// The joint.
        joint: &'static str,
        /// The value.
        value: f64,
    },
    /// All samples are identical: there is no variance to analyse.
    #[error("the {samples} samples are all identical: no variance to analyse")]
    NoVariance {
        /// Samples given.
        samples: usize,
    },
    /// The eigensolver did not converge.
    #[error("the eigendecomposition of the covariance did not converge")]
    NoConvergence,
    /// The model file could not be read.
    #[error("cannot read synergy model {path}: {source}")]
    Io {
        /// The model file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The model file is not valid JSON of the expected shape.
    #[error("synergy model {path}, line {line}, column {column}: {message}")]
    Json {
        /// The model file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// The model file has an unsupported format version.
    #[error(
        "synergy model {path} has format version {found}; this program reads version {supported}"
    )]
    UnsupportedVersion {
        /// The model file.
        path: PathBuf,
        /// The version in the file.
        found: u32,
        /// The version this program reads.
        supported: u32,
    },
    /// The model file parses but its content is inconsistent.
    #[error("synergy model {path}: field '{field}': {message}")]
    Invalid {
        /// The model file.
        path: PathBuf,
        /// The offending field.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The model could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// Relative size below which a covariance eigenvalue counts as round-off (zero variance):
/// an eigenvalue `lambda_k <= RANK_TOLERANCE * lambda_1` adds no direction the data vary
/// along. With 22 joints in double precision round-off is near 1e-16 relative.
pub const RANK_TOLERANCE: f64 = 1e-10;

/// A fitted synergy model: the PCA of a pose dataset.
///
/// Invariants (checked by [`SynergyModel::load`]): `1 <= n <= 22` components, each a unit
/// vector of 22 joint weights, mutually orthogonal; 22 non-negative eigenvalues in
/// descending order; all numbers finite.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SynergyModel {
    format_version: u32,
    joints: Vec<String>,
    mean: [f64; N_FINGER_JOINTS],
    components: Vec<[f64; N_FINGER_JOINTS]>,
    eigenvalues: [f64; N_FINGER_JOINTS],
    explained_variance_ratio: [f64; N_FINGER_JOINTS],
    projection_min: Vec<f64>,
    projection_max: Vec<f64>,
    n_samples: usize,
    source: String,
}

/// The JSON shape of a model file, before validation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawModel {
    format_version: u32,
    joints: Vec<String>,
    mean: Vec<f64>,
    components: Vec<Vec<f64>>,
    eigenvalues: Vec<f64>,
    explained_variance_ratio: Vec<f64>,
    projection_min: Vec<f64>,
    projection_max: Vec<f64>,
    n_samples: usize,
    source: String,
}

impl SynergyModel {
    /// Fits `n_components` synergies (1..=22) to `data` (postures in [`FINGER_JOINTS`]
    /// order). Needs at least `max(2, n_components)` finite samples that are not all equal.
    ///
    /// The eigenvalues are those of the sample covariance `X^T X / (m - 1)` of the centred
    /// data `X` (`m` samples); tiny negative round-off eigenvalues are set to zero. The
    /// explained variance ratio of component k is `lambda_k / sum(lambda)`.
    pub fn fit(
        data: &[[f64; N_FINGER_JOINTS]],
        n_components: usize,
    ) -> Result<SynergyModel, SynergyError> {
        const D: usize = N_FINGER_JOINTS;
        if !(1..=D).contains(&n_components) {
            return Err(SynergyError::InvalidComponents { n: n_components });
        }
        let m = data.len();
        let required = n_components.max(2);
        if m < required {
            return Err(SynergyError::TooFewSamples {
                samples: m,
                n: n_components,
                required,
            });
        }
        let mut mean = [0.0; D];
        for (r, row) in data.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                if !v.is_finite() {
                    return Err(SynergyError::NonFiniteSample {
                        row: r,
                        joint: FINGER_JOINTS[j],
                        value: v,
                    });
                }
                mean[j] += v;
            }
        }
        for v in &mut mean {
            *v /= m as f64;
        }

        // Centred data, column-major m x 22, then cov = X^T X / (m - 1).
        let x = Mat::from_fn(m, D, |i, j| data[i][j] - mean[j]);
        let mut cov = Mat::<f64>::zeros(D, D);
        faer::linalg::matmul::matmul(
            cov.as_mut(),
            Accum::Replace,
            x.transpose(),
            x.as_ref(),
            1.0 / (m as f64 - 1.0),
            Par::Seq,
        );

        let mut u = Mat::<f64>::zeros(D, D);
        let mut s = Diag::<f64>::zeros(D);
        let mut mem = MemBuffer::new(self_adjoint_evd_scratch::<f64>(
            D,
            ComputeEigenvectors::Yes,
            Par::Seq,
            Default::default(),
        ));
        self_adjoint_evd(
            cov.as_ref(),
            s.as_mut(),
            Some(u.as_mut()),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|_| SynergyError::NoConvergence)?;

        // faer sorts ascending: reverse.
        let s = s.column_vector();
        let mut eigenvalues = [0.0; D];
        for (k, e) in eigenvalues.iter_mut().enumerate() {
            *e = s[D - 1 - k].max(0.0);
        }
        let total: f64 = eigenvalues.iter().sum();
        if total <= 0.0 || !total.is_finite() || data.iter().all(|r| *r == data[0]) {
            return Err(SynergyError::NoVariance { samples: m });
        }
        let mut explained_variance_ratio = [0.0; D];
        for (r, e) in explained_variance_ratio.iter_mut().zip(&eigenvalues) {
            *r = e / total;
        }

        let mut components = Vec::with_capacity(n_components);
        for k in 0..n_components {
            let col = u.col(D - 1 - k);
            let mut c = [0.0; D];
            for (j, v) in c.iter_mut().enumerate() {
                *v = col[j];
            }
            fix_sign(&mut c);
            for v in &mut c {
                *v += 0.0; // -0.0 -> 0.0, for a tidy file
            }
            components.push(c);
        }

        let mut model = SynergyModel {
            format_version: MODEL_FORMAT_VERSION,
            joints: FINGER_JOINTS.iter().map(|s| s.to_string()).collect(),
            mean,
            components,
            eigenvalues,
            explained_variance_ratio,
            projection_min: vec![f64::INFINITY; n_components],
            projection_max: vec![f64::NEG_INFINITY; n_components],
            n_samples: m,
            source: String::new(),
        };
        let mut eps = vec![0.0; n_components];
        for row in data {
            model.project_into(row, &mut eps);
            for (k, &e) in eps.iter().enumerate() {
                model.projection_min[k] = model.projection_min[k].min(e);
                model.projection_max[k] = model.projection_max[k].max(e);
            }
        }
        Ok(model)
    }

    /// Sets the free-text description of where the data came from (e.g. the dataset path).
    pub fn with_source(mut self, source: impl Into<String>) -> Self {
        self.source = source.into();
        self
    }

    /// The model with only its first `n` components (and their projection ranges): the
    /// PCA with `n` components of the same data, since components are sorted by
    /// descending eigenvalue. The eigenvalue spectrum, mean and source are kept. Fails
    /// unless `1 <= n <= self.n_components()`.
    pub fn truncated(&self, n: usize) -> Result<SynergyModel, SynergyError> {
        if n == 0 || n > self.components.len() {
            return Err(SynergyError::TooFewComponents {
                requested: n,
                available: self.components.len(),
            });
        }
        let mut m = self.clone();
        m.components.truncate(n);
        m.projection_min.truncate(n);
        m.projection_max.truncate(n);
        Ok(m)
    }

    /// Number of components `n` (the dimension of the synergy space).
    pub fn n_components(&self) -> usize {
        self.components.len()
    }

    /// The joint names of the 22 columns ([`FINGER_JOINTS`]).
    pub fn joints(&self) -> &[String] {
        &self.joints
    }

    /// The mean posture of the data.
    pub fn mean(&self) -> &[f64; N_FINGER_JOINTS] {
        &self.mean
    }

    /// The `n` components (rows of `C`), unit vectors, by descending eigenvalue.
    pub fn components(&self) -> &[[f64; N_FINGER_JOINTS]] {
        &self.components
    }

    /// The number of independent directions the data vary along: the eigenvalues above
    /// [`RANK_TOLERANCE`] times the largest. Components beyond it are round-off (an
    /// arbitrary direction of zero variance), which `grasp pca fit` refuses to keep.
    pub fn rank(&self) -> usize {
        let tolerance = self.eigenvalues[0] * RANK_TOLERANCE;
        self.eigenvalues.iter().filter(|&&e| e > tolerance).count()
    }

    /// All 22 covariance eigenvalues (variances along the principal axes), descending.
    pub fn eigenvalues(&self) -> &[f64; N_FINGER_JOINTS] {
        &self.eigenvalues
    }

    /// All 22 explained variance ratios `lambda_k / sum(lambda)`, descending; they sum to 1.
    pub fn explained_variance_ratio(&self) -> &[f64; N_FINGER_JOINTS] {
        &self.explained_variance_ratio
    }

    /// Per joint, the share of its variance over `data` that the model's components
    /// explain: `1 - var(r_j) / var(x_j)`, where `r = (x - mean) - Cᵀ C (x - mean)` is
    /// what is left after projecting onto the span and back. A joint that does not vary
    /// in `data` counts as fully explained (1). Reveals joints the first synergies barely
    /// move (the thumb, say), which the total ratio hides.
    pub fn per_joint_explained(&self, data: &[[f64; N_FINGER_JOINTS]]) -> [f64; N_FINGER_JOINTS] {
        const D: usize = N_FINGER_JOINTS;
        let m = data.len() as f64;
        let mut mean_x = [0.0; D];
        for row in data {
            for j in 0..D {
                mean_x[j] += row[j] / m;
            }
        }
        let (mut var_x, mut var_r) = ([0.0; D], [0.0; D]);
        for row in data {
            let c: [f64; D] = std::array::from_fn(|j| row[j] - self.mean[j]);
            let mut back = [0.0; D];
            for comp in &self.components {
                let e: f64 = comp.iter().zip(&c).map(|(a, b)| a * b).sum();
                for j in 0..D {
                    back[j] += e * comp[j];
                }
            }
            for j in 0..D {
                var_x[j] += (row[j] - mean_x[j]).powi(2);
                var_r[j] += (c[j] - back[j]).powi(2);
            }
        }
        let still = RANK_TOLERANCE * var_x.iter().cloned().fold(0.0, f64::max);
        std::array::from_fn(|j| {
            if var_x[j] <= still {
                1.0
            } else {
                1.0 - var_r[j] / var_x[j]
            }
        })
    }

    /// Cumulative explained variance ratios: entry k is the sum of ratios 0..=k.
    pub fn cumulative_ratio(&self) -> [f64; N_FINGER_JOINTS] {
        let mut out = [0.0; N_FINGER_JOINTS];
        let mut acc = 0.0;
        for (o, r) in out.iter_mut().zip(&self.explained_variance_ratio) {
            acc += r;
            *o = acc;
        }
        out
    }

    /// Per component, the smallest projection `P(theta)` over the fitted data.
    pub fn projection_min(&self) -> &[f64] {
        &self.projection_min
    }

    /// Per component, the largest projection `P(theta)` over the fitted data.
    pub fn projection_max(&self) -> &[f64] {
        &self.projection_max
    }

    /// Number of samples the model was fitted on.
    pub fn n_samples(&self) -> usize {
        self.n_samples
    }

    /// Where the data came from (free text, empty if unknown).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The model as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        // Serialising plain numbers, strings and vectors cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Writes the model to `path` as JSON (atomically).
    pub fn save(&self, path: &Path) -> Result<(), SynergyError> {
        let mut text = self.to_json();
        text.push('\n');
        write_atomic(path, text.as_bytes())?;
        Ok(())
    }

    /// Reads and validates a model written by [`SynergyModel::save`].
    pub fn load(path: &Path) -> Result<SynergyModel, SynergyError> {
        let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::DATA)
            .map_err(|source| SynergyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json(path, &text)
    }

    /// Parses and validates model JSON `text`; `path` is used in error messages.
    pub fn from_json(path: &Path, text: &str) -> Result<SynergyModel, SynergyError> {
        const D: usize = N_FINGER_JOINTS;
        let raw: RawModel = serde_json::from_str(text).map_err(|e| SynergyError::Json {
            path: path.to_path_buf(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })?;
        let invalid = |field: &'static str, message: String| SynergyError::Invalid {
            path: path.to_path_buf(),
            field,
            message,
        };
        if raw.format_version != MODEL_FORMAT_VERSION {
            return Err(SynergyError::UnsupportedVersion {
                path: path.to_path_buf(),
                found: raw.format_version,
                supported: MODEL_FORMAT_VERSION,
            });
        }
        if raw.joints.len() != D || raw.joints.iter().zip(FINGER_JOINTS).any(|(a, b)| a != b) {
            return Err(invalid(
                "joints",
                format!("expected the 22 finger joints {}", FINGER_JOINTS.join(", ")),
            ));
        }
        let arr22 = |field: &'static str, v: &[f64]| -> Result<[f64; D], SynergyError> {
            let a: [f64; D] = v
                .try_into()
                .map_err(|_| invalid(field, format!("expected 22 numbers, found {}", v.len())))?;
            check_finite(field, &a).map_err(|m| invalid(field, m))?;
            Ok(a)
        };
        let mean = arr22("mean", &raw.mean)?;
        let eigenvalues = arr22("eigenvalues", &raw.eigenvalues)?;
        let explained_variance_ratio =
            arr22("explained_variance_ratio", &raw.explained_variance_ratio)?;
        if eigenvalues.iter().any(|&e| e < 0.0) || eigenvalues.windows(2).any(|w| w[0] < w[1]) {
            return Err(invalid(
                "eigenvalues",
                "expected non-negative values in descending order".into(),
            ));
        }
        let n = raw.components.len();
        if !(1..=D).contains(&n) {
            return Err(invalid(
                "components",
                format!("expected 1 to 22 components, found {n}"),
            ));
        }
        let mut components = Vec::with_capacity(n);
        for (k, c) in raw.components.iter().enumerate() {
            let a: [f64; D] = c.as_slice().try_into().map_err(|_| {
                invalid(
                    "components",
                    format!("component {} has {} entries, expected 22", k + 1, c.len()),
                )
            })?;
            check_finite("components", &a)
                .map_err(|m| invalid("components", format!("component {}: {m}", k + 1)))?;
            components.push(a);
        }
        for a in 0..n {
            for b in 0..=a {
                let dot: f64 = (0..D).map(|j| components[a][j] * components[b][j]).sum();
                let want = if a == b { 1.0 } else { 0.0 };
                if (dot - want).abs() > ORTHONORMAL_TOLERANCE {
                    return Err(invalid(
                        "components",
                        format!(
                            "not orthonormal: C{} . C{} = {} (expected {want}, tolerance {ORTHONORMAL_TOLERANCE})",
                            a + 1,
                            b + 1,
                            crate::util::num::short(dot)
                        ),
                    ));
                }
            }
        }
        for (field, v) in [
            ("projection_min", &raw.projection_min),
            ("projection_max", &raw.projection_max),
        ] {
            if v.len() != n {
                return Err(invalid(
                    field,
                    format!(
                        "expected {n} numbers (one per component), found {}",
                        v.len()
                    ),
                ));
            }
            check_finite(field, v).map_err(|m| invalid(field, m))?;
        }
        // A mean posture is a set of joint angles (rad): a value beyond half a turn is not
        // one, and decodes every action into a clamped, meaningless posture.
        if let Some(j) = mean.iter().position(|m| m.abs() > std::f64::consts::PI) {
            return Err(invalid(
                "mean",
                format!(
                    "mean[{j}] ({}) = {} rad is not a joint angle: expected a value in [-pi, pi]",
                    FINGER_JOINTS[j],
                    crate::util::num::short(mean[j])
                ),
            ));
        }
        if let Some(k) = (0..n).find(|&k| raw.projection_min[k] > raw.projection_max[k]) {
            return Err(invalid(
                "projection_min",
                format!(
                    "projection_min[{k}] = {} is above projection_max[{k}] = {}: each \
                     component's range must have min <= max",
                    crate::util::num::short(raw.projection_min[k]),
                    crate::util::num::short(raw.projection_max[k])
                ),
            ));
        }
        Ok(SynergyModel {
            format_version: raw.format_version,
            joints: raw.joints,
            mean,
            components,
            eigenvalues,
            explained_variance_ratio,
            projection_min: raw.projection_min,
            projection_max: raw.projection_max,
            n_samples: raw.n_samples,
            source: raw.source,
        })
    }
}

fn check_finite(field: &str, v: &[f64]) -> Result<(), String> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(format!("{field}[{i}] = {} is not finite", v[i])),
        None => Ok(()),
    }
}

/// Flips `c` so that its entry of largest magnitude is positive (first index on ties).
fn fix_sign(c: &mut [f64; N_FINGER_JOINTS]) {
    let mut best = 0;
    for j in 1..c.len() {
        if c[j].abs() > c[best].abs() {
            best = j;
        }
    }
    if c[best] < 0.0 {
        for v in c.iter_mut() {
            *v = -*v;
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Two orthonormal directions in R^22 with equal J1/J2 entries in the coupled fingers.
    pub(crate) fn directions() -> ([f64; 22], [f64; 22]) {
        let mut u = [0.0; 22];
        let mut v = [0.0; 22];
        // u: FFJ3, MFJ3 flex together (0.6 each), FFJ2=FFJ1=0.4 ... normalised below.
        u[1] = 3.0; // FFJ3
        u[5] = 3.0; // MFJ3
        u[2] = 2.0; // FFJ2
        u[3] = 2.0; // FFJ1
                    // v: thumb rotation and LF metacarpal: orthogonal support.
        v[17] = 4.0; // THJ5
        v[12] = -2.0; // LFJ5
        v[18] = 4.0; // THJ4
        v[13] = 1.0; // LFJ4
        let nu = u.iter().map(|x| x * x).sum::<f64>().sqrt();
        let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        u.iter_mut().for_each(|x| *x /= nu);
        v.iter_mut().for_each(|x| *x /= nv);
        (u, v)
    }

    /// A feasible mean posture with J1 = J2 in the coupled fingers.
    pub(crate) fn base_posture() -> [f64; 22] {
        let mut m = [0.0; 22];
        for f in 0..4 {
            let o = if f < 3 { 4 * f } else { 13 };
            m[o + 1] = 0.5; // J3
            m[o + 2] = 0.3; // J2
            m[o + 3] = 0.3; // J1
        }
        m[12] = 0.3; // LFJ5
        m[17] = 0.2; // THJ5
        m[18] = 0.6; // THJ4
        m[21] = 0.2; // THJ1
        m
    }

    /// Rows m + a_i u + b_i v with a = (3, -3, 0, 0), b = (0, 0, 1, -1).
    pub(crate) fn known_rows() -> Vec<[f64; 22]> {
        let (u, v) = directions();
        let m = base_posture();
        [(3.0, 0.0), (-3.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
            .iter()
            .map(|&(a, b)| {
                let mut r = m;
                for j in 0..22 {
                    r[j] += 0.1 * (a * u[j] + b * v[j]);
                }
                r
            })
            .collect()
    }

    #[test]
    fn pca_of_two_known_directions() {
        // Coordinates along u: 0.1 * (3, -3, 0, 0): mean 0, sample variance
        // (0.09 + 0.09) / 3 = 0.06. Along v: 0.1 * (0, 0, 1, -1): (0.01 + 0.01) / 3 = 0.02/3.
        // They are uncorrelated (products all zero), so the eigenvalues are 0.06 and
        // 0.00667 and the ratios 0.06 / (0.06 + 0.02/3) = 0.9 and 0.1.
        let (u, v) = directions();
        let model = SynergyModel::fit(&known_rows(), 3).unwrap();
        let ev = model.eigenvalues();
        assert_relative_eq!(ev[0], 0.06, epsilon = 1e-14);
        assert_relative_eq!(ev[1], 0.02 / 3.0, epsilon = 1e-14);
        for e in &ev[2..] {
            assert!(e.abs() < 1e-14, "{e}");
        }
        let r = model.explained_variance_ratio();
        assert_relative_eq!(r[0], 0.9, epsilon = 1e-12);
        assert_relative_eq!(r[1], 0.1, epsilon = 1e-12);
        assert_relative_eq!(model.cumulative_ratio()[21], 1.0, epsilon = 1e-12);
        // Sign rule: u's largest entry (FFJ3, first of the tie with MFJ3) is positive, and
        // v's largest (THJ5, tied with THJ4) is positive, so C1 = +u, C2 = +v.
        for j in 0..22 {
            assert_relative_eq!(model.components()[0][j], u[j], epsilon = 1e-12);
            assert_relative_eq!(model.components()[1][j], v[j], epsilon = 1e-12);
        }
        for (a, b) in model.mean().iter().zip(base_posture()) {
            assert_relative_eq!(*a, b, epsilon = 1e-15);
        }
        // Projection ranges: 0.1 * (-3, 3) along u and 0.1 * (-1, 1) along v.
        assert_relative_eq!(model.projection_min()[0], -0.3, epsilon = 1e-12);
        assert_relative_eq!(model.projection_max()[0], 0.3, epsilon = 1e-12);
        assert_relative_eq!(model.projection_min()[1], -0.1, epsilon = 1e-12);
        assert_relative_eq!(model.projection_max()[1], 0.1, epsilon = 1e-12);
        assert_eq!(model.n_samples(), 4);
        assert_eq!(model.n_components(), 3);
    }

    #[test]
    fn per_joint_explained_hand_computed() {
        // Joint 0 takes -2 or 2 and joint 1 takes -1 or 1, independently (variances 4 and
        // 1), the rest stay at 0.3: the first component is joint 0's axis, so it explains
        // all of joint 0 and none of joint 1; two components explain both. Joints that do
        // not vary count as explained.
        let rows: Vec<[f64; 22]> = [(-2.0, -1.0), (-2.0, 1.0), (2.0, -1.0), (2.0, 1.0)]
            .iter()
            .map(|&(a, b)| {
                let mut r = [0.3; 22];
                r[0] = a;
                r[1] = b;
                r
            })
            .collect();
        let one = SynergyModel::fit(&rows, 1)
            .unwrap()
            .per_joint_explained(&rows);
        assert!((one[0] - 1.0).abs() < 1e-12, "{one:?}");
        assert!(one[1].abs() < 1e-12, "{one:?}");
        assert!(one[2..].iter().all(|&v| v == 1.0), "{one:?}");
        let two = SynergyModel::fit(&rows, 2)
            .unwrap()
            .per_joint_explained(&rows);
        assert!(two.iter().all(|&v| (v - 1.0).abs() < 1e-12), "{two:?}");
    }

    #[test]
    fn truncation_equals_a_smaller_fit() {
        let full = SynergyModel::fit(&known_rows(), 3).unwrap();
        let small = SynergyModel::fit(&known_rows(), 2).unwrap();
        let t = full.truncated(2).unwrap();
        assert_eq!(t, small);
        assert_eq!(t.n_components(), 2);
        assert_eq!(t.projection_min().len(), 2);
        assert_eq!(full.truncated(3).unwrap(), full);
        assert!(matches!(
            full.truncated(4),
            Err(SynergyError::TooFewComponents {
                requested: 4,
                available: 3
            })
        ));
        assert!(full.truncated(0).is_err());
    }

    /// Agreement with scikit-learn 1.9 (`PCA(svd_solver="full")`) on the committed fixture
    /// written by `tests/data/make_pca_ref.py` (the test only reads the files).
    #[test]
    fn agrees_with_scikit_learn() {
        use crate::robot::Side;
        use crate::synergy::{finger_limits, Dataset, LoadOptions};
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
        let data = Dataset::load(
            &dir.join("pca_ref_input.csv"),
            &finger_limits(Side::Left),
            &LoadOptions::default(),
        )
        .unwrap();
        assert_eq!(data.extras, vec!["object"]);
        let text = std::fs::read_to_string(dir.join("pca_ref_sklearn.json")).unwrap();
        let r: serde_json::Value = serde_json::from_str(&text).unwrap();
        let vec = |k: &str| -> Vec<f64> {
            r[k].as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        };
        assert_eq!(r["n_samples"].as_u64(), Some(data.rows.len() as u64));
        let model = SynergyModel::fit(&data.rows, 22).unwrap();
        let (ev, ratio, mean) = (
            vec("explained_variance"),
            vec("explained_variance_ratio"),
            vec("mean"),
        );
        for k in 0..22 {
            assert!(
                (model.eigenvalues()[k] - ev[k]).abs() < 1e-9,
                "eigenvalue {k}"
            );
            assert!(
                (model.explained_variance_ratio()[k] - ratio[k]).abs() < 1e-9,
                "ratio {k}"
            );
            assert!((model.mean()[k] - mean[k]).abs() < 1e-9, "mean {k}");
        }
        let comps = r["abs_components"].as_array().unwrap();
        let mut worst: f64 = 0.0;
        for (k, row) in comps.iter().enumerate() {
            for (j, x) in row.as_array().unwrap().iter().enumerate() {
                let d = (model.components()[k][j].abs() - x.as_f64().unwrap()).abs();
                worst = worst.max(d);
            }
        }
        eprintln!("largest |component| difference vs scikit-learn: {worst:e}");
        assert!(worst < 1e-9, "largest |component| difference {worst}");
    }

    #[test]
    fn sign_rule_flips_negative_dominant_entries() {
        let mut c = [0.0; 22];
        c[0] = 0.6;
        c[5] = -0.8;
        fix_sign(&mut c);
        assert_eq!(c[5], 0.8);
        assert_eq!(c[0], -0.6);
        let mut t = [0.0; 22];
        t[2] = -0.5;
        t[7] = 0.5; // tie: the first index decides
        fix_sign(&mut t);
        assert_eq!(t[2], 0.5);
        assert_eq!(t[7], -0.5);
    }

    #[test]
    fn rank_counts_the_directions_with_variance() {
        // known_rows vary along u and v only: eigenvalues 3..22 are round-off.
        let m = SynergyModel::fit(&known_rows(), 3).unwrap();
        assert_eq!(m.rank(), 2);
        assert!(m.eigenvalues()[2] < 1e-14);
    }

    #[test]
    fn fit_rejects_bad_input() {
        let rows = known_rows();
        assert!(matches!(
            SynergyModel::fit(&rows, 0),
            Err(SynergyError::InvalidComponents { n: 0 })
        ));
        assert!(matches!(
            SynergyModel::fit(&rows, 23),
            Err(SynergyError::InvalidComponents { n: 23 })
        ));
        assert!(matches!(
            SynergyModel::fit(&rows, 5),
            Err(SynergyError::TooFewSamples {
                samples: 4,
                required: 5,
                ..
            })
        ));
        assert!(matches!(
            SynergyModel::fit(&rows[..1], 1),
            Err(SynergyError::TooFewSamples { required: 2, .. })
        ));
        assert!(matches!(
            SynergyModel::fit(&[[0.1; 22]; 6], 2),
            Err(SynergyError::NoVariance { samples: 6 })
        ));
        let mut bad = rows.clone();
        bad[2][4] = f64::NAN;
        assert!(matches!(
            SynergyModel::fit(&bad, 2),
            Err(SynergyError::NonFiniteSample {
                row: 2,
                joint: "MFJ4",
                ..
            })
        ));
    }

    #[test]
    fn save_load_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        let model = SynergyModel::fit(&known_rows(), 2)
            .unwrap()
            .with_source("known rows");
        model.save(&path).unwrap();
        let back = SynergyModel::load(&path).unwrap();
        // serde_json's default float parser may differ from the written value by one ulp.
        assert_eq!(back.n_components(), 2);
        assert_eq!(back.joints(), model.joints());
        for k in 0..2 {
            for j in 0..22 {
                assert_relative_eq!(
                    back.components()[k][j],
                    model.components()[k][j],
                    max_relative = 1e-15
                );
            }
        }
        for j in 0..22 {
            assert_relative_eq!(back.mean()[j], model.mean()[j], max_relative = 1e-15);
            assert_relative_eq!(
                back.eigenvalues()[j],
                model.eigenvalues()[j],
                max_relative = 1e-15
            );
        }
        assert_eq!(back.projection_min().len(), 2);
        assert_eq!(back.n_samples(), 4);
        assert_eq!(back.source(), "known rows");
    }

    fn edit(model: &SynergyModel, f: impl FnOnce(&mut serde_json::Value)) -> String {
        let mut v: serde_json::Value = serde_json::from_str(&model.to_json()).unwrap();
        f(&mut v);
        v.to_string()
    }

    #[test]
    fn load_rejects_inconsistent_files() {
        let model = SynergyModel::fit(&known_rows(), 2).unwrap();
        let p = Path::new("m.json");
        let e = SynergyModel::from_json(p, "{\"format_version\": 1,\n  oops").unwrap_err();
        assert!(matches!(e, SynergyError::Json { line: 2, .. }), "{e}");

        let t = edit(&model, |v| v["format_version"] = 7.into());
        assert!(matches!(
            SynergyModel::from_json(p, &t),
            Err(SynergyError::UnsupportedVersion { found: 7, .. })
        ));

        let t = edit(&model, |v| {
            v["mean"].as_array_mut().unwrap().pop();
        });
        let e = SynergyModel::from_json(p, &t).unwrap_err();
        assert!(
            e.to_string()
                .contains("'mean': expected 22 numbers, found 21"),
            "{e}"
        );

        let t = edit(&model, |v| {
            v["components"][1].as_array_mut().unwrap().push(0.0.into());
        });
        let e = SynergyModel::from_json(p, &t).unwrap_err();
        assert!(e.to_string().contains("component 2 has 23 entries"), "{e}");

        let t = edit(&model, |v| v["components"][0][3] = 0.5.into());
        let e = SynergyModel::from_json(p, &t).unwrap_err();
        assert!(e.to_string().contains("not orthonormal"), "{e}");

        // serde_json writes NaN as null, which does not read back as a number.
        let t = edit(&model, |v| v["eigenvalues"][0] = serde_json::Value::Null);
        assert!(matches!(
            SynergyModel::from_json(p, &t),
            Err(SynergyError::Json { .. })
        ));
        let t = edit(&model, |v| v["projection_max"] = serde_json::json!([1.0]));
        let e = SynergyModel::from_json(p, &t).unwrap_err();
        assert!(e.to_string().contains("projection_max"), "{e}");

        // Issue 49: finite but meaningless numbers were accepted.
        let t = edit(&model, |v| v["mean"][3] = 1e308.into());
        let e = SynergyModel::from_json(p, &t).unwrap_err().to_string();
        assert!(
            e.contains("m.json") && e.contains("mean[3] (FFJ1) = 1e308 rad is not a joint angle"),
            "{e}"
        );
        let t = edit(&model, |v| {
            v["projection_min"][1] = 2.0.into();
            v["projection_max"][1] = 1.0.into();
        });
        let e = SynergyModel::from_json(p, &t).unwrap_err().to_string();
        assert!(
            e.contains("projection_min[1] = 2 is above projection_max[1] = 1"),
            "{e}"
        );

        let t = edit(&model, |v| v["joints"][0] = "WRJ1".into());
        assert!(matches!(
            SynergyModel::from_json(p, &t),
            Err(SynergyError::Invalid {
                field: "joints",
                ..
            })
        ));
        let t = edit(&model, |v| {
            v["eigenvalues"][21] = 5.0.into();
        });
        assert!(matches!(
            SynergyModel::from_json(p, &t),
            Err(SynergyError::Invalid {
                field: "eigenvalues",
                ..
            })
        ));
        let e = SynergyModel::load(Path::new("/nonexistent/m.json")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/m.json"), "{e}");
    }
}
