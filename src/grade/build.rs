//! Building a submission: its `src/` against springlab's own manifest and student API.
//!
//! ```text
//! <target>/springlab-grade/api-<version>/      the student API crate (springlab-homework), as
//!                                               embedded in this binary, written once
//! <target>/springlab-grade/crates/<digest>/    one crate per submission and content:
//!     Cargo.toml     package `homework-<digest>`, lib `homework` = src/lib.rs, bin
//!                    `homework-<digest>` = serve/main.rs, the only dependency the API crate,
//!                    no build script, its own workspace
//!     src/           a copy of the submission's src/ (regular files; symlinks are skipped)
//!     serve/main.rs  fn main() { springlab_homework::serve_<assignment>(homework::Student) }
//! cargo build --release --offline --manifest-path …/Cargo.toml --target-dir <target>
//! ```
//! The digest covers the submission's path, every file's path and contents, the assignment
//! and the API: two submissions (or two versions of one) never share a package name, a
//! fingerprint or an executable, so any number of them can be built one after another, or at
//! once, in one target directory and each runs its own code. The student's `Cargo.toml`,
//! `build.rs`, `tests/` and any dependency they list are not used: nothing but the API crate can
//! be linked into the program, and nothing runs at build time.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use super::Assignment;
use super::homework::API_FILES;

/// At most this many bytes of source are copied from one submission.
const MAX_SOURCE_BYTES: u64 = 8 << 20;
/// At most this many files.
const MAX_SOURCE_FILES: usize = 2000;

/// Where a submission's code is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Submission {
    /// The directory given.
    pub dir: PathBuf,
    /// The directory holding `lib.rs`.
    pub src: PathBuf,
}

/// Finds the code of the submission in `dir`: `dir/src/lib.rs`, `dir/lib.rs`, or the one
/// `dir/*/src/lib.rs` (an upload of a whole crate folder).
///
/// # Errors
/// A sentence saying what was looked for.
pub fn locate(dir: &Path) -> Result<Submission, String> {
    let found = |src: PathBuf| Submission {
        dir: dir.to_path_buf(),
        src,
    };
    if dir.join("src").join("lib.rs").is_file() {
        return Ok(found(dir.join("src")));
    }
    if dir.join("lib.rs").is_file() {
        return Ok(found(dir.to_path_buf()));
    }
    let mut nested: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("cannot read {}: {e}", dir.display()))?
        .filter_map(Result::ok)
        .map(|e| e.path().join("src"))
        .filter(|src| src.join("lib.rs").is_file())
        .collect();
    nested.sort();
    match nested.len() {
        1 => Ok(found(nested.remove(0))),
        0 => Err(format!(
            "no src/lib.rs in {} (nor lib.rs, nor one folder down)",
            dir.display()
        )),
        n => Err(format!(
            "{n} crates in {}: grade them one by one, or as a class folder",
            dir.display()
        )),
    }
}

/// A source tree read into memory: relative paths (with `/`) and contents, sorted.
fn read_tree(src: &Path) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut files = Vec::new();
    let mut total = 0u64;
    let mut stack = vec![(src.to_path_buf(), String::new())];
    while let Some((dir, prefix)) = stack.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        for entry in entries.filter_map(Result::ok) {
            let name = entry.file_name().to_string_lossy().into_owned();
            let relative = if prefix.is_empty() {
                name.clone()
            } else {
                format!("{prefix}/{name}")
            };
            // symlink_metadata: a link is neither followed nor copied.
            let Ok(meta) = std::fs::symlink_metadata(entry.path()) else {
                continue;
            };
            if meta.is_dir() {
                if name != "target" && !name.starts_with('.') {
                    stack.push((entry.path(), relative));
                }
            } else if meta.is_file() {
                total += meta.len();
                if total > MAX_SOURCE_BYTES || files.len() >= MAX_SOURCE_FILES {
                    return Err(format!(
                        "{} holds more than {} MiB or {MAX_SOURCE_FILES} files",
                        src.display(),
                        MAX_SOURCE_BYTES >> 20
                    ));
                }
                let bytes = std::fs::read(entry.path()).map_err(|e| format!("{relative}: {e}"))?;
                files.push((relative, bytes));
            }
        }
    }
    files.sort();
    Ok(files)
}

