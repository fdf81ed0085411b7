//! The sandbox every build and every student program runs in.
//!
//! ```text
//! grader ─fork─▶ A  (own process group; with namespaces: unshare(pid, net, mount, ipc, uts
//!                    [, user when not root]); waits and ends as B's program ended; kills B
//!                    as soon as the grader process ends (a pidfd of it, polled))
//!                └─fork─▶ B  pid 1 of the new PID namespace (dies with A: PDEATHSIG); mounts a
//!                         fresh /proc (hidepid=invisible); reaps; when the program ends it
//!                         exits, and the kernel kills every process left in the namespace
//!                         └─fork─▶ C  rlimits, setgroups/setgid/setuid to the sandbox user,
//!                                  no_new_privs, Landlock, seccomp, exec (empty environment)
//! ```
//! Without namespaces (a container that forbids `unshare`) A and B are left out and C is the
//! grader's direct child; what it started is then found by its user: [`Sandbox::sweep`] kills
//! every process of the sandbox user (`kill(-1)` sent by a process of that user) and waits until
//! none is left.
//!
//! The layers and what each stops are in `docs/grading.md`; [`Sandbox::layers`] says which are
//! active on this machine and why any is missing (`springlab grade --sandbox-report`).
//! Everything the child does between `fork` and `exec` is a system call on data prepared
//! before the fork (no allocation, no lock): the Landlock ruleset and the seccomp program are
//! built in the grader.

#![allow(unsafe_code)]

mod child;
mod landlock;
mod reap;
pub(crate) use reap::reap;
mod report;
mod seccomp;

use std::ffi::OsString;
use std::io;
use std::os::fd::{AsRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use nix::libc;

use child::{confine, enter_namespaces};

/// The sandbox user when none is given: `nobody`.
pub const DEFAULT_UID: u32 = 65534;
/// The sandbox group when none is given: `nogroup`.
pub const DEFAULT_GID: u32 = 65534;
/// Names layers to leave out, comma-separated (`user,namespaces,landlock,seccomp`): for trying
/// what the others hold alone, as in a container that forbids one.
pub const DISABLE_ENV: &str = "SPRINGLAB_SANDBOX_DISABLE";

/// What the grader asks of the sandbox.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Config {
    /// The user id builds and programs run as (when springlab runs as root); the job `k` of
    /// `--jobs` uses `uid + k`.
    pub uid: u32,
    /// Their group id.
    pub gid: u32,
    /// Layers left out on purpose.
    pub disabled: Vec<Layer>,
}

impl Default for Config {
    /// nobody/nogroup, and the layers named in `SPRINGLAB_SANDBOX_DISABLE` left out.
    fn default() -> Config {
        let disabled = std::env::var(DISABLE_ENV)
            .unwrap_or_default()
            .split(',')
            .filter_map(|w| Layer::ALL.into_iter().find(|l| l.name() == w.trim()))
            .collect();
        Config {
            uid: DEFAULT_UID,
            gid: DEFAULT_GID,
            disabled,
        }
    }
}

/// One layer of the sandbox.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layer {
    /// Another user id and group, no supplementary groups, no_new_privs.
    User,
    /// PID, network, mount, IPC and UTS namespaces.
    Namespaces,
    /// Landlock: files, TCP, signals.
    Landlock,
    /// The seccomp filter.
    Seccomp,
    /// Resource limits (always on).
    Limits,
}

impl Layer {
    /// Every layer, in the order of the report.
    pub const ALL: [Layer; 5] = [
        Layer::User,
        Layer::Namespaces,
        Layer::Landlock,
        Layer::Seccomp,
        Layer::Limits,
    ];

    /// Its name in reports and in `SPRINGLAB_SANDBOX_DISABLE`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Layer::User => "user",
            Layer::Namespaces => "namespaces",
            Layer::Landlock => "landlock",
            Layer::Seccomp => "seccomp",
            Layer::Limits => "limits",
        }
    }
}

