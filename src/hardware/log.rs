//! Attempt logs: one JSON object per line (JSON lines).
//!
//! Every control step of a grasp attempt is one [`LogRecord::Step`] line (time, raw and
//! mapped sensors, the action, the targets sent and the clamp events); the attempt ends
//! with one [`LogRecord::Outcome`] line.
//!
//! Crash safety: unlike the crate's other files, a log grows while the robot runs, so it
//! is not written through `write_atomic`. Instead the file is opened in append mode and
//! each record is serialised to one complete line in memory, written with a single
//! `write_all` and flushed straight away (the writer is unbuffered). A crash of the
//! process therefore loses nothing that was logged; at worst the line being written when
//! the machine loses power is truncated, and [`read_log`] reports it with its line number.
//! Call [`AttemptLog::sync`] to force the data to disk (e.g. after the outcome line).

use super::safety::ClampEvent;
use crate::robot::joints::{N_ACTUATORS, N_JOINTS, N_TACTILE};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Error of the attempt log.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// The log file could not be opened, written or read.
    #[error("attempt log {path}: {source}")]
    Io {
        /// The log file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A record contains a non-finite number (JSON cannot represent it).
    #[error("attempt log {path}: record field {field} is not finite")]
    NonFinite {
        /// The log file.
        path: PathBuf,
        /// The offending field.
        field: String,
    },
    /// A line of the log is not a valid record.
    #[error("attempt log {path}, line {line}: {detail}")]
    Parse {
        /// The log file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        detail: String,
    },
}

/// One control step.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepRecord {
    /// Step index within the attempt (0-based).
    pub step: u64,
    /// Backend time of the step (s).
    pub time_s: f64,
    /// Measured hand joint angles, paper order (rad).
    pub joint_angles: [f64; N_JOINTS],
    /// Raw fingertip readings.
    pub tactile_raw: [f64; N_TACTILE],
    /// Raw tendon readings.
    pub tendon_raw: [f64; N_ACTUATORS],
    /// Binary tactile observation.
    pub tactile: [bool; N_TACTILE],
    /// Drift-compensated tendon values `tau_j - tau_j0`.
    pub torque_mapped: [f64; N_ACTUATORS],
    /// Torque levels 0..5.
    pub torque_levels: [u8; N_ACTUATORS],
    /// The policy's action (its length depends on the action space).
    pub action: Vec<f64>,
    /// The hand targets sent after clamping (rad).
    pub targets: [f64; N_JOINTS],
    /// Targets changed by the safety limiter.
    pub clamp_events: Vec<ClampEvent>,
}

/// The end of an attempt.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutcomeRecord {
    /// Backend time at the end (s).
    pub time_s: f64,
    /// Number of control steps executed.
    pub steps: u64,
    /// Whether the object was grasped and lifted.
    pub success: bool,
    /// Why the attempt ended (`lifted`, `dropped`, `timeout`, `emergency stop`, ...).
    pub reason: String,
}

/// One line of an attempt log.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LogRecord {
    /// A control step.
    Step(Box<StepRecord>),
    /// The final line of an attempt.
    Outcome(OutcomeRecord),
}

/// An append-only JSON-lines attempt log, flushed after every line.
///
/// A log file that this handle created and never wrote to is removed when the handle is
/// dropped, so a run that fails before its first step (a cloud with no grasp, say)
/// leaves no empty file behind; a file that existed before is never removed.
#[derive(Debug)]
pub struct AttemptLog {
    path: PathBuf,
    file: File,
    lines: u64,
    created: bool,
    /// Whether `file` is a regular file: only those are synced (`fsync` on `/dev/null`
    /// or a pipe fails with EINVAL after the attempt has run).
    regular: bool,
    /// Whether the file ended in a cut-off line when opened (a write that failed before
    /// this fix, or another program's): the first line appended starts on a fresh line.
    needs_newline: bool,
}

/// Whether the regular file at `path` is non-empty and does not end in a line break.
fn ends_mid_line(path: &Path) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut f) = File::open(path) else {
        return false;
    };
    let mut last = [0u8; 1];
    f.seek(SeekFrom::End(-1)).is_ok() && f.read_exact(&mut last).is_ok() && last[0] != b'\n'
}

