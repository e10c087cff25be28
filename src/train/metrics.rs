//! `metrics.csv`: one row per PPO update.
//!
//! Columns ([`HEADER`]): `update`, `global_step` (transitions so far), `episodes`
//! (episodes finished so far), `success_rate`, `episode_return`, `episode_length` (means
//! over the episodes that finished during the update; empty when none did or, for success,
//! when the environment reports none), `policy_loss`, `value_loss`, `entropy`,
//! `approx_kl`, `clip_fraction`, `explained_variance`, `curriculum_level` (mean success
//! rate `r_s` of the grasp environments' curricula; empty for other environments),
//! `transitions_per_s` (this update), `wall_s` (training seconds so far, over resumes) and
//! `physics_failures` (episodes of this update that ended in a detected physics failure).
//! Files written before the last column existed ([`HEADER_V1`]) are read with 0 failures.

use super::TrainError;
use crate::ppo::{UpdateMetrics, UpdateStats};
use std::path::Path;

/// The CSV header.
pub const HEADER: &str = "update,global_step,episodes,success_rate,episode_return,\
episode_length,policy_loss,value_loss,entropy,approx_kl,clip_fraction,explained_variance,\
curriculum_level,transitions_per_s,wall_s,physics_failures";

/// The header of metrics files written before `physics_failures` was recorded.
pub const HEADER_V1: &str = "update,global_step,episodes,success_rate,episode_return,\
episode_length,policy_loss,value_loss,entropy,approx_kl,clip_fraction,explained_variance,\
curriculum_level,transitions_per_s,wall_s";

/// Columns that depend on timing and differ between identical runs.
pub const TIME_COLUMNS: [&str; 2] = ["transitions_per_s", "wall_s"];

/// One update's metrics.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MetricsRow {
    /// Update index, from 1.
    pub update: u64,
    /// Transitions collected so far.
    pub global_step: u64,
    /// Episodes finished so far.
    pub episodes: u64,
    /// The update's success rate, mean return and length of the episodes finished in it,
    /// and its losses: the columns `success_rate` to `explained_variance`, as the trainer
    /// measured them.
    #[serde(flatten)]
    pub stats: UpdateStats,
    /// Mean curriculum success rate `r_s` over the environments.
    pub curriculum_level: Option<f64>,
    /// Transitions per second of this update.
    pub transitions_per_s: f64,
    /// Training wall time so far (s).
    pub wall_s: f64,
    /// Episodes of this update that ended in a detected physics failure.
    pub physics_failures: u64,
}

fn opt(v: Option<f64>) -> String {
    v.map(|x| x.to_string()).unwrap_or_default()
}

impl MetricsRow {
    /// The row of update `m`, with `episodes_before` episodes finished before it, the
    /// curriculum's mean level and `wall_s` training seconds so far.
    pub fn new(
        m: &UpdateMetrics,
        episodes_before: u64,
        curriculum_level: Option<f64>,
        wall_s: f64,
    ) -> Self {
        MetricsRow {
            update: m.update,
            global_step: m.global_step,
            episodes: episodes_before + m.episodes as u64,
            stats: m.stats.clone(),
            curriculum_level,
            transitions_per_s: m.transitions_per_sec,
            wall_s,
            physics_failures: m.physics_failures as u64,
        }
    }

    /// The row as one CSV line (no newline). Floats use Rust's shortest exact form.
    pub fn to_csv_line(&self) -> String {
        let s = &self.stats;
        format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            self.update,
            self.global_step,
            self.episodes,
            opt(s.success_rate),
            opt(s.episode_return),
            opt(s.episode_length),
            s.policy_loss,
            s.value_loss,
            s.entropy,
            s.approx_kl,
            s.clip_fraction,
            opt(s.explained_variance),
            opt(self.curriculum_level),
            self.transitions_per_s,
            self.wall_s,
            self.physics_failures
        )
    }

    /// The scalars logged to TensorBoard, as (tag, value); absent values are skipped.
    pub fn scalars(&self) -> Vec<(&'static str, f64)> {
        let s = &self.stats;
        let mut v = vec![
            ("charts/episodes", self.episodes as f64),
            ("losses/policy_loss", s.policy_loss),
            ("losses/value_loss", s.value_loss),
            ("losses/entropy", s.entropy),
            ("losses/approx_kl", s.approx_kl),
            ("losses/clip_fraction", s.clip_fraction),
            ("charts/transitions_per_s", self.transitions_per_s),
            ("charts/physics_failures", self.physics_failures as f64),
        ];
        let optional = [
            ("charts/success_rate", s.success_rate),
            ("charts/episode_return", s.episode_return),
            ("charts/episode_length", s.episode_length),
            ("losses/explained_variance", s.explained_variance),
            ("charts/curriculum_level", self.curriculum_level),
        ];
        v.extend(optional.into_iter().filter_map(|(k, x)| x.map(|x| (k, x))));
        v
    }
}

