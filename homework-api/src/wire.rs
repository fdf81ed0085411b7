//! The protocol between the grader (the parent) and a homework program (the child).
//!
//! ```text
//! grader → program, on the program's standard input:
//!     frame   = length: u32 LE, payload
//!     HELLO   = 0x01, version: u32, token: 16 bytes           first frame, once
//!     CALL    = 0x02, method: u8, arguments                   one per call of a trait method
//!     PHYSICS_REPLY = 0x03, 1, values: Vec<f64>               answer to a PHYSICS request
//!                   | 0x03, 0, message: String                the request was refused
//!     STEPS   = 0x04, method: u8, count: u32, arguments       an integrator `count` times, each
//!                                                            step from the last one's answer
//!                                                            (version 3 on)
//!     end of input: the program exits
//!
//! program → grader, on the program's standard output:
//!     frame   = MAGIC (8 bytes), token (16 bytes), length: u32 LE, payload
//!     HELLO   = 0x81, version: u32, assignment: String
//!     RESULT  = 0x82, the method's answer                     ends a call
//!     PANIC   = 0x83, message: String                         ends a call: the method panicked
//!     PHYSICS = 0x84, what: u8, x: Vec<DVec3>, v: Vec<DVec3>  an integrator asks for a(x, v)
//!                                                            (0), J_x (1) or J_v (2)
//!     ERROR   = 0x85, message: String                         ends a call: the request was bad
//!     STEP    = 0x86, the method's answer                     one per step of a STEPS request;
//!                                                            after the last, an empty RESULT
//!                                                            (a PANIC after k STEPs: step
//!                                                            k + 1 panicked)
//!
//! values: u8; bool = u8 0/1; u64, f64 little-endian; usize as u64; DVec3 = 3 f64;
//!         Vec<T> and String = u64 count, then the items (UTF-8 bytes); structs field by field;
//!         tuples item by item
//! ```
//!
//! One request, one reply: the grader sends a CALL (or STEPS) and reads frames until RESULT,
//! PANIC or ERROR, answering each PHYSICS request on the way. It writes nothing else meanwhile.
//!
//! # Versions
//!
//! Both HELLOs carry [`VERSION`]. The program answers the grader's HELLO with its own version
//! whatever the grader's is, and the grader talks only to a program of its own version: a
//! program built against another copy of this crate is told which version it has and which the
//! grader speaks, never misread. Version 3 added STEPS (many steps of an integrator in one
//! request, for `springlab lesson N --homework`).
//!
//! # Why the token
//!
//! The program's standard output is shared with the student's code: a `println!` left in a
//! method writes to the same stream. Every reply therefore starts with [`MAGIC`] and a token of
//! 16 random bytes that the grader sends only on the program's standard input, once, at the
//! start. The grader reads a reply only where it finds the magic followed by this session's
//! token; everything else on standard output is the student's printing and is set aside. Stray
//! output can neither split a reply nor be taken for one.
//!
//! The token does not make the program trustworthy, and does not need to: code in the program
//! can do anything the program can, including writing replies, but a reply only ever carries the
//! student's own answer to the call in progress. Scores, the cases, the reference answers, the
//! time limits and the report stay in the grader, which checks every reply it reads (its size,
//! its shape, and that its numbers are what the call asked for) and treats anything else as a
//! wrong answer to that call.

use crate::{
    Body, Bowl, ContactCoefficients, DVec3, Mass, Particle, Plane, Rope, Spring, SpringKind,
    SpringSetup, State,
};

/// Version of this protocol; the grader and the program must agree.
pub const VERSION: u32 = 3;

/// The start of every frame the program writes.
pub const MAGIC: [u8; 8] = [0xFF, b'S', b'P', b'L', b'A', b'B', 0xFE, 0x01];

/// Length of the session token.
pub const TOKEN_LEN: usize = 16;

/// The largest payload either side reads (16 MiB): larger frames are refused unread.
pub const MAX_FRAME: usize = 16 << 20;

