//! Building a submission: its `src/` against the student API, with rustc, in the sandbox.
//!
//! ```text
//! <target>/springlab-grade/                      the grader's cache (root's, read by no sandbox)
//!     api-<digest>/libspringlab_homework.rlib    the student API, compiled once per API and rustc
//!     programs/<digest>                          every program built, by content
//! <scratch>/  (springlab-grade-<pid>-<random> in the temporary directory, removed at the end;
//!              a killed grader's is removed by the next grader: `stale.rs`)
//!     toolchain/     the rustc sysroot, hard links, when the sandbox user cannot reach the real one
//!     api/           the compiled API (read-only for the sandbox)
//!     sub-<n>/crate/src/        a copy of submission n's src/ (regular files only), the grader's
//!     sub-<n>/crate/serve/main.rs   fn main() { springlab_homework::serve_<assignment>(homework::Student) }
//!     sub-<n>/out/   the build's only writable folder (the sandbox user's)
//!     sub-<n>/program           the program, copied out of out/ by the grader
//!     sub-<n>/work-<k>/         the working directory of the program's k-th start
//! rustc --crate-type rlib --crate-name homework src/lib.rs --extern springlab_homework=…  (sandbox)
//! rustc --crate-type bin serve/main.rs --extern homework=out/libhomework.rlib …         (sandbox)
//! ```
//! No cargo: no `Cargo.toml`, `build.rs`, `.cargo/config.toml`, dependency or environment
//! variable of the student's is read, and nothing runs at build time; each build writes only
//! its own `out/`. The digest covers the assignment, the API, the compiler's version and every
//! file's path and contents: the same code is built once and every later grade of it reuses the
//! program.

mod rustc;
mod source;
mod stale;
mod toolchain;

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

use super::Assignment;
use super::homework::API_FILES;
use super::sandbox::{Sandbox, reachable_by};
use rustc::common_args;
pub use source::{Submission, locate, read_regular};
use source::{digest, read_tree};
pub use toolchain::Toolchain;
use toolchain::{chown, set_mode};

/// Limits of one build (both rustc runs together).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildLimits {
    /// Wall-clock time.
    pub wall: Duration,
    /// CPU seconds of each rustc run.
    pub cpu_seconds: u64,
    /// Address space of rustc (bytes).
    pub memory_bytes: u64,
    /// Compiler output kept (bytes).
    pub output_bytes: usize,
}

impl Default for BuildLimits {
    /// One minute of wall clock and of CPU, 3 GiB of address space, 64 KiB of compiler output.
    fn default() -> BuildLimits {
        BuildLimits {
            wall: Duration::from_secs(60),
            cpu_seconds: 60,
            memory_bytes: 3 << 30,
            output_bytes: 64 << 10,
        }
    }
}

/// Why a build gave no program.
#[derive(Debug)]
pub enum BuildFailure {
    /// The compiler refused the code: its messages.
    Compile(String),
    /// The build did not finish in time.
    TimedOut(Duration),
    /// A limit of the build was reached: which, in words.
    Limit(String),
    /// The grader could not build (its folders, its toolchain): not the student's doing.
    Grader(String),
}

/// The last `n` lines of `text`.
pub(crate) fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

/// The grader's folders for one run, and the sandbox its builds run in (module docs).
pub struct Builder {
    /// The sandbox.
    pub sandbox: Arc<Sandbox>,
    /// Build limits.
    pub limits: BuildLimits,
    scratch: PathBuf,
    cache: PathBuf,
    toolchain: OnceLock<Result<Toolchain, String>>,
    api: Mutex<Option<PathBuf>>,
    next: AtomicU64,
}

impl std::fmt::Debug for Builder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Builder")
            .field("scratch", &self.scratch)
            .field("cache", &self.cache)
            .finish_non_exhaustive()
    }
}

impl Drop for Builder {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.scratch);
    }
}

/// A submission copied into the scratch space, not built yet.
#[derive(Clone, Debug)]
pub struct Staged {
    /// Its folder in the scratch space.
    pub dir: PathBuf,
    /// The digest of what goes into its build.
    id: String,
}

impl Staged {
    /// The seed of this submission's cases under `seed_per_submission`
    /// ([`super::external::ExternalOptions`]): a digest of `seed` and everything that goes
    /// into the build, so the same code gets the same cases under the same `seed`.
    #[must_use]
    pub fn seed(&self, seed: u64) -> u64 {
        let d = digest(&[&seed.to_le_bytes(), self.id.as_bytes()]);
        u64::from_str_radix(&d[..16], 16).unwrap_or(seed)
    }
}