/// Whether a layer is active, and what it is or why it is missing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayerState {
    /// The layer.
    pub layer: Layer,
    /// Active on this machine.
    pub active: bool,
    /// What it does here, or why it is missing.
    pub detail: String,
}

/// Resource limits of one sandboxed process tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rlimits {
    /// Address space (bytes).
    pub address_space: u64,
    /// CPU seconds.
    pub cpu_seconds: u64,
    /// Largest file written (bytes).
    pub file_bytes: u64,
    /// Open files.
    pub open_files: u64,
    /// Processes and threads of the sandbox user (binding only when it is not root).
    pub processes: u64,
}

/// One program to run in the sandbox.
#[derive(Clone, Debug)]
pub struct Launch {
    /// The executable (an absolute path).
    pub program: PathBuf,
    /// Its arguments.
    pub args: Vec<OsString>,
    /// Its whole environment.
    pub env: Vec<(OsString, OsString)>,
    /// Its working directory.
    pub cwd: PathBuf,
    /// Paths it may read and execute beneath (besides the system's libraries).
    pub read: Vec<PathBuf>,
    /// Paths it may write beneath.
    pub write: Vec<PathBuf>,
    /// Its limits.
    pub limits: Rlimits,
    /// The job slot (`--jobs`): the user id is the sandbox's plus this.
    pub slot: u32,
}

/// The system's libraries and tools a program or the linker needs to read and run.
const SYSTEM_READ: &[&str] = &[
    "/usr",
    "/lib",
    "/lib64",
    "/lib32",
    "/bin",
    "/sbin",
    "/etc/ld.so.cache",
    "/etc/ld.so.conf",
    "/etc/ld.so.conf.d",
    "/dev/urandom",
    "/dev/zero",
];
const DEVICES: &[&str] = &["/dev/null"];

const NS_FLAGS: libc::c_int = libc::CLONE_NEWPID
    | libc::CLONE_NEWNET
    | libc::CLONE_NEWNS
    | libc::CLONE_NEWIPC
    | libc::CLONE_NEWUTS;

/// The sandbox of this machine: the layers found at start.
#[derive(Debug)]
pub struct Sandbox {
    config: Config,
    root: bool,
    user: Result<(), String>,
    namespaces: Result<libc::c_int, String>,
    landlock: Result<i32, String>,
    seccomp: Result<Vec<libc::sock_filter>, String>,
}

fn os_error(what: &str, e: i32) -> String {
    format!("{what}: {}", io::Error::from_raw_os_error(e))
}

/// Runs `probe` in a forked child and returns its exit code (0: it worked).
fn probe(probe: impl FnOnce() -> i32) -> i32 {
    // SAFETY: the child runs only system calls (the probes below) and _exit.
    let pid = unsafe { libc::fork() };
    if pid < 0 {
        return libc::EAGAIN;
    }
    if pid == 0 {
        let code = probe();
        // SAFETY: ends the forked child without running the parent's destructors.
        unsafe { libc::_exit(code) };
    }
    let mut status = 0;
    // SAFETY: waits for our own child.
    while unsafe { libc::waitpid(pid, &raw mut status, 0) } < 0 {
        if io::Error::last_os_error().raw_os_error() != Some(libc::EINTR) {
            return libc::ECHILD;
        }
    }
    if libc::WIFEXITED(status) {
        libc::WEXITSTATUS(status)
    } else {
        libc::EPERM
    }
}

fn errno() -> i32 {
    io::Error::last_os_error()
        .raw_os_error()
        .unwrap_or(libc::EPERM)
}

