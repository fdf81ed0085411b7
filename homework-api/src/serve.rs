//! The program's side of the protocol ([`crate::wire`]): read a call, run the student's method,
//! write the answer; answer nothing else.
//!
//! The loop runs on the main thread. Each call runs under `catch_unwind`, so a panic becomes a
//! PANIC reply and the program serves the next call. `std::process::exit`, an abort, a stack
//! overflow or running out of memory end the program; the grader notices the missing reply and
//! starts a new program for the next call.

use std::cell::RefCell;
use std::io::IsTerminal;
use std::panic::{self, AssertUnwindSafe};
use std::process::ExitCode;

use crate::channel::{read_frame, send, send_step, set_token};
use crate::physics::Physics;
use crate::wire::{
    Reader, TOKEN_LEN, VERSION, Wire, WireError, encode, method, to_grader, to_program,
};
use crate::{
    Body, Bowl, ClothHomework, ContactCoefficients, DVec3, JellyHomework, Particle, Plane, Rope,
    RopeHomework, Spring, State,
};

thread_local! {
    /// The message and location of the last panic on this thread.
    static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// The arguments of a call: exactly one value of type `T`.
fn args<T: Wire>(r: &mut Reader<'_>) -> Result<T, WireError> {
    let value = T::take(r)?;
    r.finish()?;
    Ok(value)
}

fn unknown(m: u8, assignment: &str) -> WireError {
    WireError(format!(
        "method {m} is not part of the {assignment} homework"
    ))
}

/// Runs one call: `(method, steps, arguments) → the answer's bytes`; `steps` is `None` for a
/// CALL and the count of a STEPS request (an integrator only).
type Dispatch<'d> = dyn FnMut(u8, Option<u32>, &mut Reader<'_>) -> Result<Vec<u8>, WireError> + 'd;

/// Steps `value` once (a CALL: the answer is the new value) or `count` times, each step from the
/// last one's answer (STEPS: each step's value goes out in a STEP frame as soon as it is
/// computed; the answer, the final RESULT, is empty).
fn steps<T: Wire>(count: Option<u32>, mut value: T, mut step: impl FnMut(&mut T)) -> Vec<u8> {
    let Some(count) = count else {
        step(&mut value);
        return encode(&value);
    };
    let mut out = Vec::new();
    for _ in 0..count {
        step(&mut value);
        out.clear();
        value.put(&mut out);
        send_step(&out);
    }
    Vec::new()
}

