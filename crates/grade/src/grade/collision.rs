//! Collision checks of a particle against a plane or a bowl (NYCU HW1 2023 #3).
//!
//! # The task, as graded
//!
//! ```text
//! φ = signed distance to the surface, N = unit normal into the free side
//!     plane: φ = (x - p)·n,  N = n
//!     bowl:  φ = r - |x - c|, N = (c - x)/|c - x|      only where y ≤ rim_height
//! touching:     φ < ε
//! bounce:       touching and v·N < 0:            v' = -k_r v_N + v_T,   v_N = (v·N) N, v_T = v - v_N
//! contact:      touching, v·N ≤ 0 and N·f < 0:   f' = f - (N·f) N - k_f (-N·f) v_T/|v_T|
//! projection:   φ < 0:                           x' = x - φ N
//! ```
//! where `x` (m), `v` (m/s), `f` (N) are the particle's position, velocity and accumulated force,
//! `ε` (m) the contact band, `k_r` the restitution and `k_f` the friction coefficient. The
//! contact force uses the velocity before the bounce. A static obstacle is infinitely heavy, so
//! the 2021 course's factor `(m1 - m2)/(m1 + m2)` on the normal velocity is -1 and drops out.
//! Cases avoid the undefined corners (`v_T = 0` with friction, `v·N` within 1e-6 of 0).
//!
//! Each check runs the whole handler but looks at one output: the bounce check at `v'`, the
//! projection check at `x'`, the contact check at `force'`. One mistake is charged once: a
//! missing bounce costs the bounce check only, a missing projection the projection check only.

use glam::DVec3;

use super::assignments::{Bowl, ContactCoefficients, Particle, Plane};
use super::checks::{REL, Rng, close, finite, num, vec3, wrong};
use super::runner::{CheckResult, set_case};
use crate::physics::collide::Collider;

/// An obstacle of the jelly assignment.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Surface {
    Plane(Plane),
    Bowl(Bowl),
}

impl Surface {
    fn collider(&self) -> Collider {
        match *self {
            Surface::Plane(p) => Collider::plane(p.point, p.normal),
            Surface::Bowl(b) => Collider::bowl(b.center, b.radius, b.rim_height),
        }
    }

    fn describe(&self) -> String {
        match self {
            Surface::Plane(p) => format!(
                "plane through {} with normal {}",
                vec3(p.point),
                vec3(p.normal)
            ),
            Surface::Bowl(b) => format!(
                "bowl: sphere of radius {} m at {}, rim at y = {}",
                num(b.radius),
                vec3(b.center),
                num(b.rim_height)
            ),
        }
    }

    /// A point at signed distance `phi` (m) where the surface acts, and the normal there.
    fn sample(&self, rng: &mut Rng, phi: f64) -> Option<(DVec3, DVec3)> {
        let collider = self.collider();
        for _ in 0..500 {
            let x = match *self {
                Surface::Plane(p) => {
                    p.point + rng.perpendicular(p.normal) * rng.range(0.0, 2.0) + phi * p.normal
                }
                Surface::Bowl(b) => {
                    let d = rng.unit();
                    if d.y > -0.5 {
                        continue;
                    }
                    b.center + d * (b.radius - phi)
                }
            };
            if let Some(c) = collider.contact(x)
                && (c.phi - phi).abs() < 1e-9
            {
                return Some((x, c.normal));
            }
        }
        None
    }

    /// A point just inside a bowl's sphere but above its rim, where the bowl does not act, and
    /// the direction from it to the sphere's centre.
    fn above_rim(&self, rng: &mut Rng) -> Option<(DVec3, DVec3)> {
        let Surface::Bowl(b) = *self else {
            return None;
        };
        for _ in 0..500 {
            let d = rng.unit();
            let x = b.center + d * (b.radius - 0.005);
            if x.y > b.rim_height + 0.01 && self.collider().contact(x).is_none() {
                return Some((x, -d));
            }
        }
        None
    }
}

/// A velocity with normal component `vn` (m/s) along `normal` and a tangential part of length
/// drawn from `vt` (m/s).
fn velocity(rng: &mut Rng, normal: DVec3, vn: f64, vt: [f64; 2]) -> DVec3 {
    let speed = rng.range(vt[0], vt[1]);
    vn * normal + rng.perpendicular(normal) * speed
}

/// A force pushing into the surface with load `load` (N) plus a tangential part.
fn pushing(rng: &mut Rng, normal: DVec3, load: f64) -> DVec3 {
    let tangential = rng.range(0.0, 5.0);
    -load * normal + rng.perpendicular(normal) * tangential
}

/// A collision handler under test: changes the particle against the surface.
pub(crate) type Handler<'a> = &'a dyn Fn(&Surface, &mut Particle);

