//! Dynamic spheres (see the parent module's docs, "Dynamic spheres"): their motion under
//! gravity or at a set velocity, and their collisions with each other, with the static
//! colliders and with the particles (a broad phase by boxes of particles, then impulses and
//! separation).

#[allow(clippy::wildcard_imports)]
use super::*;

/// A sphere that moves: pushed by gravity and collisions, or driven at a set velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicSphere {
    /// Centre (m).
    pub center: DVec3,
    /// Velocity (m/s).
    pub velocity: DVec3,
    /// Radius (m).
    pub radius: f64,
    /// Mass (kg); ignored when `kinematic`.
    pub mass: f64,
    /// Moved only by its set velocity: infinite mass, no gravity (the 2024 arrow-key sphere).
    pub kinematic: bool,
}

impl DynamicSphere {
    /// A sphere at rest with the course's mass `1000 r³` kg (r = 0.5 m gives 125 kg).
    #[must_use]
    pub fn new(center: DVec3, radius: f64) -> DynamicSphere {
        DynamicSphere {
            center,
            velocity: DVec3::ZERO,
            radius,
            mass: 1000.0 * radius.powi(3),
            kinematic: false,
        }
    }

    /// A kinematic sphere moving at `velocity` (m/s), not affected by anything.
    #[must_use]
    pub fn kinematic(center: DVec3, radius: f64, velocity: DVec3) -> DynamicSphere {
        DynamicSphere {
            velocity,
            kinematic: true,
            ..DynamicSphere::new(center, radius)
        }
    }

    /// Inverse mass `1/m` (1/kg): zero when kinematic or of non-positive mass.
    #[must_use]
    pub fn inv_mass(&self) -> f64 {
        if self.kinematic || self.mass <= 0.0 {
            0.0
        } else {
            1.0 / self.mass
        }
    }
}

/// Advances the dynamic spheres by `dt` seconds and resolves their collisions (module docs):
///
/// 1. semi-implicit Euler, `v += dt g; c += dt v` (kinematic spheres: `c += dt v` only);
/// 2. sphere–sphere impulses and separation (restitution `sphere_sphere_restitution`);
/// 3. spheres against the static colliders, with the particles' response and the surface
///    offset by the radius (exact for planes and spheres, approximate at a bowl's rim and a
///    hole's edge);
/// 4. sphere–particle impulses and separation (restitution `sphere_particle_restitution`); a
///    pinned particle counts as infinitely heavy.
pub fn step_spheres<'a, 'b>(model: impl Into<World<'a>>, state: impl Into<Bodies<'b>>, dt: f64) {
    let (model, mut state) = (model.into(), state.into());
    advance_spheres(model, state.reborrow(), dt);
    collide_spheres(model, state, dt);
}

/// Step 1 of [`step_spheres`]: moves every dynamic sphere by `dt` seconds (semi-implicit Euler
/// under gravity; a kinematic sphere at its set velocity).
pub fn advance_spheres<'a, 'b>(model: impl Into<World<'a>>, state: impl Into<Bodies<'b>>, dt: f64) {
    let (model, state) = (model.into(), state.into());
    for s in state.spheres.iter_mut() {
        advance_sphere(s, model.gravity, dt);
    }
}

/// Moves one sphere by `dt` seconds under `gravity` (m/s²), as [`advance_spheres`] does.
fn advance_sphere(s: &mut DynamicSphere, gravity: DVec3, dt: f64) {
    if !s.kinematic {
        // Semi-implicit Euler: velocity first, then position with the new velocity.
        s.velocity += dt * gravity;
    }
    s.center += dt * s.velocity;
}

/// True when every sphere is kinematic with a finite centre and velocity: then each particle's
/// push depends only on that particle and the spheres, and no push changes a sphere (its
/// centre and velocity change by `0 · …`, exactly nothing while they are finite and the push
/// is; a zero's sign or a NaN would stay), so the parts of a body may be pushed on their own
/// ([`push_part`]).
pub(super) fn kinematic_only(spheres: &[DynamicSphere]) -> bool {
    spheres.iter().all(|s| {
        s.kinematic
            && s.center.is_finite()
            && s.velocity.is_finite()
            && !(s.center.to_array().iter())
                .chain(&s.velocity.to_array())
                .any(|c| *c == 0.0 && c.is_sign_negative())
    })
}

/// The same bits of two lists of spheres (centres and velocities).
fn same_spheres(a: &[DynamicSphere], b: &[DynamicSphere]) -> bool {
    let bits = |s: &DynamicSphere| {
        (s.center.to_array().into_iter())
            .chain(s.velocity.to_array())
            .map(f64::to_bits)
            .collect::<Vec<u64>>()
    };
    a.len() == b.len() && a.iter().zip(b).all(|(a, b)| bits(a) == bits(b))
}

