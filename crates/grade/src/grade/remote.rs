//! The student's program as a separate process: starting it with limits, one call at a time
//! over the protocol of `springlab_homework::wire`, and what happens when it misbehaves.
//!
//! ```text
//! Session::call(method, arguments, physics, deadline)
//!   no program running → start one:
//!       in the sandbox (`grade::sandbox`: another user, namespaces, Landlock, seccomp):
//!       environment cleared, working directory a fresh empty folder of its own (the only
//!       one it may write), own process group, limits (setrlimit): address space 1 GiB, CPU
//!       time, file size, no new processes or threads, no core files, 32 open files;
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
//! The thread that makes the call writes the program's stdin and reads its stdout itself, each
//! with the call's deadline (`poll`; the stdin pipe does not block, so a program that stops
//! reading holds the grader only until the deadline), and cuts out of the stdout the frames
//! that carry this session's token (everything else is the student's printing, counted and
//! dropped): a request and its reply cost one wake-up each way, no thread in between. One
//! thread per program keeps the last 16 KiB of its stderr for the crash report.
//!
//! Files: this one holds the session (start, call, stop); `remote/process.rs` starts and ends
//! the program (token, working directory, limits, reaping, what its end means);
//! `remote/frames.rs` writes its stdin and cuts the replies out of its stdout; `remote/convert.rs` converts between
//! the grader's types and the API crate's; `remote/traits.rs` implements the homework traits
//! with calls.
//!
//! The scores, the cases and the reference never leave this process. What the program writes
//! anywhere else (files, its stdout) cannot reach the report: the grader writes the report
//! itself, after the last program has been killed.

use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use springlab_homework::wire::{
    self, MAGIC, MAX_FRAME, Wire, decode, physics_request, request_frame, to_grader, to_program,
};

use super::Assignment;
use super::system::Physics;
use super::untrusted::student_text;

mod convert;
mod frames;
mod process;
mod traits;

use convert::*;
use frames::Pipes;
use process::*;
pub use traits::Remote;

use super::build::Builder;
use super::sandbox::{Launch, Rlimits};

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

/// What the program's stdout brings.
#[derive(Debug, PartialEq)]
enum Event {
    Frame(Vec<u8>),
    Oversized(usize),
    Closed,
}

/// A running program.
struct Running {
    child: Child,
    /// Its standard input and output (`None` when the sandbox gave none).
    pipes: Option<Pipes>,
    stderr: Arc<Mutex<Vec<u8>>>,
    stderr_thread: Option<thread::JoinHandle<()>>,
    workdir: PathBuf,
    /// The process has been waited for: its pid may belong to someone else now.
    reaped: bool,
}

/// Where a session's programs run: the run's builder (its sandbox and scratch space), the
/// job slot, and the submission's folder (working directories go beneath it).
#[derive(Clone)]
pub struct Place {
    /// The run's builder.
    pub builder: Arc<Builder>,
    /// The job slot (`--jobs`).
    pub slot: u32,
    /// The submission's folder in the scratch space.
    pub dir: PathBuf,
}

/// The student's program, started on demand and again after every crash.
pub struct Session {
    place: Place,
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
    /// What the answers to `Physics` requests reuse from one request to the next.
    answers: Answers,
}

/// The lists and the reply of the answers to `Physics` requests, kept between requests (the
/// 1000-particle jelly's RK4 asks four times a step): no allocation per answer.
#[derive(Default)]
struct Answers {
    /// Positions (m) of the request.
    x: Vec<glam::DVec3>,
    /// Velocities (m/s) of the request.
    v: Vec<glam::DVec3>,
    /// Accelerations (m/s²) of the answer.
    a: Vec<glam::DVec3>,
    /// The reply, framed (its length first) as [`request_frame`] frames it.
    reply: Vec<u8>,
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

impl Session {
    /// A session for the program `exe` of `assignment`; nothing starts until the first call.
    #[must_use]
    pub fn new(exe: PathBuf, assignment: Assignment, limits: Limits, place: Place) -> Session {
        Session {
            place,
            exe,
            assignment,
            limits,
            running: None,
            starts: 0,
            failed_starts: 0,
            stray: Arc::new(AtomicUsize::new(0)),
            answers: Answers::default(),
        }
    }

    /// Bytes the student's code printed on stdout so far.
    #[must_use]
    pub fn stray_bytes(&self) -> usize {
        self.stray.load(Ordering::Relaxed)
    }

