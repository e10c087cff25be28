//! Pose datasets: CSV files of the 22 finger joint angles, one posture per row.
//!
//! # Format
//! - The first line is a header of column names. The 22 finger joints of
//!   [`FINGER_JOINTS`] must each appear exactly once, with or without an `rh_`/`lh_`
//!   prefix, in any letter case and any column order (`lh_FFJ3`, `ffj3`, `RH_ffj3`).
//! - Other columns (`WRJ1`, `WRJ2`, `object`, `grasp_type`, ...) are ignored; their names are
//!   returned in [`Dataset::extras`] so a caller can report them.
//! - A column whose name (after the prefix) looks like a joint (`FFJ9`, `rh_THJ0`: two
//!   letters, `J`, digits) but is not one of the hand's 24 joints is an error: it is almost
//!   always a typo or a coupled `J0` that should have been split into J1 and J2.
//! - Angles are radians. Cells may be quoted with `"`; fields are trimmed. Blank lines are
//!   skipped; `\r\n` line ends and a UTF-8 byte-order mark are accepted.
//!
//! Every value is checked: it must parse as a number, be finite and lie within the joint
//! limits widened by a tolerance ([`LoadOptions::tolerance`], 0.05 rad by default).
//! Values inside the tolerance band are kept as they are (not clamped). Errors name the
//! file, the 1-based line and column, and the joint.

use crate::robot::joints::{canonical_name, finger_index, hand_index, Side, FINGER_JOINTS};
use crate::synergy::N_FINGER_JOINTS;
use crate::util::fsx::{write_atomic, WriteError};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Default tolerance (radians) by which a dataset angle may exceed its joint limits.
pub const DEFAULT_LIMIT_TOLERANCE: f64 = 0.05;

/// Error while reading or writing a pose dataset. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// The file could not be read.
    #[error("cannot read dataset {path}: {source}")]
    Io {
        /// The dataset file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is empty: it has no header line.
    #[error("dataset {path} is empty: expected a header line of joint names")]
    Empty {
        /// The dataset file.
        path: PathBuf,
    },
    /// A line could not be split into fields (an unterminated quote).
    #[error("dataset {path}, line {line}: {message}")]
    Syntax {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A header column looks like a joint name but names no joint of the hand.
    #[error(
        "dataset {path}, line {line}, column {column}: '{name}' looks like a joint name but \
         the hand has no joint {base} (finger joints: {})",
        FINGER_JOINTS.join(", ")
    )]
    UnknownJoint {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line of the header.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The column name as written.
        name: String,
        /// The name without prefix, upper-case.
        base: String,
    },
    /// Two header columns name the same finger joint (possibly with different prefixes).
    #[error(
        "dataset {path}, line {line}: joint {joint} appears twice, in column {first_column} \
         ('{first_name}') and column {column} ('{name}')"
    )]
    DuplicateJoint {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line of the header.
        line: usize,
        /// The joint (canonical name).
        joint: &'static str,
        /// 1-based column of the first occurrence.
        first_column: usize,
        /// The first column's name as written.
        first_name: String,
        /// 1-based column of the second occurrence.
        column: usize,
        /// The second column's name as written.
        name: String,
    },
    /// Finger joints without a column.
    #[error("dataset {path}, line {line}: missing finger joint column(s): {}", joints.join(", "))]
    MissingJoints {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line of the header.
        line: usize,
        /// The missing joints (canonical names).
        joints: Vec<&'static str>,
    },
    /// A data row has a different number of fields than the header.
    #[error("dataset {path}, line {line}: {found} fields, but the header has {expected}")]
    Ragged {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// Number of header columns.
        expected: usize,
        /// Number of fields on this line.
        found: usize,
    },
    /// A joint cell is not a number.
    #[error(
        "dataset {path}, line {line}, column {column} ({joint}): cannot read '{value}' as a number"
    )]
    NotANumber {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The joint (canonical name).
        joint: &'static str,
        /// The cell text.
        value: String,
    },
    /// A joint cell is NaN or infinite.
    #[error(
        "dataset {path}, line {line}, column {column} ({joint}): value '{value}' is not finite"
    )]
    NonFinite {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The joint (canonical name).
        joint: &'static str,
        /// The cell text.
        value: String,
    },
    /// A joint angle lies outside its limits by more than the tolerance.
    #[error(
        "dataset {path}, line {line}, column {column} ({joint}): angle {} rad is outside \
         the joint limits [{lower}, {upper}] by more than {tolerance} rad",
        crate::util::num::short(*.value)
    )]
    OutOfLimits {
        /// The dataset file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The joint (canonical name).
        joint: &'static str,
        /// The angle read.
        value: f64,
        /// Lower joint limit.
        lower: f64,
        /// Upper joint limit.
        upper: f64,
        /// The tolerance used.
        tolerance: f64,
    },
    /// The file has fewer data rows than required.
    #[error("dataset {path} has {rows} data row(s), fewer than the {required} required{why}")]
    TooFewRows {
        /// The dataset file.
        path: PathBuf,
        /// Number of data rows read.
        rows: usize,
        /// Number required.
        required: usize,
        /// Why that many are required (may be empty).
        why: String,
    },
    /// The dataset could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

