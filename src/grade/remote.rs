//! The student's program as a separate process: starting it with limits, one call at a time
//! over the protocol of `springlab_homework::wire`, and what happens when it misbehaves.
//!
//! ```text
//! Session::call(method, arguments, physics, deadline)
//!   no program running → start one:
//!       environment cleared, working directory a fresh empty temporary directory,
//!       own process group, limits (setrlimit): address space 1 GiB, CPU time, file size,
//!       no new processes or threads, no core files, 32 open files;
//!       send HELLO (version, a fresh random token) on its stdin, wait for its HELLO
//!   send CALL; read replies until RESULT, PANIC or ERROR, answering PHYSICS requests with the
//!   grader's own physics of the system being stepped
//!   no reply by the deadline            → kill the process group: TimedOut
//!   the output ends (exit, abort, stack overflow, out of memory, a signal)
//!                                       → Crashed, with what its exit status and stderr say
//!   a reply over 16 MiB, or unreadable  → Malformed (the call's answer is wrong)
//!   the next call starts a new program
//! ```
//!
//! Three threads per program move bytes: one writes requests to its stdin (so that a program
//! that stops reading can never block the grader), one reads its stdout and cuts out the frames
//! that carry this session's token (everything else is the student's printing, counted and
//! dropped), one keeps the last 16 KiB of its stderr for the crash report.
//!
//! The scores, the cases and the reference never leave this process. What the program writes
//! anywhere else (files, its stdout) cannot reach the report: the grader writes the report
//! itself, after the last program has been killed.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStderr, ChildStdout, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::thread;
use std::time::{Duration, Instant};

use glam::DVec3;
use springlab_homework as api;
use springlab_homework::wire::{
    self, MAGIC, MAX_FRAME, TOKEN_LEN, Wire, decode, encode, method, physics_request,
    request_frame, to_grader, to_program,
};

use super::assignments::{
    Body, Bowl, ClothHomework, ContactCoefficients, JellyHomework, Mass, Particle, Plane, Rope,
    RopeHomework, Spring, SpringSetup, State,
};
use super::system::Physics;
use super::{Assignment, runner};
use crate::physics::SpringKind;

/// Limits of a student's program.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Address space (bytes): allocations beyond it fail and the program aborts.
    pub memory_bytes: u64,
    /// CPU time of one program (s); a backstop: calls have their own wall-clock limit.
    pub cpu_seconds: u64,
    /// Largest file the program may write (bytes).
    pub file_bytes: u64,
    /// Longest time a new program may take to greet the grader.
    pub startup: Duration,
}

impl Default for Limits {
    /// 1 GiB of address space, 10 minutes of CPU time, files up to 16 MiB, 10 s to start.
    fn default() -> Limits {
        Limits {
            memory_bytes: 1 << 30,
            cpu_seconds: 600,
            file_bytes: 16 << 20,
            startup: Duration::from_secs(10),
        }
    }
}

/// Why a call did not return an answer.
#[derive(Clone, Debug, PartialEq)]
pub enum CallFailure {
    /// The method panicked: the message and location.
    Panicked(String),
    /// The program ended during the call: what its exit status and stderr say.
    Crashed(String),
    /// No answer by the deadline; the program was killed.
    TimedOut,
    /// The answer could not be read: why.
    Malformed(String),
    /// No program could be started: why.
    NotStarted(String),
}

/// What the reader thread hands over.
#[derive(Debug, PartialEq)]
enum Event {
    Frame(Vec<u8>),
    Oversized(usize),
    Closed,
}

/// A running program.
struct Running {
    child: Child,
    to_child: mpsc::Sender<Vec<u8>>,
    from_child: mpsc::Receiver<Event>,
    stderr: Arc<Mutex<Vec<u8>>>,
    stderr_thread: Option<thread::JoinHandle<()>>,
    workdir: PathBuf,
    /// The process has been waited for: its pid may belong to someone else now.
    reaped: bool,
}

/// The student's program, started on demand and again after every crash.
pub struct Session {
    exe: PathBuf,
    assignment: Assignment,
    limits: Limits,
    running: Option<Running>,
    /// Programs started so far.
    pub starts: u32,
    /// Starts in a row that failed; after three, calls fail at once.
    failed_starts: u32,
    /// Bytes the student's code printed on stdout (not replies).
    stray: Arc<AtomicUsize>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("exe", &self.exe)
            .field("assignment", &self.assignment)
            .field("starts", &self.starts)
            .finish_non_exhaustive()
    }
}

/// 16 random bytes for a session token: the system's random source, or, where there is none,
/// std's randomly keyed hasher.
fn random_token() -> [u8; TOKEN_LEN] {
    let mut token = [0u8; TOKEN_LEN];
    let from_os = std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut token));
    if from_os.is_err() {
        use std::hash::{BuildHasher, Hasher};
        for (i, chunk) in token.chunks_mut(8).enumerate() {
            let mut h = std::collections::hash_map::RandomState::new().build_hasher();
            h.write_usize(i);
            h.write_u128(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_nanos()),
            );
            chunk.copy_from_slice(&h.finish().to_le_bytes());
        }
    }
    token
}