    fn spawn(&self, workdir: &Path) -> std::io::Result<Child> {
        let launch = Launch {
            program: self.exe.clone(),
            args: Vec::new(),
            env: Vec::new(),
            cwd: workdir.to_path_buf(),
            read: Vec::new(),
            write: vec![workdir.to_path_buf()],
            limits: Rlimits {
                address_space: self.limits.memory_bytes,
                cpu_seconds: self.limits.cpu_seconds,
                file_bytes: self.limits.file_bytes,
                open_files: 32,
                // No new processes or threads.
                processes: 0,
            },
            slot: self.place.slot,
        };
        self.place
            .builder
            .sandbox
            .spawn(&launch, Stdio::piped(), Stdio::piped(), Stdio::piped())
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
        let workdir = self
            .place
            .builder
            .workdir(&self.place.dir, self.place.slot)
            .map_err(|e| {
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
        let token = super::token::random_token();
        let mut pattern = MAGIC.to_vec();
        pattern.extend_from_slice(&token);
        let pipes = match (child.stdin.take(), child.stdout.take()) {
            (Some(stdin), Some(stdout)) => Some(Pipes::new(stdin, stdout, pattern)),
            _ => None,
        };
        let stderr = Arc::new(Mutex::new(Vec::new()));
        let stderr_thread = child.stderr.take().map(|err| {
            let tail = Arc::clone(&stderr);
            thread::spawn(move || keep_stderr(err, &tail))
        });
        self.running = Some(Running {
            child,
            pipes,
            stderr,
            stderr_thread,
            workdir,
            reaped: false,
        });
        let mut hello = vec![to_program::HELLO];
        wire::VERSION.put(&mut hello);
        token.put(&mut hello);
        self.send(&hello, deadline);
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
                    Ok((version, assignment)) if version != wire::VERSION => {
                        self.stop();
                        Err(CallFailure::NotStarted(format!(
                            "the program speaks version {version} of the grader's protocol \
                             (its {assignment} homework was built against another copy of \
                             springlab-homework); this springlab speaks version {}: update \
                             the crate's springlab-homework and build it again",
                            wire::VERSION
                        )))
                    }
                    Ok((_, assignment)) => {
                        self.stop();
                        Err(CallFailure::NotStarted(format!(
                            "the program serves the {assignment} homework; the grader expected \
                             the {} homework",
                            self.assignment.name()
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

    /// Sends one frame by `deadline`; a program that is gone, or does not read, is noticed by
    /// the next [`Session::next_event`].
    fn send(&mut self, payload: &[u8], deadline: Instant) {
        self.send_framed(&request_frame(payload), deadline);
    }

    /// Writes a frame already framed (its length first).
    fn send_framed(&mut self, frame: &[u8], deadline: Instant) {
        if let Some(pipes) = self.running.as_mut().and_then(|r| r.pipes.as_mut()) {
            let _ = pipes.write(frame, deadline);
        }
    }

    /// The next event, or `None` at the deadline.
    fn next_event(&mut self, deadline: Instant) -> Option<Event> {
        let stray = &self.stray;
        let run = self.running.as_mut()?;
        match run.pipes.as_mut() {
            Some(pipes) => pipes.next(deadline, stray),
            None => Some(Event::Closed),
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
        // Without a PID namespace, what the program started is found by its user.
        self.place.builder.sandbox.sweep(self.place.slot);
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
        let mut payload = Vec::with_capacity(2 + arguments.len());
        payload.push(to_program::CALL);
        payload.push(m);
        payload.extend_from_slice(arguments);
        self.exchange(&payload, physics, deadline, None)
    }

    /// `count` steps of the integrator `method` in one request (STEPS), each from the last
    /// one's answer (`wire`'s module docs): the answers of the steps that came, in order (each
    /// still behind the one byte of its frame's kind, [`STEP_ANSWER`]: not copied again), and
    /// why the rest did not. Each step has `limit` from the previous answer (or the request).
    pub fn steps(
        &mut self,
        m: u8,
        count: u32,
        arguments: &[u8],
        physics: Option<&Physics>,
        limit: Duration,
    ) -> (Vec<Vec<u8>>, Result<(), CallFailure>) {
        let mut payload = Vec::with_capacity(6 + arguments.len());
        payload.push(to_program::STEPS);
        payload.push(m);
        payload.extend_from_slice(&count.to_le_bytes());
        payload.extend_from_slice(arguments);
        let mut answers = Vec::new();
        let deadline = Instant::now() + limit;
        let done = self
            .exchange(&payload, physics, deadline, Some((&mut answers, limit)))
            .map(|_| ());
        (answers, done)
    }

    /// Sends one request and reads until its answer (module docs); with `steps`, STEP frames
    /// are collected there, each moving the deadline to `limit` after it.
    fn exchange(
        &mut self,
        payload: &[u8],
        physics: Option<&Physics>,
        mut deadline: Instant,
        mut steps: Option<(&mut Vec<Vec<u8>>, Duration)>,
    ) -> Result<Vec<u8>, CallFailure> {
        if self.running.is_none() {
            self.start(deadline)?;
        }
        self.send(payload, deadline);
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
                        decode::<String>(message).map_or_else(
                            |_| "a panic (unreadable message)".to_string(),
                            |m| student_text(&m),
                        ),
                    ));
                }
                Some((&to_grader::PHYSICS, request)) => {
                    answer_physics(physics, request, &mut self.answers);
                    let reply = std::mem::take(&mut self.answers.reply);
                    self.send_framed(&reply, deadline);
                    self.answers.reply = reply;
                }
                Some((&to_grader::STEP, _)) if steps.is_some() => {
                    if let Some((answers, limit)) = steps.as_mut() {
                        answers.push(frame);
                        deadline = Instant::now() + *limit;
                    }
                }
                Some((&to_grader::ERROR, message)) => {
                    self.stop();
                    return Err(CallFailure::Malformed(format!(
                        "the program could not serve the call: {}",
                        student_text(&decode::<String>(message).unwrap_or_default())
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

/// Where a step's answer starts in what [`Session::steps`] returns (after the frame's kind).
pub const STEP_ANSWER: usize = 1;

/// The grader's answer to a PHYSICS request: accelerations or a Jacobian of `physics` at the
/// requested state, or a refusal that the program turns into a panic; framed into
/// `answers.reply`, the lists read into and computed in `answers`' own.
fn answer_physics(physics: Option<&Physics>, request: &[u8], answers: &mut Answers) {
    let reply = &mut answers.reply;
    reply.clear();
    // The length, written when the reply is complete.
    reply.extend_from_slice(&[0; 4]);
    write_answer(
        physics,
        request,
        &mut answers.x,
        &mut answers.v,
        &mut answers.a,
        reply,
    );
    // Replies are far below 4 GiB (MAX_FRAME).
    let len = (reply.len() - 4) as u32;
    reply[..4].copy_from_slice(&len.to_le_bytes());
}

/// [`answer_physics`]'s reply after its length: positions and velocities read into `x` and
/// `v`, accelerations computed in `a`.
fn write_answer(
    physics: Option<&Physics>,
    request: &[u8],
    x: &mut Vec<glam::DVec3>,
    v: &mut Vec<glam::DVec3>,
    a: &mut Vec<glam::DVec3>,
    reply: &mut Vec<u8>,
) {
    let refuse = |message: String, reply: &mut Vec<u8>| {
        reply.extend_from_slice(&[to_program::PHYSICS_REPLY, 0]);
        message.put(reply);
    };
    let Some(physics) = physics else {
        return refuse("this method has no Physics".to_string(), reply);
    };
    let parsed = (|| {
        let mut r = wire::Reader::new(request);
        let what = u8::take(&mut r)?;
        read_vecs_into(&mut r, x)?;
        read_vecs_into(&mut r, v)?;
        r.finish()?;
        Ok::<_, wire::WireError>(what)
    })();
    let Ok(what) = parsed else {
        return refuse("unreadable Physics request".to_string(), reply);
    };
    let n = physics.particle_count();
    let name = match what {
        physics_request::ACCELERATIONS => "accelerations",
        physics_request::JACOBIAN_X => "jacobian_x",
        physics_request::JACOBIAN_V => "jacobian_v",
        _ => return refuse(format!("unknown Physics request {what}"), reply),
    };
    if x.len() != n || v.len() != n {
        return refuse(
            format!(
                "Physics::{name}: the system has {n} particles, but x has {} entries and v has {}",
                x.len(),
                v.len()
            ),
            reply,
        );
    }
    // A Jacobian is dense, (3n)² numbers: one that does not fit a frame is refused before it is
    // computed, with the reason.
    let size = 3 * n;
    if what != physics_request::ACCELERATIONS && 8 * size * size + 16 > MAX_FRAME {
        return refuse(jacobian_too_large(n), reply);
    }
    reply.reserve(2 + 8 + 8 * size);
    reply.extend_from_slice(&[to_program::PHYSICS_REPLY, 1]);
    match what {
        physics_request::ACCELERATIONS => {
            // As `Physics::accelerations`, into the kept list; the numbers straight from it.
            a.clear();
            a.resize(n, glam::DVec3::ZERO);
            crate::physics::accelerations(physics.model(), x, v, a);
            size.put(reply);
            for a_i in a.iter() {
                reply.extend_from_slice(&a_i.x.to_le_bytes());
                reply.extend_from_slice(&a_i.y.to_le_bytes());
                reply.extend_from_slice(&a_i.z.to_le_bytes());
            }
        }
        physics_request::JACOBIAN_X => {
            wire::put_slice(physics.jacobian_x(x, v).as_row_major(), reply);
        }
        _ => wire::put_slice(physics.jacobian_v(x, v).as_row_major(), reply),
    }
}

/// Why a Jacobian of `n` particles is not sent: its size against the frame limit, and what a
/// dense matrix of that size would cost the student's program.
#[must_use]
pub fn jacobian_too_large(n: usize) -> String {
    let size = 3 * n;
    format!(
        "a Jacobian of {n} particles is a dense {size} × {size} matrix ({} MiB), more than \
         the {} MiB a message between springlab and your program may hold; implicit Euler \
         with Physics's dense Jacobians is for bodies of at most {} particles",
        (8 * size * size) >> 20,
        MAX_FRAME >> 20,
        largest_jacobian_body()
    )
}

/// The most particles whose dense Jacobian fits one frame.
#[must_use]
pub fn largest_jacobian_body() -> usize {
    let mut n = 1;
    while 8 * (3 * (n + 1)) * (3 * (n + 1)) + 16 <= MAX_FRAME {
        n += 1;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::frames::Scanner;
    use super::process::describe_end;
    use super::{Event, Limits};
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