/// Options for reading a dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadOptions {
    /// How far (radians) an angle may lie outside its joint limits before it is an error.
    pub tolerance: f64,
    /// The minimum number of data rows (for a PCA: at least the number of components and
    /// at least 2).
    pub min_rows: usize,
    /// Why `min_rows` rows are needed, appended to the error message, e.g.
    /// `" to fit 5 components"`.
    pub min_rows_reason: String,
}

impl Default for LoadOptions {
    /// Tolerance [`DEFAULT_LIMIT_TOLERANCE`], at least one row.
    fn default() -> Self {
        LoadOptions {
            tolerance: DEFAULT_LIMIT_TOLERANCE,
            min_rows: 1,
            min_rows_reason: String::new(),
        }
    }
}

/// A pose dataset: rows of the 22 finger joint angles (radians, [`FINGER_JOINTS`] order).
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// The postures, one per data line, in file order.
    pub rows: Vec<[f64; N_FINGER_JOINTS]>,
    /// Names of the ignored columns, as written in the header, in column order.
    pub extras: Vec<String>,
    /// The file the dataset was read from (or will be written to).
    pub path: PathBuf,
}

/// What a header column holds.
#[derive(Debug, Clone, Copy, PartialEq)]
enum ColumnRole {
    Joint(usize),
    Extra,
}

impl Dataset {
    /// Reads and validates the dataset at `path` against `limits` (lower, upper per finger
    /// joint, [`FINGER_JOINTS`] order; see [`finger_limits`](crate::synergy::finger_limits)).
    pub fn load(
        path: &Path,
        limits: &[(f64, f64); N_FINGER_JOINTS],
        opts: &LoadOptions,
    ) -> Result<Dataset, DatasetError> {
        let text = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::DATA)
            .map_err(|source| DatasetError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(path, &text, limits, opts)
    }

    /// Parses dataset text `text`; `path` is used in error messages and stored in the
    /// result. Same rules as [`Dataset::load`].
    pub fn parse(
        path: &Path,
        text: &str,
        limits: &[(f64, f64); N_FINGER_JOINTS],
        opts: &LoadOptions,
    ) -> Result<Dataset, DatasetError> {
        let p = || path.to_path_buf();
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
            .filter(|(_, l)| !l.trim().is_empty());

        let (header_line, header) = lines.next().ok_or(DatasetError::Empty { path: p() })?;
        let names = split_fields(header).map_err(|message| DatasetError::Syntax {
            path: p(),
            line: header_line,
            message,
        })?;
        let roles = header_roles(path, header_line, &names)?;

        let mut rows = Vec::new();
        let mut fields = Vec::with_capacity(names.len());
        for (line, l) in lines {
            fields.clear();
            split_fields_into(l, &mut fields).map_err(|message| DatasetError::Syntax {
                path: p(),
                line,
                message,
            })?;
            if fields.len() != names.len() {
                return Err(DatasetError::Ragged {
                    path: p(),
                    line,
                    expected: names.len(),
                    found: fields.len(),
                });
            }
            let mut row = [0.0; N_FINGER_JOINTS];
            for (col, (cell, role)) in fields.iter().zip(&roles).enumerate() {
                let ColumnRole::Joint(j) = *role else {
                    continue;
                };
                let joint = FINGER_JOINTS[j];
                let column = col + 1;
                let value: f64 = cell.parse().map_err(|_| DatasetError::NotANumber {
                    path: p(),
                    line,
                    column,
                    joint,
                    value: cell.to_string(),
                })?;
                if !value.is_finite() {
                    return Err(DatasetError::NonFinite {
                        path: p(),
                        line,
                        column,
                        joint,
                        value: cell.to_string(),
                    });
                }
                let (lower, upper) = limits[j];
                if value < lower - opts.tolerance || value > upper + opts.tolerance {
                    return Err(DatasetError::OutOfLimits {
                        path: p(),
                        line,
                        column,
                        joint,
                        value,
                        lower,
                        upper,
                        tolerance: opts.tolerance,
                    });
                }
                row[j] = value;
            }
            rows.push(row);
        }

        let required = opts.min_rows.max(1);
        if rows.len() < required {
            return Err(DatasetError::TooFewRows {
                path: p(),
                rows: rows.len(),
                required,
                why: opts.min_rows_reason.clone(),
            });
        }
        let extras = names
            .iter()
            .zip(&roles)
            .filter(|(_, r)| **r == ColumnRole::Extra)
            .map(|(n, _)| n.to_string())
            .collect();
        Ok(Dataset {
            rows,
            extras,
            path: p(),
        })
    }