static WORKDIRS: AtomicU64 = AtomicU64::new(0);

/// A new empty directory only this user can enter, for one program's working directory.
fn fresh_workdir() -> std::io::Result<PathBuf> {
    let n = WORKDIRS.fetch_add(1, Ordering::Relaxed);
    let tag: String = random_token()[..6]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let dir = std::env::temp_dir().join(format!(
        "springlab-homework-{}-{n}-{tag}",
        std::process::id()
    ));
    std::fs::create_dir(&dir)?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700))?;
    }
    Ok(dir)
}

/// Applies `limits` in the child between fork and exec (only system calls, no allocation).
#[cfg(unix)]
fn apply_limits(limits: Limits) -> std::io::Result<()> {
    use nix::sys::resource::{Resource, setrlimit};
    let set = |resource, value: u64| {
        setrlimit(resource, value, value).map_err(|e| std::io::Error::from_raw_os_error(e as i32))
    };
    set(Resource::RLIMIT_AS, limits.memory_bytes)?;
    set(Resource::RLIMIT_CPU, limits.cpu_seconds)?;
    set(Resource::RLIMIT_FSIZE, limits.file_bytes)?;
    set(Resource::RLIMIT_CORE, 0)?;
    set(Resource::RLIMIT_NOFILE, 32)?;
    // No new processes or threads (not binding on root, which the kernel exempts).
    set(Resource::RLIMIT_NPROC, 0)?;
    Ok(())
}

/// Cuts frames that start with `pattern` (magic + token) out of the program's stdout, fed in
/// pieces of any size; everything between frames is stray output, counted and dropped.
struct Scanner {
    pattern: Vec<u8>,
    buf: Vec<u8>,
    stray: usize,
}

impl Scanner {
    fn new(pattern: Vec<u8>) -> Scanner {
        Scanner {
            pattern,
            buf: Vec::new(),
            stray: 0,
        }
    }

    /// The events completed by `bytes`; after an oversized frame nothing more is read.
    fn push(&mut self, bytes: &[u8]) -> Vec<Event> {
        self.buf.extend_from_slice(bytes);
        let header = self.pattern.len() + 4;
        let mut events = Vec::new();
        loop {
            let found = self
                .buf
                .windows(self.pattern.len())
                .position(|w| w == self.pattern.as_slice());
            let Some(start) = found else {
                // Keep a tail that may be the start of the pattern.
                let keep = self.pattern.len() - 1;
                if self.buf.len() > keep {
                    self.stray += self.buf.len() - keep;
                    self.buf.drain(..self.buf.len() - keep);
                }
                return events;
            };
            self.stray += start;
            self.buf.drain(..start);
            if self.buf.len() < header {
                return events;
            }
            let at = self.pattern.len();
            let len = u32::from_le_bytes([
                self.buf[at],
                self.buf[at + 1],
                self.buf[at + 2],
                self.buf[at + 3],
            ]) as usize;
            if len > MAX_FRAME {
                events.push(Event::Oversized(len));
                return events;
            }
            if self.buf.len() < header + len {
                return events;
            }
            events.push(Event::Frame(self.buf[header..header + len].to_vec()));
            self.buf.drain(..header + len);
        }
    }
}

/// Reads the program's stdout through a [`Scanner`] and hands the frames over.
fn read_replies(
    mut out: ChildStdout,
    pattern: Vec<u8>,
    tx: &mpsc::Sender<Event>,
    stray: &AtomicUsize,
) {
    let mut scanner = Scanner::new(pattern);
    let mut chunk = vec![0u8; 64 << 10];
    loop {
        let n = match out.read(&mut chunk) {
            Ok(0) | Err(_) => {
                let _ = tx.send(Event::Closed);
                return;
            }
            Ok(n) => n,
        };
        let before = scanner.stray;
        for event in scanner.push(&chunk[..n]) {
            let stop = matches!(event, Event::Oversized(_));
            if tx.send(event).is_err() || stop {
                return;
            }
        }
        stray.fetch_add(scanner.stray - before, Ordering::Relaxed);
    }
}

/// Keeps the last 16 KiB of the program's stderr.
fn keep_stderr(mut err: ChildStderr, tail: &Mutex<Vec<u8>>) {
    let mut chunk = [0u8; 4096];
    while let Ok(n) = err.read(&mut chunk) {
        if n == 0 {
            break;
        }
        if let Ok(mut t) = tail.lock() {
            t.extend_from_slice(&chunk[..n]);
            let excess = t.len().saturating_sub(16 << 10);
            t.drain(..excess);
        }
    }
}

