//! Flat action buffers: `n` rows of `k + 1` native-endian `float32` values, the `k`
//! continuous components (synergy increments, then the two wrist increments; the
//! environment clips them to [-1, 1]) and the lift entry, which lifts when > 0.

use crate::env::api::Action;
use pyo3::exceptions::PyValueError;
use pyo3::PyErr;

/// Decodes `bytes` into `n` actions of `k` continuous components plus the lift entry.
/// Errors name the environment and the component: a wrong length or a non-finite value.
pub fn decode(bytes: &[u8], n: usize, k: usize) -> Result<Vec<Action>, PyErr> {
    let width = k + 1;
    if bytes.len() != n * width * 4 {
        return Err(PyValueError::new_err(format!(
            "the action buffer holds {} bytes, expected {} ({n} x {width} float32 values: {k} \
             continuous components and the lift entry per environment)",
            bytes.len(),
            n * width * 4
        )));
    }
    let values: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|c| f32::from_ne_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    values
        .chunks_exact(width)
        .enumerate()
        .map(|(i, row)| {
            if let Some(j) = row.iter().position(|v| !v.is_finite()) {
                let what = if j == k {
                    "the lift entry".to_string()
                } else {
                    format!("component {j}")
                };
                return Err(PyValueError::new_err(format!(
                    "action of environment {i}: {what} is {} (actions must be finite)",
                    row[j]
                )));
            }
            Ok(Action {
                cont: row[..k].to_vec(),
                lift: row[k] > 0.0,
            })
        })
        .collect()
}

/// `values` as native-endian bytes.
pub fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_ne_bytes()).collect()
}
