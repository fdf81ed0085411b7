//! Output files that are complete or absent.
//!
//! Every file springlab writes (CSV, PNG charts and frames, GIF, APNG) is written to a temporary
//! file in the target's own directory and renamed over the target when complete: a run that is
//! killed, interrupted or fails leaves no half-written file at the target path (at most a hidden
//! `.NAME.*.tmp` beside it after a `kill -9`; Ctrl-C and errors remove that too). Renaming
//! within one directory is atomic on POSIX file systems.
//!
//! [`check_file`] and [`check_dir`] test every output path before any simulation starts, so a
//! bad path costs nothing.

use std::fs::File;
use std::io;
use std::path::{Path, PathBuf};

/// A file being written at a temporary path beside its target; [`AtomicFile::commit`] renames
/// it over the target, dropping it removes it.
#[derive(Debug)]
pub struct AtomicFile {
    temp: tempfile::NamedTempFile,
    path: PathBuf,
}

impl AtomicFile {
    /// A temporary file `.NAME.XXXXXX.tmp` in the directory of `path`.
    ///
    /// # Errors
    /// The directory does not exist or is not writable.
    pub fn create(path: &Path) -> io::Result<AtomicFile> {
        let dir = parent(path);
        let name = path
            .file_name()
            .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o644));
        }
        let temp = builder.tempfile_in(dir)?;
        Ok(AtomicFile {
            temp,
            path: path.to_path_buf(),
        })
    }

    /// The temporary file, to write to.
    pub fn file(&mut self) -> &mut File {
        self.temp.as_file_mut()
    }

    /// The target path.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes the file and renames it over the target.
    ///
    /// # Errors
    /// The data cannot be flushed or the rename fails.
    pub fn commit(self) -> io::Result<()> {
        self.temp.as_file().sync_all()?;
        self.temp.persist(&self.path).map(drop).map_err(|e| e.error)
    }
}

impl io::Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.temp.write(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.temp.flush()
    }
}

impl io::Seek for AtomicFile {
    fn seek(&mut self, pos: io::SeekFrom) -> io::Result<u64> {
        self.temp.seek(pos)
    }
}

/// Writes `bytes` to `path` through an [`AtomicFile`].
///
/// # Errors
/// As [`AtomicFile::create`] and [`AtomicFile::commit`].
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    use io::Write;
    let mut file = AtomicFile::create(path)?;
    file.write_all(bytes)?;
    file.commit()
}

/// The directory of `path` (`.` for a bare file name).
fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// What is wrong with an output path, said once.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {reason}")]
pub struct OutputError {
    /// The path, as given.
    pub path: String,
    /// Why not.
    pub reason: String,
}

fn output_error(path: &Path, reason: impl Into<String>) -> OutputError {
    OutputError {
        path: path.display().to_string(),
        reason: reason.into(),
    }
}

/// Checks that `path` can be written: not a directory, in an existing directory where a file
/// can be created (tested by creating and removing a temporary file there).
///
/// # Errors
/// An [`OutputError`] saying why not.
pub fn check_file(path: &Path) -> Result<(), OutputError> {
    if path.as_os_str().is_empty() {
        return Err(output_error(path, "the path is empty"));
    }
    if path.is_dir() {
        return Err(output_error(path, "it is a directory"));
    }
    let dir = parent(path);
    if !dir.is_dir() {
        return Err(output_error(
            path,
            format!("directory {} does not exist", dir.display()),
        ));
    }
    probe(path, dir)
}

/// Checks that `dir` is a directory where files can be created, creating it (and its parents)
/// when missing.
///
/// # Errors
/// An [`OutputError`] saying why not.
pub fn check_dir(dir: &Path) -> Result<(), OutputError> {
    if dir.exists() && !dir.is_dir() {
        return Err(output_error(dir, "it exists and is not a directory"));
    }
    std::fs::create_dir_all(dir).map_err(|e| output_error(dir, os_reason(&e)))?;
    probe(dir, dir)
}

fn probe(path: &Path, dir: &Path) -> Result<(), OutputError> {
    tempfile::Builder::new()
        .prefix(".springlab-probe.")
        .tempfile_in(dir)
        .map(drop)
        .map_err(|e| output_error(path, os_reason(&e)))
}

/// The OS's reason (`Permission denied (os error 13)`), without the temporary file's path that
/// `tempfile` adds.
fn os_reason(e: &io::Error) -> String {
    match e.raw_os_error() {
        Some(code) => io::Error::from_raw_os_error(code).to_string(),
        None => io::Error::from(e.kind()).to_string(),
    }
}