/// The exit status of `child` if it has ended, and its peak resident memory (KiB) where the
/// system reports it (Linux: `wait4`). Before reaping, the rest of its process group is killed,
/// while the ended leader still holds the group's id.
#[cfg(unix)]
fn reap(child: &mut Child) -> Option<(ExitStatus, Option<u64>)> {
    use nix::libc;
    use std::os::unix::process::ExitStatusExt;
    let pid = libc::pid_t::try_from(child.id()).ok()?;
    // SAFETY: an all-zero siginfo_t is a valid value of this plain C struct.
    let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
    // SAFETY: waitid on our own child with a valid pointer; WNOHANG | WNOWAIT neither blocks
    // nor reaps.
    let polled = unsafe {
        libc::waitid(
            libc::P_PID,
            pid as libc::id_t,
            &raw mut info,
            libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
        )
    };
    // SAFETY: si_pid is set by waitid (zero while the child runs).
    if polled != 0 || unsafe { info.si_pid() } == 0 {
        return None;
    }
    let _ = nix::sys::signal::killpg(
        nix::unistd::Pid::from_raw(pid),
        nix::sys::signal::Signal::SIGKILL,
    );
    let mut status: libc::c_int = 0;
    // SAFETY: an all-zero rusage is a valid value of this plain C struct.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: wait4 on our own ended child with valid pointers to locals; it returns at once.
    let got = unsafe { libc::wait4(pid, &raw mut status, 0, &raw mut usage) };
    (got == pid).then(|| {
        (
            ExitStatus::from_raw(status),
            u64::try_from(usage.ru_maxrss).ok(),
        )
    })
}

#[cfg(not(unix))]
fn reap(child: &mut Child) -> Option<(ExitStatus, Option<u64>)> {
    child.try_wait().ok().flatten().map(|s| (s, None))
}

/// Mebibytes, for messages.
fn mib(bytes: u64) -> u64 {
    bytes >> 20
}

/// What an exit status and the end of stderr say about how a program ended.
fn describe_end(status: Option<ExitStatus>, stderr: &str, limits: Limits) -> String {
    let last_line = stderr
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .map(|l| format!(" (stderr: \"{}\")", l.trim()))
        .unwrap_or_default();
    if let Some(line) = stderr.lines().find(|l| l.contains("memory allocation of")) {
        return format!(
            "it ran out of memory: \"{}\"; a homework program may use {} MiB of address space",
            line.trim(),
            mib(limits.memory_bytes)
        );
    }
    if stderr.contains("has overflowed its stack") {
        return "its stack overflowed (a recursion without end?)".to_string();
    }
    let Some(status) = status else {
        return format!("it stopped answering{last_line}");
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            let name = nix::sys::signal::Signal::try_from(signal)
                .map_or_else(|_| format!("signal {signal}"), |s| s.as_str().to_string());
            let why = match signal {
                6 => "it aborted (std::process::abort, or a panic inside a panic)".to_string(),
                9 => "it was killed".to_string(),
                11 => "it crashed with a segmentation fault".to_string(),
                24 => format!(
                    "it used up its CPU time ({} s for one program)",
                    limits.cpu_seconds
                ),
                25 => format!(
                    "it wrote a file larger than the limit of {} MiB",
                    mib(limits.file_bytes)
                ),
                _ => "it was stopped by a signal".to_string(),
            };
            return format!("{why} ({name}){last_line}");
        }
    }
    match status.code() {
        Some(code) => format!(
            "it exited with status {code} in the middle of a call (std::process::exit?){last_line}"
        ),
        None => format!("it ended ({status}){last_line}"),
    }
}

impl Session {
    /// A session for the program `exe` of `assignment`; nothing starts until the first call.
    #[must_use]
    pub fn new(exe: PathBuf, assignment: Assignment, limits: Limits) -> Session {
        Session {
            exe,
            assignment,
            limits,
            running: None,
            starts: 0,
            failed_starts: 0,
            stray: Arc::new(AtomicUsize::new(0)),
        }
    }

    /// Bytes the student's code printed on stdout so far.
    #[must_use]
    pub fn stray_bytes(&self) -> usize {
        self.stray.load(Ordering::Relaxed)
    }

    fn spawn(&self, workdir: &Path) -> std::io::Result<Child> {
        let mut command = Command::new(&self.exe);
        command
            .env_clear()
            .current_dir(workdir)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        #[cfg(unix)]
        {
            use std::os::unix::process::CommandExt;
            let limits = self.limits;
            command.process_group(0);
            // SAFETY: the closure makes only setrlimit system calls, which are safe between
            // fork and exec; it allocates nothing and takes no lock.
            unsafe {
                command.pre_exec(move || apply_limits(limits));
            }
        }
        command.spawn()
    }

