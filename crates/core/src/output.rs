//! Output files that are complete or absent, and never replace what is not theirs.
//!
//! Every file springlab writes (CSV, PNG charts and frames, GIF, APNG) is first written to a
//! temporary file, and only a complete file reaches the target. What happens then depends on
//! what is at the target path ([`target`]):
//!
//! - **nothing, or a regular file**: the temporary file is `.NAME.XXXXXX.tmp` in the target's own
//!   directory, created with `O_EXCL` under a random name (never a fixed name that a symbolic
//!   link could be waiting at), and renamed over the target when complete. Renaming within one
//!   directory is atomic on POSIX file systems, so a run that is killed, interrupted or fails
//!   leaves no half-written file at the target path (at most the hidden temporary file after a
//!   `kill -9`; signals and errors remove that too);
//! - **a symbolic link to a regular file**: the link is followed and the file it names is
//!   replaced as above (the temporary file is created beside that file); a link that leads
//!   nowhere is refused. The link itself is never replaced;
//! - **a character device, FIFO or terminal** (`/dev/null`, `/dev/stdout`, a named pipe): written
//!   in place, never replaced. The output is kept in an unnamed temporary file (removed by the
//!   system even after a `kill -9`) and copied to the device when complete;
//! - **`-`**: standard output, in the same way;
//! - a directory, a block device or a socket is refused.
//!
//! [`check_file`] and [`check_dir`] test every output path before any simulation starts, so a
//! bad path costs nothing; [`same_target`] tells two outputs that would overwrite each other.

use std::fs::{self, File};
use std::io::{self, Seek, Write};
use std::path::{Path, PathBuf};

/// The path that means standard output, where a format allows it.
pub const STDOUT: &str = "-";

/// How an output path is written (module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// Nothing or a regular file at `real` (the path with its symbolic links followed, when it
    /// was one): a temporary file beside `real` is renamed over it.
    Replace {
        /// The file that is replaced (or created).
        real: PathBuf,
    },
    /// A character device or a FIFO (a terminal, `/dev/null`, `/dev/stdout` on a pipe): written
    /// in place when complete.
    InPlace,
    /// `-`: standard output.
    Stdout,
}

/// What is at `path`, and so how an output there is written.
///
/// # Errors
/// An [`OutputError`] for an empty path, a directory, a block device, a socket, a symbolic link
/// that leads nowhere, or a path whose kind cannot be read.
pub fn target(path: &Path) -> Result<Target, OutputError> {
    if path.as_os_str().is_empty() {
        return Err(output_error(path, "the path is empty"));
    }
    if path.as_os_str() == STDOUT {
        return Ok(Target::Stdout);
    }
    let link = match fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Ok(Target::Replace {
                real: path.to_path_buf(),
            });
        }
        Err(e) => return Err(output_error(path, os_reason(&e))),
    };
    if !link.file_type().is_symlink() {
        return kind(path, &link.file_type(), path.to_path_buf());
    }
    match fs::metadata(path) {
        Ok(m) if m.is_file() => {
            let real = fs::canonicalize(path).map_err(|e| output_error(path, os_reason(&e)))?;
            Ok(Target::Replace { real })
        }
        Ok(m) => kind(path, &m.file_type(), path.to_path_buf()),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Err(output_error(
            path,
            "it is a symbolic link to a file that does not exist; springlab follows links to \
             existing files only and never replaces a link (give the real path)",
        )),
        Err(e) => Err(output_error(path, os_reason(&e))),
    }
}

/// The target of a path that exists and is not a symbolic link (or what a link leads to).
fn kind(path: &Path, kind: &fs::FileType, real: PathBuf) -> Result<Target, OutputError> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() || kind.is_fifo() {
            return Ok(Target::InPlace);
        }
        if kind.is_block_device() {
            return Err(output_error(
                path,
                "it is a block device; outputs go to a file, a FIFO, a character device such as \
                 /dev/null, or `-` (standard output)",
            ));
        }
        if kind.is_socket() {
            return Err(output_error(path, "it is a socket"));
        }
    }
    if kind.is_dir() {
        return Err(output_error(path, "it is a directory"));
    }
    if kind.is_file() {
        return Ok(Target::Replace { real });
    }
    Err(output_error(path, "it is neither a file nor a device"))
}

/// A file being written to a temporary file; [`AtomicFile::commit`] puts it at its target
/// (module docs), dropping it removes it.
#[derive(Debug)]
pub struct AtomicFile {
    temp: Temp,
    path: PathBuf,
}

#[derive(Debug)]
enum Temp {
    /// Beside `real`, renamed over it.
    Beside {
        temp: tempfile::NamedTempFile,
        real: PathBuf,
    },
    /// Unnamed; copied to the device at `path` or to standard output.
    Unnamed { file: File, stdout: bool },
}