/// Surfaces of a check: case `i` of three.
pub(crate) type Surfaces<'a> = &'a dyn Fn(&mut Rng, usize) -> Surface;

/// The output a check looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Field {
    /// The position `x'` (projection).
    X,
    /// The velocity `v'` (bounce).
    V,
    /// The force `force'` (contact force and friction).
    Force,
}

/// Runs one case and compares `field` with the reference.
fn compare(
    student: Handler<'_>,
    reference: Handler<'_>,
    surface: &Surface,
    start: Particle,
    c: &ContactCoefficients,
    field: Field,
    why: &str,
) -> CheckResult {
    let input = format!(
        "{}; particle x = {}, v = {}, force = {}; ε = {}, k_r = {}, k_f = {}",
        surface.describe(),
        vec3(start.x),
        vec3(start.v),
        vec3(start.force),
        num(c.epsilon),
        num(c.restitution),
        num(c.friction)
    );
    let mut got = start;
    set_case(&input);
    student(surface, &mut got);
    let mut want = start;
    reference(surface, &mut want);
    let (what, g, w, scale) = match field {
        Field::X => ("x", got.x, want.x, 1.0),
        Field::V => ("v", got.v, want.v, 1.0),
        Field::Force => ("force", got.force, want.force, start.force.length() + 1.0),
    };
    finite(what, &input, &[g])?;
    if close(g, w, REL, scale) {
        return Ok(());
    }
    let unchanged = match field {
        Field::X => start.x,
        Field::V => start.v,
        Field::Force => start.force,
    };
    let hint = if g == unchanged && w != unchanged {
        format!("{why} ({what} did not change)")
    } else if w == unchanged {
        format!("{why} ({what} should not change here)")
    } else {
        why.to_string()
    };
    Err(wrong(
        input,
        format!("{what}' = {}", vec3(w)),
        format!("{what}' = {}", vec3(g)),
        hint,
    ))
}

/// A point of the contact band: at `φ` in [0.001, 0.009) m from `surface` (inside `ε`), its
/// position and the surface normal there.
fn in_band(
    rng: &mut Rng,
    surface: &Surface,
) -> Result<(f64, DVec3, DVec3), super::runner::Failure> {
    let phi = rng.range(0.001, 0.009);
    let (x, n) = surface.sample(rng, phi).ok_or_else(|| no_sample(surface))?;
    Ok((phi, x, n))
}

fn no_sample(surface: &Surface) -> super::runner::Failure {
    wrong(
        surface.describe(),
        "a test point",
        "none found",
        "internal: the grader could not place a test point (please report)",
    )
}

/// Bounce within ε when approaching; nothing when farther, moving away, or above a bowl's rim.
pub(crate) fn check_bounce(
    student: Handler<'_>,
    reference: Handler<'_>,
    rng: &mut Rng,
    surfaces: Surfaces<'_>,
    c: &ContactCoefficients,
) -> CheckResult {
    for i in 0..3 {
        let surface = surfaces(rng, i);
        // Touching and approaching: bounce.
        let (phi, x, n) = in_band(rng, &surface)?;
        let vn = rng.range(-3.0, -0.5);
        let p = Particle {
            x,
            v: velocity(rng, n, vn, [0.0, 2.0]),
            force: DVec3::ZERO,
        };
        compare(
            student,
            reference,
            &surface,
            p,
            c,
            Field::V,
            &format!(
                "φ = {} m < ε and v·N = {} < 0: bounce, v' = -k_r v_N + v_T with N = {}",
                num(phi),
                num(vn),
                vec3(n)
            ),
        )?;
        // Farther than ε: nothing, even when the force pushes towards the surface.
        let phi = rng.range(0.05, 1.0);
        let (x, n) = surface
            .sample(rng, phi)
            .ok_or_else(|| no_sample(&surface))?;
        let (vn, load) = (rng.range(-3.0, -0.5), rng.range(1.0, 20.0));
        let p = Particle {
            x,
            v: velocity(rng, n, vn, [0.0, 2.0]),
            force: pushing(rng, n, load),
        };
        compare(
            student,
            reference,
            &surface,
            p,
            c,
            Field::V,
            &format!(
                "φ = {} m is farther than ε = {}: no collision, nothing changes",
                num(phi),
                num(c.epsilon)
            ),
        )?;
        // Touching but moving away: nothing.
        let (_, x, n) = in_band(rng, &surface)?;
        let (vn, load) = (rng.range(0.2, 2.0), rng.range(1.0, 20.0));
        let p = Particle {
            x,
            v: velocity(rng, n, vn, [0.0, 2.0]),
            force: pushing(rng, n, load),
        };
        compare(
            student,
            reference,
            &surface,
            p,
            c,
            Field::V,
            &format!(
                "v·N = {} > 0: the particle moves away, so no bounce and no contact force",
                num(vn)
            ),
        )?;
        // Above a bowl's rim: the bowl is not there.
        if let Some((x, inward)) = surface.above_rim(rng) {
            let load = rng.range(1.0, 20.0);
            let p = Particle {
                x,
                v: velocity(rng, inward, -1.0, [0.0, 2.0]),
                force: pushing(rng, inward, load),
            };
            compare(
                student,
                reference,
                &surface,
                p,
                c,
                Field::V,
                "the particle is above the rim (y > rim_height), where there is no bowl: nothing changes",
            )?;
        }
    }
    Ok(())
}

