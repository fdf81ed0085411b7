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
    pub(super) fn push(&mut self, bytes: &[u8]) -> Vec<Event> {
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
        Pipes {
            stdin,
            stdout,
            scanner: Scanner::new(pattern),
            events: VecDeque::new(),
            done: false,
            chunk: vec![0u8; 64 << 10],
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
            for event in self.scanner.push(&self.chunk[..n]) {
                // After an oversized frame nothing more is read.
                self.done |= matches!(event, Event::Oversized(_));
                self.events.push_back(event);
            }
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
