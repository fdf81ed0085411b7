//! Velocity response and projection after a step (module docs of `collide`, "Velocity response
//! and projection").

use glam::DVec3;

use super::budget::take_kinetic_with_spheres;
use super::{
    Bodies, Broad, Collider, Contact, ContactParams, PartBounds, World, keep_verlet_history,
    step_spheres,
};
use crate::physics::fast::bounds::boxes;

/// Velocity response and positional projection of every free particle against the model's
/// colliders, after a step of `dt` seconds (module docs). Keeps position Verlet's history
/// consistent: a particle whose velocity changed gets `x_prev = x - dt v`.
pub fn resolve<'a, 'b>(model: impl Into<World<'a>>, state: impl Into<Bodies<'b>>, dt: f64) {
    resolve_logged(model, state, dt, None);
}

/// [`resolve`], recording in `log` (when given) every particle it changes.
///
/// The energy budget of the module docs: each particle pays its projection from its own kinetic
/// energy first; what it cannot pay the whole body pays at the end ([`take_kinetic`]).
pub fn resolve_logged<'a, 'b>(
    model: impl Into<World<'a>>,
    state: impl Into<Bodies<'b>>,
    dt: f64,
    log: Option<&mut Changes>,
) {
    resolve_prepared(model, state, dt, log, None);
}

/// [`resolve_logged`] with the particles that may touch a collider taken from the parts'
/// summaries `parts` (made at the positions the state has now, `prepared.rs`) instead of a
/// scan of every particle: the same result.
pub fn resolve_prepared<'a, 'b>(
    model: impl Into<World<'a>>,
    state: impl Into<Bodies<'b>>,
    dt: f64,
    mut log: Option<&mut Changes>,
    parts: Option<&[PartBounds]>,
) {
    let (model, state) = (model.into(), state.into());
    if model.colliders.is_empty() {
        return;
    }
    let params = &model.contact;
    let gravity = model.gravity;
    let n = state.x.len().min(model.particle_count());
    // Where every particle was before the responses: each particle's springs are measured
    // against these, so that no particle's answer depends on the order (module docs). The
    // positions stay as they are until every particle has been answered: the new positions
    // and velocities of the particles that respond wait in `moved`.
    let before: &[DVec3] = &state.x[..n];
    let mut moved: Vec<(usize, DVec3, DVec3)> = Vec::new();
    // Each collider's bounds once per call, not once per particle as `Collider::may_touch` in
    // `respond` makes them: a particle they rule out is one `respond` leaves as it is. A plane's
    // bound is its own `φ < ε` test (with a margin), inline: most particles of a body resting
    // on a plane are far from it, and calling `respond` for each cost more than the response.
    let broads: Vec<Broad> = (model.colliders.iter())
        .map(|c| c.broad(params.epsilon))
        .collect();
    // Far from every collider (most particles of a body resting on one): nothing to do. The
    // others, in index order.
    let near = if parts.is_some() {
        Vec::new()
    } else {
        near_any(&broads, before)
    };
    let scanned = near.iter().enumerate().flat_map(|(k, &word)| {
        let mut bits = word;
        std::iter::from_fn(move || {
            (bits != 0).then(|| {
                let i = 64 * k + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                i
            })
        })
    });
    let summed =
        (parts.unwrap_or_default().iter()).flat_map(|p| p.near.iter().map(|&i| i as usize));
    let candidates = scanned.chain(summed);
    let mut owed = 0.0;
    for i in candidates {
        let w = model.inv_mass[i];
        if w == 0.0 {
            continue;
        }
        let (x_old, v_old) = (before[i], state.v[i]);
        let (mut x, mut v) = (x_old, v_old);
        let mut touched = false;
        for (collider, broad) in model.colliders.iter().zip(&broads) {
            if !broad.may_touch(x) {
                continue;
            }
            // The rise of potential energy per kg from `from` to `to` (J/kg): gravity, and the
            // springs at i (neighbours where they were) where they gain; a release is not paid
            // back.
            let rise = |from: DVec3, to: DVec3| {
                let elastic = model.elastic_at(before, i, to) - model.elastic_at(before, i, from);
                -gravity.dot(to - from) + w * elastic.max(0.0)
            };
            if let Some(debt) = respond(collider, 0.0, params, &rise, &mut x, &mut v) {
                touched = true;
                owed += debt / w;
            }
        }
        if touched {
            moved.push((i, x, v));
            if let Some(log) = log.as_deref_mut() {
                log.record(i, x_old, v_old);
            }
        }
    }
    for (i, x, v) in moved {
        state.x[i] = x;
        state.v[i] = v;
        keep_verlet_history(state.history_valid, &mut state.x_prev[i], x, v, dt);
    }
    if owed > 0.0 {
        // Every particle's velocity changes: record them all (the records made above come first
        // and are the ones kept).
        if let Some(log) = log {
            log.record_free(model.inv_mass, &state.x[..n], &state.v[..n]);
        }
        take_kinetic(model.inv_mass, &mut state.v[..n], owed);
        for i in (0..n).filter(|&i| model.inv_mass[i] != 0.0) {
            keep_verlet_history(
                state.history_valid,
                &mut state.x_prev[i],
                state.x[i],
                state.v[i],
                dt,
            );
        }
    }
}

