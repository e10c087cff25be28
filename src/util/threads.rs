//! The one rule for worker-thread counts, wherever a count is given (`--threads` of every
//! command, `threads` in training configs, `env_threads`, `grasp bench`): 1 to
//! [`MAX_THREADS`]. The default is the number of available cores, capped the same way.

/// Most worker threads a pool may have. Far above any machine this runs on; a larger
/// count is a typo (100000 threads took the process minutes to even start).
pub const MAX_THREADS: usize = 256;

/// Checks a thread count: `Err` says why, e.g. "0 must be in 1..=256"; the caller names
/// the field or flag.
pub fn check(n: usize) -> Result<usize, String> {
    if (1..=MAX_THREADS).contains(&n) {
        Ok(n)
    } else {
        Err(format!("{n} must be in 1..={MAX_THREADS}"))
    }
}

/// The available cores (1 when unknown), at most [`MAX_THREADS`].
pub fn available() -> usize {
    std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(MAX_THREADS)
}

/// A thread count given or not: checked when given, else [`available`].
pub fn resolve(given: Option<usize>) -> Result<usize, String> {
    given.map_or_else(|| Ok(available()), check)
}

/// [`resolve`] of a command's `--threads` flag: the error names the flag, e.g.
/// "--threads 0 must be in 1..=256".
pub fn from_flag(given: Option<usize>) -> Result<usize, String> {
    resolve(given).map_err(|m| format!("--threads {m}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_range_for_every_count() {
        assert_eq!(check(1), Ok(1));
        assert_eq!(check(MAX_THREADS), Ok(MAX_THREADS));
        assert_eq!(check(0).unwrap_err(), "0 must be in 1..=256");
        assert!(check(100_000).is_err());
        assert!(resolve(None).is_ok_and(|n| (1..=MAX_THREADS).contains(&n)));
        assert_eq!(resolve(Some(3)), Ok(3));
        assert!(resolve(Some(0)).is_err());
        assert_eq!(from_flag(Some(4)), Ok(4));
        assert_eq!(
            from_flag(Some(0)).unwrap_err(),
            "--threads 0 must be in 1..=256"
        );
    }
}