    /// Starts a program and exchanges greetings.
    fn start(&mut self, deadline: Instant) -> Result<(), CallFailure> {
        if self.failed_starts >= 3 {
            return Err(CallFailure::NotStarted(
                "the program failed to start three times in a row; the grader gave up on it"
                    .to_string(),
            ));
        }
        self.starts += 1;
        let result = self.try_start(deadline.min(Instant::now() + self.limits.startup));
        match &result {
            Ok(()) => self.failed_starts = 0,
            Err(_) => self.failed_starts += 1,
        }
        result
    }

    fn try_start(&mut self, deadline: Instant) -> Result<(), CallFailure> {
        let workdir = fresh_workdir().map_err(|e| {
            CallFailure::NotStarted(format!("cannot create a working directory: {e}"))
        })?;
        let mut child = match self.spawn(&workdir) {
            Ok(child) => child,
            Err(e) => {
                let _ = std::fs::remove_dir_all(&workdir);
                return Err(CallFailure::NotStarted(format!(
                    "cannot start {}: {e}",
                    self.exe.display()
                )));
            }
        };
        let token = random_token();
        let mut pattern = MAGIC.to_vec();
        pattern.extend_from_slice(&token);
        let (event_tx, from_child) = mpsc::channel();
        let (to_child, request_rx) = mpsc::channel::<Vec<u8>>();
        let stderr = Arc::new(Mutex::new(Vec::new()));
        if let Some(mut stdin) = child.stdin.take() {
            thread::spawn(move || {
                for frame in request_rx {
                    if stdin
                        .write_all(&frame)
                        .and_then(|()| stdin.flush())
                        .is_err()
                    {
                        break;
                    }
                }
            });
        }
        if let Some(out) = child.stdout.take() {
            let stray = Arc::clone(&self.stray);
            thread::spawn(move || read_replies(out, pattern, &event_tx, &stray));
        }
        let stderr_thread = child.stderr.take().map(|err| {
            let tail = Arc::clone(&stderr);
            thread::spawn(move || keep_stderr(err, &tail))
        });
        self.running = Some(Running {
            child,
            to_child,
            from_child,
            stderr,
            stderr_thread,
            workdir,
            reaped: false,
        });
        let mut hello = vec![to_program::HELLO];
        wire::VERSION.put(&mut hello);
        token.put(&mut hello);
        self.send(&hello);
        match self.next_event(deadline) {
            Some(Event::Frame(frame)) => {
                let greeting = (|| {
                    let mut r = wire::Reader::new(&frame);
                    if u8::take(&mut r)? != to_grader::HELLO {
                        return Err(wire::WireError("not a greeting".to_string()));
                    }
                    Ok((u32::take(&mut r)?, String::take(&mut r)?))
                })();
                match greeting {
                    Ok((version, assignment))
                        if version == wire::VERSION && assignment == self.assignment.name() =>
                    {
                        Ok(())
                    }
                    Ok((version, assignment)) => {
                        self.stop();
                        Err(CallFailure::NotStarted(format!(
                            "the program serves the {assignment} homework with protocol \
                             version {version}; the grader expected the {} homework, version {}",
                            self.assignment.name(),
                            wire::VERSION
                        )))
                    }
                    Err(e) => {
                        self.stop();
                        Err(CallFailure::NotStarted(format!(
                            "the program's greeting is unreadable: {e}"
                        )))
                    }
                }
            }
            Some(Event::Closed) => Err(CallFailure::NotStarted(format!(
                "the program ended before greeting the grader: {}",
                self.ended()
            ))),
            Some(Event::Oversized(_)) => {
                self.stop();
                Err(CallFailure::NotStarted(
                    "the program's greeting is too large".to_string(),
                ))
            }
            None => {
                self.stop();
                Err(CallFailure::NotStarted(
                    "the program did not greet the grader in time".to_string(),
                ))
            }
        }
    }

    fn send(&self, payload: &[u8]) {
        if let Some(run) = &self.running {
            // A program that is gone is noticed by the reader.
            let _ = run.to_child.send(request_frame(payload));
        }
    }

    /// The next event, or `None` at the deadline.
    fn next_event(&self, deadline: Instant) -> Option<Event> {
        let run = self.running.as_ref()?;
        let wait = deadline.saturating_duration_since(Instant::now());
        match run.from_child.recv_timeout(wait) {
            Ok(event) => Some(event),
            Err(mpsc::RecvTimeoutError::Disconnected) => Some(Event::Closed),
            Err(mpsc::RecvTimeoutError::Timeout) => None,
        }
    }

    /// Kills the running program's process group and removes its working directory.
    fn stop(&mut self) {
        let Some(mut run) = self.running.take() else {
            return;
        };
        if !run.reaped {
            #[cfg(unix)]
            {
                use nix::sys::signal::{Signal, killpg};
                use nix::unistd::Pid;
                if let Ok(pid) = i32::try_from(run.child.id()) {
                    let _ = killpg(Pid::from_raw(pid), Signal::SIGKILL);
                }
            }
            let _ = run.child.kill();
            let _ = run.child.wait();
        }
        let _ = std::fs::remove_dir_all(&run.workdir);
    }