/// The particles at `x` that one of `broads` may touch ([`Broad::may_touch`]), as bits: bit
/// `i % 64` of word `i / 64`. One loop per collider over all the particles, without a branch
/// per particle ([`Broad::marks`]), so that a body resting on a collider costs a few
/// operations per particle far from it.
pub(super) fn near_any(broads: &[Broad], x: &[DVec3]) -> Vec<u64> {
    let mut near = Vec::new();
    near_any_into(broads, x, &mut near);
    near
}

/// [`near_any`] into `near` (its allocation reused). The points go in tiles of [`TILE`]: a
/// tile whose box a collider's bounds rule out as a whole ([`Broad::box_may_touch`]) is not
/// looked at point by point for that collider (a body's inside, far from every collider, or a
/// body falling towards a bowl: most tiles), with the same marks. A collider that ruled out
/// no tile in a call is tested point by point, without boxes, for the next [`PAUSE`] calls
/// on the same thread (a body resting across a floor's level, in every tile): whether a
/// tile's box is looked at never changes a mark, only the time.
pub(super) fn near_any_into(broads: &[Broad], x: &[DVec3], near: &mut Vec<u64>) {
    near.clear();
    near.resize(x.len().div_ceil(64), 0);
    if broads.is_empty() {
        return;
    }
    TILES.with(|tiles| {
        let Tiles {
            boxes: tiles,
            pause,
        } = &mut *tiles.borrow_mut();
        if pause.len() < broads.len() {
            pause.resize(broads.len(), 0);
        }
        if pause[..broads.len()].contains(&0) {
            boxes(x, TILE, tiles, |lo, hi| (lo, hi));
        }
        for (broad, pause) in broads.iter().zip(pause.iter_mut()) {
            if *pause > 0 {
                *pause -= 1;
                for (word, xs) in near.iter_mut().zip(x.chunks(64)) {
                    *word |= broad.marks(xs);
                }
                continue;
            }
            let mut ruled_out = false;
            for (t, (&(lo, hi), xs)) in tiles.iter().zip(x.chunks(TILE)).enumerate() {
                if broad.box_may_touch(lo, hi) {
                    let first = t * TILE;
                    near[first / 64] |= broad.marks(xs) << (first % 64);
                } else {
                    ruled_out = true;
                }
            }
            if !ruled_out {
                *pause = PAUSE;
            }
        }
    });
}

/// Points per tile of [`near_any_into`] (a divisor of 64 and a multiple of 8).
const TILE: usize = 64;

/// Calls of [`near_any_into`] without boxes for a collider after one in which they ruled out
/// nothing.
const PAUSE: u8 = 15;

