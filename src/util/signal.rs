//! Stopping long work on SIGINT or SIGTERM: the first signal sets [`STOP`] (the work
//! starts nothing new, finishes what runs, prints and writes it), a second one exits at
//! once with 130. Used by `grasp eval` and `grasp rollout`; training has its own
//! checkpointing handler.

use std::sync::atomic::{AtomicBool, Ordering};

/// Set by the first SIGINT or SIGTERM after [`stop_on_signal`].
pub static STOP: AtomicBool = AtomicBool::new(false);

/// Whether a stop was asked for.
pub fn stopped() -> bool {
    STOP.load(Ordering::SeqCst)
}

/// Whether the stop flag a long piece of work was handed (often [`STOP`]) is set; `false`
/// without one.
pub fn is_set(flag: Option<&AtomicBool>) -> bool {
    flag.is_some_and(|f| f.load(Ordering::SeqCst))
}

/// Installs the handler: the first signal sets [`STOP`] and, unless `quiet`, prints
/// `"\ninterrupted (SIGINT or SIGTERM): {doing} (again to quit at once)"` on stderr; a
/// second exits with 130 (128 + SIGINT, as a shell reports a process ended by Ctrl-C).
pub fn stop_on_signal(doing: &'static str, quiet: bool) -> Result<(), ctrlc::Error> {
    ctrlc::set_handler(move || {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        if !quiet {
            eprintln!("\ninterrupted (SIGINT or SIGTERM): {doing} (again to quit at once)");
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_flag_is_set_only_when_given_and_raised() {
        let flag = AtomicBool::new(false);
        assert!(!is_set(None));
        assert!(!is_set(Some(&flag)));
        flag.store(true, Ordering::SeqCst);
        assert!(is_set(Some(&flag)));
    }
}
