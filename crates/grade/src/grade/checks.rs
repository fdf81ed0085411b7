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

mod integrators;
pub(crate) use integrators::{
    check_implicit_linear, check_implicit_residual, check_implicit_stable, check_one_step,
    check_order, check_oscillator_run,
};

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

/// Names, under every failed check of an integrator item, the lesson step that shows the
/// method live beside the reference (`see it: springlab lesson 4 --homework .`): appended to
/// the check's hint, or to the item's reason when a check failed without feedback (a panic, a
/// time-out).
pub(crate) fn link_back(report: &mut super::Report, assignment: super::Assignment) {
    use super::{CheckOutcome, ItemStatus};
    for item in &mut report.items {
        if item.status == ItemStatus::Full {
            continue;
        }
        let Some(command) = super::live::see_it(assignment, &item.id) else {
            continue;
        };
        let line = format!("see it: {command}");
        let mut unexplained = item.checks.is_empty();
        for check in &mut item.checks {
            if check.outcome != CheckOutcome::Failed {
                continue;
            }
            match &mut check.feedback {
                Some(f) => f.hint = format!("{}; {line}", f.hint),
                None => unexplained = true,
            }
        }
        if unexplained {
            item.reason = Some(match item.reason.take() {
                Some(r) => format!("{r}; {line}"),
                None => line,
            });
        }
    }
}