    /// After the program's output closed: how it ended (waits up to 2 s for it to exit).
    fn ended(&mut self) -> String {
        let Some(mut run) = self.running.take() else {
            return "it is not running".to_string();
        };
        let start = Instant::now();
        let mut end = None;
        while start.elapsed() < Duration::from_secs(2) {
            if let Some(e) = reap(&mut run.child) {
                end = Some(e);
                break;
            }
            thread::sleep(Duration::from_millis(2));
        }
        let Some((status, peak_kib)) = end else {
            self.running = Some(run);
            self.stop();
            return "it closed its output and stopped answering".to_string();
        };
        run.reaped = true;
        if let Some(t) = run.stderr_thread.take() {
            let _ = t.join();
        }
        let stderr = run
            .stderr
            .lock()
            .map(|t| String::from_utf8_lossy(&t).into_owned())
            .unwrap_or_default();
        self.running = Some(run);
        self.stop();
        let mut how = describe_end(Some(status), &stderr, self.limits);
        if let Some(kib) = peak_kib.filter(|&k| k >= 64 << 10) {
            how.push_str(&format!("; it had {} MiB in use", kib >> 10));
        }
        how
    }

    /// One call: `arguments` of `method`, answered by the program by `deadline` (module docs).
    ///
    /// # Errors
    /// [`CallFailure`] when no answer came; the program is then stopped and the next call
    /// starts a new one.
    pub fn call(
        &mut self,
        m: u8,
        arguments: &[u8],
        physics: Option<&Physics>,
        deadline: Instant,
    ) -> Result<Vec<u8>, CallFailure> {
        if self.running.is_none() {
            self.start(deadline)?;
        }
        let mut payload = Vec::with_capacity(2 + arguments.len());
        payload.push(to_program::CALL);
        payload.push(m);
        payload.extend_from_slice(arguments);
        self.send(&payload);
        loop {
            let Some(event) = self.next_event(deadline) else {
                self.stop();
                return Err(CallFailure::TimedOut);
            };
            let frame = match event {
                Event::Frame(frame) => frame,
                Event::Oversized(n) => {
                    self.stop();
                    return Err(CallFailure::Malformed(format!(
                        "an answer of {n} bytes; the grader reads at most {} MiB",
                        MAX_FRAME >> 20
                    )));
                }
                Event::Closed => return Err(CallFailure::Crashed(self.ended())),
            };
            match frame.split_first() {
                Some((&to_grader::RESULT, answer)) => return Ok(answer.to_vec()),
                Some((&to_grader::PANIC, message)) => {
                    return Err(CallFailure::Panicked(
                        decode::<String>(message)
                            .unwrap_or_else(|_| "a panic (unreadable message)".to_string()),
                    ));
                }
                Some((&to_grader::PHYSICS, request)) => {
                    let reply = answer_physics(physics, request);
                    self.send(&reply);
                }
                Some((&to_grader::ERROR, message)) => {
                    self.stop();
                    return Err(CallFailure::Malformed(format!(
                        "the program could not serve the call: {}",
                        decode::<String>(message).unwrap_or_default()
                    )));
                }
                _ => {
                    self.stop();
                    return Err(CallFailure::Malformed(
                        "a reply of an unknown kind".to_string(),
                    ));
                }
            }
        }
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        self.stop();
    }
}

/// The grader's answer to a PHYSICS request: accelerations or a Jacobian of `physics` at the
/// requested state, or a refusal that the program turns into a panic.
fn answer_physics(physics: Option<&Physics>, request: &[u8]) -> Vec<u8> {
    let refuse = |message: String| {
        let mut reply = vec![to_program::PHYSICS_REPLY, 0];
        message.put(&mut reply);
        reply
    };
    let Some(physics) = physics else {
        return refuse("this method has no Physics".to_string());
    };
    let Ok((what, x, v)) = decode::<(u8, Vec<api::DVec3>, Vec<api::DVec3>)>(request) else {
        return refuse("unreadable Physics request".to_string());
    };
    let n = physics.particle_count();
    let name = match what {
        physics_request::ACCELERATIONS => "accelerations",
        physics_request::JACOBIAN_X => "jacobian_x",
        physics_request::JACOBIAN_V => "jacobian_v",
        _ => return refuse(format!("unknown Physics request {what}")),
    };
    if x.len() != n || v.len() != n {
        return refuse(format!(
            "Physics::{name}: the system has {n} particles, but x has {} entries and v has {}",
            x.len(),
            v.len()
        ));
    }
    let x: Vec<DVec3> = x.into_iter().map(local_vec).collect();
    let v: Vec<DVec3> = v.into_iter().map(local_vec).collect();
    let values: Vec<f64> = match what {
        physics_request::ACCELERATIONS => super::system::flatten(&physics.accelerations(&x, &v)),
        physics_request::JACOBIAN_X => physics.jacobian_x(&x, &v).row_major().to_vec(),
        _ => physics.jacobian_v(&x, &v).row_major().to_vec(),
    };
    let mut reply = vec![to_program::PHYSICS_REPLY, 1];
    values.put(&mut reply);
    reply
}

