//! File-system helpers. Everything the crate writes goes through [`write_atomic`], so a
//! killed process never leaves a half-written file behind.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Error while writing a file.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct WriteError {
    /// The file that could not be written.
    pub path: PathBuf,
    /// The underlying I/O error.
    #[source]
    pub source: std::io::Error,
}

/// Writes `bytes` to `path` atomically: the data goes to a temporary file in the same
/// directory, is flushed to disk, and is then renamed over `path`. Parent directories are
/// created when missing.
///
/// What is at `path` is respected: a symbolic link is followed (the file it points to is
/// replaced, the link stays), and anything but a regular file (a directory, a device such
/// as `/dev/full`, a FIFO, a socket) is refused with an error instead of being replaced
/// by a regular file. A full disk (`ENOSPC`) or any other failed write, flush or rename is
/// an error; the temporary file is then removed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let wrap = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    let target = regular_target(path).map_err(wrap)?;
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(wrap)?;
    let mut tmp = tempfile::NamedTempFile::new_in(&dir).map_err(wrap)?;
    tmp.write_all(bytes).map_err(wrap)?;
    tmp.flush().map_err(wrap)?;
    // The temporary file is private (0600); the result is an ordinary file that others
    // may read, like one written by `std::fs::write` under the usual umask.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(wrap)?;
    }
    tmp.as_file().sync_all().map_err(wrap)?;
    tmp.persist(&target).map_err(|e| wrap(e.error))?;
    Ok(())
}

/// Checks, before any work is done, that [`write_atomic`] could write `path` later: what
/// is there is a regular file (or a link to one, or nothing), and the nearest existing
/// folder above it is a folder this process can create files in (missing folders are
/// created by the write). One rule for every output file, so that a long computation is
/// not thrown away by a write that was bound to fail.
pub fn check_writable_file(path: &Path) -> Result<(), WriteError> {
    let wrap = |source| WriteError {
        path: path.to_path_buf(),
        source,
    };
    let target = match regular_target(path) {
        Ok(t) => t,
        // A file where a folder of the path goes: said by the folder check below.
        Err(e) if e.kind() == std::io::ErrorKind::NotADirectory => path.to_path_buf(),
        Err(e) => return Err(wrap(e)),
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    probe_folder(&dir).map_err(wrap)
}

/// Checks, before any work is done, that files can be written into the folder `dir`
/// later: it is a folder (or missing, with the nearest existing folder above it one)
/// this process can create files in.
pub fn check_writable_dir(dir: &Path) -> Result<(), WriteError> {
    probe_folder(dir).map_err(|source| WriteError {
        path: dir.to_path_buf(),
        source,
    })
}

/// The nearest existing ancestor of `dir` (itself included) must be a folder in which a
/// file can be created (tried with an empty file, removed at once).
fn probe_folder(dir: &Path) -> std::io::Result<()> {
    use std::io::{Error, ErrorKind};
    let mut p = dir.to_path_buf();
    loop {
        match std::fs::metadata(&p) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => {
                return Err(Error::new(
                    ErrorKind::NotADirectory,
                    format!("{} is a file, not a folder", p.display()),
                ))
            }
            Err(e) if matches!(e.kind(), ErrorKind::NotFound | ErrorKind::NotADirectory) => {
                p = match p.parent() {
                    Some(q) if !q.as_os_str().is_empty() => q.to_path_buf(),
                    // The current folder itself is gone: nothing above it to try.
                    _ if p == Path::new(".") => return Err(e),
                    _ => PathBuf::from("."),
                };
            }
            Err(e) => return Err(e),
        }
    }
    // A file of a name no one else uses, created and removed at once.
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let probe = p.join(format!(".grasp-write-check-{}-{nanos}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(Error::new(
            e.kind(),
            format!("cannot create files in {}: {e}", p.display()),
        )),
    }
}

