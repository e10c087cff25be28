//! Library errors as Python exceptions: configuration problems raise `ValueError`, failures
//! while running raise `RuntimeError`; the message is the library's, which names the
//! field, file or environment.

use crate::env::api::EnvError;
use crate::train::TrainError;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::PyErr;

/// A config or setup error (`ValueError`).
pub fn config_error(e: impl Into<TrainError>) -> PyErr {
    let e: TrainError = e.into();
    match e {
        TrainError::Ppo(_) | TrainError::Write(_) | TrainError::Plot { .. } => {
            PyRuntimeError::new_err(e.to_string())
        }
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// An error of the vector environment: wrong actions are `ValueError`, the rest
/// `RuntimeError`.
pub fn env_error(e: EnvError) -> PyErr {
    match e {
        EnvError::ActionCount { .. } | EnvError::ActionLength { .. } => {
            PyValueError::new_err(e.to_string())
        }
        _ => PyRuntimeError::new_err(e.to_string()),
    }
}

/// Runs `f`, turning a panic into a `RuntimeError` naming `what`.
pub fn no_panic<T>(what: &str, f: impl FnOnce() -> T) -> Result<T, PyErr> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|p| {
        let msg = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        PyRuntimeError::new_err(format!("{what} failed inside the simulator: {msg}"))
    })
}

/// Runs `f` on what `m` guards (`object` names it in errors) with the GIL released:
/// the lock is taken and dropped without the GIL, so a second Python thread waiting for
/// it cannot deadlock, and a panic in `f` is a `RuntimeError` naming `what`.
pub fn locked<S: Send, T: Send>(
    py: pyo3::Python<'_>,
    m: &std::sync::Mutex<S>,
    object: &str,
    what: &str,
    f: impl FnOnce(&mut S) -> Result<T, PyErr> + Send,
) -> Result<T, PyErr> {
    py.detach(|| {
        let mut guard = m.lock().map_err(|_| poisoned(object))?;
        no_panic(what, || f(&mut guard))?
    })
}

/// A poisoned lock (a panic while stepping earlier) as a `RuntimeError`.
pub fn poisoned(what: &str) -> PyErr {
    PyRuntimeError::new_err(format!(
        "the {what} is unusable after an earlier internal error: create a new one"
    ))
}
