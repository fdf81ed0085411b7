//! The byte channel to the grader: frames read from stdin, replies written to stdout with the
//! session's token, and the one question the program asks back ([`ask_grader`]: the grader's
//! physics). Both the serving loop ([`crate::serve`]) and [`crate::physics::Physics`] use it.

use std::cell::RefCell;
use std::fs::File;
use std::io::{Read, Write};

use crate::DVec3;
use crate::wire::{
    MAGIC, MAX_FRAME, Reader, TOKEN_LEN, Wire, WireError, put_slice, to_grader, to_program,
};

thread_local! {
    /// The session token while the loop runs on this thread.
    static TOKEN: RefCell<Option<[u8; TOKEN_LEN]>> = const { RefCell::new(None) };
    /// The frame being written (kept between frames: no allocation per reply).
    static OUT: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
    /// The grader's answers to `Physics` (kept between requests).
    static ANSWER: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
    /// Standard output written directly (a copy of its descriptor), past the line buffer of
    /// `std::io::stdout`, which would scan every reply for line ends; `None` where it cannot be
    /// had.
    static RAW_OUT: Option<File> = raw_stdout();
}

/// A second handle to standard output, or `None`.
fn raw_stdout() -> Option<File> {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        std::io::stdout()
            .as_fd()
            .try_clone_to_owned()
            .ok()
            .map(File::from)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Sets the session token of this thread (after the grader's HELLO).
pub(crate) fn set_token(token: [u8; TOKEN_LEN]) {
    TOKEN.with(|t| *t.borrow_mut() = Some(token));
}

/// The next frame from the grader; `None` at the end of its input.
pub(crate) fn read_frame() -> Option<Vec<u8>> {
    let mut payload = Vec::new();
    read_frame_into(&mut payload).then_some(payload)
}

/// The next frame from the grader into `payload` (its memory reused); false at the end of its
/// input.
fn read_frame_into(payload: &mut Vec<u8>) -> bool {
    let mut input = std::io::stdin().lock();
    let mut len = [0u8; 4];
    if input.read_exact(&mut len).is_err() {
        return false;
    }
    let len = u32::from_le_bytes(len) as usize;
    if len > MAX_FRAME {
        return false;
    }
    payload.clear();
    payload.resize(len, 0);
    input.read_exact(payload).is_ok()
}

/// Writes one reply; the program ends when the grader is gone.
pub(crate) fn send(token: &[u8; TOKEN_LEN], payload: &[u8]) {
    send_parts(token, &[payload]);
}

/// Writes one reply whose payload is `parts` one after another, in one write of one buffer
/// kept between replies; the program ends when the grader is gone.
fn send_parts(token: &[u8; TOKEN_LEN], parts: &[&[u8]]) {
    let len: usize = parts.iter().map(|p| p.len()).sum();
    let written = OUT.with(|out| {
        let mut out = out.borrow_mut();
        out.clear();
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(token);
        (len as u32).put(&mut out);
        for part in parts {
            out.extend_from_slice(part);
        }
        // The student's printing first, in order.
        let mut stdout = std::io::stdout().lock();
        stdout.flush()?;
        RAW_OUT.with(|raw| match raw {
            Some(file) => (&*file).write_all(&out),
            None => stdout.write_all(&out).and_then(|()| stdout.flush()),
        })
    });
    if written.is_err() {
        std::process::exit(0);
    }
}

/// Sends one STEP frame: the answer `value` of one step of a STEPS request.
pub(crate) fn send_step(value: &[u8]) {
    if let Some(token) = token() {
        send_parts(&token, &[&[to_grader::STEP], value]);
    }
}

/// The session token while the loop runs on this thread.
fn token() -> Option<[u8; TOKEN_LEN]> {
    TOKEN.with(|t| *t.borrow())
}

/// Asks the grader for accelerations (`what` = 0) or a Jacobian (1: J_x, 2: J_v) at `(x, v)`;
/// `expected` numbers come back.
pub(crate) fn ask_grader(what: u8, x: &[DVec3], v: &[DVec3], expected: usize) -> Vec<f64> {
    ask_grader_as(what, x, v, expected, |bytes| {
        bytes
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
            .collect()
    })
}

/// The accelerations at `(x, v)` from the grader, read straight into vectors.
pub(crate) fn ask_accelerations(x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
    let f = |b: &[u8]| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]);
    ask_grader_as(
        crate::wire::physics_request::ACCELERATIONS,
        x,
        v,
        3 * x.len(),
        |bytes| {
            bytes
                .chunks_exact(24)
                .map(|b| DVec3::new(f(&b[..8]), f(&b[8..16]), f(&b[16..])))
                .collect()
        },
    )
}

/// [`ask_grader`] with the answer's `expected` numbers (little-endian `f64`) read by `read`.
fn ask_grader_as<T>(
    what: u8,
    x: &[DVec3],
    v: &[DVec3],
    expected: usize,
    read: impl FnOnce(&[u8]) -> T,
) -> T {
    let Some(token) = token() else {
        panic!(
            "Physics: the grader's physics answers only during a call from the grader, on the \
             thread that received it"
        );
    };
    // The positions and velocities written straight from the slices (no copies of the lists)
    // into a buffer kept between requests.
    ANSWER.with(|buffer| {
        let mut buffer = buffer.borrow_mut();
        buffer.clear();
        buffer.extend_from_slice(&[to_grader::PHYSICS, what]);
        put_slice(x, &mut buffer);
        put_slice(v, &mut buffer);
        send(&token, &buffer);
        if !read_frame_into(&mut buffer) {
            // The grader stopped listening: nothing left to do.
            std::process::exit(0);
        }
        answer_of(&buffer, expected, read)
    })
}

/// The numbers of the grader's reply `reply`, read by `read`; a refusal or a malformed reply
/// panics with its reason.
fn answer_of<T>(reply: &[u8], expected: usize, read: impl FnOnce(&[u8]) -> T) -> T {
    let mut r = Reader::new(reply);
    let answer = (|| -> Result<Result<&[u8], String>, WireError> {
        if u8::take(&mut r)? != to_program::PHYSICS_REPLY {
            return Err(WireError("the grader sent something else".to_string()));
        }
        Ok(if bool::take(&mut r)? {
            let n = usize::take(&mut r)?;
            if n != expected {
                return Ok(Err(format!(
                    "Physics: the grader answered {n} numbers, {expected} expected"
                )));
            }
            let bytes = r.bytes(
                n.checked_mul(8)
                    .ok_or_else(|| WireError(format!("a list of {n} numbers")))?,
            )?;
            r.finish()?;
            Ok(bytes)
        } else {
            Err(String::take(&mut r)?)
        })
    })();
    match answer {
        Ok(Ok(values)) => read(values),
        Ok(Err(message)) => panic!("{message}"),
        Err(e) => panic!("Physics: unreadable answer from the grader: {e}"),
    }
}