    /// The dataset as CSV text: a header of the 22 prefixed joint names of `side`
    /// (`lh_FFJ4, ...`) and one line per row. Numbers are written in Rust's shortest
    /// round-trip form, so reading the text back gives the same bits.
    pub fn to_csv_string(&self, side: Side) -> String {
        let mut s = String::with_capacity(32 + self.rows.len() * N_FINGER_JOINTS * 20);
        let prefix = side.prefix();
        for (i, j) in FINGER_JOINTS.iter().enumerate() {
            if i > 0 {
                s.push(',');
            }
            s.push_str(prefix);
            s.push_str(j);
        }
        s.push('\n');
        for row in &self.rows {
            for (i, v) in row.iter().enumerate() {
                if i > 0 {
                    s.push(',');
                }
                let _ = write!(s, "{v}");
            }
            s.push('\n');
        }
        s
    }

    /// Writes the dataset to `path` (atomically) in the format [`Dataset::load`] reads,
    /// with the joint names of `side`. Extra columns are not written.
    pub fn to_csv(&self, path: &Path, side: Side) -> Result<(), DatasetError> {
        write_atomic(path, self.to_csv_string(side).as_bytes())?;
        Ok(())
    }
}

/// True for names shaped like a hand joint: two ASCII letters, `J`, one or more digits.
fn looks_like_joint(base: &str) -> bool {
    let b = base.as_bytes();
    b.len() >= 4
        && b[0].is_ascii_alphabetic()
        && b[1].is_ascii_alphabetic()
        && b[2] == b'J'
        && b[3..].iter().all(u8::is_ascii_digit)
}

/// Classifies the header columns, checking for unknown joint-like names, duplicates and
/// missing finger joints.
fn header_roles(path: &Path, line: usize, names: &[&str]) -> Result<Vec<ColumnRole>, DatasetError> {
    let mut roles = Vec::with_capacity(names.len());
    let mut seen: [Option<usize>; N_FINGER_JOINTS] = [None; N_FINGER_JOINTS];
    for (col, name) in names.iter().enumerate() {
        let base = canonical_name(name);
        match finger_index(&base) {
            Some(j) => {
                if let Some(first) = seen[j] {
                    return Err(DatasetError::DuplicateJoint {
                        path: path.to_path_buf(),
                        line,
                        joint: FINGER_JOINTS[j],
                        first_column: first + 1,
                        first_name: names[first].to_string(),
                        column: col + 1,
                        name: name.to_string(),
                    });
                }
                seen[j] = Some(col);
                roles.push(ColumnRole::Joint(j));
            }
            None if looks_like_joint(&base) && hand_index(&base).is_none() => {
                return Err(DatasetError::UnknownJoint {
                    path: path.to_path_buf(),
                    line,
                    column: col + 1,
                    name: name.to_string(),
                    base,
                });
            }
            None => roles.push(ColumnRole::Extra),
        }
    }
    let missing: Vec<&'static str> = FINGER_JOINTS
        .iter()
        .zip(&seen)
        .filter(|(_, s)| s.is_none())
        .map(|(j, _)| *j)
        .collect();
    if !missing.is_empty() {
        return Err(DatasetError::MissingJoints {
            path: path.to_path_buf(),
            line,
            joints: missing,
        });
    }
    Ok(roles)
}

/// Splits one CSV line into trimmed fields (see [`split_fields_into`]).
fn split_fields(line: &str) -> Result<Vec<&str>, String> {
    let mut out = Vec::new();
    split_fields_into(line, &mut out)?;
    Ok(out)
}

