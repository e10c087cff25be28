//! TOML configuration loading with precise errors.
//!
//! Configs are deserialised with serde; structs use `#[serde(deny_unknown_fields)]` so a
//! typo is an error. The error names the file, the line and column, and the offending key.

use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// Error while loading a TOML config file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read config {path}: {source}")]
    Io {
        /// The config file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid TOML or does not match the expected schema.
    #[error("invalid config {path}, line {line}, column {column}: {message}")]
    Parse {
        /// The config file.
        path: PathBuf,
        /// 1-based line of the error.
        line: usize,
        /// 1-based column of the error.
        column: usize,
        /// What is wrong (names the key for unknown or mistyped fields).
        message: String,
    },
}

/// Parses TOML text `src` (read from `path`, used in error messages) into `T`.
pub fn parse_toml<T: DeserializeOwned>(path: &Path, src: &str) -> Result<T, ConfigError> {
    toml::from_str(src).map_err(|e| {
        let (line, column) = e.span().map(|s| line_col(src, s.start)).unwrap_or((1, 1));
        ConfigError::Parse {
            path: path.to_path_buf(),
            line,
            column,
            message: e.message().trim().to_string(),
        }
    })
}

/// Reads and parses the TOML file at `path` into `T`.
pub fn load_toml<T: DeserializeOwned>(path: &Path) -> Result<T, ConfigError> {
    let src = crate::util::fsx::read_to_string_bounded(path, crate::util::fsx::limits::CONFIG)
        .map_err(|source| ConfigError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    parse_toml(path, &src)
}

/// 1-based (line, column) of byte offset `pos` in `src`.
pub fn line_col(src: &str, pos: usize) -> (usize, usize) {
    let pos = pos.min(src.len());
    let before = &src[..pos];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Demo {
        alpha: f64,
        beta: Option<u32>,
    }

    #[test]
    fn line_col_counts_from_one() {
        assert_eq!(line_col("ab\ncd", 0), (1, 1));
        assert_eq!(line_col("ab\ncd", 4), (2, 2));
    }

    #[test]
    fn unknown_key_is_named_with_its_line() {
        let err = parse_toml::<Demo>(Path::new("x.toml"), "alpha = 1.0\nbetta = 2\n").unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("x.toml"), "{msg}");
        assert!(msg.contains("line 2"), "{msg}");
        assert!(msg.contains("betta"), "{msg}");
    }

    #[test]
    fn wrong_type_is_an_error() {
        let err = parse_toml::<Demo>(Path::new("x.toml"), "alpha = \"no\"\n").unwrap_err();
        assert!(err.to_string().contains("line 1"), "{err}");
    }
}
