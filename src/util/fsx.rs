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
    create_dirs(&dir).map_err(wrap)?;
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

/// `std::fs::create_dir_all` whose error names a file that stands where a folder of
/// the path goes ("x is a file, not a folder") instead of "File exists (os error 17)".
pub fn create_dirs(dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| {
        let file = dir
            .ancestors()
            .find(|a| std::fs::metadata(a).is_ok_and(|m| !m.is_dir()));
        match file {
            Some(f)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::AlreadyExists | std::io::ErrorKind::NotADirectory
                ) =>
            {
                std::io::Error::new(
                    std::io::ErrorKind::NotADirectory,
                    format!("{} is a file, not a folder", f.display()),
                )
            }
            _ => e,
        }
    })
}

/// Byte limits of the files the crate reads with [`read_bounded`]: each kind's limit is
/// far above any real file of the kind and far below what would exhaust memory.
pub mod limits {
    /// A TOML config, grid, perturbation file, object manifest, calibration, grasp or
    /// checkpoint `config.toml`: 16 MiB.
    pub const CONFIG: u64 = 16 << 20;
    /// A JSON or CSV data file (saved evaluation, synergy model, pose dataset, metrics,
    /// attempt log, hull cache): 512 MiB.
    pub const DATA: u64 = 512 << 20;
    /// A mesh (OBJ, STL) or point cloud (PCD, PLY): 2 GiB.
    pub const MESH: u64 = 2 << 30;
    /// A checkpoint's weights (safetensors): 4 GiB.
    pub const WEIGHTS: u64 = 4 << 30;
}

/// Reads the file at `path` whole, refusing anything but a regular file (or a link to
/// one): a FIFO, a device such as `/dev/zero` or a folder is refused before it is opened
/// (a FIFO would block, `/dev/zero` never end), and so is a file larger than `max_bytes`
/// (one of [`limits`]). The error names the limit; the caller names the file.
pub fn read_bounded(path: &Path, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let meta = std::fs::metadata(path)?;
    let ft = meta.file_type();
    if !ft.is_file() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!(
                "a {}, not a regular file; refusing to read it",
                kind_name(&ft)
            ),
        ));
    }
    let too_large = |n: u64| {
        Error::new(
            ErrorKind::InvalidData,
            format!(
                "{} bytes, more than the limit of {} bytes for this kind of file",
                n, max_bytes
            ),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_large(meta.len()));
    }
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // The file may grow after the check: never read past the limit.
    file.take(max_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// [`read_bounded`] as UTF-8 text.
pub fn read_to_string_bounded(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    String::from_utf8(read_bounded(path, max_bytes)?).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

/// Whether `path` may be replaced by a cache write: nothing is there yet, or a regular
/// file that is not a symbolic link. A cache is an optimisation: a link (which could
/// point at any file of the user's), a FIFO or a device at its path is left alone and
/// the cache skipped.
pub fn is_plain_file_or_missing(path: &Path) -> bool {
    match std::fs::symlink_metadata(path) {
        Ok(m) => m.file_type().is_file(),
        Err(e) => e.kind() == std::io::ErrorKind::NotFound,
    }
}

/// A path a command reads or writes, with the flag that names it.
#[derive(Debug, Clone, Copy)]
pub struct Named<'a> {
    /// The flag (or argument) that gives the path, e.g. `--csv`.
    pub flag: &'a str,
    /// The path.
    pub path: &'a Path,
}

impl<'a> Named<'a> {
    /// `path` given by `flag`.
    pub fn new(flag: &'a str, path: &'a Path) -> Self {
        Named { flag, path }
    }
}

/// An output that would overwrite an input or another output.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct OverlapError(pub String);

/// Refuses, before any work, outputs that would destroy what the command reads or
/// writes: an output file that is an input file, two outputs that are one file, an
/// output file inside an output folder (`folders`, e.g. `--record`), and two output
/// folders one inside the other. Paths are compared after resolving links
/// and `..` (the existing part of each), and existing files also by device and inode
/// (a hard link is the same file).
pub fn check_outputs(
    inputs: &[Named],
    files: &[Named],
    folders: &[Named],
) -> Result<(), OverlapError> {
    let show = |n: &Named| format!("{} {}", n.flag, n.path.display());
    for (i, out) in files.iter().enumerate() {
        for inp in inputs {
            if same_file(out.path, inp.path) {
                return Err(OverlapError(format!(
                    "{} is the file given by {}: writing it would overwrite that input; \
                     choose another file",
                    show(out),
                    show(inp)
                )));
            }
        }
        for other in &files[..i] {
            if same_file(out.path, other.path) {
                return Err(OverlapError(format!(
                    "{} and {} are the same file: one output would overwrite the other; \
                     choose two files",
                    show(other),
                    show(out)
                )));
            }
        }
        for dir in folders {
            if inside(out.path, dir.path) {
                return Err(OverlapError(format!(
                    "{} lies inside the folder of {}, whose files would overwrite it or be \
                     overwritten by it; choose a file outside it",
                    show(out),
                    show(dir)
                )));
            }
        }
    }
    for (i, dir) in folders.iter().enumerate() {
        for other in &folders[..i] {
            if inside(dir.path, other.path) || inside(other.path, dir.path) {
                return Err(OverlapError(format!(
                    "{} and {} are the same folder or one holds the other: their files \
                     could overwrite each other; choose two separate folders",
                    show(other),
                    show(dir)
                )));
            }
        }
    }
    Ok(())
}

/// `path` made absolute with links and `..` resolved in its existing part (the rest,
/// which does not exist yet, appended as given).
pub fn resolved(path: &Path) -> PathBuf {
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    };
    let mut rest = Vec::new();
    let mut p = abs.as_path();
    loop {
        if let Ok(c) = std::fs::canonicalize(p) {
            let mut out = c;
            for part in rest.iter().rev() {
                out.push(part);
            }
            return normalise(&out);
        }
        match (p.parent(), p.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                p = parent;
            }
            _ => return normalise(&abs),
        }
    }
}