impl AttemptLog {
    /// Opens (creating if needed, parent directories included) `path` for appending.
    pub fn open(path: &Path) -> Result<Self, LogError> {
        let io = |source| LogError::Io {
            path: path.to_path_buf(),
            source,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            crate::util::fsx::create_dirs(dir).map_err(io)?;
        }
        // `create` here too: a dangling symbolic link at `path` is "already there" for
        // `create_new`, and its target is made as before (and kept).
        let append = || {
            std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(path)
        };
        let (file, created) = match std::fs::OpenOptions::new()
            .append(true)
            .create_new(true)
            .open(path)
        {
            Ok(f) => (f, true),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                (append().map_err(io)?, false)
            }
            Err(e) => return Err(io(e)),
        };
        let regular = file.metadata().map_err(io)?.is_file();
        Ok(AttemptLog {
            path: path.to_path_buf(),
            file,
            lines: 0,
            created,
            regular,
            needs_newline: regular && ends_mid_line(path),
        })
    }

    /// The log file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Lines written through this handle.
    pub fn lines_written(&self) -> u64 {
        self.lines
    }

    /// Appends one record as one line and flushes it.
    pub fn append(&mut self, record: &LogRecord) -> Result<(), LogError> {
        if let Some(field) = non_finite_field(record) {
            return Err(LogError::NonFinite {
                path: self.path.clone(),
                field,
            });
        }
        let mut line = serde_json::to_string(record).map_err(|e| LogError::Io {
            path: self.path.clone(),
            source: std::io::Error::other(e),
        })?;
        line.push('\n');
        if self.needs_newline {
            line.insert(0, '\n');
        }
        let io = |source: std::io::Error| LogError::Io {
            path: self.path.clone(),
            source: std::io::Error::new(source.kind(), format!("cannot write: {source}")),
        };
        // All or nothing: a line cut off by a full disk is truncated away, so the log
        // holds whole lines only and the next one starts where this one would have.
        let before = if self.regular {
            Some(self.file.metadata().map_err(io)?.len())
        } else {
            None
        };
        let written = self
            .file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush());
        if let Err(e) = written {
            if let Some(len) = before {
                if self.file.set_len(len).is_err() {
                    // Could not take the part back: the next line starts afresh.
                    self.needs_newline = true;
                }
            }
            return Err(io(e));
        }
        self.needs_newline = false;
        self.lines += 1;
        Ok(())
    }

    /// Appends a step record.
    pub fn step(&mut self, step: StepRecord) -> Result<(), LogError> {
        self.append(&LogRecord::Step(Box::new(step)))
    }

    /// Appends the outcome record and syncs the file to disk.
    pub fn outcome(&mut self, outcome: OutcomeRecord) -> Result<(), LogError> {
        self.append(&LogRecord::Outcome(outcome))?;
        self.sync()
    }

    /// Forces the written data to disk; nothing to do where the log is not a regular
    /// file (`/dev/null`, a pipe: each line was written whole when it was appended).
    pub fn sync(&mut self) -> Result<(), LogError> {
        if !self.regular {
            return Ok(());
        }
        self.file.sync_data().map_err(|source| LogError::Io {
            path: self.path.clone(),
            source,
        })
    }
}