impl Sandbox {
    /// Finds which layers this machine allows (a few forked probes, milliseconds).
    #[must_use]
    pub fn detect(config: &Config) -> Sandbox {
        let off = |l: Layer| config.disabled.contains(&l);
        let off_reason = |l: Layer| format!("left out ({DISABLE_ENV} names {})", l.name());
        // SAFETY: geteuid cannot fail.
        let root = unsafe { libc::geteuid() } == 0;
        let user = if off(Layer::User) {
            Err(off_reason(Layer::User))
        } else if !root {
            Err("springlab is not running as root, so it cannot switch to another user".into())
        } else if config.uid == 0 {
            Err("--sandbox-uid 0 keeps builds and programs as root".into())
        } else {
            Ok(())
        };
        let namespaces = if off(Layer::Namespaces) {
            Err(off_reason(Layer::Namespaces))
        } else {
            let flags = NS_FLAGS | if root { 0 } else { libc::CLONE_NEWUSER };
            match probe(|| {
                // SAFETY: unshare in the forked probe only.
                if unsafe { libc::unshare(flags) } == 0 {
                    0
                } else {
                    errno()
                }
            }) {
                0 => Ok(flags),
                e => Err(os_error(
                    "unshare(pid, net, mount, ipc, uts) is refused (a container's default \
                     seccomp profile does this)",
                    e,
                )),
            }
        };
        let landlock = if off(Layer::Landlock) {
            Err(off_reason(Layer::Landlock))
        } else {
            landlock::abi()
        };
        let seccomp = if off(Layer::Seccomp) {
            Err(off_reason(Layer::Seccomp))
        } else {
            match seccomp::filter() {
                None => Err("no filter is written for this architecture".into()),
                Some(filter) => {
                    let probe_filter = filter.clone();
                    match probe(|| {
                        // SAFETY: prctl in the forked probe only.
                        if unsafe { libc::prctl(libc::PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) } != 0 {
                            return errno();
                        }
                        if seccomp::install(&probe_filter) {
                            0
                        } else {
                            errno()
                        }
                    }) {
                        0 => Ok(filter),
                        e => Err(os_error("the kernel refused the filter", e)),
                    }
                }
            }
        };
        Sandbox {
            config: config.clone(),
            root,
            user,
            namespaces,
            landlock,
            seccomp,
        }
    }

    /// The user id of job `slot`, when builds and programs run as another user.
    #[must_use]
    pub fn uid(&self, slot: u32) -> Option<u32> {
        self.user.is_ok().then(|| self.config.uid + slot)
    }

    /// True when a PID namespace holds every process of a launch.
    #[must_use]
    pub fn has_pid_namespace(&self) -> bool {
        self.namespaces.is_ok()
    }