/// The whole file: header and rows, newline-terminated.
pub fn to_csv(rows: &[MetricsRow]) -> String {
    let mut s = String::with_capacity(64 + rows.len() * 160);
    s.push_str(HEADER);
    s.push('\n');
    for r in rows {
        s.push_str(&r.to_csv_line());
        s.push('\n');
    }
    s
}

/// Parses a metrics file's text (`path` names it in errors).
pub fn parse_csv(path: &Path, text: &str) -> Result<Vec<MetricsRow>, TrainError> {
    let bad = |line: usize, message: String| TrainError::Metrics {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut lines = text.lines();
    let columns = match lines.next() {
        Some(h) if h.trim_end() == HEADER => 16,
        Some(h) if h.trim_end() == HEADER_V1 => 15,
        Some(_) => return Err(bad(1, format!("the header is not `{HEADER}`"))),
        None => return Err(bad(1, "the file is empty".into())),
    };
    let mut rows: Vec<MetricsRow> = Vec::new();
    for (i, line) in lines.enumerate() {
        let n = i + 2;
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.trim_end().split(',').collect();
        if f.len() != columns {
            return Err(bad(n, format!("{} fields, expected {columns}", f.len())));
        }
        let int = |k: usize, name: &str| -> Result<u64, TrainError> {
            f[k].parse()
                .map_err(|_| bad(n, format!("column {name}: '{}' is not an integer", f[k])))
        };
        let real = |k: usize, name: &str| -> Result<f64, TrainError> {
            let v: f64 = f[k]
                .parse()
                .map_err(|_| bad(n, format!("column {name}: '{}' is not a number", f[k])))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(bad(n, format!("column {name}: {v} is not finite")))
            }
        };
        let maybe = |k: usize, name: &str| -> Result<Option<f64>, TrainError> {
            if f[k].is_empty() {
                Ok(None)
            } else {
                real(k, name).map(Some)
            }
        };
        let row = MetricsRow {
            update: int(0, "update")?,
            global_step: int(1, "global_step")?,
            episodes: int(2, "episodes")?,
            stats: UpdateStats {
                success_rate: maybe(3, "success_rate")?,
                episode_return: maybe(4, "episode_return")?,
                episode_length: maybe(5, "episode_length")?,
                policy_loss: real(6, "policy_loss")?,
                value_loss: real(7, "value_loss")?,
                entropy: real(8, "entropy")?,
                approx_kl: real(9, "approx_kl")?,
                clip_fraction: real(10, "clip_fraction")?,
                explained_variance: maybe(11, "explained_variance")?,
            },
            curriculum_level: maybe(12, "curriculum_level")?,
            transitions_per_s: real(13, "transitions_per_s")?,
            wall_s: real(14, "wall_s")?,
            physics_failures: if columns > 15 {
                int(15, "physics_failures")?
            } else {
                0
            },
        };
        if let Some(prev) = rows.last() {
            if row.update <= prev.update {
                return Err(bad(
                    n,
                    format!(
                        "update {} does not follow update {}",
                        row.update, prev.update
                    ),
                ));
            }
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Reads the metrics file at `path`.
pub fn read_csv(path: &Path) -> Result<Vec<MetricsRow>, TrainError> {
    let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::DATA)
        .map_err(|source| TrainError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    parse_csv(path, &text)
}

/// The selection score of the last `window` rows: the mean success rate when any row has
/// one, else the mean return (for environments without success); `None` when the window
/// holds neither.
pub fn window_score(rows: &[MetricsRow], window: usize) -> Option<f64> {
    let tail = &rows[rows.len().saturating_sub(window)..];
    let mean = |vals: Vec<f64>| {
        if vals.is_empty() {
            None
        } else {
            Some(vals.iter().sum::<f64>() / vals.len() as f64)
        }
    };
    let succ: Vec<f64> = tail.iter().filter_map(|r| r.stats.success_rate).collect();
    if !succ.is_empty() {
        return mean(succ);
    }
    mean(tail.iter().filter_map(|r| r.stats.episode_return).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(update: u64, success: Option<f64>, ret: Option<f64>) -> MetricsRow {
        MetricsRow {
            update,
            global_step: update * 64,
            episodes: update * 3,
            stats: UpdateStats {
                success_rate: success,
                episode_return: ret,
                episode_length: ret.map(|r| r / 2.0),
                policy_loss: -0.012,
                value_loss: 0.5,
                entropy: 1.4189385,
                approx_kl: 1e-4,
                clip_fraction: 0.0625,
                explained_variance: None,
            },
            curriculum_level: success,
            transitions_per_s: 1234.5,
            wall_s: update as f64 * 0.1,
            physics_failures: update % 2,
        }
    }

    #[test]
    fn csv_round_trips_with_empty_optionals() {
        let rows = vec![row(1, None, None), row(2, Some(0.25), Some(13.0 / 3.0))];
        let text = to_csv(&rows);
        assert!(text.starts_with(HEADER));
        assert_eq!(text.lines().count(), 3);
        assert!(text.lines().nth(1).unwrap().starts_with("1,64,3,,,,"));
        let back = parse_csv(Path::new("m.csv"), &text).unwrap();
        assert_eq!(back, rows);
    }

    #[test]
    fn the_csv_and_json_forms_of_a_row_are_pinned() {
        // metrics.csv and `grasp train --json`'s `last` as written on 2026-12-07: same
        // columns, same order, same number formatting.
        let r = row(2, Some(0.25), Some(13.0 / 3.0));
        assert_eq!(
            to_csv(std::slice::from_ref(&r)),
            "update,global_step,episodes,success_rate,episode_return,episode_length,\
             policy_loss,value_loss,entropy,approx_kl,clip_fraction,explained_variance,\
             curriculum_level,transitions_per_s,wall_s,physics_failures\n\
             2,128,6,0.25,4.333333333333333,2.1666666666666665,-0.012,0.5,1.4189385,0.0001,\
             0.0625,,0.25,1234.5,0.2,0\n"
        );
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            "{\"update\":2,\"global_step\":128,\"episodes\":6,\"success_rate\":0.25,\
             \"episode_return\":4.333333333333333,\"episode_length\":2.1666666666666665,\
             \"policy_loss\":-0.012,\"value_loss\":0.5,\"entropy\":1.4189385,\
             \"approx_kl\":0.0001,\"clip_fraction\":0.0625,\"explained_variance\":null,\
             \"curriculum_level\":0.25,\"transitions_per_s\":1234.5,\"wall_s\":0.2,\
             \"physics_failures\":0}"
        );
        let pretty = serde_json::to_string_pretty(&r).unwrap();
        assert!(
            pretty.starts_with("{\n  \"update\": 2,\n  \"global_step\": 128,"),
            "{pretty}"
        );
    }

    #[test]
    fn files_without_the_physics_failure_column_still_read() {
        let r = row(2, Some(0.5), Some(1.0));
        let line = r.to_csv_line();
        let old = line.rsplit_once(',').unwrap().0;
        let back = parse_csv(Path::new("m.csv"), &format!("{HEADER_V1}\n{old}\n")).unwrap();
        assert_eq!(back[0].physics_failures, 0);
        assert!(HEADER.ends_with(",physics_failures"));
        assert!(r.scalars().contains(&("charts/physics_failures", 0.0)));
    }

    #[test]
    fn malformed_files_name_line_and_column() {
        let p = Path::new("m.csv");
        assert!(parse_csv(p, "").unwrap_err().to_string().contains("empty"));
        assert!(parse_csv(p, "a,b\n")
            .unwrap_err()
            .to_string()
            .contains("header"));
        let good = row(1, None, None).to_csv_line();
        let e = parse_csv(p, &format!("{HEADER}\n{good}\n1,2\n")).unwrap_err();
        assert!(e.to_string().contains("line 3"), "{e}");
        let e = parse_csv(p, &format!("{HEADER}\n{}\n", good.replacen("64", "x", 1))).unwrap_err();
        assert!(e.to_string().contains("global_step"), "{e}");
        let e = parse_csv(p, &format!("{HEADER}\n{good}\n{good}\n")).unwrap_err();
        assert!(e.to_string().contains("does not follow"), "{e}");
        let nan = good.replacen("0.5", "NaN", 1);
        assert!(parse_csv(p, &format!("{HEADER}\n{nan}\n")).is_err());
    }

    #[test]
    fn window_score_prefers_success_then_return() {
        let rows = vec![
            row(1, Some(0.0), Some(1.0)),
            row(2, Some(0.5), Some(2.0)),
            row(3, None, Some(3.0)),
            row(4, Some(1.0), Some(4.0)),
        ];
        assert_eq!(window_score(&rows, 3), Some(0.75));
        assert_eq!(window_score(&rows, 100), Some(0.5));
        let r = vec![row(1, None, Some(10.0)), row(2, None, Some(20.0))];
        assert_eq!(window_score(&r, 2), Some(15.0));
        assert_eq!(window_score(&[row(1, None, None)], 5), None);
        assert_eq!(window_score(&[], 5), None);
    }
}