/// Splits one CSV line at commas into `out`. A field may be wrapped in double quotes
/// (then it may contain commas; `""` inside stands for one quote and is kept doubled,
/// which is harmless for the names and numbers read here). Fields are trimmed and their
/// outer quotes removed.
fn split_fields_into<'a>(line: &'a str, out: &mut Vec<&'a str>) -> Result<(), String> {
    let bytes = line.as_bytes();
    let mut start = 0;
    let mut in_quotes = false;
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'"' => in_quotes = !in_quotes,
            b',' if !in_quotes => {
                out.push(unquote(&line[start..i]));
                start = i + 1;
            }
            _ => {}
        }
    }
    if in_quotes {
        return Err("unterminated quoted field (quoted fields cannot span lines)".to_string());
    }
    out.push(unquote(&line[start..]));
    Ok(())
}

fn unquote(field: &str) -> &str {
    let t = field.trim();
    if t.len() >= 2 && t.starts_with('"') && t.ends_with('"') {
        t[1..t.len() - 1].trim()
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synergy::finger_limits;

    fn header(prefix: &str) -> String {
        FINGER_JOINTS
            .iter()
            .map(|j| format!("{prefix}{j}"))
            .collect::<Vec<_>>()
            .join(",")
    }

    fn zeros_line() -> String {
        vec!["0.1"; 22].join(",")
    }

    fn parse(text: &str) -> Result<Dataset, DatasetError> {
        Dataset::parse(
            Path::new("poses.csv"),
            text,
            &finger_limits(Side::Left),
            &LoadOptions::default(),
        )
    }

    #[test]
    fn reads_any_prefix_case_and_order_and_reports_extras() {
        // Reverse order, lower case, mixed prefixes, extras in between.
        let mut names: Vec<String> = FINGER_JOINTS
            .iter()
            .rev()
            .enumerate()
            .map(|(i, j)| match i % 3 {
                0 => format!("lh_{}", j.to_lowercase()),
                1 => format!("RH_{j}"),
                _ => j.to_string(),
            })
            .collect();
        names.insert(3, "object".into());
        names.push("WRJ1".into());
        let values: Vec<String> = (0..22)
            .rev()
            .map(|j| format!("{}", 0.01 * j as f64))
            .collect();
        let mut cells = values.clone();
        cells.insert(3, "\"mug, blue\"".into());
        cells.push("-0.2".into());
        let text = format!("\u{feff}{}\r\n{}\r\n\n", names.join(","), cells.join(", "));
        let d = parse(&text).unwrap();
        assert_eq!(d.rows.len(), 1);
        for j in 0..22 {
            assert_eq!(d.rows[0][j], 0.01 * j as f64);
        }
        assert_eq!(d.extras, vec!["object".to_string(), "WRJ1".to_string()]);
    }

    #[test]
    fn empty_file_is_an_error() {
        assert!(matches!(parse(""), Err(DatasetError::Empty { .. })));
        assert!(matches!(parse("\n  \n"), Err(DatasetError::Empty { .. })));
    }

    #[test]
    fn unknown_joint_like_column_is_an_error_other_names_are_extras() {
        let text = format!("{},rh_FFJ9\n{},0\n", header("lh_"), zeros_line());
        let e = parse(&text).unwrap_err();
        assert!(
            matches!(e, DatasetError::UnknownJoint { column: 23, ref base, .. } if base == "FFJ9"),
            "{e}"
        );
        assert!(
            e.to_string().contains("poses.csv, line 1, column 23"),
            "{e}"
        );
        let text = format!(
            "{},rh_object,grasp_type\n{},0,3\n",
            header(""),
            zeros_line()
        );
        assert_eq!(
            parse(&text).unwrap().extras,
            vec!["rh_object", "grasp_type"]
        );
    }

    #[test]
    fn duplicates_after_prefix_stripping_are_errors() {
        let text = format!("{},rh_ffj2\n{},0\n", header("lh_"), zeros_line());
        let e = parse(&text).unwrap_err();
        match &e {
            DatasetError::DuplicateJoint {
                joint,
                first_column,
                column,
                ..
            } => {
                assert_eq!(*joint, "FFJ2");
                assert_eq!(*first_column, 3);
                assert_eq!(*column, 23);
            }
            other => panic!("unexpected {other}"),
        }
    }

    #[test]
    fn missing_joints_are_listed() {
        let names: Vec<&str> = FINGER_JOINTS
            .iter()
            .copied()
            .filter(|j| *j != "MFJ1" && *j != "THJ5")
            .collect();
        let text = format!("{}\n{}\n", names.join(","), vec!["0"; 20].join(","));
        let e = parse(&text).unwrap_err();
        assert!(
            matches!(&e, DatasetError::MissingJoints { joints, .. } if joints == &["MFJ1", "THJ5"]),
            "{e}"
        );
    }

    #[test]
    fn bad_cells_name_line_and_column() {
        let mut cells = vec!["0.1".to_string(); 22];
        cells[4] = "abc".into();
        let text = format!("{}\n{}\n{}\n", header("lh_"), zeros_line(), cells.join(","));
        let e = parse(&text).unwrap_err();
        assert!(
            matches!(&e, DatasetError::NotANumber { line: 3, column: 5, joint: "MFJ4", value, .. } if value == "abc"),
            "{e}"
        );
        assert!(e.to_string().contains("line 3, column 5 (MFJ4)"), "{e}");

        cells[4] = "".into();
        let text = format!("{}\n{}\n", header(""), cells.join(","));
        assert!(matches!(
            parse(&text),
            Err(DatasetError::NotANumber { line: 2, .. })
        ));

        for bad in ["NaN", "inf", "-Infinity"] {
            cells[4] = bad.into();
            let text = format!("{}\n{}\n", header(""), cells.join(","));
            assert!(
                matches!(
                    parse(&text),
                    Err(DatasetError::NonFinite {
                        line: 2,
                        column: 5,
                        ..
                    })
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn limits_are_checked_with_tolerance() {
        // FFJ3 limits [-0.2618, 1.5708]; tolerance 0.05.
        let mut cells = vec!["0.1".to_string(); 22];
        cells[1] = "1.60".into(); // 0.0292 over: accepted, kept as is
        let text = format!("{}\n{}\n", header(""), cells.join(","));
        assert_eq!(parse(&text).unwrap().rows[0][1], 1.60);
        cells[1] = "1.63".into(); // 0.0592 over: rejected
        let text = format!("{}\n{}\n", header(""), cells.join(","));
        let e = parse(&text).unwrap_err();
        assert!(
            matches!(
                e,
                DatasetError::OutOfLimits {
                    line: 2,
                    column: 2,
                    joint: "FFJ3",
                    ..
                }
            ),
            "{e}"
        );
        // A tolerance of zero rejects the first value too.
        cells[1] = "1.60".into();
        let text = format!("{}\n{}\n", header(""), cells.join(","));
        let strict = LoadOptions {
            tolerance: 0.0,
            ..LoadOptions::default()
        };
        let limits = finger_limits(Side::Left);
        assert!(Dataset::parse(Path::new("p.csv"), &text, &limits, &strict).is_err());
    }

    #[test]
    fn ragged_rows_and_quotes_are_errors() {
        let text = format!("{}\n{}\n{},0.3\n", header(""), zeros_line(), zeros_line());
        assert!(matches!(
            parse(&text),
            Err(DatasetError::Ragged {
                line: 3,
                expected: 22,
                found: 23,
                ..
            })
        ));
        let text = format!("{}\n\"0.1,{}\n", header(""), zeros_line());
        assert!(matches!(
            parse(&text),
            Err(DatasetError::Syntax { line: 2, .. })
        ));
    }

    #[test]
    fn too_few_rows_is_an_error() {
        let text = format!("{}\n", header(""));
        assert!(matches!(
            parse(&text),
            Err(DatasetError::TooFewRows {
                rows: 0,
                required: 1,
                ..
            })
        ));
        let text = format!("{}\n{}\n{}\n", header(""), zeros_line(), zeros_line());
        let opts = LoadOptions {
            min_rows: 5,
            min_rows_reason: " to fit 5 components".into(),
            ..LoadOptions::default()
        };
        let e = Dataset::parse(Path::new("p.csv"), &text, &finger_limits(Side::Left), &opts)
            .unwrap_err();
        assert!(
            e.to_string()
                .contains("2 data row(s), fewer than the 5 required to fit 5 components"),
            "{e}"
        );
    }

    #[test]
    fn csv_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out/poses.csv");
        let mut row = [0.0; 22];
        for (j, v) in row.iter_mut().enumerate() {
            *v = 0.1 + (j as f64) / 370.0;
        }
        let d = Dataset {
            rows: vec![row, [0.2; 22]],
            extras: vec![],
            path: path.clone(),
        };
        d.to_csv(&path, Side::Left).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("lh_FFJ4,lh_FFJ3,"));
        let back =
            Dataset::load(&path, &finger_limits(Side::Left), &LoadOptions::default()).unwrap();
        assert_eq!(back, d);
    }

    #[test]
    fn missing_file_is_an_io_error_naming_it() {
        let e = Dataset::load(
            Path::new("/nonexistent/poses.csv"),
            &finger_limits(Side::Left),
            &LoadOptions::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("/nonexistent/poses.csv"), "{e}");
    }
}