/// A thread's scratch of [`near_any_into`]: the tiles' boxes, and per collider (by its index)
/// the calls left without them.
#[derive(Default)]
struct Tiles {
    boxes: Vec<(DVec3, DVec3)>,
    pause: Vec<u8>,
}

thread_local! {
    static TILES: std::cell::RefCell<Tiles> = std::cell::RefCell::new(Tiles::default());
}

/// The body pays `amount` J from its kinetic energy ([`take_kinetic_with_spheres`]); every
/// free particle's velocity changes, so `log` records them all (the records made before come
/// first and are the ones kept) and Verlet's history follows.
pub(super) fn pay(
    world: World,
    state: &mut Bodies,
    amount: f64,
    dt: f64,
    log: Option<&mut Changes>,
) {
    let n = state.x.len().min(world.particle_count());
    let free = || (0..n).filter(|&i| world.inv_mass[i] != 0.0);
    if let Some(log) = log {
        log.record_free(world.inv_mass, &state.x[..n], &state.v[..n]);
    }
    take_kinetic_with_spheres(world.inv_mass, &mut state.v[..n], state.spheres, amount);
    if !state.history_valid {
        return;
    }
    for i in free() {
        keep_verlet_history(
            state.history_valid,
            &mut state.x_prev[i],
            state.x[i],
            state.v[i],
            dt,
        );
    }
}

/// Takes `amount` joules (at most all there is) out of the kinetic energy of the free particles
/// by scaling every velocity by one factor, and returns what it took (J):
///
/// ```text
/// K  = Σ ½ m_i |v_i|²
/// v' = √(1 - ΔE/K) v,       ΔE = min(amount, K)
/// ```
/// where `m_i` (kg) are the masses (`inv_mass`: 1/kg, zero for a pinned particle, which is
/// left alone) and `v_i` (m/s) the velocities. One factor for all keeps the shape of the motion
/// (the direction of every velocity and their ratios); it is the body's payment for a contact
/// correction that raised its potential energy (module docs, "energy budget").
pub fn take_kinetic(inv_mass: &[f64], v: &mut [DVec3], amount: f64) -> f64 {
    take_kinetic_with_spheres(inv_mass, v, &mut [], amount)
}

/// What a collision response changed, for the energy it removed without a pass over the whole
/// system ([`crate::physics::energy::energy_change`]): every particle it moved or slowed, with its
/// position (m) and velocity (m/s) before the first change, and the dynamic spheres' energy
/// before (J).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Changes {
    /// `(particle, x before, v before)`, sorted by particle, each once after [`Changes::finish`].
    pub particles: Vec<(u32, DVec3, DVec3)>,
    /// Kinetic and gravitational energy of the non-kinematic spheres before (J).
    pub(crate) spheres_before: f64,
    /// After [`Changes::finish`]: `slot[i]` is the index of particle `i` in `particles`, or
    /// `u32::MAX` when it did not change (grown to the particle count on first use).
    slot: Vec<u32>,
    /// Scratch of [`Changes::finish`] (reused).
    sorted: Vec<(u32, DVec3, DVec3)>,
    /// False when `particles` may hold a particle twice or out of order; true while it is
    /// already what [`Changes::finish`] makes of it (sorted by particle, each once, `slot`
    /// pointing at each): records made in increasing particle order, or [`Changes::record_free`].
    /// Then a record of a particle already recorded is left out (the first is the one kept) and
    /// `finish` has nothing to do.
    disordered: bool,
}

impl Changes {
    /// Forgets everything recorded.
    pub fn clear(&mut self) {
        for &(i, ..) in &self.particles {
            if let Some(s) = self.slot.get_mut(i as usize) {
                *s = u32::MAX;
            }
        }
        self.particles.clear();
        self.spheres_before = 0.0;
        self.disordered = false;
    }