/// The regular file that writing `path` should replace: `path` itself, or the end of its
/// chain of symbolic links (which may not exist yet). Anything else is an error.
fn regular_target(path: &Path) -> std::io::Result<PathBuf> {
    use std::io::{Error, ErrorKind};
    let mut p = path.to_path_buf();
    // The kernel's own limit on a chain of links (ELOOP) is 40.
    for _ in 0..40 {
        let meta = match std::fs::symlink_metadata(&p) {
            Ok(m) => m,
            Err(e) if e.kind() == ErrorKind::NotFound => return Ok(p),
            Err(e) => return Err(e),
        };
        let ft = meta.file_type();
        if ft.is_file() {
            return Ok(p);
        }
        if !ft.is_symlink() {
            return Err(Error::new(
                ErrorKind::InvalidInput,
                format!(
                    "{} is a {}, not a regular file; refusing to replace it",
                    p.display(),
                    kind_name(&ft)
                ),
            ));
        }
        let link = std::fs::read_link(&p)?;
        p = match p.parent() {
            Some(parent) if link.is_relative() => parent.join(link),
            _ => link,
        };
    }
    Err(Error::new(
        ErrorKind::InvalidInput,
        "too many levels of symbolic links",
    ))
}

fn kind_name(ft: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "FIFO";
        }
        if ft.is_char_device() {
            return "character device";
        }
        if ft.is_block_device() {
            return "block device";
        }
        if ft.is_socket() {
            return "socket";
        }
    }
    if ft.is_dir() {
        "directory"
    } else {
        "special file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_content_and_leaves_no_temp_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub/out.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        let entries: Vec<_> = std::fs::read_dir(p.parent().unwrap()).unwrap().collect();
        assert_eq!(entries.len(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o644);
        }
    }

    #[test]
    fn writability_is_checked_before_the_work() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a");
        std::fs::write(&file, b"x").unwrap();
        // Missing folders are fine (the write creates them); an existing file is replaced.
        check_writable_file(&dir.path().join("new/sub/out.csv")).unwrap();
        check_writable_file(&file).unwrap();
        check_writable_dir(&dir.path().join("rec/new")).unwrap();
        check_writable_dir(dir.path()).unwrap();
        // A folder where a file goes, a file where a folder goes.
        let e = check_writable_file(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is a directory, not a regular file"), "{e}");
        let e = check_writable_file(&file.join("x.svg"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("a is a file, not a folder"), "{e}");
        let e = check_writable_dir(&file.join("b/c"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("a is a file, not a folder"), "{e}");
        let e = check_writable_dir(&file).unwrap_err().to_string();
        assert!(e.contains("a is a file, not a folder"), "{e}");
        // Nothing was left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_are_followed_and_special_files_refused() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.json");
        let link = dir.path().join("link.json");
        std::fs::write(&real, b"old").unwrap();
        std::os::unix::fs::symlink("real.json", &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        // A dangling link creates its target.
        let dangling = dir.path().join("dangling.json");
        std::os::unix::fs::symlink("made.json", &dangling).unwrap();
        write_atomic(&dangling, b"made").unwrap();
        assert_eq!(
            std::fs::read(dir.path().join("made.json")).unwrap(),
            b"made"
        );
        // A FIFO and a directory stay what they are.
        let fifo = dir.path().join("fifo");
        let st = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(st.success());
        let e = write_atomic(&fifo, b"x").unwrap_err();
        assert!(e.to_string().contains("FIFO, not a regular file"), "{e}");
        use std::os::unix::fs::FileTypeExt;
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let e = write_atomic(&sub, b"x").unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        // A link to a device is refused too, and nothing is left behind.
        let dev = dir.path().join("dev.json");
        std::os::unix::fs::symlink("/dev/null", &dev).unwrap();
        let e = write_atomic(&dev, b"x").unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names,
            [
                "dangling.json",
                "dev.json",
                "fifo",
                "link.json",
                "made.json",
                "real.json",
                "sub"
            ]
        );
    }
}