// ---------------------------------------------------------------------------------------------
// The grader's types and the program's

fn api_vec(v: DVec3) -> api::DVec3 {
    api::DVec3::new(v.x, v.y, v.z)
}

fn local_vec(v: api::DVec3) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

fn api_vecs(v: &[DVec3]) -> Vec<api::DVec3> {
    v.iter().copied().map(api_vec).collect()
}

fn local_vecs(v: Vec<api::DVec3>) -> Vec<DVec3> {
    v.into_iter().map(local_vec).collect()
}

fn api_spring(s: &Spring) -> api::Spring {
    api::Spring {
        a: s.a,
        b: s.b,
        rest_length: s.rest_length,
        stiffness: s.stiffness,
        damping: s.damping,
    }
}

fn local_spring(s: &api::Spring) -> Spring {
    Spring {
        a: s.a,
        b: s.b,
        rest_length: s.rest_length,
        stiffness: s.stiffness,
        damping: s.damping,
    }
}

fn api_rope(r: &Rope) -> api::Rope {
    api::Rope {
        masses: r
            .masses
            .iter()
            .map(|m| api::Mass {
                position: api_vec(m.position),
                velocity: api_vec(m.velocity),
                last_position: api_vec(m.last_position),
                mass: m.mass,
                pinned: m.pinned,
            })
            .collect(),
        springs: r.springs.iter().map(api_spring).collect(),
    }
}

fn local_rope(r: &api::Rope) -> Rope {
    Rope {
        masses: r
            .masses
            .iter()
            .map(|m| Mass {
                position: local_vec(m.position),
                velocity: local_vec(m.velocity),
                last_position: local_vec(m.last_position),
                mass: m.mass,
                pinned: m.pinned,
            })
            .collect(),
        springs: r.springs.iter().map(local_spring).collect(),
    }
}

fn api_state(s: &State) -> api::State {
    api::State {
        x: api_vecs(&s.x),
        v: api_vecs(&s.v),
    }
}

fn local_state(s: api::State) -> State {
    State {
        x: local_vecs(s.x),
        v: local_vecs(s.v),
    }
}

fn local_setup(s: &api::SpringSetup) -> SpringSetup {
    SpringSetup {
        a: s.a,
        b: s.b,
        kind: match s.kind {
            api::SpringKind::Struct => SpringKind::Struct,
            api::SpringKind::Shear => SpringKind::Shear,
            api::SpringKind::Bend => SpringKind::Bend,
        },
    }
}

fn api_particle(p: &Particle) -> api::Particle {
    api::Particle {
        x: api_vec(p.x),
        v: api_vec(p.v),
        force: api_vec(p.force),
    }
}

fn local_particle(p: &api::Particle) -> Particle {
    Particle {
        x: local_vec(p.x),
        v: local_vec(p.v),
        force: local_vec(p.force),
    }
}

fn api_contact(c: &ContactCoefficients) -> api::ContactCoefficients {
    api::ContactCoefficients {
        epsilon: c.epsilon,
        restitution: c.restitution,
        friction: c.friction,
    }
}

fn api_body(b: &Body) -> api::Body {
    api::Body {
        x: api_vec(b.x),
        v: api_vec(b.v),
        inverse_mass: b.inverse_mass,
    }
}

fn local_body(b: &api::Body) -> Body {
    Body {
        x: local_vec(b.x),
        v: local_vec(b.v),
        inverse_mass: b.inverse_mass,
    }
}

// ---------------------------------------------------------------------------------------------
// The homework traits, answered by the program

/// A student's program behind the homework traits: every method is a call to the program.
///
/// A call that gets no answer (module docs) unwinds with its [`CallFailure`] as the payload
/// (`std::panic::resume_unwind`, so no panic hook runs); the runner scores the check in progress
/// accordingly, and the next call starts a new program.
#[derive(Clone)]
pub struct Remote {
    session: Arc<Mutex<Session>>,
    /// Deadline of a call made outside a graded check.
    default_limit: Duration,
}

impl std::fmt::Debug for Remote {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Remote").finish_non_exhaustive()
    }
}

impl Remote {
    /// The homework served by `session`; calls outside a check get `default_limit`.
    #[must_use]
    pub fn new(session: Session, default_limit: Duration) -> Remote {
        Remote {
            session: Arc::new(Mutex::new(session)),
            default_limit,
        }
    }