/// The loop (module docs); `dispatch(method, arguments)` runs one call.
fn serve(assignment: &str, dispatch: &mut Dispatch<'_>) -> ExitCode {
    if std::io::stdin().is_terminal() {
        eprintln!(
            "This program answers springlab's grader, which runs it: use `cargo test` in this \
             crate, or `springlab grade DIR`."
        );
        return ExitCode::from(2);
    }
    let Some(hello) = read_frame() else {
        return ExitCode::FAILURE;
    };
    let mut r = Reader::new(&hello);
    let parsed = (|| -> Result<(u32, [u8; TOKEN_LEN]), WireError> {
        if u8::take(&mut r)? != to_program::HELLO {
            return Err(WireError("the first frame is not a greeting".to_string()));
        }
        let version = u32::take(&mut r)?;
        let token = <[u8; TOKEN_LEN]>::take(&mut r)?;
        Ok((version, token))
    })();
    let Ok((_their_version, token)) = parsed else {
        return ExitCode::FAILURE;
    };
    set_token(token);
    let mut greeting = vec![to_grader::HELLO];
    VERSION.put(&mut greeting);
    assignment.to_string().put(&mut greeting);
    send(&token, &greeting);
    // Panics become PANIC replies: record them instead of printing.
    panic::set_hook(Box::new(|info| {
        let location = info
            .location()
            .map(|l| format!(" at {}:{}:{}", l.file(), l.line(), l.column()))
            .unwrap_or_default();
        let message = panic_text(info.payload());
        LAST_PANIC.with(|p| *p.borrow_mut() = Some(format!("{message}{location}")));
    }));
    while let Some(frame) = read_frame() {
        let call = match frame.as_slice() {
            [to_program::CALL, m, arguments @ ..] => Ok((*m, None, arguments)),
            [to_program::STEPS, m, c0, c1, c2, c3, arguments @ ..] => {
                if method::is_integrator(*m) {
                    Ok((
                        *m,
                        Some(u32::from_le_bytes([*c0, *c1, *c2, *c3])),
                        arguments,
                    ))
                } else {
                    Err(format!(
                        "method {m} is not an integrator: it cannot be stepped"
                    ))
                }
            }
            _ => Err("expected a call".to_string()),
        };
        let reply = match call {
            Ok((m, count, arguments)) => {
                let outcome = panic::catch_unwind(AssertUnwindSafe(|| {
                    dispatch(m, count, &mut Reader::new(arguments))
                }));
                match outcome {
                    Ok(Ok(answer)) => {
                        let mut reply = Vec::with_capacity(1 + answer.len());
                        reply.push(to_grader::RESULT);
                        reply.extend_from_slice(&answer);
                        reply
                    }
                    Ok(Err(e)) => {
                        let mut reply = vec![to_grader::ERROR];
                        e.0.put(&mut reply);
                        reply
                    }
                    Err(payload) => {
                        let message = LAST_PANIC
                            .with(|p| p.borrow_mut().take())
                            .unwrap_or_else(|| panic_text(payload.as_ref()));
                        let mut reply = vec![to_grader::PANIC];
                        message.put(&mut reply);
                        reply
                    }
                }
            }
            Err(why) => {
                let mut reply = vec![to_grader::ERROR];
                why.put(&mut reply);
                reply
            }
        };
        send(&token, &reply);
    }
    ExitCode::SUCCESS
}

/// Serves a rope homework to the grader (the `main` of a rope crate's program).
pub fn serve_rope<H: RopeHomework>(homework: H) -> ExitCode {
    serve("rope", &mut |m, count, r| {
        Ok(match m {
            method::ROPE_ROPE => {
                let (start, end, nodes, node_mass, stiffness, pinned): (
                    DVec3,
                    DVec3,
                    usize,
                    f64,
                    f64,
                    Vec<usize>,
                ) = args(r)?;
                encode(&homework.rope(start, end, nodes, node_mass, stiffness, &pinned))
            }
            method::ROPE_SPRING_FORCE => {
                let (a, b, k, l): (DVec3, DVec3, f64, f64) = args(r)?;
                encode(&homework.spring_force(a, b, k, l))
            }
            method::ROPE_SPRING_FORCES => {
                let rope: Rope = args(r)?;
                encode(&homework.spring_forces(&rope))
            }
            method::ROPE_EXPLICIT_EULER => {
                let (rope, dt, w): (Rope, f64, Vec<f64>) = args(r)?;
                steps(count, rope, |rope| {
                    homework.explicit_euler(rope, dt, &Physics::grader(w.clone()));
                })
            }
            method::ROPE_SEMI_IMPLICIT_EULER => {
                let (rope, dt, w): (Rope, f64, Vec<f64>) = args(r)?;
                steps(count, rope, |rope| {
                    homework.semi_implicit_euler(rope, dt, &Physics::grader(w.clone()));
                })
            }
            method::ROPE_VERLET => {
                let (rope, dt, damping, w): (Rope, f64, f64, Vec<f64>) = args(r)?;
                steps(count, rope, |rope| {
                    homework.verlet(rope, dt, damping, &Physics::grader(w.clone()));
                })
            }
            other => return Err(unknown(other, "rope")),
        })
    })
}

/// One step (or `count`) of an integrator on a state: `(State, dt, inverse_mass) → State`.
fn step(
    count: Option<u32>,
    r: &mut Reader<'_>,
    f: impl Fn(&mut State, f64, &Physics),
) -> Result<Vec<u8>, WireError> {
    let (state, dt, w): (State, f64, Vec<f64>) = args(r)?;
    Ok(steps(count, state, |s| {
        f(s, dt, &Physics::grader(w.clone()))
    }))
}