    /// Starts `launch` in the sandbox with the given standard streams.
    ///
    /// # Errors
    /// When the Landlock ruleset cannot be built or the program cannot be started.
    pub fn spawn(
        &self,
        launch: &Launch,
        stdin: Stdio,
        stdout: Stdio,
        stderr: Stdio,
    ) -> io::Result<Child> {
        use std::os::unix::process::CommandExt;
        let mut command = Command::new(&launch.program);
        command
            .args(&launch.args)
            .env_clear()
            .envs(launch.env.iter().map(|(k, v)| (k, v)))
            .current_dir(&launch.cwd)
            .stdin(stdin)
            .stdout(stdout)
            .stderr(stderr)
            .process_group(0);
        let uid = self.uid(launch.slot);
        let gid = self.config.gid;
        let ns = self.namespaces.as_ref().ok().copied().unwrap_or(0);
        let userns = ns & libc::CLONE_NEWUSER != 0;
        // SAFETY: getuid/getgid cannot fail.
        let (my_uid, my_gid) = unsafe { (libc::getuid(), libc::getgid()) };
        let uid_map = format!("{my_uid} {my_uid} 1");
        let gid_map = format!("{my_gid} {my_gid} 1");
        // /proc (a fresh one, of the sandbox's processes only) when another user is active;
        // without namespaces or as one's own user, no /proc at all.
        let proc_rule = ns != 0 && uid.is_some();
        let ruleset: Option<OwnedFd> = match &self.landlock {
            Ok(abi) => {
                let mut read: Vec<&Path> = SYSTEM_READ.iter().map(Path::new).collect();
                read.extend(launch.read.iter().map(PathBuf::as_path));
                read.push(&launch.program);
                let write: Vec<&Path> = launch.write.iter().map(PathBuf::as_path).collect();
                let devices: Vec<&Path> = DEVICES.iter().map(Path::new).collect();
                Some(landlock::ruleset(*abi, &read, &write, &devices)?)
            }
            Err(_) => None,
        };
        let filter = self.seccomp.as_ref().ok().cloned();
        let limits = launch.limits;
        let grader = libc::pid_t::try_from(std::process::id()).unwrap_or(-1);
        let pre_exec = move || -> io::Result<()> {
            let ruleset_fd = ruleset.as_ref().map_or(-1, AsRawFd::as_raw_fd);
            if ns != 0 {
                // SAFETY: system calls on data prepared before the fork (module docs).
                unsafe {
                    enter_namespaces(
                        grader, ns, userns, &uid_map, &gid_map, proc_rule, ruleset_fd,
                    )?
                };
            }
            // SAFETY: as above.
            unsafe { confine(uid, gid, limits, ruleset_fd, filter.as_deref()) }
        };
        // SAFETY: the closure makes only system calls (no allocation, no lock).
        unsafe {
            command.pre_exec(pre_exec);
        }
        // No executable is open for writing in this process while a child is between fork and
        // exec (it would inherit the descriptor and the exec of that file would fail with
        // ETXTBSY): see [`writing_executable`]. spawn returns once the program has been exec'd.
        // A child forked by code that does not take this lock (a `Command` elsewhere in the
        // process: a test harness's, a library's) may still hold such a descriptor until its
        // own exec; the exec then fails with ETXTBSY for that moment only, so it is tried again
        // (at most `ETXTBSY_TRIES` times, 10, 20, … ms apart).
        let mut tries = 1;
        loop {
            let spawned = {
                let _forking = FORKS
                    .read()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                command.spawn()
            };
            match spawned {
                Err(e) if e.raw_os_error() == Some(libc::ETXTBSY) && tries < ETXTBSY_TRIES => {
                    std::thread::sleep(Duration::from_millis(10 * u64::from(tries)));
                    tries += 1;
                }
                other => return other,
            }
        }
    }

    /// Without a PID namespace: kills every process of job `slot`'s user and waits (up to 5 s)
    /// until none is left. Returns how many were found. Without another user: nothing to find.
    pub fn sweep(&self, slot: u32) -> usize {
        if self.has_pid_namespace() {
            return 0;
        }
        self.sweep_uid(slot)
    }

    /// Kills every process of job `slot`'s user (namespaces or not); returns how many were
    /// found.
    pub fn sweep_uid(&self, slot: u32) -> usize {
        let Some(uid) = self.uid(slot) else { return 0 };
        let gid = self.config.gid;
        let found = processes_of(uid).len();
        let start = Instant::now();
        while !processes_of(uid).is_empty() && start.elapsed() < Duration::from_secs(5) {
            probe(|| {
                // SAFETY: in the forked child: become the sandbox user, then signal every
                // process it may signal (all of that user but itself).
                unsafe {
                    if libc::setgroups(0, std::ptr::null()) != 0
                        || libc::setresgid(gid, gid, gid) != 0
                        || libc::setresuid(uid, uid, uid) != 0
                    {
                        return 1;
                    }
                    libc::kill(-1, libc::SIGKILL);
                }
                0
            });
            std::thread::sleep(Duration::from_millis(5));
        }
        found
    }

    /// The sandbox group id.
    #[must_use]
    pub fn gid(&self) -> u32 {
        self.config.gid
    }

    /// True when springlab runs as root.
    #[must_use]
    pub fn is_root(&self) -> bool {
        self.root
    }
}

static FORKS: std::sync::RwLock<()> = std::sync::RwLock::new(());

/// How many times [`Sandbox::spawn`] tries an exec that failed with ETXTBSY.
const ETXTBSY_TRIES: u32 = 8;