impl Drop for AttemptLog {
    fn drop(&mut self) {
        if self.created && self.lines == 0 {
            // Best effort: an empty file left behind is harmless, only untidy.
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

fn non_finite_field(record: &LogRecord) -> Option<String> {
    let first_bad = |name: &str, v: &[f64]| {
        v.iter()
            .position(|x| !x.is_finite())
            .map(|k| format!("{name}[{k}]"))
    };
    match record {
        LogRecord::Step(s) => {
            if !s.time_s.is_finite() {
                return Some("time_s".into());
            }
            first_bad("joint_angles", &s.joint_angles)
                .or_else(|| first_bad("tactile_raw", &s.tactile_raw))
                .or_else(|| first_bad("tendon_raw", &s.tendon_raw))
                .or_else(|| first_bad("torque_mapped", &s.torque_mapped))
                .or_else(|| first_bad("action", &s.action))
                .or_else(|| first_bad("targets", &s.targets))
                .or_else(|| {
                    s.clamp_events
                        .iter()
                        .position(|e| !(e.requested.is_finite() && e.applied.is_finite()))
                        .map(|k| format!("clamp_events[{k}]"))
                })
        }
        LogRecord::Outcome(o) => (!o.time_s.is_finite()).then(|| "time_s".into()),
    }
}

/// Reads an attempt log back; the error names the file and the line.
pub fn read_log(path: &Path) -> Result<Vec<LogRecord>, LogError> {
    let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::DATA)
        .map_err(|source| LogError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let r = serde_json::from_str(line).map_err(|e| LogError::Parse {
            path: path.to_path_buf(),
            line: i + 1,
            detail: e.to_string(),
        })?;
        out.push(r);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hardware::safety::ClampReason;

    fn step(k: u64) -> StepRecord {
        StepRecord {
            step: k,
            time_s: 0.05 * k as f64,
            joint_angles: [0.1; 24],
            tactile_raw: [200.0; 5],
            tendon_raw: [-3.0; 20],
            tactile: [false, true, false, false, true],
            torque_mapped: [1.5; 20],
            torque_levels: [3; 20],
            action: vec![0.5, -0.25],
            targets: [0.2; 24],
            clamp_events: vec![ClampEvent {
                joint: "FFJ3".into(),
                requested: 1.9,
                applied: 1.5,
                reason: ClampReason::JointLimit,
            }],
        }
    }

    #[test]
    fn round_trip_and_append_across_handles() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("logs/attempt.jsonl");
        let mut log = AttemptLog::open(&p).unwrap();
        log.step(step(0)).unwrap();
        log.step(step(1)).unwrap();
        // Nothing is buffered: the lines are in the file before the handle is dropped.
        assert_eq!(read_log(&p).unwrap().len(), 2);
        drop(log);
        let mut log = AttemptLog::open(&p).unwrap();
        let out = OutcomeRecord {
            time_s: 0.1,
            steps: 2,
            success: true,
            reason: "lifted".into(),
        };
        log.outcome(out.clone()).unwrap();
        let recs = read_log(&p).unwrap();
        assert_eq!(recs.len(), 3);
        assert_eq!(recs[1], LogRecord::Step(Box::new(step(1))));
        assert_eq!(recs[2], LogRecord::Outcome(out));
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text
            .lines()
            .nth(2)
            .unwrap()
            .starts_with(r#"{"kind":"outcome""#));
    }

    #[test]
    fn a_line_after_a_cut_off_one_starts_on_a_fresh_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.jsonl");
        let mut log = AttemptLog::open(&p).unwrap();
        log.step(step(0)).unwrap();
        drop(log);
        // A line cut off by a full disk (before appends were all or nothing).
        let mut text = std::fs::read_to_string(&p).unwrap();
        text.push_str(r#"{"kind":"step","ste"#);
        std::fs::write(&p, &text).unwrap();
        let mut log = AttemptLog::open(&p).unwrap();
        log.step(step(1)).unwrap();
        log.step(step(2)).unwrap();
        drop(log);
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 4, "{text}");
        assert_eq!(lines[1], r#"{"kind":"step","ste"#);
        for l in [lines[0], lines[2], lines[3]] {
            serde_json::from_str::<LogRecord>(l).unwrap();
        }
    }

    #[test]
    fn an_unwritten_log_is_removed_only_when_this_handle_made_it() {
        let dir = tempfile::tempdir().unwrap();
        // Made here, nothing written: gone when dropped.
        let p = dir.path().join("new.jsonl");
        drop(AttemptLog::open(&p).unwrap());
        assert!(!p.exists());
        // Made here and written to: kept.
        let mut log = AttemptLog::open(&p).unwrap();
        log.step(step(0)).unwrap();
        drop(log);
        assert_eq!(read_log(&p).unwrap().len(), 1);
        // There before (even empty), nothing written: kept as it was.
        drop(AttemptLog::open(&p).unwrap());
        assert_eq!(read_log(&p).unwrap().len(), 1);
        let empty = dir.path().join("empty.jsonl");
        std::fs::write(&empty, "").unwrap();
        drop(AttemptLog::open(&empty).unwrap());
        assert!(empty.exists());
        // A dangling symbolic link is followed and its target made, as before.
        #[cfg(unix)]
        {
            let link = dir.path().join("link.jsonl");
            let target = dir.path().join("target.jsonl");
            std::os::unix::fs::symlink(&target, &link).unwrap();
            let mut log = AttemptLog::open(&link).unwrap();
            log.step(step(0)).unwrap();
            drop(log);
            assert_eq!(read_log(&target).unwrap().len(), 1);
        }
    }

    #[cfg(unix)]
    #[test]
    fn a_log_that_is_not_a_regular_file_takes_the_outcome() {
        // `--log /dev/null`: syncing it failed with EINVAL after the attempt had run, and
        // its result was lost.
        let mut log = AttemptLog::open(Path::new("/dev/null")).unwrap();
        log.step(step(0)).unwrap();
        let out = OutcomeRecord {
            time_s: 0.1,
            steps: 1,
            success: true,
            reason: "lifted".into(),
        };
        log.outcome(out).unwrap();
        drop(log);
        assert!(Path::new("/dev/null").exists());
    }

    #[test]
    fn non_finite_is_refused_and_bad_lines_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.jsonl");
        let mut log = AttemptLog::open(&p).unwrap();
        let mut s = step(0);
        s.targets[4] = f64::NAN;
        let e = log.step(s).unwrap_err().to_string();
        assert!(e.contains("targets[4]"), "{e}");
        assert_eq!(log.lines_written(), 0);
        log.step(step(0)).unwrap();
        std::fs::write(
            &p,
            format!(
                "{}{{\"kind\":\"step\"",
                std::fs::read_to_string(&p).unwrap()
            ),
        )
        .unwrap();
        let e = read_log(&p).unwrap_err().to_string();
        assert!(e.contains("a.jsonl, line 2"), "{e}");
    }
}