/// Serves a jelly homework to the grader (the `main` of a jelly crate's program).
pub fn serve_jelly<H: JellyHomework>(homework: H) -> ExitCode {
    let hw = &homework;
    serve("jelly", &mut |m, count, r| {
        Ok(match m {
            method::JELLY_SPRINGS => {
                let counts: [usize; 3] = args(r)?;
                encode(&hw.springs(counts))
            }
            method::JELLY_SPRING_FORCE => {
                let (a, b, k, l): (DVec3, DVec3, f64, f64) = args(r)?;
                encode(&hw.spring_force(a, b, k, l))
            }
            method::JELLY_DAMPER_FORCE => {
                let (xa, xb, va, vb, kd): (DVec3, DVec3, DVec3, DVec3, f64) = args(r)?;
                encode(&hw.damper_force(xa, xb, va, vb, kd))
            }
            method::JELLY_INTERNAL_FORCES => {
                let (x, v, springs): (Vec<DVec3>, Vec<DVec3>, Vec<Spring>) = args(r)?;
                encode(&hw.internal_forces(&x, &v, &springs))
            }
            method::JELLY_PLANE_COLLISION => {
                let (plane, mut p, c): (Plane, Particle, ContactCoefficients) = args(r)?;
                hw.plane_collision(&plane, &mut p, &c);
                encode(&p)
            }
            method::JELLY_BOWL_COLLISION => {
                let (bowl, mut p, c): (Bowl, Particle, ContactCoefficients) = args(r)?;
                hw.bowl_collision(&bowl, &mut p, &c);
                encode(&p)
            }
            method::JELLY_EXPLICIT_EULER => step(count, r, |s, dt, p| hw.explicit_euler(s, dt, p))?,
            method::JELLY_IMPLICIT_EULER => step(count, r, |s, dt, p| hw.implicit_euler(s, dt, p))?,
            method::JELLY_MIDPOINT => step(count, r, |s, dt, p| hw.midpoint(s, dt, p))?,
            method::JELLY_RK4 => step(count, r, |s, dt, p| hw.rk4(s, dt, p))?,
            other => return Err(unknown(other, "jelly")),
        })
    })
}

/// Serves a cloth homework to the grader (the `main` of a cloth crate's program).
pub fn serve_cloth<H: ClothHomework>(homework: H) -> ExitCode {
    let hw = &homework;
    serve("cloth", &mut |m, count, r| {
        Ok(match m {
            method::CLOTH_SPRINGS => {
                let n: usize = args(r)?;
                encode(&hw.springs(n))
            }
            method::CLOTH_SPRING_FORCE => {
                let (a, b, k, l): (DVec3, DVec3, f64, f64) = args(r)?;
                encode(&hw.spring_force(a, b, k, l))
            }
            method::CLOTH_DAMPER_FORCE => {
                let (xa, xb, va, vb, kd): (DVec3, DVec3, DVec3, DVec3, f64) = args(r)?;
                encode(&hw.damper_force(xa, xb, va, vb, kd))
            }
            method::CLOTH_SPRING_ACCELERATIONS => {
                let (x, v, w, springs): (Vec<DVec3>, Vec<DVec3>, Vec<f64>, Vec<Spring>) = args(r)?;
                encode(&hw.spring_accelerations(&x, &v, &w, &springs))
            }
            method::CLOTH_SPHERE_COLLISION => {
                let (mut sphere, radius, mut particle, e): (Body, f64, Body, f64) = args(r)?;
                hw.sphere_collision(&mut sphere, radius, &mut particle, e);
                encode(&(sphere, particle))
            }
            method::CLOTH_EXPLICIT_EULER => step(count, r, |s, dt, p| hw.explicit_euler(s, dt, p))?,
            method::CLOTH_IMPLICIT_EULER => step(count, r, |s, dt, p| hw.implicit_euler(s, dt, p))?,
            method::CLOTH_MIDPOINT => step(count, r, |s, dt, p| hw.midpoint(s, dt, p))?,
            method::CLOTH_RK4 => step(count, r, |s, dt, p| hw.rk4(s, dt, p))?,
            other => return Err(unknown(other, "cloth")),
        })
    })
}
