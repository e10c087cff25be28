//! Where a default that names a shipped file lies, from any working directory.
//!
//! A command-line default such as `grasp run`'s `--policy` (`crate::run::DEFAULT_POLICY`)
//! is a path relative to the repository. The one
//! rule: the path as given, relative to the working directory, when it exists there;
//! otherwise the same path under the crate's source folder, baked in at compile time
//! ([`SOURCE_DIR`]), so that the defaults work from another folder and from an installed
//! binary (`cargo install --path .`) as long as that folder exists; otherwise an error
//! that names both places and the flag that takes another path.
//!
//! Only defaults go through this rule ([`default_or_given`]): a path the user typed is
//! used as typed.

use std::path::{Path, PathBuf};

/// The crate's source folder (its `Cargo.toml`'s folder) at compile time.
pub const SOURCE_DIR: &str = env!("CARGO_MANIFEST_DIR");

/// A shipped file found neither in the working directory nor in [`SOURCE_DIR`].
#[derive(Debug, thiserror::Error)]
#[error(
    "{}: not found in the working directory ({}) nor in the crate's source folder ({}); \
     pass {flag} with its path",
    .path.display(),
    .cwd.display(),
    .source_dir.display()
)]
pub struct NotShipped {
    /// The path as given.
    pub path: PathBuf,
    /// The working directory it was looked for in.
    pub cwd: PathBuf,
    /// The source folder it was looked for in.
    pub source_dir: PathBuf,
    /// The flag that takes another path.
    pub flag: String,
}

/// `path` where it exists: as given (relative to the working directory, or absolute),
/// else under [`SOURCE_DIR`] for a relative path; else [`NotShipped`] naming `flag`.
pub fn shipped(path: &Path, flag: &str) -> Result<PathBuf, NotShipped> {
    shipped_in(path, flag, Path::new(SOURCE_DIR))
}

/// [`shipped`] with the source folder given (for tests).
pub fn shipped_in(path: &Path, flag: &str, source_dir: &Path) -> Result<PathBuf, NotShipped> {
    if path.exists() {
        return Ok(path.to_path_buf());
    }
    if path.is_relative() {
        let there = source_dir.join(path);
        if there.exists() {
            return Ok(there);
        }
    }
    Err(NotShipped {
        path: path.to_path_buf(),
        cwd: std::env::current_dir().unwrap_or_else(|_| PathBuf::from(".")),
        source_dir: source_dir.to_path_buf(),
        flag: flag.to_string(),
    })
}

/// A flag's value: when it is the flag's default (`default`, naming a shipped file), where
/// that file lies by [`shipped`]'s rule; any other value as given.
pub fn default_or_given(given: &Path, default: &str, flag: &str) -> Result<PathBuf, NotShipped> {
    if given == Path::new(default) {
        shipped(given, flag)
    } else {
        Ok(given.to_path_buf())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_found_in_the_working_directory_is_kept_else_the_source_folder_is_tried() {
        // Cargo runs unit tests in the crate's folder, where Cargo.toml lies.
        let empty = tempfile::tempdir().unwrap();
        assert_eq!(
            shipped_in(Path::new("Cargo.toml"), "--x", empty.path()).unwrap(),
            PathBuf::from("Cargo.toml")
        );
        let src = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(src.path().join("assets/policies/p")).unwrap();
        let found = shipped_in(Path::new("assets/policies/p"), "--policy", src.path()).unwrap();
        assert_eq!(found, src.path().join("assets/policies/p"));
        // The crate's own source folder holds the shipped default policy.
        assert!(shipped(
            Path::new("assets/policies/grip_long_gru_m3_pca5"),
            "--policy"
        )
        .is_ok());
    }

    #[test]
    fn a_missing_file_names_both_places_and_the_flag() {
        let src = tempfile::tempdir().unwrap();
        let e = shipped_in(Path::new("assets/nothing/here"), "--policy", src.path())
            .unwrap_err()
            .to_string();
        assert!(e.contains("assets/nothing/here"), "{e}");
        assert!(e.contains("working directory"), "{e}");
        assert!(e.contains(&src.path().display().to_string()), "{e}");
        assert!(e.contains("pass --policy"), "{e}");
        // An absolute path is not looked for under the source folder.
        let abs = src.path().join("missing");
        assert!(shipped_in(&abs, "--x", Path::new(SOURCE_DIR)).is_err());
    }

    #[test]
    fn only_the_default_goes_through_the_rule() {
        let typed = Path::new("no/such/policy");
        assert_eq!(
            default_or_given(typed, "assets/policies/x", "--policy").unwrap(),
            typed
        );
        assert!(default_or_given(
            Path::new("assets/policies/x"),
            "assets/policies/x",
            "--policy"
        )
        .is_err());
    }
}