impl AtomicFile {
    /// A temporary file for `path`: `.NAME.XXXXXX.tmp` beside the (real) target for a file, an
    /// unnamed one for a device, a FIFO or `-`.
    ///
    /// # Errors
    /// The target is refused ([`target`]), or the directory does not exist or is not writable.
    pub fn create(path: &Path) -> io::Result<AtomicFile> {
        let target = target(path).map_err(|e| io::Error::other(e.reason))?;
        let temp = match target {
            Target::Replace { real } => {
                let name = real
                    .file_name()
                    .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
                let prefix = format!(".{name}.");
                let mut builder = tempfile::Builder::new();
                builder.prefix(&prefix).suffix(".tmp");
                #[cfg(unix)]
                {
                    use std::os::unix::fs::PermissionsExt;
                    builder.permissions(fs::Permissions::from_mode(0o644));
                }
                let temp = builder.tempfile_in(parent(&real))?;
                Temp::Beside { temp, real }
            }
            Target::InPlace => Temp::Unnamed {
                file: tempfile::tempfile()?,
                stdout: false,
            },
            Target::Stdout => Temp::Unnamed {
                file: tempfile::tempfile()?,
                stdout: true,
            },
        };
        Ok(AtomicFile {
            temp,
            path: path.to_path_buf(),
        })
    }

    /// The temporary file, to write to (and read back: it is always a seekable file).
    pub fn file(&mut self) -> &mut File {
        match &mut self.temp {
            Temp::Beside { temp, .. } => temp.as_file_mut(),
            Temp::Unnamed { file, .. } => file,
        }
    }

    /// The target path, as given.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Puts the complete file at its target: flushes it and renames it over the (real) target
    /// file, or copies it to the device or standard output.
    ///
    /// # Errors
    /// The data cannot be flushed, the target changed into something that is not a regular file
    /// while the file was written, or the rename or the copy fails (a full device).
    pub fn commit(self) -> io::Result<()> {
        match self.temp {
            Temp::Beside { temp, real } => {
                temp.as_file().sync_all()?;
                // Between create and commit the target may have become a link or a device:
                // still never replace what is not a regular file.
                if let Ok(m) = fs::symlink_metadata(&real)
                    && !m.is_file()
                {
                    return Err(io::Error::other(
                        "the path changed into something that is not a regular file while the \
                         output was written; it was not replaced",
                    ));
                }
                temp.persist(&real).map(drop).map_err(|e| e.error)
            }
            Temp::Unnamed { mut file, stdout } => {
                file.flush()?;
                file.rewind()?;
                if stdout {
                    let mut out = io::stdout().lock();
                    io::copy(&mut file, &mut out)?;
                    out.flush()
                } else {
                    // No create, no truncate: the device or FIFO stays what it is.
                    let mut out = open_in_place(&self.path)?;
                    io::copy(&mut file, &mut out)?;
                    out.flush()
                }
            }
        }
    }
}

impl io::Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.file().write(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.file().flush()
    }
}

impl io::Seek for AtomicFile {
    fn seek(&mut self, pos: io::SeekFrom) -> io::Result<u64> {
        self.file().seek(pos)
    }
}

/// Set when the process is asked to stop (the command line's Ctrl-C and signal handlers set
/// it): an output waiting for a FIFO's reader gives up instead of holding the process.
pub static STOP: std::sync::LazyLock<std::sync::Arc<std::sync::atomic::AtomicBool>> =
    std::sync::LazyLock::new(std::sync::Arc::default);

/// Opens the device or FIFO at `path` for writing. Opening a FIFO waits for a reader; that
/// wait is made in steps of 20 ms (a non-blocking open until one is there), so [`STOP`] ends it
/// with [`io::ErrorKind::Interrupted`].
fn open_in_place(path: &Path) -> io::Result<File> {
    #[cfg(unix)]
    {
        use rustix::fs::{Mode, OFlags};
        use std::os::unix::fs::FileTypeExt;
        if fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo()) {
            loop {
                match rustix::fs::open(
                    path,
                    OFlags::WRONLY | OFlags::NONBLOCK | OFlags::CLOEXEC,
                    Mode::empty(),
                ) {
                    Ok(fd) => {
                        // Writes block again from here on, as on any file.
                        rustix::fs::fcntl_setfl(&fd, OFlags::WRONLY)?;
                        return Ok(File::from(fd));
                    }
                    Err(rustix::io::Errno::NXIO) => {
                        if STOP.load(std::sync::atomic::Ordering::Relaxed) {
                            return Err(io::Error::new(
                                io::ErrorKind::Interrupted,
                                "stopped while waiting for a reader of the FIFO",
                            ));
                        }
                        std::thread::sleep(std::time::Duration::from_millis(20));
                    }
                    Err(e) => return Err(e.into()),
                }
            }
        }
    }
    fs::OpenOptions::new().write(true).open(path)
}

/// Writes `bytes` to `path` through an [`AtomicFile`].
///
/// # Errors
/// As [`AtomicFile::create`] and [`AtomicFile::commit`].
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
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