/// A built submission: the program and its folder in the scratch space.
#[derive(Clone, Debug)]
pub struct Built {
    /// The program.
    pub exe: PathBuf,
    /// The submission's folder (working directories go beneath it).
    pub dir: PathBuf,
    /// True when the program came from the cache.
    pub cached: bool,
}

impl Builder {
    /// The cache under `target/springlab-grade` and a new scratch folder.
    ///
    /// # Errors
    /// A sentence for the grader: a folder that cannot be made (an unwritable `--target-dir`).
    pub fn new(
        target: &Path,
        sandbox: Arc<Sandbox>,
        limits: BuildLimits,
    ) -> Result<Builder, String> {
        let cache = target.join("springlab-grade");
        std::fs::create_dir_all(cache.join("programs")).map_err(|e| {
            format!(
                "cannot make the build cache {}: {e} (choose another --target-dir)",
                cache.display()
            )
        })?;
        let probe = cache.join(format!(".probe-{}", std::process::id()));
        std::fs::write(&probe, b"").map_err(|e| {
            format!(
                "cannot write in the build cache {}: {e} (choose another --target-dir)",
                cache.display()
            )
        })?;
        let _ = std::fs::remove_file(&probe);
        let tag: String = super::token::random_tag();
        let temp = std::env::temp_dir();
        let scratch = temp.join(format!("{}{}-{tag}", stale::PREFIX, std::process::id()));
        std::fs::create_dir(&scratch)
            .and_then(|()| set_mode(&scratch, 0o711))
            .map_err(|e| format!("cannot make the scratch folder {}: {e}", scratch.display()))?;
        // What killed graders left behind (their copies of sources and toolchain) goes first.
        if let Ok(meta) = std::fs::metadata(&scratch) {
            stale::sweep(&temp, std::os::unix::fs::MetadataExt::uid(&meta));
        }
        if let Some(uid) = sandbox.uid(0)
            && !reachable_by(&scratch, uid, 0)
        {
            let _ = std::fs::remove_dir(&scratch);
            return Err(format!(
                "the sandbox user {uid} cannot reach {} (a folder above it is closed); set \
                 TMPDIR to a folder others can enter",
                scratch.display()
            ));
        }
        Ok(Builder {
            sandbox,
            limits,
            scratch,
            cache,
            toolchain: OnceLock::new(),
            api: Mutex::new(None),
            next: AtomicU64::new(0),
        })
    }

    /// Removes the scratch folder (also done when the builder is dropped; a check thread that
    /// outlived its deadline may still hold it).
    pub fn finish(&self) {
        let _ = std::fs::remove_dir_all(&self.scratch);
    }

    /// The scratch folder of this run.
    #[must_use]
    pub fn scratch(&self) -> &Path {
        &self.scratch
    }

    fn owner(&self, slot: u32) -> Option<(u32, u32)> {
        self.sandbox.uid(slot).map(|u| (u, self.sandbox_gid()))
    }

    fn sandbox_gid(&self) -> u32 {
        self.sandbox.gid()
    }

    /// The toolchain (found once per run).
    ///
    /// # Errors
    /// [`Toolchain::find`]'s sentence.
    pub fn toolchain(&self) -> Result<&Toolchain, String> {
        self.toolchain
            .get_or_init(|| Toolchain::find(&self.scratch, self.owner(0)))
            .as_ref()
            .map_err(Clone::clone)
    }

    fn api_digest(&self, toolchain: &Toolchain) -> String {
        let mut parts: Vec<&[u8]> = vec![toolchain.version.as_bytes()];
        for (p, c) in API_FILES {
            parts.push(p.as_bytes());
            parts.push(c.as_bytes());
        }
        digest(&parts)[..16].to_string()
    }

    /// A new folder in the scratch space: the grader's (0755), or the sandbox user's (0700).
    fn folder(&self, path: &Path, owner: Option<(u32, u32)>) -> Result<(), BuildFailure> {
        let io = |e: std::io::Error| {
            BuildFailure::Grader(format!("cannot make {}: {e}", path.display()))
        };
        std::fs::create_dir_all(path).map_err(io)?;
        if owner.is_some() {
            chown(path, owner).map_err(io)?;
            set_mode(path, 0o700).map_err(io)?;
        } else {
            set_mode(path, 0o755).map_err(io)?;
        }
        Ok(())
    }