/// Kinds of frames from the grader.
pub mod to_program {
    /// First frame: version and token.
    pub const HELLO: u8 = 0x01;
    /// A call of a trait method.
    pub const CALL: u8 = 0x02;
    /// The answer to a PHYSICS request.
    pub const PHYSICS_REPLY: u8 = 0x03;
    /// Many steps of an integrator (version 3 on).
    pub const STEPS: u8 = 0x04;
}

/// Kinds of frames from the program.
pub mod to_grader {
    /// Answer to the HELLO: version and assignment.
    pub const HELLO: u8 = 0x81;
    /// The method's answer.
    pub const RESULT: u8 = 0x82;
    /// The method panicked.
    pub const PANIC: u8 = 0x83;
    /// An integrator asks for accelerations or a Jacobian.
    pub const PHYSICS: u8 = 0x84;
    /// The request could not be served.
    pub const ERROR: u8 = 0x85;
    /// The answer of one step of a STEPS request (version 3 on).
    pub const STEP: u8 = 0x86;
}

/// What a PHYSICS request asks for.
pub mod physics_request {
    /// `a(x, v)`: 3n numbers.
    pub const ACCELERATIONS: u8 = 0;
    /// `J_x = ∂a/∂x`: (3n)² numbers, row-major.
    pub const JACOBIAN_X: u8 = 1;
    /// `J_v = ∂a/∂v`: (3n)² numbers, row-major.
    pub const JACOBIAN_V: u8 = 2;
}

/// The trait methods, one code each. Arguments and answers are listed as `args → answer`.
pub mod method {
    /// `(start, end, nodes, node_mass, stiffness, pinned: Vec<usize>) → Rope`
    pub const ROPE_ROPE: u8 = 1;
    /// `(a, b, stiffness, rest_length) → DVec3`
    pub const ROPE_SPRING_FORCE: u8 = 2;
    /// `Rope → Vec<DVec3>`
    pub const ROPE_SPRING_FORCES: u8 = 3;
    /// `(Rope, dt, inverse_mass: Vec<f64>) → Rope`
    pub const ROPE_EXPLICIT_EULER: u8 = 4;
    /// `(Rope, dt, inverse_mass) → Rope`
    pub const ROPE_SEMI_IMPLICIT_EULER: u8 = 5;
    /// `(Rope, dt, damping, inverse_mass) → Rope`
    pub const ROPE_VERLET: u8 = 6;

    /// `[usize; 3] → Vec<SpringSetup>`
    pub const JELLY_SPRINGS: u8 = 11;
    /// `(xa, xb, stiffness, rest_length) → DVec3`
    pub const JELLY_SPRING_FORCE: u8 = 12;
    /// `(xa, xb, va, vb, damping) → DVec3`
    pub const JELLY_DAMPER_FORCE: u8 = 13;
    /// `(x, v, springs) → Vec<DVec3>`
    pub const JELLY_INTERNAL_FORCES: u8 = 14;
    /// `(Plane, Particle, ContactCoefficients) → Particle`
    pub const JELLY_PLANE_COLLISION: u8 = 15;
    /// `(Bowl, Particle, ContactCoefficients) → Particle`
    pub const JELLY_BOWL_COLLISION: u8 = 16;
    /// `(State, dt, inverse_mass) → State`
    pub const JELLY_EXPLICIT_EULER: u8 = 17;
    /// `(State, dt, inverse_mass) → State`
    pub const JELLY_IMPLICIT_EULER: u8 = 18;
    /// `(State, dt, inverse_mass) → State`
    pub const JELLY_MIDPOINT: u8 = 19;
    /// `(State, dt, inverse_mass) → State`
    pub const JELLY_RK4: u8 = 20;