/// Checks that `path` can be written ([`target`]): for a file, an existing directory where a
/// file can be created (tested by creating and removing a temporary file there); for a
/// character device, that it opens for writing; a FIFO and `-` are accepted as they are.
///
/// # Errors
/// An [`OutputError`] saying why not.
pub fn check_file(path: &Path) -> Result<(), OutputError> {
    match target(path)? {
        Target::Replace { real } => {
            let dir = parent(&real);
            if !dir.is_dir() {
                return Err(output_error(
                    path,
                    format!("directory {} does not exist", dir.display()),
                ));
            }
            probe(path, dir)
        }
        Target::InPlace => {
            #[cfg(unix)]
            {
                use std::os::unix::fs::FileTypeExt;
                // Opening a FIFO for writing waits for a reader: only devices are opened here.
                let fifo = fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo());
                if !fifo {
                    fs::OpenOptions::new()
                        .write(true)
                        .open(path)
                        .map_err(|e| output_error(path, os_reason(&e)))?;
                }
            }
            Ok(())
        }
        Target::Stdout => Ok(()),
    }
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
    fs::create_dir_all(dir).map_err(|e| output_error(dir, os_reason(&e)))?;
    probe(dir, dir)
}

fn probe(path: &Path, dir: &Path) -> Result<(), OutputError> {
    tempfile::Builder::new()
        .prefix(".springlab-probe.")
        .tempfile_in(dir)
        .map(drop)
        .map_err(|e| output_error(path, os_reason(&e)))
}

/// True when `path` writes to this process's standard output: `-`, or a device or FIFO that is
/// standard output itself (`/dev/stdout` on a pipe or a terminal).
#[must_use]
pub fn is_stdout(path: &Path) -> bool {
    if path.as_os_str() == STDOUT {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        use std::os::unix::fs::MetadataExt;
        let Ok(meta) = fs::metadata(path) else {
            return false;
        };
        if meta.is_file() {
            return false;
        }
        let stdout = io::stdout();
        let Ok(fd) = stdout.as_fd().try_clone_to_owned() else {
            return false;
        };
        File::from(fd)
            .metadata()
            .is_ok_and(|s| s.dev() == meta.dev() && s.ino() == meta.ino())
    }
    #[cfg(not(unix))]
    false
}

/// True when outputs at `a` and `b` would write the same file: the same path, the same existing
/// file under two names (links included), two new files of the same name in one directory, or
/// both standard output.
#[must_use]
pub fn same_target(a: &Path, b: &Path) -> bool {
    identity(a) == identity(b)
}

#[derive(PartialEq, Eq)]
enum Identity {
    Stdout,
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

fn identity(path: &Path) -> Identity {
    if is_stdout(path) {
        return Identity::Stdout;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let Ok(m) = fs::metadata(path) {
            return Identity::Inode(m.dev(), m.ino());
        }
    }
    // Not there yet: its directory (links followed) and its name.
    let dir = fs::canonicalize(parent(path)).unwrap_or_else(|_| parent(path).to_path_buf());
    Identity::Path(dir.join(path.file_name().unwrap_or_default()))
}

/// The OS's reason (`Permission denied (os error 13)`), without the temporary file's path that
/// `tempfile` adds.
fn os_reason(e: &io::Error) -> String {
    match e.raw_os_error() {
        Some(code) => io::Error::from_raw_os_error(code).to_string(),
        None => io::Error::from(e.kind()).to_string(),
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn a_new_file_and_a_regular_file_are_replaced_in_their_directory() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("a.csv");
        assert_eq!(
            target(&path).expect("target"),
            Target::Replace { real: path.clone() }
        );
        write(&path, b"one").expect("write");
        write(&path, b"two").expect("rewrite");
        assert_eq!(fs::read(&path).expect("read"), b"two");
        // Nothing else is left in the directory.
        assert_eq!(fs::read_dir(dir.path()).expect("list").count(), 1);
    }

    #[test]
    fn a_link_to_a_file_is_followed_and_kept() {
        let dir = tempfile::tempdir().expect("temp dir");
        let real = dir.path().join("real.csv");
        fs::write(&real, b"old").expect("write");
        let link = dir.path().join("link.csv");
        std::os::unix::fs::symlink(&real, &link).expect("symlink");
        write(&link, b"new").expect("write through the link");
        assert!(
            fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        assert_eq!(fs::read(&real).expect("read"), b"new");
    }

    #[test]
    fn a_dangling_link_is_refused_and_left() {
        let dir = tempfile::tempdir().expect("temp dir");
        let link = dir.path().join("link.csv");
        std::os::unix::fs::symlink(dir.path().join("nowhere"), &link).expect("symlink");
        let e = check_file(&link).expect_err("refused");
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert!(write(&link, b"x").is_err());
        assert!(
            fs::symlink_metadata(&link)
                .expect("link")
                .file_type()
                .is_symlink()
        );
        assert!(!dir.path().join("nowhere").exists());
    }

    #[test]
    fn outputs_on_one_file_are_the_same_target() {
        let dir = tempfile::tempdir().expect("temp dir");
        let a = dir.path().join("a.gif");
        assert!(same_target(&a, &dir.path().join(".").join("a.gif")));
        assert!(!same_target(&a, &dir.path().join("b.gif")));
        fs::write(&a, b"x").expect("write");
        let link = dir.path().join("l.gif");
        std::os::unix::fs::symlink(&a, &link).expect("symlink");
        assert!(same_target(&a, &link));
        assert!(same_target(Path::new("-"), Path::new("-")));
    }
}
