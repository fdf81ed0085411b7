//! Checks shared by the assignments: random cases, comparisons with tolerances, feedback text,
//! and the force, spring set-up and integrator checks that the jelly and the cloth (and partly
//! the rope) have in common.
//!
//! # Tolerances
//!
//! ```text
//! |got - expected| ≤ rel · (|expected| + scale)
//! ```
//! where `rel = 1e-9` for a single evaluation or step (round-off differences of a correct
//! implementation are ~1e-15 relative) and `scale` is the size of the quantity in the case (for
//! a force `k_s L0`, for a position 1 m). Runs of many steps and Jacobian-based solves use looser
//! `rel` stated at each check. Measured convergence orders are fitted by least squares to the
//! errors at four step sizes and accepted in a band around the method's order.

use std::collections::BTreeSet;

use glam::DVec3;

use super::assignments::{SpringSetup, State};
use super::reference::model_of;
use super::report::Feedback;
use super::runner::{CheckResult, Failure, set_case};
use super::system::Physics;
use crate::physics::{Model, SpringKind};
use crate::random::XorShift64Star;
use crate::scene::builder::Builder;

/// Relative tolerance of one evaluation or one step.
pub(crate) const REL: f64 = 1e-9;

/// A small deterministic pseudo-random generator ([`XorShift64Star`]) seeded per check.
pub(crate) struct Rng(XorShift64Star);

impl Rng {
    /// A generator for check `salt` under the run's `seed`.
    pub fn new(seed: u64, salt: u64) -> Rng {
        // SplitMix64 of the mix, so that nearby seeds give unrelated streams; never zero.
        let mut z = seed ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Rng(XorShift64Star::new(z | 1))
    }

