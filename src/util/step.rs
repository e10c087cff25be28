//! A failed step of a set-up, with what the step was and why: the library's counterpart
//! of a command line's error context (`loading policy DIR: ...`). The command prints the
//! step, then its causes.

/// What failed (the step, naming the file it read where there is one) and its cause.
#[derive(Debug, thiserror::Error)]
#[error("{what}")]
pub struct StepError {
    /// The step.
    pub what: String,
    /// Why it failed.
    #[source]
    pub source: Box<dyn std::error::Error + Send + Sync>,
}

/// Wraps a result's error with what the step was, as `anyhow`'s `with_context` does for a
/// command: `SimConfig::load(p).step(|| format!("loading {}", p.display()))?`.
pub trait StepContext<T> {
    /// The result, its error wrapped with `what()`.
    fn step(self, what: impl FnOnce() -> String) -> Result<T, StepError>;
}

impl<T, E> StepContext<T> for Result<T, E>
where
    E: std::error::Error + Send + Sync + 'static,
{
    fn step(self, what: impl FnOnce() -> String) -> Result<T, StepError> {
        self.map_err(|e| StepError {
            what: what(),
            source: Box::new(e),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_says_what_it_was_and_keeps_its_cause() {
        let r: Result<(), std::io::Error> = Err(std::io::Error::other("disk full"));
        let e = r.step(|| "writing x.toml".into()).unwrap_err();
        assert_eq!(e.to_string(), "writing x.toml");
        let cause = std::error::Error::source(&e).map(|c| c.to_string());
        assert_eq!(cause.as_deref(), Some("disk full"));
        assert_eq!(Ok::<u8, std::io::Error>(3).step(String::new).unwrap(), 3);
    }
}