/// A particle that went through the surface is moved back onto it (and bounces if approaching).
pub(crate) fn check_penetration(
    student: Handler<'_>,
    reference: Handler<'_>,
    rng: &mut Rng,
    surfaces: Surfaces<'_>,
    c: &ContactCoefficients,
) -> CheckResult {
    for i in 0..3 {
        let surface = surfaces(rng, i);
        for vn in [rng.range(-3.0, -0.5), rng.range(0.2, 1.0)] {
            let phi = -rng.range(0.01, 0.3);
            let (x, n) = surface
                .sample(rng, phi)
                .ok_or_else(|| no_sample(&surface))?;
            let p = Particle {
                x,
                v: velocity(rng, n, vn, [0.0, 2.0]),
                force: DVec3::ZERO,
            };
            compare(
                student,
                reference,
                &surface,
                p,
                c,
                Field::X,
                &format!(
                    "φ = {} m < 0: the particle is inside; move it onto the surface, x' = x - φ N \
                     with N = {} (here v·N = {})",
                    num(phi),
                    vec3(n),
                    num(vn)
                ),
            )?;
        }
        // Touching from the free side: the position stays.
        let (phi, x, n) = in_band(rng, &surface)?;
        let vn = rng.range(-3.0, -0.5);
        let p = Particle {
            x,
            v: velocity(rng, n, vn, [0.0, 2.0]),
            force: DVec3::ZERO,
        };
        compare(
            student,
            reference,
            &surface,
            p,
            c,
            Field::X,
            &format!(
                "φ = {} m ≥ 0: the particle is on the free side; only a particle inside (φ < 0) is \
                 moved",
                num(phi)
            ),
        )?;
    }
    Ok(())
}

/// Contact force and Coulomb friction when touching, not moving away, and pushed in.
pub(crate) fn check_contact_force(
    student: Handler<'_>,
    reference: Handler<'_>,
    rng: &mut Rng,
    surfaces: Surfaces<'_>,
    c: &ContactCoefficients,
) -> CheckResult {
    for i in 0..3 {
        let surface = surfaces(rng, i);
        for _ in 0..2 {
            let (_, x, n) = in_band(rng, &surface)?;
            let load = rng.range(1.0, 20.0);
            let vn = rng.range(-1.0, -0.1);
            let p = Particle {
                x,
                v: velocity(rng, n, vn, [0.2, 2.0]),
                force: pushing(rng, n, load),
            };
            compare(
                student,
                reference,
                &surface,
                p,
                c,
                Field::Force,
                &format!(
                    "touching (φ < ε), approaching, and N·f = {} < 0 pushes into the surface: \
                     f' = f - (N·f) N - k_f (-N·f) v_T/|v_T| with v_T from the velocity before \
                     the bounce; and the bounce as usual",
                    num(-load)
                ),
            )?;
        }
        // Farther than ε, or moving away: no contact force even when pushed in.
        for (phi, vn, why) in [
            (
                rng.range(0.05, 1.0),
                rng.range(-3.0, -0.5),
                "the particle is farther than ε: no contact force",
            ),
            (
                rng.range(0.001, 0.009),
                rng.range(0.2, 2.0),
                "v·N > 0: the particle moves away, so no contact force",
            ),
        ] {
            let (x, n) = surface
                .sample(rng, phi)
                .ok_or_else(|| no_sample(&surface))?;
            let load = rng.range(1.0, 20.0);
            let p = Particle {
                x,
                v: velocity(rng, n, vn, [0.2, 2.0]),
                force: pushing(rng, n, load),
            };
            compare(student, reference, &surface, p, c, Field::Force, why)?;
        }
        // Above a bowl's rim: the bowl is not there.
        if let Some((x, inward)) = surface.above_rim(rng) {
            let load = rng.range(1.0, 20.0);
            let p = Particle {
                x,
                v: velocity(rng, inward, -1.0, [0.2, 2.0]),
                force: pushing(rng, inward, load),
            };
            compare(
                student,
                reference,
                &surface,
                p,
                c,
                Field::Force,
                "the particle is above the rim (y > rim_height), where there is no bowl: no \
                 contact force",
            )?;
        }
    }
    Ok(())
}