/// A 128-bit digest, as 32 hex digits, of everything that goes into a build.
fn digest(parts: &[&[u8]]) -> String {
    let mut out = String::new();
    for salt in [0x5350_4c41_u64, 0x4247_5244_u64] {
        let mut h = DefaultHasher::new();
        salt.hash(&mut h);
        for p in parts {
            p.hash(&mut h);
        }
        out.push_str(&format!("{:016x}", h.finish()));
    }
    out
}

/// Writes `contents` to `path` unless it already holds exactly that. The file is written beside
/// and renamed into place, so a build reading it meanwhile sees the old or the new file whole.
fn write_if_changed(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    if std::fs::read(path).is_ok_and(|old| old == contents) {
        return Ok(());
    }
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".{}.partial", std::process::id()));
    std::fs::write(&tmp, contents)?;
    std::fs::rename(&tmp, path)
}

/// One writer of the API crate at a time in this process (`--jobs`).
static API_WRITER: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The API crate's directory under `root`, written from the embedded copy.
fn write_api(root: &Path) -> std::io::Result<PathBuf> {
    let _one = API_WRITER
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = root.join(format!(
        "api-{}",
        &digest(
            &API_FILES
                .iter()
                .flat_map(|(p, c)| [p.as_bytes(), c.as_bytes()])
                .collect::<Vec<_>>()
        )[..12]
    ));
    for (relative, contents) in API_FILES {
        write_if_changed(&dir.join(relative), contents.as_bytes())?;
    }
    Ok(dir)
}

/// A crate ready to build.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The generated crate's directory.
    pub dir: PathBuf,
    /// The name of its executable.
    pub bin: String,
}

/// Writes the crate that builds `submission` as `assignment` under `target/springlab-grade`.
///
/// # Errors
/// A sentence: the source cannot be read or is too large, or a file cannot be written.
pub fn prepare(
    submission: &Submission,
    assignment: Assignment,
    target: &Path,
) -> Result<Prepared, String> {
    let files = read_tree(&submission.src)?;
    let root = target.join("springlab-grade");
    let api = write_api(&root).map_err(|e| format!("cannot write the student API: {e}"))?;
    let canonical = submission
        .src
        .canonicalize()
        .unwrap_or_else(|_| submission.src.clone());
    let mut parts: Vec<&[u8]> = vec![
        canonical.as_os_str().as_encoded_bytes(),
        assignment.name().as_bytes(),
        api.as_os_str().as_encoded_bytes(),
    ];
    for (path, contents) in &files {
        parts.push(path.as_bytes());
        parts.push(contents);
    }
    let id = &digest(&parts)[..20];
    let bin = format!("homework-{id}");
    let dir = root.join("crates").join(&bin);
    let io = |e: std::io::Error| format!("cannot write the build crate {}: {e}", dir.display());
    // A fresh copy: files removed from the submission must not linger.
    if dir.join("src").exists() {
        std::fs::remove_dir_all(dir.join("src")).map_err(io)?;
    }
    for (relative, contents) in &files {
        write_if_changed(&dir.join("src").join(relative), contents).map_err(io)?;
    }
    let api_path = toml::Value::String(api.display().to_string()).to_string();
    let manifest = format!(
        "# Written by `springlab grade` for {}; the submission's own Cargo.toml is not used.\n\
         [package]\nname = \"{bin}\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\
         build = false\nautobins = false\nautoexamples = false\nautotests = false\n\
         autobenches = false\n\n[lib]\nname = \"homework\"\npath = \"src/lib.rs\"\n\n\
         [[bin]]\nname = \"{bin}\"\npath = \"serve/main.rs\"\n\n\
         [dependencies]\nspringlab-homework = {{ path = {api_path} }}\n\n\
         [profile.release]\npanic = \"unwind\"\ndebug = false\nincremental = false\n\n\
         [workspace]\n",
        submission.dir.display()
    );
    write_if_changed(&dir.join("Cargo.toml"), manifest.as_bytes()).map_err(io)?;
    let main = format!(
        "// Written by `springlab grade`: serves the student's homework to the grader.\n\
         fn main() -> std::process::ExitCode {{\n    \
         springlab_homework::serve_{}(homework::Student)\n}}\n",
        assignment.name()
    );
    write_if_changed(&dir.join("serve").join("main.rs"), main.as_bytes()).map_err(io)?;
    Ok(Prepared { dir, bin })
}