    /// A folder for a program's working directory under `dir`, the sandbox user's.
    ///
    /// # Errors
    /// When it cannot be made.
    pub fn workdir(&self, dir: &Path, slot: u32) -> std::io::Result<PathBuf> {
        let n = self.next.fetch_add(1, Ordering::Relaxed);
        let work = dir.join(format!("work-{n}"));
        std::fs::create_dir(&work)?;
        chown(&work, self.owner(slot))?;
        set_mode(&work, 0o700)?;
        Ok(work)
    }

    /// The compiled API in the scratch space (compiled in the sandbox once per API and rustc,
    /// then kept in the cache).
    fn api(&self, toolchain: &Toolchain) -> Result<PathBuf, BuildFailure> {
        let mut guard = self
            .api
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(dir) = guard.as_ref() {
            return Ok(dir.clone());
        }
        let grader = |e: std::io::Error| BuildFailure::Grader(format!("the student API: {e}"));
        let name = "libspringlab_homework.rlib";
        let cached = self
            .cache
            .join(format!("api-{}", self.api_digest(toolchain)))
            .join(name);
        let dir = self.scratch.join("api");
        self.folder(&dir, None)?;
        if !cached.is_file() {
            let src = self.scratch.join("api-src");
            self.folder(&src, None)?;
            for (relative, contents) in API_FILES {
                let path = src.join(relative);
                if let Some(parent) = path.parent() {
                    self.folder(parent, None)?;
                }
                std::fs::write(&path, contents).map_err(grader)?;
            }
            let out = self.scratch.join("api-out");
            self.folder(&out, self.owner(0))?;
            let mut args = common_args();
            args.extend(
                [
                    "--crate-type",
                    "rlib",
                    "--crate-name",
                    "springlab_homework",
                    "-o",
                ]
                .map(OsString::from),
            );
            args.push(out.join(name).into_os_string());
            args.push("src/lib.rs".into());
            let deadline = Instant::now() + self.limits.wall.max(Duration::from_secs(120));
            match self.rustc(toolchain, args, &src, vec![src.clone()], &out, 0, deadline) {
                Ok(()) => {}
                Err(BuildFailure::Compile(e) | BuildFailure::Limit(e)) => {
                    return Err(BuildFailure::Grader(format!(
                        "this rustc cannot build the student API ({}): {e}",
                        toolchain.version.lines().next().unwrap_or_default()
                    )));
                }
                Err(other) => return Err(other),
            }
            copy_in(&out.join(name), &cached).map_err(grader)?;
        }
        copy_in(&cached, &dir.join(name)).map_err(grader)?;
        *guard = Some(dir.clone());
        Ok(dir)
    }

    /// Copies `submission` into a new folder of the scratch space (the grader's; done for every
    /// submission of a run before any student code runs) and names its build by content.
    ///
    /// # Errors
    /// [`BuildFailure::Compile`] when the source cannot be read or is too large (the student's),
    /// [`BuildFailure::Grader`] when the toolchain or the scratch space fails.
    pub fn stage(
        &self,
        submission: &Submission,
        assignment: Assignment,
    ) -> Result<Staged, BuildFailure> {
        let files = read_tree(&submission.src).map_err(BuildFailure::Compile)?;
        let toolchain = self.toolchain().map_err(BuildFailure::Grader)?;
        let mut parts: Vec<&[u8]> =
            vec![assignment.name().as_bytes(), toolchain.version.as_bytes()];
        let api_digest = self.api_digest(toolchain);
        parts.push(api_digest.as_bytes());
        for (path, contents) in &files {
            parts.push(path.as_bytes());
            parts.push(contents);
        }
        let id = digest(&parts);
        let n = self.next.fetch_add(1, Ordering::Relaxed);
        let dir = self.scratch.join(format!("sub-{n}"));
        let krate = dir.join("crate");
        self.folder(&dir, None)?;
        let grader = |e: std::io::Error| {
            BuildFailure::Grader(format!(
                "cannot copy the submission into {}: {e}",
                dir.display()
            ))
        };
        for (relative, contents) in &files {
            let path = krate.join("src").join(relative);
            if let Some(parent) = path.parent() {
                self.folder(parent, None)?;
            }
            std::fs::write(&path, contents).map_err(grader)?;
        }
        self.folder(&krate.join("serve"), None)?;
        let main = format!(
            "// Written by `springlab grade`: serves the student's homework to the grader.\n\
             fn main() -> std::process::ExitCode {{\n    \
             springlab_homework::serve_{}(homework::Student)\n}}\n",
            assignment.name()
        );
        std::fs::write(krate.join("serve").join("main.rs"), main).map_err(grader)?;
        Ok(Staged { dir, id })
    }