    /// Records particle `i` at `x` (m), `v` (m/s) before a change; its first record is
    /// [`Changes::of`] it from now on.
    #[inline]
    pub(crate) fn record(&mut self, i: usize, x: DVec3, v: DVec3) {
        if self.slot.len() <= i {
            self.slot.resize(i + 1, u32::MAX);
        }
        if self.slot[i] == u32::MAX {
            self.slot[i] = self.particles.len() as u32;
        } else if !self.disordered {
            // Recorded before, and the list is in order: the first record is the one kept.
            return;
        }
        if self
            .particles
            .last()
            .is_some_and(|last| last.0 as usize >= i)
        {
            self.disordered = true;
        }
        self.particles.push((i as u32, x, v));
    }

    /// Records every free particle (`inv_mass` not zero) at `x` (m), `v` (m/s) before a change
    /// of them all (the body's payment): the same as [`Changes::record`] of each in turn, with
    /// the list left as [`Changes::finish`] makes it (each particle's first record, in order).
    pub(super) fn record_free(&mut self, inv_mass: &[f64], x: &[DVec3], v: &[DVec3]) {
        let n = x.len().min(v.len()).min(inv_mass.len());
        if self.particles.iter().any(|p| p.0 as usize >= n) {
            // Records beyond the particles given (none in the callers): one at a time.
            for i in (0..n).filter(|&i| inv_mass[i] != 0.0) {
                self.record(i, x[i], v[i]);
            }
            return;
        }
        if self.slot.len() < n {
            self.slot.resize(n, u32::MAX);
        }
        // Each record written field by field into its place: a tuple put together first went
        // through the stack in pieces of other sizes than it was read back in, a stalled load
        // per record and most of this loop's time (measured).
        // Grown by copies of a blank slice (`resize` put each blank together on the stack too).
        const BLANK: [(u32, DVec3, DVec3); 64] = [(0, DVec3::ZERO, DVec3::ZERO); 64];
        self.sorted.truncate(n);
        while self.sorted.len() < n {
            let more = (n - self.sorted.len()).min(BLANK.len());
            self.sorted.extend_from_slice(&BLANK[..more]);
        }
        let (slot, earlier) = (&mut self.slot[..n], &self.particles);
        let mut k = 0;
        for i in 0..n {
            let first = slot[i];
            let record = &mut self.sorted[k];
            if first != u32::MAX {
                // Its first record, made before.
                let (j, x, v) = &earlier[first as usize];
                (record.0, record.1, record.2) = (*j, *x, *v);
            } else if inv_mass[i] != 0.0 {
                (record.0, record.1, record.2) = (i as u32, x[i], v[i]);
            } else {
                continue;
            }
            slot[i] = k as u32;
            k += 1;
        }
        self.sorted.truncate(k);
        std::mem::swap(&mut self.particles, &mut self.sorted);
        self.disordered = false;
    }

    /// Sorts the records by particle and keeps each particle's first (its state before any
    /// change); `particles` is the system's particle count.
    pub fn finish(&mut self, particles: usize) {
        if self.slot.len() < particles {
            self.slot.resize(particles, u32::MAX);
        }
        if !self.disordered {
            // Already in order, each particle once.
            return;
        }
        self.disordered = false;
        if self.particles.len() < self.slot.len() / 4 {
            // A few records: a stable sort keeps the records of one particle in the order they
            // were made.
            self.particles.sort_by_key(|p| p.0);
            self.particles.dedup_by_key(|p| p.0);
            for (k, &(i, ..)) in self.particles.iter().enumerate() {
                self.slot[i as usize] = k as u32;
            }
            return;
        }
        // Many (a payment records every free particle): each particle's first record, found
        // through `slot` (unrecorded particles hold u32::MAX there), then the particles in
        // order; the same list as the sort's, without comparisons.
        for (k, &(i, ..)) in self.particles.iter().enumerate() {
            let s = &mut self.slot[i as usize];
            if *s == u32::MAX {
                *s = k as u32;
            }
        }
        self.sorted.clear();
        for s in &mut self.slot {
            if *s != u32::MAX {
                let k = std::mem::replace(s, self.sorted.len() as u32);
                self.sorted.push(self.particles[k as usize]);
            }
        }
        std::mem::swap(&mut self.particles, &mut self.sorted);
    }