    /// `usize → Vec<SpringSetup>`
    pub const CLOTH_SPRINGS: u8 = 21;
    /// `(xa, xb, stiffness, rest_length) → DVec3`
    pub const CLOTH_SPRING_FORCE: u8 = 22;
    /// `(xa, xb, va, vb, damping) → DVec3`
    pub const CLOTH_DAMPER_FORCE: u8 = 23;
    /// `(x, v, inverse_mass, springs) → Vec<DVec3>`
    pub const CLOTH_SPRING_ACCELERATIONS: u8 = 24;
    /// `(sphere: Body, radius, particle: Body, restitution) → (Body, Body)`
    pub const CLOTH_SPHERE_COLLISION: u8 = 25;
    /// `(State, dt, inverse_mass) → State`
    pub const CLOTH_EXPLICIT_EULER: u8 = 26;
    /// `(State, dt, inverse_mass) → State`
    pub const CLOTH_IMPLICIT_EULER: u8 = 27;
    /// `(State, dt, inverse_mass) → State`
    pub const CLOTH_MIDPOINT: u8 = 28;
    /// `(State, dt, inverse_mass) → State`
    pub const CLOTH_RK4: u8 = 29;

    /// The integrators: the methods a STEPS request may repeat (each answer is the next
    /// step's first argument).
    #[must_use]
    pub fn is_integrator(m: u8) -> bool {
        matches!(
            m,
            ROPE_EXPLICIT_EULER
                | ROPE_SEMI_IMPLICIT_EULER
                | ROPE_VERLET
                | JELLY_EXPLICIT_EULER..=JELLY_RK4
                | CLOTH_EXPLICIT_EULER..=CLOTH_RK4
        )
    }
}

/// A value that could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WireError(pub String);

impl std::fmt::Display for WireError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for WireError {}

/// Reads values from a payload, checking every length against what is left.
#[derive(Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `bytes`.
    #[must_use]
    pub fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader { bytes, pos: 0 }
    }

    /// Bytes not read yet.
    #[must_use]
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// The next `n` bytes.
    ///
    /// # Errors
    /// When fewer than `n` are left.
    pub fn bytes(&mut self, n: usize) -> Result<&'a [u8], WireError> {
        if n > self.remaining() {
            return Err(WireError(format!(
                "the message ends early: {n} more bytes expected at byte {}, {} left",
                self.pos,
                self.remaining()
            )));
        }
        let out = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    /// The rest of the payload.
    #[must_use]
    pub fn rest(&mut self) -> &'a [u8] {
        let out = &self.bytes[self.pos..];
        self.pos = self.bytes.len();
        out
    }

    /// Succeeds when everything was read.
    ///
    /// # Errors
    /// When bytes are left over.
    pub fn finish(&self) -> Result<(), WireError> {
        if self.remaining() == 0 {
            Ok(())
        } else {
            Err(WireError(format!(
                "{} unexpected bytes after the value",
                self.remaining()
            )))
        }
    }
}

/// A value with a wire form (module docs).
pub trait Wire: Sized {
    /// Appends the value to `out`.
    fn put(&self, out: &mut Vec<u8>);
    /// Reads one value.
    ///
    /// # Errors
    /// When the bytes do not hold one.
    fn take(input: &mut Reader<'_>) -> Result<Self, WireError>;
}

/// The wire form of `value`.
#[must_use]
pub fn encode<T: Wire>(value: &T) -> Vec<u8> {
    let mut out = Vec::new();
    value.put(&mut out);
    out
}

/// The value of `bytes`, which must hold exactly one.
///
/// # Errors
/// When the bytes do not hold one value of type `T`, or hold more.
pub fn decode<T: Wire>(bytes: &[u8]) -> Result<T, WireError> {
    let mut r = Reader::new(bytes);
    let value = T::take(&mut r)?;
    r.finish()?;
    Ok(value)
}

impl Wire for u8 {
    fn put(&self, out: &mut Vec<u8>) {
        out.push(*self);
    }
    fn take(input: &mut Reader<'_>) -> Result<u8, WireError> {
        Ok(input.bytes(1)?[0])
    }
}

impl Wire for bool {
    fn put(&self, out: &mut Vec<u8>) {
        out.push(u8::from(*self));
    }
    fn take(input: &mut Reader<'_>) -> Result<bool, WireError> {
        match u8::take(input)? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(WireError(format!("a bool must be 0 or 1, not {b}"))),
        }
    }
}