    /// Programs started so far and bytes they printed.
    #[must_use]
    pub fn stats(&self) -> (u32, usize) {
        let s = self
            .session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        (s.starts, s.stray_bytes())
    }

    /// Stops the running program (the report is written after this).
    pub fn shut_down(&self) {
        self.session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .stop();
    }

    fn ask<A: Wire, R: Wire>(&self, m: u8, arguments: &A, physics: Option<&Physics>) -> R {
        let deadline =
            runner::check_deadline().unwrap_or_else(|| Instant::now() + self.default_limit);
        let answer = {
            let mut session = self
                .session
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            session.call(m, &encode(arguments), physics, deadline)
        };
        let value = answer.and_then(|bytes| {
            decode::<R>(&bytes).map_err(|e| CallFailure::Malformed(format!("unreadable: {e}")))
        });
        match value {
            Ok(v) => v,
            Err(failure) => std::panic::resume_unwind(Box::new(failure)),
        }
    }

    fn inverse_mass(physics: &Physics) -> Vec<f64> {
        physics.inverse_mass().to_vec()
    }

    fn rope_step(&self, m: u8, rope: &mut Rope, dt: f64, damping: Option<f64>, p: &Physics) {
        let w = Self::inverse_mass(p);
        let out: api::Rope = match damping {
            None => self.ask(m, &(api_rope(rope), dt, w), Some(p)),
            Some(g) => self.ask(m, &(api_rope(rope), dt, g, w), Some(p)),
        };
        *rope = local_rope(&out);
    }

    fn state_step(&self, m: u8, state: &mut State, dt: f64, p: &Physics) {
        let out: api::State = self.ask(m, &(api_state(state), dt, Self::inverse_mass(p)), Some(p));
        *state = local_state(out);
    }

    fn pair(&self, m: u8, a: DVec3, b: DVec3, k: f64, l: f64) -> DVec3 {
        local_vec(self.ask(m, &(api_vec(a), api_vec(b), k, l), None))
    }

    fn damper(&self, m: u8, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
        let args = (api_vec(xa), api_vec(xb), api_vec(va), api_vec(vb), kd);
        local_vec(self.ask(m, &args, None))
    }
}

impl RopeHomework for Remote {
    fn rope(
        &self,
        start: DVec3,
        end: DVec3,
        nodes: usize,
        node_mass: f64,
        stiffness: f64,
        pinned: &[usize],
    ) -> Rope {
        let args = (
            api_vec(start),
            api_vec(end),
            nodes,
            node_mass,
            stiffness,
            pinned.to_vec(),
        );
        local_rope(&self.ask::<_, api::Rope>(method::ROPE_ROPE, &args, None))
    }

    fn spring_force(&self, a: DVec3, b: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        self.pair(method::ROPE_SPRING_FORCE, a, b, stiffness, rest_length)
    }

    fn spring_forces(&self, rope: &Rope) -> Vec<DVec3> {
        local_vecs(self.ask(method::ROPE_SPRING_FORCES, &api_rope(rope), None))
    }

    fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        self.rope_step(method::ROPE_EXPLICIT_EULER, rope, dt, None, physics);
    }

    fn semi_implicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        self.rope_step(method::ROPE_SEMI_IMPLICIT_EULER, rope, dt, None, physics);
    }

    fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics) {
        self.rope_step(method::ROPE_VERLET, rope, dt, Some(damping), physics);
    }
}

impl JellyHomework for Remote {
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup> {
        let got: Vec<api::SpringSetup> = self.ask(method::JELLY_SPRINGS, &counts, None);
        got.iter().map(local_setup).collect()
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        self.pair(method::JELLY_SPRING_FORCE, xa, xb, stiffness, rest_length)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3 {
        self.damper(method::JELLY_DAMPER_FORCE, xa, xb, va, vb, damping)
    }

    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3> {
        let springs: Vec<api::Spring> = springs.iter().map(api_spring).collect();
        let args = (api_vecs(x), api_vecs(v), springs);
        local_vecs(self.ask(method::JELLY_INTERNAL_FORCES, &args, None))
    }

    fn plane_collision(&self, plane: &Plane, particle: &mut Particle, c: &ContactCoefficients) {
        let plane = api::Plane {
            point: api_vec(plane.point),
            normal: api_vec(plane.normal),
        };
        let args = (plane, api_particle(particle), api_contact(c));
        let out: api::Particle = self.ask(method::JELLY_PLANE_COLLISION, &args, None);
        *particle = local_particle(&out);
    }

    fn bowl_collision(&self, bowl: &Bowl, particle: &mut Particle, c: &ContactCoefficients) {
        let bowl = api::Bowl {
            center: api_vec(bowl.center),
            radius: bowl.radius,
            rim_height: bowl.rim_height,
        };
        let args = (bowl, api_particle(particle), api_contact(c));
        let out: api::Particle = self.ask(method::JELLY_BOWL_COLLISION, &args, None);
        *particle = local_particle(&out);
    }

    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_EXPLICIT_EULER, state, dt, physics);
    }

    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_IMPLICIT_EULER, state, dt, physics);
    }

    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_MIDPOINT, state, dt, physics);
    }

    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_RK4, state, dt, physics);
    }
}