    /// Kinetic and gravitational energy of the non-kinematic spheres before the responses (J).
    #[must_use]
    pub fn spheres_before(&self) -> f64 {
        self.spheres_before
    }

    /// The record of particle `i` (its first), if it changed.
    pub(crate) fn of(&self, i: usize) -> Option<&(u32, DVec3, DVec3)> {
        let k = *self.slot.get(i)?;
        self.particles.get(k as usize)
    }
}

/// The response of one point (a particle, or a sphere's centre with `offset` its radius, m) to
/// one collider: projection, climb, bounce, impact friction (module docs). `rise(from, to)` is
/// the potential energy per kg (J/kg) that moving the point from `from` to `to` adds. Returns
/// `None` when nothing changed, else what the point's own kinetic energy could not pay and it
/// owes its body (J/kg).
pub(super) fn respond(
    collider: &Collider,
    offset: f64,
    params: &ContactParams,
    rise: &dyn Fn(DVec3, DVec3) -> f64,
    x: &mut DVec3,
    v: &mut DVec3,
) -> Option<f64> {
    let (phi, normal, v_n) = touching(collider, offset, params, *x, *v)?;
    let mut v_t = *v - v_n * normal;
    // Squared normal speed at the surface: s² = v_N² - 2 Δu, with Δu = u(x + Δx) - u(x) and
    // Δx = -φ N.
    let mut s2 = v_n * v_n;
    if phi < 0.0 {
        let start = *x;
        *x = start - phi * normal;
        s2 -= 2.0 * rise(start, *x);
    }
    let mut debt = 0.0;
    if s2 < 0.0 {
        // The climb costs more than the normal motion has: take the rest (J/kg) from the
        // tangential kinetic energy, ½|v_T|² → max(0, ½|v_T|² - ½|s²|), and owe the body what
        // that does not cover.
        let t2 = v_t.length_squared();
        if t2 + s2 > 0.0 {
            v_t *= ((t2 + s2) / t2).sqrt();
        } else {
            debt = -0.5 * (t2 + s2);
            v_t = DVec3::ZERO;
        }
        s2 = 0.0;
    }
    let s = s2.sqrt();
    let v_n_new = if v_n >= 0.0 {
        // Already moving away: only the climb to the surface slows it.
        s
    } else if s > params.rest_speed {
        // Colliding: v_N' = -k_r v_N at the surface.
        params.restitution * s
    } else {
        // Resting contact: no bounce.
        0.0
    };
    // Impact friction: |v_T| loses k_f times the normal velocity gained, never reversing.
    let gained = v_n_new - v_n;
    let t = v_t.length();
    if gained > 0.0 && t > 0.0 {
        v_t *= (1.0 - params.friction * gained / t).max(0.0);
    }
    *v = v_t + v_n_new * normal;
    Some(debt)
}

/// The contact [`respond`] answers for a point at `x` (m) moving at `v` (m/s): its distance
/// `φ` past the surface (m, less `offset`), the normal and the normal speed `v·N` (m/s); `None`
/// when [`respond`] leaves the point as it is (out of reach, or within `ε` and not moving in).
fn touching(
    collider: &Collider,
    offset: f64,
    params: &ContactParams,
    x: DVec3,
    v: DVec3,
) -> Option<(f64, DVec3, f64)> {
    if !collider.may_touch(x, params.epsilon + offset) {
        return None;
    }
    touching_past_bounds(collider, offset, params, x, v)
}

/// [`touching`] for a point its collider's bounds do not rule out (the bounds already asked).
fn touching_past_bounds(
    collider: &Collider,
    offset: f64,
    params: &ContactParams,
    x: DVec3,
    v: DVec3,
) -> Option<(f64, DVec3, f64)> {
    let Contact { phi, normal } = collider.contact(x)?;
    // A sphere touches when its centre is within its radius of the surface.
    let phi = phi - offset;
    let v_n = v.dot(normal);
    if phi >= params.epsilon || (phi >= 0.0 && v_n >= 0.0) {
        return None;
    }
    Some((phi, normal, v_n))
}