/// `path` with `.` and `..` components folded lexically.
fn normalise(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

/// Whether `a` and `b` are one file: the same resolved path, or (both existing) the same
/// device and inode.
pub fn same_file(a: &Path, b: &Path) -> bool {
    if resolved(a) == resolved(b) {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    false
}

/// Whether `path` is the folder `dir` or lies inside it (resolved paths).
pub fn inside(path: &Path, dir: &Path) -> bool {
    resolved(path).starts_with(resolved(dir))
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

    #[cfg(unix)]
    #[test]
    fn bounded_reads_refuse_special_and_oversized_files() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.toml");
        std::fs::write(&f, b"0123456789").unwrap();
        assert_eq!(read_bounded(&f, 10).unwrap(), b"0123456789");
        assert_eq!(read_to_string_bounded(&f, 100).unwrap(), "0123456789");
        let e = read_bounded(&f, 9).unwrap_err().to_string();
        assert!(
            e.contains("10 bytes, more than the limit of 9 bytes"),
            "{e}"
        );
        let e = read_bounded(Path::new("/dev/zero"), 100)
            .unwrap_err()
            .to_string();
        assert!(e.contains("character device, not a regular file"), "{e}");
        let fifo = dir.path().join("fifo");
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        // Refused before it is opened: the read would block for good.
        let e = read_bounded(&fifo, 100).unwrap_err().to_string();
        assert!(e.contains("FIFO, not a regular file"), "{e}");
        let e = read_bounded(dir.path(), 100).unwrap_err().to_string();
        assert!(e.contains("directory, not a regular file"), "{e}");
        // A link is no plain file to replace, a FIFO neither; a regular file or none is.
        let link = dir.path().join("link");
        std::os::unix::fs::symlink("a.toml", &link).unwrap();
        assert!(!is_plain_file_or_missing(&link));
        assert!(!is_plain_file_or_missing(&fifo));
        assert!(is_plain_file_or_missing(&f));
        assert!(is_plain_file_or_missing(&dir.path().join("none")));
    }

    #[cfg(unix)]
    #[test]
    fn outputs_that_are_inputs_or_each_other_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let input = d.join("e.json");
        std::fs::write(&input, b"{}").unwrap();
        let hard = d.join("hard.json");
        std::fs::hard_link(&input, &hard).unwrap();
        let link = d.join("link.json");
        std::os::unix::fs::symlink("e.json", &link).unwrap();
        let inp = [Named::new("--from-json", &input)];
        let csv = d.join("sub/../e.json");
        let e = check_outputs(&inp, &[Named::new("--csv", &csv)], &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--csv") && e.contains("--from-json"), "{e}");
        for other in [&hard, &link] {
            assert!(check_outputs(&inp, &[Named::new("--csv", other)], &[]).is_err());
        }
        let svg = d.join("x.svg");
        let e = check_outputs(
            &[],
            &[Named::new("--csv", &svg), Named::new("--plot", &svg)],
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("--csv") && e.contains("--plot") && e.contains("same file"),
            "{e}"
        );
        let rec = d.join("rec");
        let index = rec.join("index.html");
        let e = check_outputs(
            &[],
            &[Named::new("--csv", &index)],
            &[Named::new("--record", &rec)],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("inside the folder of --record"), "{e}");
        // Distinct files pass, existing or not.
        check_outputs(
            &inp,
            &[
                Named::new("--csv", &d.join("a.csv")),
                Named::new("--plot", &svg),
            ],
            &[Named::new("--record", &rec)],
        )
        .unwrap();
    }
}
