//! Protocol framing on the program's stdout: the frames that carry this session's token are
//! cut out and handed over; everything else is the student's printing, counted and dropped.
//! [`Pipes`]: both pipes, used by the calling thread with a deadline.

use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::os::fd::{AsFd, BorrowedFd};
use std::process::{ChildStdin, ChildStdout};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nix::errno::Errno;
use nix::fcntl::{FcntlArg, OFlag, fcntl};
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use springlab_homework::wire::MAX_FRAME;

use super::Event;

/// Cuts frames that start with `pattern` (magic + token) out of the program's stdout, fed in
/// pieces of any size; everything between frames is stray output, counted and dropped.
pub(super) struct Scanner {
    pub(super) pattern: Vec<u8>,
    pub(super) buf: Vec<u8>,
    pub(super) stray: usize,
}

impl Scanner {
    pub(super) fn new(pattern: Vec<u8>) -> Scanner {
        Scanner {
            pattern,
            buf: Vec::new(),
            stray: 0,
        }
    }

    /// The events completed by `bytes`; after an oversized frame nothing more is read.
    #[cfg(test)]
    pub(super) fn push(&mut self, bytes: &[u8]) -> Vec<Event> {
        let mut events = Vec::new();
        self.push_into(bytes, &mut events);
        events
    }

    /// [`Scanner::push`] into `events`. The bytes left over are moved to the front once per
    /// call, not once per frame (a read may hold many frames).
    fn push_into<E: Extend<Event>>(&mut self, bytes: &[u8], events: &mut E) {
        self.buf.extend_from_slice(bytes);
        let header = self.pattern.len() + 4;
        // Where the unread bytes start.
        let mut at = 0;
        loop {
            let found = self.buf[at..]
                .windows(self.pattern.len())
                .position(|w| w == self.pattern.as_slice());
            let Some(start) = found else {
                // Keep a tail that may be the start of the pattern.
                let keep = self.pattern.len() - 1;
                let left = self.buf.len() - at;
                if left > keep {
                    self.stray += left - keep;
                    at = self.buf.len() - keep;
                }
                break;
            };
            self.stray += start;
            at += start;
            if self.buf.len() - at < header {
                break;
            }
            let p = at + self.pattern.len();
            let len = u32::from_le_bytes([
                self.buf[p],
                self.buf[p + 1],
                self.buf[p + 2],
                self.buf[p + 3],
            ]) as usize;
            if len > MAX_FRAME {
                events.extend([Event::Oversized(len)]);
                break;
            }
            if self.buf.len() - at < header + len {
                break;
            }
            events.extend([Event::Frame(
                self.buf[at + header..at + header + len].to_vec(),
            )]);
            at += header + len;
        }
        self.buf.drain(..at);
    }
}

/// The size asked for both pipes (bytes; an unprivileged process may ask up to
/// `/proc/sys/fs/pipe-max-size`, 1 MiB by default), and of one read.
const PIPE_BYTES: i32 = 512 << 10;

/// The program's standard input and output, written and read by the thread that makes the
/// call, each with the call's deadline (`poll`): no thread in between, so a request and its
/// reply cost one wake-up each way (a `Physics` request of the 1000-particle jelly's RK4 comes
/// four times a step). The write end does not block (`O_NONBLOCK`): a program that stops
/// reading holds a write only until the deadline. The program's printing is read only during
/// a call, which is when its code runs.
pub(super) struct Pipes {
    stdin: ChildStdin,
    stdout: ChildStdout,
    scanner: Scanner,
    events: VecDeque<Event>,
    /// Nothing more is read: the output ended, or a frame was oversized.
    done: bool,
    chunk: Vec<u8>,
}

impl Pipes {
    /// The pipes of a program whose replies start with `pattern` (magic + token).
    pub(super) fn new(stdin: ChildStdin, stdout: ChildStdout, pattern: Vec<u8>) -> Pipes {
        // Without it a write larger than the pipe's free space waits for the reader.
        if let Ok(flags) = fcntl(&stdin, FcntlArg::F_GETFL) {
            let flags = OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK;
            let _ = fcntl(&stdin, FcntlArg::F_SETFL(flags));
        }
        // Pipes that hold a whole request or answer of a large body (the 1000-particle jelly's
        // positions and velocities are 48 KB) and several steps' answers: fewer waits and
        // wake-ups on either side. Where the system refuses, the default size stays.
        #[cfg(target_os = "linux")]
        for fd in [stdin.as_fd(), stdout.as_fd()] {
            let _ = fcntl(fd, FcntlArg::F_SETPIPE_SZ(PIPE_BYTES));
        }
        Pipes {
            stdin,
            stdout,
            scanner: Scanner::new(pattern),
            events: VecDeque::new(),
            done: false,
            chunk: vec![0u8; PIPE_BYTES as usize],
        }
    }

    /// Writes `bytes` by `deadline`; false when the program is gone or did not read them in
    /// time (the next [`Pipes::next`] then says which).
    pub(super) fn write(&mut self, bytes: &[u8], deadline: Instant) -> bool {
        let mut done = 0;
        while done < bytes.len() {
            match self.stdin.write(&bytes[done..]) {
                Ok(0) => return false,
                Ok(n) => done += n,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    if !ready(self.stdin.as_fd(), PollFlags::POLLOUT, deadline) {
                        return false;
                    }
                }
                Err(_) => return false,
            }
        }
        true
    }

    /// The next event, or `None` at `deadline`; the printing between frames is added to
    /// `stray`.
    pub(super) fn next(&mut self, deadline: Instant, stray: &AtomicUsize) -> Option<Event> {
        loop {
            if let Some(event) = self.events.pop_front() {
                return Some(event);
            }
            if self.done {
                return Some(Event::Closed);
            }
            if !ready(self.stdout.as_fd(), PollFlags::POLLIN, deadline) {
                return None;
            }
            let n = match self.stdout.read(&mut self.chunk) {
                Ok(0) => {
                    self.done = true;
                    continue;
                }
                Ok(n) => n,
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(_) => {
                    self.done = true;
                    continue;
                }
            };
            let before = self.scanner.stray;
            let queued = self.events.len();
            self.scanner.push_into(&self.chunk[..n], &mut self.events);
            // After an oversized frame nothing more is read.
            self.done |= (self.events.range(queued..)).any(|e| matches!(e, Event::Oversized(_)));
            stray.fetch_add(self.scanner.stray - before, Ordering::Relaxed);
        }
    }
}

/// Waits until `fd` is ready for `flags` (or hung up), by `deadline`; false at the deadline.
fn ready(fd: BorrowedFd<'_>, flags: PollFlags, deadline: Instant) -> bool {
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        // Whole milliseconds, rounded up: a wait never ends before the deadline.
        let ms = i32::try_from(left.as_micros().div_ceil(1000)).unwrap_or(i32::MAX);
        let mut fds = [PollFd::new(fd, flags)];
        match poll(
            &mut fds,
            PollTimeout::try_from(ms).unwrap_or(PollTimeout::MAX),
        ) {
            Ok(n) if n > 0 => return true,
            Ok(_) if left.is_zero() => return false,
            Ok(_) | Err(Errno::EINTR) => {}
            // A descriptor poll cannot wait on: let the read or write report it.
            Err(_) => return true,
        }
    }
}