/// The pushes of the kinematic spheres `spheres` (as they are before this step's
/// [`advance_spheres`], which this moves a copy of) on one part of a body, particles
/// `part.start..part.end` at positions `x` and velocities `v` (that part only), by the
/// thread that stepped the part: the same operations on each particle as
/// [`collide_spheres_prepared`]'s, which then only records them (the parts together are
/// that function's pushes, sphere by sphere over every particle, because no particle's push
/// depends on another's and no push changes a sphere, [`kinematic_only`]). Each pushed
/// particle's first state goes into `part.pushed`, the moved copies of the spheres into
/// `part.spheres`; nothing is pushed unless [`kinematic_only`].
pub(super) fn push_part(
    world: &World,
    spheres: &[DynamicSphere],
    dt: f64,
    part: &mut PartBounds,
    x: &mut [DVec3],
    v: &mut [DVec3],
) {
    part.pushed.clear();
    part.spheres.clear();
    part.spheres.extend_from_slice(spheres);
    for s in &mut part.spheres {
        advance_sphere(s, world.gravity, dt);
    }
    if !kinematic_only(&part.spheres) {
        part.spheres.clear();
        return;
    }
    let start = part.start;
    let e = world.contact.sphere_particle_restitution;
    let mut spheres = std::mem::take(&mut part.spheres);
    let mut pushed = std::mem::take(&mut part.pushed);
    let mut highest = 0;
    for s in &mut spheres {
        let ws = s.inv_mass();
        let reach2 = s.radius * s.radius * (1.0 + 1e-9);
        for (range, bounds) in part.boxes_mut() {
            if bounds.distance_squared(s.center) >= reach2 {
                continue;
            }
            for i in range {
                let k = i - start;
                if (x[k] - s.center).length_squared() >= reach2 {
                    continue;
                }
                let (x_old, v_old) = (x[k], v[k]);
                let (mut x_new, mut v_new) = (x_old, v_old);
                // A kinematic sphere's push is not paid: `collide_spheres_prepared`'s climb
                // is 0 J.
                let touched = impulse_pair(
                    Side {
                        x: &mut s.center,
                        v: &mut s.velocity,
                        w: ws,
                    },
                    Side {
                        x: &mut x_new,
                        v: &mut v_new,
                        w: world.inv_mass[i],
                    },
                    s.radius,
                    e,
                    &|_, _| 0.0,
                );
                if touched.is_some() {
                    (x[k], v[k]) = (x_new, v_new);
                    bounds.include(x[k]);
                    // Its first push only (a later sphere may push it again); the records
                    // rise while one sphere pushes, so only a lower particle can be in them.
                    let i = i as u32;
                    if i > highest || !pushed.iter().any(|p| p.0 == i) {
                        pushed.push((i, x_old, v_old));
                        highest = highest.max(i);
                    }
                }
            }
        }
    }
    part.spheres = spheres;
    part.pushed = pushed;
    part.pushed_here = true;
}

/// Steps 2–4 of [`step_spheres`]: the impulses and separations between spheres, colliders and
/// particles after the spheres moved. `dt` (s) keeps Verlet's history consistent.
pub fn collide_spheres<'a, 'b>(model: impl Into<World<'a>>, state: impl Into<Bodies<'b>>, dt: f64) {
    collide_spheres_logged(model, state, dt, None);
}

/// [`collide_spheres`], recording in `log` (when given) the spheres' energy before and every
/// particle it changes.
pub fn collide_spheres_logged<'a, 'b>(
    model: impl Into<World<'a>>,
    state: impl Into<Bodies<'b>>,
    dt: f64,
    log: Option<&mut Changes>,
) {
    collide_spheres_prepared(model, state, dt, log, None);
}