impl ClothHomework for Remote {
    fn springs(&self, n: usize) -> Vec<SpringSetup> {
        let got: Vec<api::SpringSetup> = self.ask(method::CLOTH_SPRINGS, &n, None);
        got.iter().map(local_setup).collect()
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        self.pair(method::CLOTH_SPRING_FORCE, xa, xb, stiffness, rest_length)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3 {
        self.damper(method::CLOTH_DAMPER_FORCE, xa, xb, va, vb, damping)
    }

    fn spring_accelerations(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        inverse_mass: &[f64],
        springs: &[Spring],
    ) -> Vec<DVec3> {
        let springs: Vec<api::Spring> = springs.iter().map(api_spring).collect();
        let args = (api_vecs(x), api_vecs(v), inverse_mass.to_vec(), springs);
        local_vecs(self.ask(method::CLOTH_SPRING_ACCELERATIONS, &args, None))
    }

    fn sphere_collision(
        &self,
        sphere: &mut Body,
        radius: f64,
        particle: &mut Body,
        restitution: f64,
    ) {
        let args = (api_body(sphere), radius, api_body(particle), restitution);
        let (s, p): (api::Body, api::Body) = self.ask(method::CLOTH_SPHERE_COLLISION, &args, None);
        *sphere = local_body(&s);
        *particle = local_body(&p);
    }

    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_EXPLICIT_EULER, state, dt, physics);
    }

    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_IMPLICIT_EULER, state, dt, physics);
    }

    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_MIDPOINT, state, dt, physics);
    }

    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_RK4, state, dt, physics);
    }
}

#[cfg(test)]
mod tests {
    use super::{Event, Limits, Scanner, describe_end};
    use springlab_homework::wire::{MAGIC, reply_frame};

    #[test]
    fn frames_are_found_among_stray_output_in_pieces_of_any_size() {
        let token = [7u8; 16];
        let mut stream = b"debug: hello\n".to_vec();
        stream.extend_from_slice(&reply_frame(&token, &[0x82, 1, 2, 3]));
        // Printing that imitates a reply: the magic with a wrong token, a partial magic.
        stream.extend_from_slice(&reply_frame(&[0u8; 16], &[0x82, 9, 9]));
        stream.extend_from_slice(&MAGIC[..5]);
        stream.extend_from_slice(&reply_frame(&token, &[]));
        stream.extend_from_slice(&reply_frame(&token, &[0x83, 4]));
        stream.extend_from_slice(b"trailing");
        let want = vec![
            Event::Frame(vec![0x82, 1, 2, 3]),
            Event::Frame(vec![]),
            Event::Frame(vec![0x83, 4]),
        ];
        let mut pattern = MAGIC.to_vec();
        pattern.extend_from_slice(&token);
        for piece in 1..=9 {
            let mut scanner = Scanner::new(pattern.clone());
            let mut got = Vec::new();
            for chunk in stream.chunks(piece) {
                got.extend(scanner.push(chunk));
            }
            assert_eq!(got, want, "pieces of {piece}");
        }
    }

    #[test]
    fn an_oversized_frame_is_refused_unread() {
        let token = [1u8; 16];
        let mut pattern = MAGIC.to_vec();
        pattern.extend_from_slice(&token);
        let mut header = pattern.clone();
        header.extend_from_slice(&(64u32 << 20).to_le_bytes());
        let mut scanner = Scanner::new(pattern);
        assert_eq!(scanner.push(&header), vec![Event::Oversized(64 << 20)]);
    }

    #[cfg(unix)]
    #[test]
    fn endings_are_told_apart() {
        use std::os::unix::process::ExitStatusExt;
        let limits = Limits::default();
        let exit0 = std::process::ExitStatus::from_raw(0);
        let signal = |s: i32| std::process::ExitStatus::from_raw(s);
        assert!(describe_end(Some(exit0), "", limits).contains("exited with status 0"));
        assert!(describe_end(Some(signal(6)), "", limits).contains("aborted"));
        assert!(describe_end(Some(signal(24)), "", limits).contains("CPU time (600 s"));
        assert!(describe_end(Some(signal(25)), "", limits).contains("16 MiB"));
        let oom = "memory allocation of 1048576 bytes failed\n";
        assert!(describe_end(Some(signal(6)), oom, limits).contains("1024 MiB of address space"));
        let overflow =
            "\nthread 'main' has overflowed its stack\nfatal runtime error: stack overflow\n";
        assert!(describe_end(Some(signal(6)), overflow, limits).contains("stack overflowed"));
    }
}
