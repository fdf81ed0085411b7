//! The byte channel to the grader: frames read from stdin, replies written to stdout with the
//! session's token, and the one question the program asks back ([`ask_grader`]: the grader's
//! physics). Both the serving loop ([`crate::serve`]) and [`crate::physics::Physics`] use it.

use std::cell::RefCell;
use std::io::{Read, Write};

use crate::DVec3;
use crate::wire::{
    MAX_FRAME, Reader, TOKEN_LEN, Wire, WireError, put_slice, reply_frame, to_grader, to_program,
};

thread_local! {
    /// The session token while the loop runs on this thread.
    static TOKEN: RefCell<Option<[u8; TOKEN_LEN]>> = const { RefCell::new(None) };
}

/// Sets the session token of this thread (after the grader's HELLO).
pub(crate) fn set_token(token: [u8; TOKEN_LEN]) {
    TOKEN.with(|t| *t.borrow_mut() = Some(token));
}

/// The next frame from the grader; `None` at the end of its input.
pub(crate) fn read_frame() -> Option<Vec<u8>> {
    let mut input = std::io::stdin().lock();
    let mut len = [0u8; 4];
    input.read_exact(&mut len).ok()?;
    let len = u32::from_le_bytes(len) as usize;
    if len > MAX_FRAME {
        return None;
    }
    let mut payload = vec![0u8; len];
    input.read_exact(&mut payload).ok()?;
    Some(payload)
}

/// Writes one reply; the program ends when the grader is gone.
pub(crate) fn send(token: &[u8; TOKEN_LEN], payload: &[u8]) {
    let mut out = std::io::stdout().lock();
    let written = out
        .write_all(&reply_frame(token, payload))
        .and_then(|()| out.flush());
    if written.is_err() {
        std::process::exit(0);
    }
}

/// Sends one STEP frame: the answer `value` of one step of a STEPS request.
pub(crate) fn send_step(value: &[u8]) {
    if let Some(token) = token() {
        let mut payload = Vec::with_capacity(1 + value.len());
        payload.push(to_grader::STEP);
        payload.extend_from_slice(value);
        send(&token, &payload);
    }
}

/// The session token while the loop runs on this thread.
fn token() -> Option<[u8; TOKEN_LEN]> {
    TOKEN.with(|t| *t.borrow())
}

/// Asks the grader for accelerations (`what` = 0) or a Jacobian (1: J_x, 2: J_v) at `(x, v)`;
/// `expected` numbers come back.
pub(crate) fn ask_grader(what: u8, x: &[DVec3], v: &[DVec3], expected: usize) -> Vec<f64> {
    let Some(token) = token() else {
        panic!(
            "Physics: the grader's physics answers only during a call from the grader, on the \
             thread that received it"
        );
    };
    // One buffer of the exact size, the positions and velocities written straight from the
    // slices (no copies of the lists).
    let mut payload = Vec::with_capacity(2 + 2 * (8 + 24 * x.len()));
    payload.extend_from_slice(&[to_grader::PHYSICS, what]);
    put_slice(x, &mut payload);
    put_slice(v, &mut payload);
    send(&token, &payload);
    let Some(reply) = read_frame() else {
        // The grader stopped listening: nothing left to do.
        std::process::exit(0);
    };
    let mut r = Reader::new(&reply);
    let answer = (|| -> Result<Result<Vec<f64>, String>, WireError> {
        if u8::take(&mut r)? != to_program::PHYSICS_REPLY {
            return Err(WireError("the grader sent something else".to_string()));
        }
        Ok(if bool::take(&mut r)? {
            Ok(Vec::<f64>::take(&mut r)?)
        } else {
            Err(String::take(&mut r)?)
        })
    })();
    match answer {
        Ok(Ok(values)) if values.len() == expected => values,
        Ok(Ok(values)) => panic!(
            "Physics: the grader answered {} numbers, {expected} expected",
            values.len()
        ),
        Ok(Err(message)) => panic!("{message}"),
        Err(e) => panic!("Physics: unreadable answer from the grader: {e}"),
    }
}
