//! Protocol framing on the program's stdout: the frames that carry this session's token are
//! cut out and handed over; everything else is the student's printing, counted and dropped.

use std::io::Read;
use std::process::ChildStdout;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

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

/// Reads the program's stdout through a [`Scanner`] and hands the frames over.
pub(super) fn read_replies(
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