/// True when [`respond`] would answer a particle at `x` (m) moving at `v` (m/s) with a change
/// (its tests before it reads the body's springs): a particle for which this is false for
/// every collider is one [`resolve`] leaves as it is. `broad` is the collider's bounds at
/// `params.epsilon` (`collider.broad(params.epsilon)`), made once for many points.
pub(super) fn responds_within(
    broad: &Broad,
    collider: &Collider,
    params: &ContactParams,
    x: DVec3,
    v: DVec3,
) -> bool {
    let passes = match collider {
        // `Collider::may_touch` asks no bounds of a plane.
        Collider::Plane { .. } => true,
        _ => broad.may_touch(x),
    };
    passes && touching_past_bounds(collider, 0.0, params, x, v).is_some()
}

/// Everything collisions do after an integrator step of `dt` seconds: [`step_spheres`], then
/// [`resolve`]. Returns at once when the model has no colliders and the state no spheres, so
/// scenes without obstacles pay nothing. `Simulation::step` calls it for every body.
pub fn after_step<'a, 'b>(model: impl Into<World<'a>>, state: impl Into<Bodies<'b>>, dt: f64) {
    let (model, mut state) = (model.into(), state.into());
    step_spheres(model, state.reborrow(), dt);
    resolve(model, state, dt);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// While records are made (before `finish`), `of` gives each particle's first record, and
    /// nothing for a particle not recorded (the spheres' separations read their neighbours'
    /// positions before the call through it); after `finish` and `clear` as before.
    #[test]
    fn of_gives_the_first_record_while_recording() {
        let mut changes = Changes::default();
        let p = |k: f64| DVec3::splat(k);
        for round in 0..2 {
            changes.clear();
            changes.record(5, p(1.0), p(-1.0));
            changes.record(2, p(2.0), p(-2.0));
            changes.record(5, p(3.0), p(-3.0));
            changes.record(40, p(4.0), p(-4.0));
            assert_eq!(changes.of(5).map(|r| r.1), Some(p(1.0)), "round {round}");
            assert_eq!(changes.of(2).map(|r| r.2), Some(p(-2.0)));
            assert_eq!(changes.of(40).map(|r| r.1), Some(p(4.0)));
            assert!(changes.of(3).is_none() && changes.of(41).is_none());
            changes.finish(50);
            assert_eq!(changes.of(5).map(|r| r.1), Some(p(1.0)));
            assert_eq!(changes.particles.len(), 3);
            assert!(changes.of(3).is_none());
        }
        changes.clear();
        assert!(changes.of(5).is_none() && changes.of(2).is_none() && changes.of(40).is_none());
    }

    #[test]
    fn finish_keeps_each_particles_first_record_in_particle_order() {
        // Few records (the sort) and many (through `slot`), with repeats in any order, against
        // a stable sort and dedup; then cleared and used again.
        let mut changes = Changes::default();
        let mut seed = 7u64;
        for (count, particles) in [(5, 100), (300, 100), (40, 64), (64, 64), (0, 10)] {
            changes.clear();
            let mut expected = Vec::new();
            for k in 0..count {
                seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                let i = (seed >> 33) as usize % particles;
                let r = (i as u32, DVec3::splat(k as f64), DVec3::splat(-(k as f64)));
                changes.record(i, r.1, r.2);
                expected.push(r);
            }
            expected.sort_by_key(|p| p.0);
            expected.dedup_by_key(|p| p.0);
            changes.finish(particles);
            assert_eq!(
                changes.particles, expected,
                "{count} records of {particles}"
            );
            for i in 0..particles {
                let want = expected.iter().find(|r| r.0 as usize == i);
                assert_eq!(changes.of(i), want, "particle {i}");
            }
        }
    }

    #[test]
    fn record_free_is_a_record_of_every_free_particle() {
        // Records before (in order, out of order, repeated), the payment's records of every
        // free particle, and records after it (a free particle again, a pinned one out of
        // order): the list `finish` ends with is the stable sort and dedup of all the records
        // made one at a time, as before `record_free` and `finish`'s shortcut existed; `of`
        // agrees while recording and after.
        let n = 150;
        let inv_mass: Vec<f64> = (0..n).map(|i| if i % 7 == 3 { 0.0 } else { 0.5 }).collect();
        let p = |k: usize| DVec3::new(k as f64, -(k as f64), 0.25 * k as f64);
        let x: Vec<DVec3> = (0..n).map(|i| p(1000 + i)).collect();
        let v: Vec<DVec3> = (0..n).map(|i| p(2000 + i)).collect();
        let before: [&[usize]; 4] = [&[], &[4, 9, 70], &[70, 4, 9, 4, 3], &[149, 0, 3]];
        let after: [&[usize]; 3] = [&[], &[5, 9], &[140, 10, 17]];
        let mut changes = Changes::default();
        for (b, first) in before.iter().enumerate() {
            for (a, last) in after.iter().enumerate() {
                changes.clear();
                let mut all = Vec::new();
                let record = |changes: &mut Changes, all: &mut Vec<_>, i: usize, k: usize| {
                    changes.record(i, p(k), p(k + 1));
                    all.push((i as u32, p(k), p(k + 1)));
                };
                for (k, &i) in first.iter().enumerate() {
                    record(&mut changes, &mut all, i, 10 * k);
                }
                changes.record_free(&inv_mass, &x, &v);
                all.extend(
                    (0..n)
                        .filter(|&i| inv_mass[i] != 0.0)
                        .map(|i| (i as u32, x[i], v[i])),
                );
                for i in 0..n {
                    let want = all.iter().find(|r| r.0 as usize == i);
                    assert_eq!(changes.of(i), want, "{b} {a}: particle {i} while recording");
                }
                for (k, &i) in last.iter().enumerate() {
                    record(&mut changes, &mut all, i, 500 + 10 * k);
                }
                changes.finish(n);
                all.sort_by_key(|r| r.0);
                all.dedup_by_key(|r| r.0);
                assert_eq!(changes.particles, all, "{b} {a}");
                for i in 0..n {
                    let want = all.iter().find(|r| r.0 as usize == i);
                    assert_eq!(changes.of(i), want, "{b} {a}: particle {i}");
                }
            }
        }
    }

    #[test]
    fn near_any_marks_what_some_collider_may_touch() {
        // Every kind of collider, alone and together, against particles on a grid through
        // them (inside, near, far), a NaN position and a count that is not a whole word.
        let colliders = [
            Collider::Plane {
                point: DVec3::new(0.0, 0.1, 0.0),
                normal: DVec3::new(0.0, 1.0, 0.0),
            },
            Collider::Sphere {
                center: DVec3::new(0.3, 0.5, 0.0),
                radius: 0.25,
            },
            Collider::Bowl {
                center: DVec3::new(-0.4, 0.6, 0.1),
                radius: 0.5,
                rim_height: 0.6,
            },
            Collider::HolePlane {
                point: DVec3::ZERO,
                normal: DVec3::new(0.0, 1.0, 0.0),
                hole_center: DVec3::new(0.5, 0.0, -0.2),
                hole_radius: 0.3,
            },
        ];
        let mut x: Vec<DVec3> = (0..7 * 7 * 4)
            .map(|i| {
                let (a, b, c) = (i % 7, (i / 7) % 7, i / 49);
                DVec3::new(
                    0.2 * f64::from(a) - 0.6,
                    0.2 * f64::from(b) - 0.3,
                    0.1 * f64::from(c),
                )
            })
            .collect();
        x[70] = DVec3::new(f64::NAN, 0.0, 0.0);
        for k in 0..=colliders.len() {
            let list = if k == colliders.len() {
                &colliders[..]
            } else {
                &colliders[k..=k]
            };
            let broads: Vec<Broad> = list.iter().map(|c| c.broad(1e-3)).collect();
            let near = near_any(&broads, &x);
            let mut touching = 0;
            for (i, p) in x.iter().enumerate() {
                let expected = broads.iter().any(|b| b.may_touch(*p));
                assert_eq!(
                    near[i / 64] >> (i % 64) & 1 == 1,
                    expected,
                    "particle {i}, {list:?}"
                );
                touching += usize::from(expected);
            }
            // Neither none nor all: the grid reaches both sides of every bound.
            assert!(touching > 1 && touching < x.len(), "{list:?}: {touching}");
        }
    }

    /// Tiles ruled out as a whole (`Broad::box_may_touch`) hold no point the point test lets
    /// through, so `near_any` marks exactly the points `Broad::may_touch` does: clusters of 64
    /// points, small and large, jittered around every collider's bounds (a hair inside and
    /// outside each, above and below a floor, at a bowl's rim), with floors along +y, -x and
    /// tilted, and clusters holding a NaN or an infinite coordinate. Many tiles are ruled out
    /// (else the tiles would save nothing) and many are not.
    #[test]
    fn tiles_ruled_out_as_a_whole_hold_no_point_that_may_touch() {
        let epsilon = 0.01;
        let colliders = [
            Collider::plane(DVec3::new(0.0, -1.0, 0.5), DVec3::new(0.3, 1.0, -0.2)),
            Collider::sphere(DVec3::new(0.5, 0.2, -0.3), 1.5),
            Collider::course_2023_terrain()[1],
            Collider::course_2023_terrain()[0],
            Collider::hole_plane(
                DVec3::new(1.0, 0.0, 0.0),
                -DVec3::X,
                DVec3::new(1.0, 2.0, 1.0),
                3.0,
            ),
            Collider::hole_plane(
                DVec3::ZERO,
                DVec3::new(0.1, 1.0, 0.0),
                DVec3::new(2.0, 0.0, 1.0),
                6.0,
            ),
        ];
        // Centres of clusters: a walk through and around every collider.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut random = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (mut ruled_out, mut kept) = (0, 0);
        for collider in colliders {
            let broads = [collider.broad(epsilon)];
            for c in 0..400 {
                let mut centre = DVec3::new(
                    2.0 + 24.0 * random(),
                    12.0 * random(),
                    1.0 + 24.0 * random(),
                );
                let size = [1e-9, 1e-3, 0.05, 0.5, 3.0][c % 5];
                // Every other cluster on the surface (give or take its size and the band).
                if c % 2 == 1
                    && let Some(contact) = collider.contact(centre)
                {
                    centre -= (contact.phi + epsilon * 2.0 * random()) * contact.normal;
                }
                let mut x: Vec<DVec3> = (0..64)
                    .map(|_| centre + size * DVec3::new(random(), random(), random()))
                    .collect();
                if c % 37 == 0 {
                    x[17].z = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][c % 3];
                }
                // The box `near_any` takes (a NaN coordinate: that axis infinite).
                let super::super::prepared::Aabb { lo, hi } = super::super::prepared::Aabb::of(&x);
                let whole = broads[0].box_may_touch(lo, hi);
                let each: u64 = (x.iter().enumerate())
                    .map(|(i, p)| u64::from(broads[0].may_touch(*p)) << i)
                    .sum();
                if !whole {
                    assert_eq!(each, 0, "{collider:?}: {lo} {hi}");
                }
                assert_eq!(near_any(&broads, &x), vec![each], "{collider:?}: {lo} {hi}");
                ruled_out += usize::from(!whole);
                kept += usize::from(whole);
            }
        }
        assert!(
            ruled_out > 400 && kept > 400,
            "{ruled_out} ruled out, {kept} kept"
        );
    }
}