    /// A float in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.0.unit()
    }

    /// An integer in `0..n` (`n > 0`).
    pub fn index(&mut self, n: usize) -> usize {
        ((self.range(0.0, 1.0) * n as f64) as usize).min(n - 1)
    }

    /// A vector with components in `[-r, r)`.
    pub fn vec(&mut self, r: f64) -> DVec3 {
        DVec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }

    /// A unit vector (uniform on the sphere).
    pub fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.vec(1.0);
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }

    /// A unit vector perpendicular to `n`.
    pub fn perpendicular(&mut self, n: DVec3) -> DVec3 {
        loop {
            let u = self.unit();
            let t = u - u.dot(n) * n;
            if t.length() > 0.2 {
                return t.normalize();
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Text

/// A number for feedback: 7 significant digits, exponent form when very small or large.
pub(crate) fn num(x: f64) -> String {
    if x == 0.0 {
        return "0".to_string();
    }
    if !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if (1e-3..1e7).contains(&a) {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{x:.6e}")
    }
}

/// A vector for feedback: `(x, y, z)`.
pub(crate) fn vec3(v: DVec3) -> String {
    format!("({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

/// A wrong answer.
pub(crate) fn wrong(
    input: impl Into<String>,
    expected: impl Into<String>,
    got: impl Into<String>,
    hint: impl Into<String>,
) -> Failure {
    Failure::Wrong(Feedback {
        input: input.into(),
        expected: expected.into(),
        got: got.into(),
        hint: hint.into(),
    })
}

/// `Err(NotFinite)` when any component of `values` is NaN or infinite.
pub(crate) fn finite(what: &str, input: &str, values: &[DVec3]) -> CheckResult {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Failure::NotFinite(Feedback {
            input: input.to_string(),
            expected: "finite numbers".to_string(),
            got: format!("{what}[{i}] = {}", vec3(values[i])),
            hint: "a division by a zero length, or a step that blew up; NaN is never worth points"
                .to_string(),
        })),
    }
}

/// `Err(NotFinite)` when `value` is NaN or infinite.
pub(crate) fn finite1(what: &str, input: &str, value: DVec3) -> CheckResult {
    finite(what, input, &[value])
}

/// True when `got` is within `rel · (|want| + scale)` of `want`.
pub(crate) fn close(got: DVec3, want: DVec3, rel: f64, scale: f64) -> bool {
    (got - want).length() <= rel * (want.length() + scale)
}

/// The index of the first entry of `got` not close to `want` (or the first missing one).
pub(crate) fn first_mismatch(got: &[DVec3], want: &[DVec3], rel: f64, scale: f64) -> Option<usize> {
    if got.len() != want.len() {
        return Some(got.len().min(want.len()));
    }
    (0..want.len()).find(|&i| !close(got[i], want[i], rel, scale))
}

/// What is recognisably wrong with `got` compared with `want`: zero, the opposite sign, or the
/// right direction with the wrong length.
pub(crate) fn diagnose(got: DVec3, want: DVec3) -> Option<String> {
    let (g, w) = (got.length(), want.length());
    if g == 0.0 && w > 0.0 {
        return Some("it is zero (is the TODO implemented?)".to_string());
    }
    if w > 0.0 && g > 0.0 {
        let cos = got.dot(want) / (g * w);
        if cos < -0.999_999 && (g / w - 1.0).abs() < 1e-6 {
            return Some("it has the opposite sign (direction flipped)".to_string());
        }
        if cos > 0.999_999 {
            return Some(format!(
                "right direction, but {} times the expected length",
                num(g / w)
            ));
        }
    }
    None
}

/// [`diagnose`], then the `formula` to compare with.
pub(crate) fn vector_hint(got: DVec3, want: DVec3, formula: &str) -> String {
    match diagnose(got, want) {
        Some(d) => format!("{d}; expected {formula}"),
        None => format!("expected {formula}"),
    }
}

/// Lists the first `n` entries, for feedback.
fn sample<T>(items: &[T], n: usize, show: impl Fn(&T) -> String) -> String {
    let mut parts: Vec<String> = items.iter().take(n).map(show).collect();
    if items.len() > n {
        parts.push("…".to_string());
    }
    parts.join(", ")
}

// ---------------------------------------------------------------------------------------------
// Forces

/// A pair-force function: `(x_a, x_b, v_a, v_b, coefficient, rest_length) -> f_a`.
pub(crate) type PairForce<'a> = &'a dyn Fn(DVec3, DVec3, DVec3, DVec3, f64, f64) -> DVec3;

/// Hooke's law on random pairs, stretched (`stretched`) or compressed, against `reference`.
pub(crate) fn check_hooke(
    student: PairForce<'_>,
    reference: PairForce<'_>,
    rng: &mut Rng,
    stretched: bool,
) -> CheckResult {
    for _ in 0..20 {
        let xa = rng.vec(2.0);
        let rest = rng.range(0.2, 2.0);
        let factor = if stretched {
            rng.range(1.1, 2.0)
        } else {
            rng.range(0.3, 0.9)
        };
        let xb = xa + rng.unit() * rest * factor;
        let k = rng.range(10.0, 5000.0);
        let zero = DVec3::ZERO;
        let input = format!(
            "x_a = {}, x_b = {}, k_s = {} N/m, rest length {} m ({} to {} m)",
            vec3(xa),
            vec3(xb),
            num(k),
            num(rest),
            if stretched { "stretched" } else { "compressed" },
            num((xb - xa).length())
        );
        let want = reference(xa, xb, zero, zero, k, rest);
        set_case(&input);
        let got = student(xa, xb, zero, zero, k, rest);
        finite1("f_a", &input, got)?;
        if !close(got, want, REL, k * rest) {
            return Err(wrong(
                input,
                format!("f_a = {} N", vec3(want)),
                format!("f_a = {} N", vec3(got)),
                vector_hint(
                    got,
                    want,
                    "f_a = -k_s (|x_a - x_b| - L0) (x_a - x_b)/|x_a - x_b|: pulls a towards b when stretched",
                ),
            ));
        }
    }
    Ok(())
}

/// The damper on random pairs (`rotation = false`), or on pairs whose relative velocity is
/// perpendicular to the spring, a rigid rotation that must not be damped (`rotation = true`).
pub(crate) fn check_damper(
    student: PairForce<'_>,
    reference: PairForce<'_>,
    rng: &mut Rng,
    rotation: bool,
) -> CheckResult {
    for _ in 0..20 {
        let xa = rng.vec(2.0);
        let d = rng.unit() * rng.range(0.2, 2.0);
        let xb = xa + d;
        let va = rng.vec(3.0);
        let vb = if rotation {
            // A relative velocity along the spring, plus ω × (x_b - x_a), perpendicular to it:
            // the second part must not change the force.
            let along = rng.range(0.5, 2.0) * if rng.range(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
            va + along * d.normalize() + rng.vec(3.0).cross(d)
        } else {
            rng.vec(3.0)
        };
        let kd = rng.range(1.0, 100.0);
        let input = format!(
            "x_a = {}, x_b = {}, v_a = {}, v_b = {}, k_d = {} N·s/m",
            vec3(xa),
            vec3(xb),
            vec3(va),
            vec3(vb),
            num(kd)
        );
        let want = reference(xa, xb, va, vb, kd, 0.0);
        set_case(&input);
        let got = student(xa, xb, va, vb, kd, 0.0);
        finite1("f_a", &input, got)?;
        let scale = kd * ((va - vb).length() + 1.0);
        if !close(got, want, REL, scale) {
            let hint = if rotation {
                format!(
                    "{}; the relative velocity here has a part perpendicular to the spring (a \
                     rigid rotation) that the damper must ignore: use only the component along \
                     the spring, f_a = -k_d ((v_a - v_b)·l̂) l̂ with l̂ = (x_a - x_b)/|x_a - x_b|",
                    diagnose(got, want).unwrap_or_else(|| "wrong".to_string())
                )
            } else {
                vector_hint(
                    got,
                    want,
                    "f_a = -k_d ((v_a - v_b)·l̂) l̂ with l̂ = (x_a - x_b)/|x_a - x_b|",
                )
            };
            return Err(wrong(
                input,
                format!("f_a = {} N", vec3(want)),
                format!("f_a = {} N", vec3(got)),
                hint,
            ));
        }
    }
    Ok(())
}

/// A random spring system for the accumulation checks: `n` particles in a 2 m box with random
/// velocities, `m` springs between distinct random pairs with rest lengths 0.5–1.5 × their
/// current length, stiffness 20–500 N/m and damping 0–5 N·s/m.
pub(crate) fn random_springs(
    rng: &mut Rng,
    n: usize,
    m: usize,
) -> (Vec<DVec3>, Vec<DVec3>, Vec<super::assignments::Spring>) {
    let x: Vec<DVec3> = (0..n).map(|_| rng.vec(1.0)).collect();
    let v: Vec<DVec3> = (0..n).map(|_| rng.vec(1.0)).collect();
    let mut pairs = BTreeSet::new();
    let mut springs = Vec::with_capacity(m);
    while springs.len() < m && pairs.len() < n * (n - 1) / 2 {
        let (a, b) = (rng.index(n), rng.index(n));
        if a == b || !pairs.insert((a.min(b), a.max(b))) {
            continue;
        }
        let length = (x[b] - x[a]).length();
        springs.push(super::assignments::Spring {
            a,
            b,
            rest_length: length * rng.range(0.5, 1.5),
            stiffness: rng.range(20.0, 500.0),
            damping: rng.range(0.0, 5.0),
        });
    }
    (x, v, springs)
}

/// Describes a spring system for feedback.
pub(crate) fn describe_springs(
    x: &[DVec3],
    v: &[DVec3],
    springs: &[super::assignments::Spring],
) -> String {
    let mut s = format!(
        "{} particles, {} springs; x = [{}]; v = [{}]; springs (a, b, L0, k_s, k_d) = [{}]",
        x.len(),
        springs.len(),
        sample(x, 3, |p| vec3(*p)),
        sample(v, 3, |p| vec3(*p)),
        sample(springs, 3, |s| format!(
            "({}, {}, {}, {}, {})",
            s.a,
            s.b,
            num(s.rest_length),
            num(s.stiffness),
            num(s.damping)
        ))
    );
    s.truncate(2000);
    s
}

/// Accumulated per-particle results: pass when `got` matches `want` (reference physics) or what
/// `own()` returns (the student's own pair forces, correctly accumulated), so that a mistake in
/// the pair force is not charged twice. `own` is asked only when `got` differs from `want`; if
/// it fails (the student's pair force panics or its program crashes), only `want` counts.
pub(crate) fn check_accumulated(
    input: &str,
    got: &[DVec3],
    want: &[DVec3],
    own: &dyn Fn() -> Vec<DVec3>,
    scale: f64,
    unit: &str,
    formula: &str,
) -> CheckResult {
    finite("result", input, got)?;
    if got.len() != want.len() {
        return Err(wrong(
            input,
            format!("{} entries, one per particle", want.len()),
            format!("{} entries", got.len()),
            "return one vector per particle, in particle order",
        ));
    }
    let matches = |w: &[DVec3]| first_mismatch(got, w, REL, scale).is_none();
    if matches(want) {
        return Ok(());
    }
    // The student's own pair forces count only when they are not all zero (an unimplemented
    // pair force summed correctly is still nothing).
    let own = std::panic::catch_unwind(std::panic::AssertUnwindSafe(own)).ok();
    if own.is_some_and(|o| o.iter().any(|v| *v != DVec3::ZERO) && matches(&o)) {
        return Ok(());
    }
    let i = first_mismatch(got, want, REL, scale).unwrap_or(0);
    Err(wrong(
        input,
        format!("particle {i}: {} {unit}", vec3(want[i])),
        format!("particle {i}: {} {unit}", vec3(got[i])),
        vector_hint(got[i], want[i], formula),
    ))
}

// ---------------------------------------------------------------------------------------------
// Spring set-ups

/// Compares the springs of `kind` in `got` with those in `want` for a lattice of `particles`
/// particles; `label(i)` names particle `i` by its lattice coordinates.
pub(crate) fn check_setup(
    kind: SpringKind,
    input: &str,
    got: &[SpringSetup],
    want: &[SpringSetup],
    particles: usize,
    label: &dyn Fn(usize) -> String,
    hint: &str,
) -> CheckResult {
    let name = kind.name();
    let mut seen = BTreeSet::new();
    let mut duplicates = Vec::new();
    for s in got.iter().filter(|s| s.kind == kind) {
        if s.a >= particles || s.b >= particles {
            return Err(wrong(
                input,
                format!("indices below {particles}"),
                format!("a {name} spring ({}, {})", s.a, s.b),
                "an index is out of range: check the index formula and the loop bounds",
            ));
        }
        if s.a == s.b {
            return Err(wrong(
                input,
                "springs between two different particles",
                format!("a {name} spring from particle {} to itself", s.a),
                "an offset of zero slipped into the neighbour list",
            ));
        }
        if !seen.insert((s.a.min(s.b), s.a.max(s.b))) {
            duplicates.push((s.a, s.b));
        }
    }
    let expected: BTreeSet<(usize, usize)> = want
        .iter()
        .filter(|s| s.kind == kind)
        .map(|s| (s.a.min(s.b), s.a.max(s.b)))
        .collect();
    let missing: Vec<(usize, usize)> = expected.difference(&seen).copied().collect();
    let extra: Vec<(usize, usize)> = seen.difference(&expected).copied().collect();
    if missing.is_empty() && extra.is_empty() && duplicates.is_empty() {
        return Ok(());
    }
    let show = |p: &(usize, usize)| format!("{}–{}", label(p.0), label(p.1));
    let mut got_text = format!("{} {name} springs", seen.len() + duplicates.len());
    if !missing.is_empty() {
        got_text += &format!("; missing {}: {}", missing.len(), sample(&missing, 3, show));
    }
    if !extra.is_empty() {
        got_text += &format!("; extra {}: {}", extra.len(), sample(&extra, 3, show));
    }
    if !duplicates.is_empty() {
        got_text += &format!(
            "; listed twice {}: {}",
            duplicates.len(),
            sample(&duplicates, 3, show)
        );
    }
    Err(wrong(
        input,
        format!("{} {name} springs", expected.len()),
        got_text,
        hint,
    ))
}

// ---------------------------------------------------------------------------------------------
// Systems for the integrators

/// A model from a [`Builder`] with `gravity` (m/s²) and no drag.
fn model_from(builder: Builder, gravity: DVec3) -> (Model, crate::physics::State) {
    builder.build(gravity, 0.0)
}

/// The oscillator of the built-in scene: particle 0 pinned at the origin, particle 1 of 1 kg at
/// `(1.1, 0, 0)`, one spring of rest length 1 m, stiffness 100 N/m and damping `damping` N·s/m,
/// no gravity. Undamped: `x(t) = 1 + 0.1 cos(10 t)` (m).
pub(crate) fn oscillator(damping: f64) -> (Physics, State) {
    let mut b = Builder::new();
    let p0 = b.particle(DVec3::ZERO, 1.0);
    let p1 = b.particle(DVec3::new(1.0, 0.0, 0.0), 1.0);
    b.spring(p0, p1, 100.0, damping, SpringKind::Struct);
    b.x[1] = DVec3::new(1.1, 0.0, 0.0);
    b.pinned[0] = true;
    let (model, state) = model_from(b, DVec3::ZERO);
    (
        Physics::from_model(model),
        State {
            x: state.x,
            v: state.v,
        },
    )
}

/// A random system for one-step checks: 5 particles (particle 0 pinned) of 0.5–2 kg in a 2 m
/// box with velocities up to 1 m/s, 7 springs of 20–200 N/m and 0–2 N·s/m stretched to 1.1–2 ×
/// their rest length (so that their Jacobian needs no clamping), gravity 9.8 m/s² down.
pub(crate) fn random_system(rng: &mut Rng) -> (Physics, State) {
    let n = 5;
    let x: Vec<DVec3> = (0..n).map(|_| rng.vec(1.0)).collect();
    let v: Vec<DVec3> = (0..n)
        .map(|i| if i == 0 { DVec3::ZERO } else { rng.vec(1.0) })
        .collect();
    let masses: Vec<f64> = (0..n).map(|_| rng.range(0.5, 2.0)).collect();
    let mut pinned = vec![false; n];
    pinned[0] = true;
    let mut pairs = BTreeSet::new();
    let mut springs = Vec::new();
    while springs.len() < 7 {
        let (a, b) = (rng.index(n), rng.index(n));
        if a == b || !pairs.insert((a.min(b), a.max(b))) {
            continue;
        }
        let length = (x[b] - x[a]).length();
        springs.push(super::assignments::Spring {
            a,
            b,
            rest_length: length / rng.range(1.1, 2.0),
            stiffness: rng.range(20.0, 200.0),
            damping: rng.range(0.0, 2.0),
        });
    }
    let mut model = model_of(&masses, &pinned, &springs).unwrap_or_else(|| {
        // Unreachable: every index is below n.
        Model::new(vec![1.0], &[false], Vec::new(), DVec3::ZERO, 0.0)
    });
    model.gravity = DVec3::new(0.0, -9.8, 0.0);
    (Physics::from_model(model), State { x, v })
}

/// Describes a state for feedback.
pub(crate) fn describe_state(state: &State) -> String {
    format!(
        "{} particles; x = [{}]; v = [{}]",
        state.x.len(),
        sample(&state.x, 3, |p| vec3(*p)),
        sample(&state.v, 3, |p| vec3(*p))
    )
}

/// An integrator step under test: advances the state by `dt` with the physics.
pub(crate) type Step<'a> = &'a dyn Fn(&mut State, f64, &Physics);

/// Runs `step` once, checking that it keeps the particle count and stays finite.
pub(crate) fn step_checked(
    step: Step<'_>,
    state: &mut State,
    dt: f64,
    physics: &Physics,
    input: &str,
) -> CheckResult {
    let n = state.x.len();
    set_case(input);
    step(state, dt, physics);
    if state.x.len() != n || state.v.len() != n {
        return Err(wrong(
            input,
            format!("{n} positions and {n} velocities"),
            format!(
                "{} positions and {} velocities",
                state.x.len(),
                state.v.len()
            ),
            "update the vectors in place; do not add or remove particles",
        ));
    }
    finite("x", input, &state.x)?;
    finite("v", input, &state.v)
}

/// Compares a state stepped from `start` with the reference's.
pub(crate) fn compare_states(
    input: &str,
    start: &State,
    got: &State,
    want: &State,
    rel: f64,
    formula: &str,
) -> CheckResult {
    for (what, g, w) in [("x", &got.x, &want.x), ("v", &got.v, &want.v)] {
        if let Some(i) = first_mismatch(g, w, rel, 1.0) {
            let (gi, wi) = (
                g.get(i).copied().unwrap_or(DVec3::NAN),
                w.get(i).copied().unwrap_or(DVec3::NAN),
            );
            let unchanged = got == start;
            let hint = if unchanged {
                format!("the state did not change: is the TODO implemented? Expected {formula}")
            } else {
                format!("expected {formula}")
            };
            return Err(wrong(
                input,
                format!("{what}[{i}] = {}", vec3(wi)),
                format!("{what}[{i}] = {}", vec3(gi)),
                hint,
            ));
        }
    }
    Ok(())
}

/// What the position update of particle `i` did, when it matches a recognisable term: the
/// change of `x` compared with `dt·v` (old velocity), `dt·v'` (new velocity) and `dt·a` (the
/// acceleration at the start).
fn position_update(start: &State, got: &State, dt: f64, physics: &Physics) -> Option<String> {
    let a = physics.accelerations(&start.x, &start.v);
    let i = (0..start.x.len()).find(|&i| got.x.get(i) != start.x.get(i))?;
    let dx = got.x[i] - start.x[i];
    let near = |w: DVec3| close(dx, w, 1e-9, 1e-12);
    let candidates = [
        (
            dt * a[i],
            "dt·a(t), the acceleration, where the velocity belongs",
        ),
        (dt * start.v[i], "dt·v(t), with the OLD velocity"),
        (dt * got.v[i], "dt·v(t+dt), with the NEW velocity"),
    ];
    candidates
        .iter()
        .find(|(w, _)| near(*w))
        .map(|(_, what)| format!("x of particle {i} moved by {what}"))
}

/// One step on three random systems against the reference step, `dt = 0.01` s.
pub(crate) fn check_one_step(
    student: Step<'_>,
    reference: Step<'_>,
    rng: &mut Rng,
    formula: &str,
) -> CheckResult {
    for _ in 0..3 {
        let (physics, start) = random_system(rng);
        let dt = 0.01;
        let input = format!("one step of dt = {dt} s from {}", describe_state(&start));
        let mut want = start.clone();
        reference(&mut want, dt, &physics);
        let mut got = start.clone();
        step_checked(student, &mut got, dt, &physics, &input)?;
        if let Err(Failure::Wrong(mut f)) =
            compare_states(&input, &start, &got, &want, REL, formula)
        {
            if let Some(what) = position_update(&start, &got, dt, &physics) {
                f.hint = format!("{what}; {}", f.hint);
            }
            return Err(Failure::Wrong(f));
        }
    }
    Ok(())
}

/// `steps` steps of `dt` on the undamped oscillator against the reference.
pub(crate) fn check_oscillator_run(
    student: Step<'_>,
    reference: Step<'_>,
    steps: usize,
    dt: f64,
    formula: &str,
) -> CheckResult {
    let (physics, start) = oscillator(0.0);
    let input = format!(
        "{steps} steps of dt = {dt} s on the oscillator (particle 0 pinned at the origin, particle 1 \
         of 1 kg at (1.1, 0, 0), spring 100 N/m of rest length 1 m)"
    );
    let mut want = start.clone();
    let mut got = start.clone();
    for _ in 0..steps {
        reference(&mut want, dt, &physics);
        step_checked(student, &mut got, dt, &physics, &input)?;
    }
    compare_states(&input, &start, &got, &want, 1e-8, formula)
}

/// Least-squares slope of `ln(error)` against `ln(dt)`.
pub(crate) fn fitted_order(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(dt, e)| (dt.ln(), e.ln())).unzip();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

/// The measured order of `student` on the oscillator: error of `x(1 s)` against the exact
/// `1 + 0.1 cos(10 t)` at `dt = 0.02, 0.01, 0.005, 0.0025` s, accepted in `[lo, hi]`.
pub(crate) fn check_order(
    student: Step<'_>,
    order: f64,
    lo: f64,
    hi: f64,
    formula: &str,
) -> CheckResult {
    let time: f64 = 1.0;
    let exact = 1.0 + 0.1 * (10.0 * time).cos();
    let mut points = Vec::new();
    let input = "the oscillator x(t) = 1 + 0.1 cos(10 t) m run to t = 1 s with dt = 0.02, 0.01, \
                 0.005, 0.0025 s";
    let mut moved = false;
    for k in 0..4 {
        let dt = 0.02 / f64::from(1u32 << k);
        let steps = (time / dt).round() as usize;
        let (physics, start) = oscillator(0.0);
        let mut state = start.clone();
        for _ in 0..steps {
            step_checked(student, &mut state, dt, &physics, input)?;
        }
        moved |= state != start;
        points.push((dt, (state.x[1].x - exact).abs()));
    }
    let errors = points
        .iter()
        .map(|&(_, e)| num(e))
        .collect::<Vec<_>>()
        .join(", ");
    if points.iter().any(|&(_, e)| e == 0.0 || !e.is_finite()) {
        return Err(wrong(
            input,
            format!("errors shrinking like dt^{}", num(order)),
            format!("errors {errors} m"),
            "an error of exactly zero or not finite: the step does not integrate the oscillator",
        ));
    }
    let measured = fitted_order(&points);
    if (lo..=hi).contains(&measured) {
        return Ok(());
    }
    // What the errors do as dt halves: the last ratio says whether they still shrink.
    let last_ratio = points[3].1 / points[2].1;
    let hint = if !moved {
        format!("the state never changed: the step is not advanced at all; expected {formula}")
    } else if last_ratio > 0.85 || measured.abs() < 0.3 {
        format!(
            "the error stays the same size when dt shrinks (last ratio {}): the steps converge, \
             but to another motion than the oscillator's, so some update adds the wrong \
             quantity; expected {formula}",
            num(last_ratio)
        )
    } else if measured < order {
        let rk4 = if order == 4.0 {
            " (RK4: every slope k1..k4 enters both updates with weights 1, 2, 2, 1)"
        } else {
            ""
        };
        format!(
            "a method of order {} should shrink the error {}× when dt halves; yours shrinks it \
             {}×: a stage or a weight is probably wrong{rk4}; expected {formula}",
            num(order),
            num(2f64.powf(order)),
            num(2f64.powf(measured))
        )
    } else {
        format!("higher than expected: are you using a different method? Expected {formula}")
    };
    Err(wrong(
        input,
        format!("order {} (accepted {}–{})", num(order), num(lo), num(hi)),
        format!("order {} (errors {errors} m)", num(measured)),
        hint,
    ))
}

// ---------------------------------------------------------------------------------------------
// Implicit Euler

/// The backward Euler residuals of a step from `(x, v)` to `(x', v')`:
/// `max_i |v'_i - v_i - dt a_i(x', v')|` (m/s) and `max_i |x'_i - x_i - dt v'_i|` (m).
pub(crate) fn implicit_residuals(
    physics: &Physics,
    start: &State,
    end: &State,
    dt: f64,
) -> (f64, f64) {
    let a = physics.accelerations(&end.x, &end.v);
    let mut rv: f64 = 0.0;
    let mut rx: f64 = 0.0;
    for i in 0..start.x.len() {
        rv = rv.max((end.v[i] - start.v[i] - dt * a[i]).length());
        rx = rx.max((end.x[i] - start.x[i] - dt * end.v[i]).length());
    }
    (rv, rx)
}

/// Backward Euler is exact on a linear system: one step on the oscillator (undamped at
/// `dt = 0.05` s, damped 2 N·s/m at `dt = 0.1` s) against the reference's Newton step.
pub(crate) fn check_implicit_linear(student: Step<'_>, reference: Step<'_>) -> CheckResult {
    for (damping, dt) in [(0.0, 0.05), (2.0, 0.1)] {
        let (physics, mut start) = oscillator(damping);
        start.v[1] = DVec3::new(-0.3, 0.0, 0.0);
        let input = format!(
            "one step of dt = {dt} s on the oscillator (spring 100 N/m, damper {damping} N·s/m) \
             from x1 = (1.1, 0, 0) m, v1 = (-0.3, 0, 0) m/s"
        );
        let mut want = start.clone();
        reference(&mut want, dt, &physics);
        let mut got = start.clone();
        step_checked(student, &mut got, dt, &physics, &input)?;
        compare_states(
            &input,
            &start,
            &got,
            &want,
            1e-7,
            "the solution of v' = v + dt a(x + dt v', v'), x' = x + dt v': for a linear spring one \
             Newton step (I - dt J_v - dt² J_x) Δv = dt (a + dt J_x v) solves it exactly; a \
             predictor–corrector (explicit prediction, one re-evaluation) does not",
        )?;
    }
    Ok(())
}

/// Backward Euler is unconditionally stable: 50 steps at `dt·ω = 10` on the undamped oscillator
/// must shrink the amplitude below half and never grow it.
pub(crate) fn check_implicit_stable(student: Step<'_>) -> CheckResult {
    let (physics, mut state) = oscillator(0.0);
    let dt = 1.0;
    let amplitude = |s: &State| (s.x[1] - DVec3::X).length();
    let initial = amplitude(&state);
    let input = "50 steps of dt = 1 s (dt·ω = 10) on the undamped oscillator from amplitude 0.1 m";
    for step in 1..=50 {
        step_checked(student, &mut state, dt, &physics, input)?;
        let a = amplitude(&state);
        if a > initial * 1.01 {
            return Err(wrong(
                input,
                "the amplitude never grows; backward Euler damps it by 1/|1 - i dt ω| ≈ 0.1 per step",
                format!("amplitude {} m after step {step}", num(a)),
                "the step is not implicit: explicit Euler and the predictor–corrector blow up at \
                 dt·ω = 10; solve for the end-of-step velocity instead of predicting it",
            ));
        }
    }
    let last = amplitude(&state);
    if last > 0.5 * initial {
        return Err(wrong(
            input,
            "an amplitude below 0.05 m after 50 steps (backward Euler loses energy at large dt)",
            format!("amplitude {} m", num(last)),
            "the state hardly changes: is the step implemented?",
        ));
    }
    Ok(())
}

/// On a nonlinear 3-D system the step must solve backward Euler at least as well as one Newton
/// step: residual of `v' = v + dt a(x', v')` at most twice the reference's (plus 1e-9 m/s), and
/// `x' = x + dt v'` to round-off.
pub(crate) fn check_implicit_residual(
    student: Step<'_>,
    reference: Step<'_>,
    rng: &mut Rng,
) -> CheckResult {
    for _ in 0..3 {
        let (physics, start) = random_system(rng);
        let dt = 0.02;
        let input = format!("one step of dt = {dt} s from {}", describe_state(&start));
        let mut want = start.clone();
        reference(&mut want, dt, &physics);
        let mut got = start.clone();
        step_checked(student, &mut got, dt, &physics, &input)?;
        let (ref_v, _) = implicit_residuals(&physics, &start, &want, dt);
        let (rv, rx) = implicit_residuals(&physics, &start, &got, dt);
        let scale = got.v.iter().map(|v| v.length()).fold(1.0, f64::max);
        if rx > 1e-9 * scale * dt.max(1.0) {
            return Err(wrong(
                input,
                "x' = x + dt v' with the NEW velocity",
                format!("|x' - x - dt v'| up to {} m", num(rx)),
                "backward Euler moves the positions with the end-of-step velocity v'",
            ));
        }
        if rv > 2.0 * ref_v + 1e-9 {
            return Err(wrong(
                input,
                format!(
                    "|v' - v - dt a(x', v')| ≤ {} m/s (twice one Newton step's residual)",
                    num(2.0 * ref_v + 1e-9)
                ),
                format!("residual {} m/s", num(rv)),
                "the end state does not satisfy v' = v + dt a(x', v'): solve (I - dt J_v - dt² J_x) \
                 Δv = dt (a + dt J_x v) with physics.jacobian_x / jacobian_v and Matrix::solve",
            ));
        }
    }
    Ok(())
}