/// Held while this process has an executable open for writing (copying a program): no sandbox
/// child is forked meanwhile.
pub(crate) fn writing_executable() -> std::sync::RwLockWriteGuard<'static, ()> {
    FORKS
        .write()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The processes (pids) whose real user id is `uid`, from `/proc`.
#[must_use]
pub fn processes_of(uid: u32) -> Vec<u32> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .filter_map(Result::ok)
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            std::fs::read_to_string(format!("/proc/{pid}/status"))
                .ok()
                .and_then(|s| {
                    s.lines()
                        .find(|l| l.starts_with("Uid:"))
                        .and_then(|l| l.split_whitespace().nth(1)?.parse::<u32>().ok())
                })
                == Some(uid)
        })
        .collect()
}

/// True when every directory above and including `path` can be searched by `uid`/`gid`
/// (another user reading a file there).
#[must_use]
pub fn reachable_by(path: &Path, uid: u32, gid: u32) -> bool {
    use std::os::unix::fs::MetadataExt;
    let mut p = Some(path);
    while let Some(dir) = p {
        let Ok(m) = std::fs::metadata(dir) else {
            return false;
        };
        if m.is_dir() {
            let mode = m.mode();
            let ok = if m.uid() == uid {
                mode & 0o100 != 0
            } else if m.gid() == gid {
                mode & 0o010 != 0
            } else {
                mode & 0o001 != 0
            };
            if !ok {
                return false;
            }
        }
        p = dir.parent();
    }
    true
}

#[cfg(test)]
mod tests {
    use super::{Config, Launch, Layer, Rlimits, Sandbox, libc};
    use std::io::Write;
    use std::os::unix::fs::PermissionsExt;
    use std::process::Stdio;
    use std::time::Duration;

    /// A script in a folder of its own, and a launch of it with every layer left out (what is
    /// tested is the exec, not the confinement).
    fn script() -> (tempfile::TempDir, Launch, Sandbox) {
        let dir = tempfile::tempdir().expect("tempdir");
        let program = dir.path().join("prog.sh");
        std::fs::write(&program, "#!/bin/sh\nexit 7\n").expect("write script");
        std::fs::set_permissions(&program, std::fs::Permissions::from_mode(0o755)).expect("chmod");
        let launch = Launch {
            program,
            args: Vec::new(),
            env: Vec::new(),
            cwd: dir.path().to_path_buf(),
            read: Vec::new(),
            write: Vec::new(),
            limits: Rlimits {
                address_space: 1 << 32,
                cpu_seconds: 10,
                file_bytes: 1 << 20,
                open_files: 64,
                processes: 4096,
            },
            slot: 0,
        };
        let config = Config {
            disabled: Layer::ALL.to_vec(),
            ..Config::default()
        };
        (dir, launch, Sandbox::detect(&config))
    }

    fn spawn(sandbox: &Sandbox, launch: &Launch) -> std::io::Result<std::process::Child> {
        sandbox.spawn(launch, Stdio::null(), Stdio::null(), Stdio::null())
    }

    #[test]
    fn an_exec_that_meets_a_descriptor_open_for_writing_is_tried_again_until_it_closes() {
        let (_dir, launch, sandbox) = script();
        // Held open for writing, as a child forked elsewhere in the process holds a copied
        // program until its own exec: the kernel refuses to run the file meanwhile.
        let mut writer = std::fs::OpenOptions::new()
            .append(true)
            .open(&launch.program)
            .expect("open for writing");
        writer.write_all(b"\n").expect("write");
        let err = spawn(&sandbox, &launch).expect_err("no exec while a writer is open");
        assert_eq!(err.raw_os_error(), Some(libc::ETXTBSY), "{err}");
        // Closed while the spawn waits between its tries: the spawn succeeds.
        let closer = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(15));
            drop(writer);
        });
        let mut child = spawn(&sandbox, &launch).expect("spawned once the writer closed");
        closer.join().expect("closer");
        assert_eq!(child.wait().expect("wait").code(), Some(7));
    }
}