impl Wire for u32 {
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn take(input: &mut Reader<'_>) -> Result<u32, WireError> {
        let b = input.bytes(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

impl Wire for u64 {
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn take(input: &mut Reader<'_>) -> Result<u64, WireError> {
        let b = input.bytes(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
}

impl Wire for usize {
    fn put(&self, out: &mut Vec<u8>) {
        (*self as u64).put(out);
    }
    fn take(input: &mut Reader<'_>) -> Result<usize, WireError> {
        let v = u64::take(input)?;
        usize::try_from(v).map_err(|_| WireError(format!("index {v} does not fit a usize")))
    }
}

impl Wire for f64 {
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn take(input: &mut Reader<'_>) -> Result<f64, WireError> {
        Ok(f64::from_bits(u64::take(input)?))
    }
}

impl Wire for DVec3 {
    fn put(&self, out: &mut Vec<u8>) {
        let mut b = [0u8; 24];
        b[..8].copy_from_slice(&self.x.to_le_bytes());
        b[8..16].copy_from_slice(&self.y.to_le_bytes());
        b[16..].copy_from_slice(&self.z.to_le_bytes());
        out.extend_from_slice(&b);
    }
    fn take(input: &mut Reader<'_>) -> Result<DVec3, WireError> {
        // One length check for the three numbers (a body's lists are thousands of vectors).
        let b = input.bytes(24)?;
        let f = |i: usize| {
            let mut a = [0u8; 8];
            a.copy_from_slice(&b[8 * i..8 * i + 8]);
            f64::from_le_bytes(a)
        };
        Ok(DVec3::new(f(0), f(1), f(2)))
    }
}

impl Wire for String {
    fn put(&self, out: &mut Vec<u8>) {
        self.len().put(out);
        out.extend_from_slice(self.as_bytes());
    }
    fn take(input: &mut Reader<'_>) -> Result<String, WireError> {
        let n = usize::take(input)?;
        let bytes = input.bytes(n)?;
        Ok(String::from_utf8_lossy(bytes).into_owned())
    }
}

/// Appends `items` in the wire form of a `Vec<T>` (count, then the items) without copying
/// them into a list first.
pub fn put_slice<T: Wire>(items: &[T], out: &mut Vec<u8>) {
    out.reserve(8 + std::mem::size_of_val(items));
    items.len().put(out);
    for item in items {
        item.put(out);
    }
}

impl<T: Wire> Wire for Vec<T> {
    fn put(&self, out: &mut Vec<u8>) {
        put_slice(self, out);
    }
    fn take(input: &mut Reader<'_>) -> Result<Vec<T>, WireError> {
        let n = usize::take(input)?;
        // Every item takes at least one byte: a count larger than what is left is a lie, and
        // must not reserve memory.
        if n > input.remaining() {
            return Err(WireError(format!(
                "a list of {n} items in {} bytes",
                input.remaining()
            )));
        }
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            out.push(T::take(input)?);
        }
        Ok(out)
    }
}

impl<T: Wire + Copy + Default, const N: usize> Wire for [T; N] {
    fn put(&self, out: &mut Vec<u8>) {
        for item in self {
            item.put(out);
        }
    }
    fn take(input: &mut Reader<'_>) -> Result<[T; N], WireError> {
        let mut out = [T::default(); N];
        for item in &mut out {
            *item = T::take(input)?;
        }
        Ok(out)
    }
}

macro_rules! wire_tuple {
    ($($t:ident $i:tt),+) => {
        impl<$($t: Wire),+> Wire for ($($t,)+) {
            fn put(&self, out: &mut Vec<u8>) {
                $(self.$i.put(out);)+
            }
            fn take(input: &mut Reader<'_>) -> Result<Self, WireError> {
                Ok(($($t::take(input)?,)+))
            }
        }
    };
}

wire_tuple!(A 0, B 1);
wire_tuple!(A 0, B 1, C 2);
wire_tuple!(A 0, B 1, C 2, D 3);
wire_tuple!(A 0, B 1, C 2, D 3, E 4);
wire_tuple!(A 0, B 1, C 2, D 3, E 4, F 5);

macro_rules! wire_struct {
    ($name:ident { $($field:ident),+ }) => {
        impl Wire for $name {
            fn put(&self, out: &mut Vec<u8>) {
                $(self.$field.put(out);)+
            }
            fn take(input: &mut Reader<'_>) -> Result<$name, WireError> {
                Ok($name { $($field: Wire::take(input)?),+ })
            }
        }
    };
}

wire_struct!(Mass {
    position,
    velocity,
    last_position,
    mass,
    pinned
});
wire_struct!(Spring {
    a,
    b,
    rest_length,
    stiffness,
    damping
});
wire_struct!(Rope { masses, springs });
wire_struct!(State { x, v });
wire_struct!(SpringSetup { a, b, kind });
wire_struct!(Particle { x, v, force });
wire_struct!(Plane { point, normal });
wire_struct!(Bowl {
    center,
    radius,
    rim_height
});
wire_struct!(ContactCoefficients {
    epsilon,
    restitution,
    friction
});
wire_struct!(Body { x, v, inverse_mass });

impl Wire for SpringKind {
    fn put(&self, out: &mut Vec<u8>) {
        out.push(match self {
            SpringKind::Struct => 0,
            SpringKind::Shear => 1,
            SpringKind::Bend => 2,
        });
    }
    fn take(input: &mut Reader<'_>) -> Result<SpringKind, WireError> {
        match u8::take(input)? {
            0 => Ok(SpringKind::Struct),
            1 => Ok(SpringKind::Shear),
            2 => Ok(SpringKind::Bend),
            k => Err(WireError(format!("unknown spring kind {k}"))),
        }
    }
}

/// A frame from the grader: the length, then the payload.
#[must_use]
pub fn request_frame(payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(4 + payload.len());
    // Payloads are far below 4 GiB (MAX_FRAME).
    (payload.len() as u32).put(&mut out);
    out.extend_from_slice(payload);
    out
}

/// A frame from the program: magic, token, length, payload.
#[must_use]
pub fn reply_frame(token: &[u8; TOKEN_LEN], payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(MAGIC.len() + TOKEN_LEN + 4 + payload.len());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(token);
    (payload.len() as u32).put(&mut out);
    out.extend_from_slice(payload);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip() {
        let rope = Rope {
            masses: vec![Mass {
                position: DVec3::new(1.0, -2.0, 0.5),
                velocity: DVec3::X,
                last_position: DVec3::NAN,
                mass: 2.0,
                pinned: true,
            }],
            springs: vec![Spring {
                a: 0,
                b: 7,
                rest_length: 1.5,
                stiffness: 100.0,
                damping: 0.0,
            }],
        };
        let args = (rope.clone(), 0.01, vec![1.0, 0.0]);
        let back: (Rope, f64, Vec<f64>) = decode(&encode(&args)).expect("decodes");
        assert_eq!(back.0.springs, rope.springs);
        assert!(back.0.masses[0].last_position.is_nan());
        assert_eq!(back.2, vec![1.0, 0.0]);
        let setup = vec![SpringSetup {
            a: 3,
            b: 4,
            kind: SpringKind::Bend,
        }];
        assert_eq!(decode::<Vec<SpringSetup>>(&encode(&setup)), Ok(setup));
    }

    #[test]
    fn lies_about_lengths_are_refused_without_allocating() {
        // A list claiming 2^60 entries in 8 bytes.
        let mut bytes = encode(&(1u64 << 60));
        bytes.extend_from_slice(&[0; 8]);
        assert!(decode::<Vec<f64>>(&bytes).is_err());
        assert!(decode::<DVec3>(&[0; 23]).is_err());
        assert!(decode::<f64>(&[0; 9]).is_err(), "trailing bytes");
        assert!(decode::<bool>(&[2]).is_err());
        assert!(decode::<SpringKind>(&[3]).is_err());
    }
}