/// [`collide_spheres_logged`] with the broad phase's boxes taken from the parts' summaries
/// `parts` (made at the positions the state has now, `prepared.rs`) instead of boxes of every
/// particle made here: the same result.
pub fn collide_spheres_prepared<'a, 'b>(
    model: impl Into<World<'a>>,
    state: impl Into<Bodies<'b>>,
    dt: f64,
    mut log: Option<&mut Changes>,
    parts: Option<&mut [PartBounds]>,
) {
    let (model, state) = (model.into(), state.into());
    if state.spheres.is_empty() {
        return;
    }
    let spheres_before = spheres_energy(model.gravity, state.spheres);
    if let Some(log) = log.as_deref_mut() {
        log.spheres_before += spheres_before;
    }
    let params = model.contact;
    let gravity = model.gravity;
    // The potential energy (J) that moving a body of inverse mass `w` (1/kg) by `dx` (m) adds
    // under gravity (a kinematic sphere or a pinned particle does not move).
    let lift = move |dx: DVec3, w: f64| if w == 0.0 { 0.0 } else { -gravity.dot(dx) / w };
    let Bodies {
        x,
        v,
        x_prev,
        history_valid,
        spheres,
    } = state;
    let mut parts = parts;
    if let Some(parts) = parts.as_deref_mut()
        && parts.iter().any(|p| p.pushed_here)
    {
        // The parts pushed their particles ([`push_part`]): the same as the loops below when
        // every part did, with this step's spheres (then they are kinematic and nothing below
        // changes them); else their pushes are undone and the loops below make them.
        let agree = !history_valid
            && kinematic_only(spheres)
            && (parts.iter()).all(|p| p.pushed_here && same_spheres(&p.spheres, spheres));
        for p in parts.iter_mut() {
            p.pushed_here = false;
            if agree {
                if let Some(log) = log.as_deref_mut() {
                    for &(i, x_old, v_old) in &p.pushed {
                        log.record(i as usize, x_old, v_old);
                    }
                }
            } else {
                for &(i, x_old, v_old) in p.pushed.iter().rev() {
                    (x[i as usize], v[i as usize]) = (x_old, v_old);
                }
            }
        }
        if agree {
            return;
        }
    }
    for b in 1..spheres.len() {
        let (before, rest) = spheres.split_at_mut(b);
        let sb = &mut rest[0];
        for sa in before.iter_mut() {
            let (wa, wb) = (sa.inv_mass(), sb.inv_mass());
            let reach = sa.radius + sb.radius;
            impulse_pair(
                Side {
                    x: &mut sa.center,
                    v: &mut sa.velocity,
                    w: wa,
                },
                Side {
                    x: &mut sb.center,
                    v: &mut sb.velocity,
                    w: wb,
                },
                reach,
                params.sphere_sphere_restitution,
                &|dx_a, dx_b| lift(dx_a, wa) + lift(dx_b, wb),
            );
        }
    }
    for s in spheres.iter_mut().filter(|s| !s.kinematic) {
        for collider in model.colliders {
            // A sphere has no springs: its climb is paid from its own motion (what that cannot
            // pay, the system pays at the end).
            let rise = |from: DVec3, to: DVec3| -gravity.dot(to - from);
            respond(
                collider,
                s.radius,
                params,
                &rise,
                &mut s.center,
                &mut s.velocity,
            );
        }
    }
    // Broad phase by bounds: the box of every chunk of `BOX` particles, grown when a particle
    // is pushed, so that a sphere skips the chunks it cannot reach (`prepared.rs`).
    let n = x.len().min(model.particle_count());
    OWN.with(|own| {
        let own = &mut *own.borrow_mut();
        own.clear();
        own.spheres_before = spheres_before;
        WHOLE.with(|whole| {
            let whole = &mut *whole.borrow_mut();
            let parts = match parts {
                Some(parts) => parts,
                None => {
                    whole.fill(&[], 0, &x[..n], true);
                    std::slice::from_mut(whole)
                }
            };
            for s in spheres.iter_mut() {
                let ws = s.inv_mass();
                // A particle at |x - c|² ≥ r² (with a margin against rounding) does not touch and
                // needs no square root.
                let reach2 = s.radius * s.radius * (1.0 + 1e-9);
                for (range, bounds) in parts.iter_mut().flat_map(PartBounds::boxes_mut) {
                    if bounds.distance_squared(s.center) >= reach2 {
                        continue;
                    }
                    for i in range {
                        if (x[i] - s.center).length_squared() >= reach2 {
                            continue;
                        }
                        let (x_old, v_old) = (x[i], v[i]);
                        let (mut x_new, mut v_new) = (x_old, v_old);
                        let w = model.inv_mass[i];
                        // Where a particle was before the separations (its first record, else
                        // where it is): a particle's springs are measured against these (as in
                        // `resolve`), so that no answer depends on the order.
                        let x_shared: &[DVec3] = x;
                        let own_shared: &Changes = own;
                        let before = |j: usize| own_shared.of(j).map_or(x_shared[j], |c| c.1);
                        // The separation's potential energy (J): gravity on both, and the
                        // springs at i (neighbours where they were) where they gain.
                        let rise = |dx_s: DVec3, dx: DVec3| {
                            if ws == 0.0 {
                                // A kinematic sphere is driven: its pushes are not paid.
                                return 0.0;
                            }
                            let elastic = if w == 0.0 {
                                0.0
                            } else {
                                let (to, from) =
                                    model.elastic_at_both(before, i, x_old + dx, x_old);
                                to - from
                            };
                            lift(dx_s, ws) + lift(dx, w) + elastic.max(0.0)
                        };
                        let touched = impulse_pair(
                            Side {
                                x: &mut s.center,
                                v: &mut s.velocity,
                                w: ws,
                            },
                            Side {
                                x: &mut x_new,
                                v: &mut v_new,
                                w,
                            },
                            s.radius,
                            params.sphere_particle_restitution,
                            &rise,
                        );
                        if touched.is_some() {
                            (x[i], v[i]) = (x_new, v_new);
                            bounds.include(x[i]);
                            keep_verlet_history(history_valid, &mut x_prev[i], x[i], v[i], dt);
                            own.record(i, x_old, v_old);
                            if let Some(log) = log.as_deref_mut() {
                                log.record(i, x_old, v_old);
                            }
                        }
                    }
                }
            }
        });
        // What the pairs could not pay, and the springs between two separated particles,
        // exactly; the system pays it from its kinetic energy (`budget`). Not with a kinematic
        // sphere: driven from outside, it may do work on the cloth.
        own.finish(n);
        if spheres.iter().any(|s| s.kinematic) {
            return;
        }
        let (rise, size) = energy_rise(&model, x, v, Some(spheres), own);
        if above_rounding(rise, size) {
            let mut bodies = Bodies {
                x,
                v,
                x_prev,
                history_valid,
                spheres,
            };
            pay(model, &mut bodies, rise, dt, log);
        }
    });
}