    /// Builds a staged submission in job `slot`'s sandbox (module docs).
    ///
    /// # Errors
    /// [`BuildFailure`]: the student's ([`BuildFailure::Compile`], time-out, limits) or the
    /// grader's.
    pub fn build(&self, staged: &Staged, slot: u32) -> Result<Built, BuildFailure> {
        let start = Instant::now();
        let toolchain = self.toolchain().map_err(BuildFailure::Grader)?;
        let api = self.api(toolchain)?;
        let dir = staged.dir.clone();
        let id = &staged.id;
        let krate = dir.join("crate");
        let grader = |e: std::io::Error| {
            BuildFailure::Grader(format!(
                "cannot write the program into {}: {e}",
                dir.display()
            ))
        };
        let exe = dir.join("program");
        let cached = self.cache.join("programs").join(id);
        if cached.is_file() {
            copy_in(&cached, &exe).map_err(grader)?;
            return Ok(Built {
                exe,
                dir,
                cached: true,
            });
        }
        let out = dir.join("out");
        self.folder(&out, self.owner(slot))?;
        let deadline = start + self.limits.wall;
        let extern_api = {
            let mut s = OsString::from("springlab_homework=");
            s.push(api.join("libspringlab_homework.rlib"));
            s
        };
        let mut dependency = OsString::from("dependency=");
        dependency.push(&api);
        let read = vec![api.clone(), krate.clone()];
        let mut lib = common_args();
        lib.extend(["--crate-type", "rlib", "--crate-name", "homework"].map(OsString::from));
        lib.extend([
            "--extern".into(),
            extern_api.clone(),
            "-L".into(),
            dependency.clone(),
        ]);
        lib.push("-o".into());
        lib.push(out.join("libhomework.rlib").into_os_string());
        lib.push("src/lib.rs".into());
        self.rustc(toolchain, lib, &krate, read.clone(), &out, slot, deadline)?;
        let mut bin = common_args();
        bin.extend(["--crate-type", "bin", "--crate-name", "serve"].map(OsString::from));
        let mut extern_lib = OsString::from("homework=");
        extern_lib.push(out.join("libhomework.rlib"));
        bin.extend(["--extern".into(), extern_api, "--extern".into(), extern_lib]);
        bin.extend(["-L".into(), dependency]);
        bin.push("-o".into());
        bin.push(out.join("program").into_os_string());
        bin.push("serve/main.rs".into());
        self.rustc(toolchain, bin, &krate, read, &out, slot, deadline)?;
        // The build's processes are gone (sweep in rustc()); the program is copied out of the
        // sandbox user's folder into the grader's.
        let built = out.join("program");
        let meta = std::fs::symlink_metadata(&built).map_err(|e| {
            BuildFailure::Grader(format!("rustc reported success but left no program: {e}"))
        })?;
        if !meta.is_file() {
            return Err(BuildFailure::Grader(
                "the built program is not a file".into(),
            ));
        }
        copy_in(&built, &exe).map_err(grader)?;
        let _ = copy_in(&exe, &cached);
        let _ = std::fs::remove_dir_all(&out);
        Ok(Built {
            exe,
            dir,
            cached: false,
        })
    }
}

/// Copies `from` to `to` (the grader's, 0755) through a temporary file beside it, created
/// exclusively and renamed: a reader sees the old file or the new one, whole.
fn copy_in(from: &Path, to: &Path) -> std::io::Result<()> {
    use std::os::unix::fs::OpenOptionsExt;
    if let Some(parent) = to.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let tmp = to.with_extension(format!("tmp-{}", super::token::random_tag()));
    let _no_fork = super::sandbox::writing_executable();
    let mut src = std::fs::File::open(from)?;
    let mut dst = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o755)
        .custom_flags(nix::libc::O_NOFOLLOW)
        .open(&tmp)?;
    std::io::copy(&mut src, &mut dst)?;
    drop(dst);
    std::fs::rename(&tmp, to).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
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