/// Why a build gave no program.
#[derive(Debug)]
pub enum BuildFailure {
    /// The compiler refused the code: its messages.
    Compile(String),
    /// The build did not finish in time.
    TimedOut(Duration),
    /// cargo could not be run.
    Cargo(String),
}

/// The last `n` lines of `text`.
pub(crate) fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

/// The compiler's error messages in cargo's stderr: everything from the first line starting with
/// `error`, without cargo's progress lines, at most 80 lines; or the tail when there is none.
fn compiler_errors(stderr: &str) -> String {
    let Some(start) = stderr.lines().position(|l| l.starts_with("error")) else {
        return tail(stderr, 30);
    };
    let progress = [
        "Compiling ",
        "Checking ",
        "Building ",
        "Finished ",
        "Downloaded ",
        "Locking ",
        "Blocking ",
    ];
    stderr
        .lines()
        .skip(start)
        .filter(|l| !progress.iter().any(|p| l.trim_start().starts_with(p)))
        .take(80)
        .collect::<Vec<_>>()
        .join("\n")
}

/// The executable named `bin` in cargo's JSON messages.
fn executable(stdout: &str, bin: &str) -> Option<PathBuf> {
    stdout
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|v| v.get("reason").and_then(|r| r.as_str()) == Some("compiler-artifact"))
        .filter(|v| {
            v.get("target")
                .and_then(|t| t.get("name"))
                .and_then(|n| n.as_str())
                == Some(bin)
        })
        .find_map(|v| {
            v.get("executable")
                .and_then(|e| e.as_str())
                .map(PathBuf::from)
        })
}

/// Builds `prepared` in `target` with a wall-clock `limit`; returns the executable.
///
/// # Errors
/// [`BuildFailure`].
pub fn build(prepared: &Prepared, target: &Path, limit: Duration) -> Result<PathBuf, BuildFailure> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut command = Command::new(cargo);
    command
        .args(["build", "--release", "--offline", "--manifest-path"])
        .arg(prepared.dir.join("Cargo.toml"))
        .arg("--target-dir")
        .arg(target)
        .arg("--message-format=json-render-diagnostics")
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("CARGO_BUILD_TARGET_DIR")
        .current_dir(&prepared.dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = command
        .spawn()
        .map_err(|e| BuildFailure::Cargo(format!("cannot run cargo: {e}")))?;
    let reader = |pipe: Option<Box<dyn Read + Send>>| {
        thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_end(&mut bytes);
            }
            String::from_utf8_lossy(&bytes).into_owned()
        })
    };
    let out = reader(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = reader(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(BuildFailure::TimedOut(limit));
            }
            Ok(None) => thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(BuildFailure::Cargo(e.to_string())),
        }
    };
    let stdout = out.join().unwrap_or_default();
    let stderr = err.join().unwrap_or_default();
    match executable(&stdout, &prepared.bin) {
        Some(exe) if status.success() => Ok(exe),
        _ => Err(BuildFailure::Compile(compiler_errors(&stderr))),
    }
}

/// The default target directory of `springlab grade`: `$CARGO_TARGET_DIR`, else
/// `$XDG_CACHE_HOME/springlab/grade`, else `$HOME/.cache/springlab/grade`, else one under the
/// system's temporary directory.
#[must_use]
pub fn default_target_dir() -> PathBuf {
    let env = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    if let Some(dir) = env("CARGO_TARGET_DIR") {
        return dir;
    }
    if let Some(dir) = env("XDG_CACHE_HOME") {
        return dir.join("springlab").join("grade");
    }
    if let Some(dir) = env("HOME") {
        return dir.join(".cache").join("springlab").join("grade");
    }
    std::env::temp_dir().join("springlab-grade")
}