thread_local! {
    /// The particles one call of [`collide_spheres_logged`] changed (reused).
    static OWN: std::cell::RefCell<Changes> = std::cell::RefCell::new(Changes::default());
    /// The boxes of the whole body when no parts' summaries are given (reused, so steps do not
    /// allocate).
    static WHOLE: std::cell::RefCell<PartBounds> = std::cell::RefCell::new(PartBounds::default());
}

/// One side of a two-body contact: position (m), velocity (m/s), inverse mass (1/kg).
struct Side<'a> {
    x: &'a mut DVec3,
    v: &'a mut DVec3,
    w: f64,
}

/// Impulse and separation of two bodies whose centres should stay `reach` (m) apart, with
/// restitution `e`, the separation paid from the pair's relative normal motion (module docs at
/// the top of this file). `rise(Δx_a, Δx_b)` is the potential energy (J) that the two moves
/// add. Returns `None` when they do not touch, else what the pair could not pay (J).
fn impulse_pair(
    a: Side<'_>,
    b: Side<'_>,
    reach: f64,
    e: f64,
    rise: &dyn Fn(DVec3, DVec3) -> f64,
) -> Option<f64> {
    let w = a.w + b.w;
    let (distance, d) = distance_and_direction(*b.x - *a.x);
    if distance >= reach || w == 0.0 {
        return None;
    }
    // Separate by the penetration p, shared in proportion to the inverse masses.
    let p = reach - distance;
    let (dx_a, dx_b) = (-(a.w / w * p) * d, (b.w / w * p) * d);
    *a.x += dx_a;
    *b.x += dx_b;
    // v_rel = (v_b - v_a)·d̂ < 0: approaching; s² = v_rel² - 2 ΔU (w_a + w_b) at contact.
    let v_rel = (*b.v - *a.v).dot(d);
    let climb = rise(dx_a, dx_b);
    if climb == 0.0 {
        // Nothing to pay: the textbook impulse J = -(1 + e) v_rel / (w_a + w_b).
        if v_rel < 0.0 {
            let j = -(1.0 + e) * v_rel / w;
            *a.v -= (a.w * j) * d;
            *b.v += (b.w * j) * d;
        }
        return Some(0.0);
    }
    let mut s2 = v_rel * v_rel - 2.0 * climb * w;
    let mut debt = 0.0;
    if s2 < 0.0 {
        // ½ μ s² < 0: the relative normal motion cannot pay the separation; the rest is owed.
        debt = -0.5 * s2 / w;
        s2 = 0.0;
    }
    let s = s2.sqrt();
    let v_rel_new = if v_rel < 0.0 { e * s } else { s };
    // J = μ (v_rel' - v_rel), equal and opposite on the two bodies.
    let j = (v_rel_new - v_rel) / w;
    *a.v -= (a.w * j) * d;
    *b.v += (b.w * j) * d;
    Some(debt)
}
