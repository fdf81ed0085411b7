//! The collision response's broad phase, prepared part by part while the particles are in the
//! cache of the thread that stepped them.
//!
//! The response after a step ([`super::resolve`], [`super::collide_spheres`]) first asks which
//! particles may touch something, and the energy ledger asks whether every position is calm
//! ([`super::calm`]): questions about every particle, whose answers are the same whichever
//! thread computes them. When a team of threads steps a body in parts
//! (`physics::fast::stencil`'s team), each thread answers them for its own part right after
//! writing it ([`Prepared::prepare`]); the response, on one thread, then reads one summary per
//! part instead of every particle, whose cache lines would otherwise move to its core at every
//! step. For a part of particles `q0..q1` at positions `x` and velocities `v`:
//!
//! ```text
//! box_j  = [min x_i, max x_i]   over i in q0 + B j .. min(q0 + B (j + 1), q1)   (m)
//!          (an axis with a NaN coordinate: (-∞, ∞))
//! calm   = every x_i calm (|coordinate| < 1e50 m)  ⟺  every box_j inside (-1e50, 1e50)³
//! near   = { i : some collider's bounds may hold x_i            (Broad::may_touch)
//!                and some collider answers (x_i, v_i) }         (response::responds_within)
//!          in index order
//! ```
//! where `B` is [`BOX`] particles (`fast::bounds`, eight points at a time), and a collider
//! answers a particle when its response's first tests let it through: within reach of the
//! surface, and inside it or within `ε` of it moving in (`φ < 0`, or `φ < ε` and `v·N < 0`).
//! A body resting on a collider has most of its lowest layer within the bounds but, measured
//! on the resting jelly cube, about one particle in a hundred of those answered: the response
//! on one thread then visits one or two particles a step instead of a hundred. When every
//! collider is a plane, both questions are asked in one pass, eight particles at a time
//! (`fast::bounds::plane_answer_bits`: a plane answers only particles its bounds hold, so the
//! same set). Without `v` (a caller that has none) `near` is the bounds' set alone.
//! A box only lets the sphere–particle test skip particles it
//! cannot reach, and `near` only the colliders' test: both rule out exactly the particles the
//! exact tests would leave alone, so the response's result is the same bit for bit whether its
//! boxes are one part's or the whole body's (any split). The response uses a summary only when
//! every part of the body has one from the step just taken ([`Prepared::take`]); otherwise it
//! scans the particles itself, as without a team.
//!
//! **Kinematic spheres push in the parts.** When every sphere is kinematic (driven, infinitely
//! heavy: `spheres::kinematic_only`), a particle's push depends only on that particle and the
//! spheres, and no push changes a sphere. The thread that summed up a part then also pushes its
//! particles ([`Prepared::prepare`], `spheres::push_part`), with the spheres moved as the
//! response moves them first:
//!
//! ```text
//! c'  = c + dt u                                  (each kinematic sphere, velocity u)
//! for each sphere, each box of the part within reach, each particle i of the box in order:
//!     |x_i - c'|² < r² (1 + 1e-9)  ⟹  impulse and separation, as the response makes them
//! ```
//! where `dt` is the step (s), `c`, `c'` the centre before and after (m) and `r` the radius
//! (m). The response then records each part's pushes (the first state of each particle it
//! changed) instead of making them: the same particles, records and spheres, bit for bit
//! (tested), on both threads instead of one. When the spheres it moved are not those the parts
//! were given, bit for bit, it puts the parts' particles back and pushes them itself.

use std::cell::RefCell;
use std::sync::{Mutex, MutexGuard, PoisonError};

use glam::DVec3;

#[cfg(test)]
use super::response::near_any;
use super::response::{near_any_into, responds_within};
use super::spheres::push_part;
use super::{Broad, Collider, DynamicSphere, World, calm};
use crate::physics::fast::bounds::{boxes, plane_answer_bits, plane_bits};

/// Particles per box of the sphere–particle broad phase.
pub(super) const BOX: usize = 32;

/// At most this many planes are tested together in one pass over a part
/// ([`PartBounds::sum_up`] with velocities); more go through the bounds one by one.
const PLANES: usize = 4;

/// An axis-aligned bounding box (m).
#[derive(Clone, Copy, Debug)]
pub(super) struct Aabb {
    pub(super) lo: DVec3,
    pub(super) hi: DVec3,
}

impl Aabb {
    /// The box of `points` (NaN coordinates make it cover everything on their axis), the same
    /// box as [`Aabb::include`] of every point in turn: `min` and `max` pass over a NaN, and a
    /// NaN anywhere on an axis makes that axis infinite at the end (one dependent operation per
    /// point and axis instead of two). The textbook form of `fast::bounds::boxes`, which
    /// [`PartBounds`] uses.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) fn of(points: &[DVec3]) -> Aabb {
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let mut nan = glam::BVec3::FALSE;
        for &p in points {
            lo = lo.min(p);
            hi = hi.max(p);
            nan |= p.is_nan_mask();
        }
        Aabb {
            lo: DVec3::select(nan, DVec3::NEG_INFINITY, lo),
            hi: DVec3::select(nan, DVec3::INFINITY, hi),
        }
    }

    /// Grows the box to hold `p`; a NaN coordinate makes it infinite on that axis.
    pub(super) fn include(&mut self, p: DVec3) {
        let nan = p.is_nan_mask();
        self.lo = DVec3::select(nan, DVec3::NEG_INFINITY, self.lo.min(p));
        self.hi = DVec3::select(nan, DVec3::INFINITY, self.hi.max(p));
    }

    /// The squared distance (m²) from `c` to the nearest point of the box (0 inside).
    pub(super) fn distance_squared(&self, c: DVec3) -> f64 {
        let d = (self.lo - c).max(c - self.hi).max(DVec3::ZERO);
        d.length_squared()
    }
}

/// One part's summary (module docs).
#[derive(Clone, Debug, Default)]
pub struct PartBounds {
    /// The part is particles `start..end`.
    pub(super) start: usize,
    pub(super) end: usize,
    /// The box of every [`BOX`] particles from `start` (the last may hold fewer).
    pub(super) boxes: Vec<Aabb>,
    /// Every position of the part calm when it was summed up.
    pub(super) calm: bool,
    /// The particles some collider may touch, in index order.
    pub(super) near: Vec<u32>,
    /// Bits of `near` before they become indices (scratch).
    bits: Vec<u64>,
    /// Made after the last [`Prepared::take`].
    fresh: bool,
    /// The kinematic spheres pushed the part's particles (`spheres::push_part`) since it was
    /// summed up: `pushed` holds each pushed particle's first `(particle, x, v)`, in the order
    /// of the pushes, and `spheres` the spheres as the part moved them.
    pub(super) pushed_here: bool,
    pub(super) pushed: Vec<(u32, DVec3, DVec3)>,
    pub(super) spheres: Vec<DynamicSphere>,
}

impl PartBounds {
    /// Sums up particles `start..start + x.len()` at positions `x` (m): the boxes when
    /// `with_boxes` (the body has spheres), `near` for the colliders' `broads` (none: left
    /// empty), `calm` always. Planes' bounds and the calm test go eight points at a time
    /// (`fast::bounds::plane_bits`, the same answers), other colliders' one by one.
    pub(super) fn fill(&mut self, broads: &[Broad], start: usize, x: &[DVec3], with_boxes: bool) {
        self.fill_with(start, x, with_boxes, |x, _, bits| {
            let mut calm_known = None;
            let planes = broads.iter().all(|b| matches!(b, Broad::Plane { .. }));
            if planes {
                for broad in broads {
                    if let Broad::Plane {
                        point,
                        normal,
                        phi_max,
                    } = *broad
                    {
                        let all_calm = plane_bits(x, point, normal, phi_max, bits);
                        calm_known = calm_known.or(Some(all_calm));
                    }
                }
            } else {
                near_any_into(broads, x, bits);
            }
            calm_known
        });
    }

    /// The summary of particles `start..start + x.len()` at positions `x` (m) whose `near`
    /// bits `mark(x, boxes, bits)` sets (given the boxes, empty without `with_boxes`; returning,
    /// when it knows it, whether every position is calm): the boxes when `with_boxes`, then
    /// `calm`, then `near` from the bits.
    fn fill_with(
        &mut self,
        start: usize,
        x: &[DVec3],
        with_boxes: bool,
        mark: impl FnOnce(&[DVec3], &[Aabb], &mut Vec<u64>) -> Option<bool>,
    ) {
        self.start = start;
        self.end = start + x.len();
        self.pushed_here = false;
        self.boxes.clear();
        self.near.clear();
        let mut calm_known = None;
        if with_boxes {
            boxes(x, BOX, &mut self.boxes, |lo, hi| Aabb { lo, hi });
            calm_known = Some(self.boxes.iter().all(|b| calm(b.lo) && calm(b.hi)));
        }
        self.bits.clear();
        self.bits.resize(x.len().div_ceil(64), 0);
        let marked = mark(x, &self.boxes, &mut self.bits);
        calm_known = calm_known.or(marked);
        self.calm = calm_known.unwrap_or_else(|| x.iter().all(|p| calm(*p)));
        for (k, &word) in self.bits.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                self.near
                    .push((start + 64 * k + bits.trailing_zeros() as usize) as u32);
                bits &= bits - 1;
            }
        }
    }

    /// Sums up particles `start..start + x.len()` at positions `x` (m) for the colliders of
    /// `world`, with the boxes of the spheres' broad phase when `with_boxes`. With their
    /// velocities `v` (m/s), `near` keeps only the particles some collider would answer
    /// ([`responds_within`]: the response's own first tests, on the same numbers), most often none
    /// of a body resting on a collider, so that the response on one thread visits only those.
    pub fn sum_up<'a>(
        &mut self,
        world: impl Into<World<'a>>,
        start: usize,
        x: &[DVec3],
        v: Option<&[DVec3]>,
        with_boxes: bool,
    ) {
        let world = world.into();
        if let Some(v) = v
            && self.planes_answered(&world, start, x, v, with_boxes)
        {
            return;
        }
        let broads: Vec<Broad> = (world.colliders.iter())
            .map(|c| c.broad(world.contact.epsilon))
            .collect();
        self.fill(&broads, start, x, with_boxes);
        if let Some(v) = v {
            let params = &world.contact;
            self.near.retain(|&i| {
                let k = i as usize - start;
                (world.colliders.iter().zip(&broads))
                    .any(|(c, b)| responds_within(b, c, params, x[k], v[k]))
            });
        }
    }

    /// [`PartBounds::sum_up`] with velocities when every collider is a plane (at most
    /// [`PLANES`]) and the contact band is a number: the particles a plane answers marked in
    /// one pass over `x` and `v`, eight at a time (`fast::bounds::plane_answer_bits`, the
    /// tests of [`responds_within`] on the same numbers). A plane answers only particles its bounds
    /// hold (`φ < ε ≤ φ_max`, or NaN), so `near` is the same as the bounds' set filtered by
    /// [`responds_within`]. False, with nothing done, for other colliders.
    fn planes_answered(
        &mut self,
        world: &World<'_>,
        start: usize,
        x: &[DVec3],
        v: &[DVec3],
        with_boxes: bool,
    ) -> bool {
        let epsilon = world.contact.epsilon;
        let count = world.colliders.len();
        if count > PLANES || epsilon.is_nan() {
            return false;
        }
        let mut planes = [(DVec3::ZERO, DVec3::ZERO); PLANES];
        for (plane, collider) in planes.iter_mut().zip(world.colliders) {
            let Collider::Plane { point, normal } = *collider else {
                return false;
            };
            *plane = (point, normal);
        }
        let broads = planes.map(|(point, normal)| Collider::Plane { point, normal }.broad(epsilon));
        let planes = &planes[..count];
        // With boxes (a body with spheres), only the boxes some plane's bounds may reach are
        // looked at: a plane answers only particles its bounds hold (`φ < ε < φ_max`), and a
        // box ruled out as a whole holds none (`Broad::box_may_touch`); the boxes tell `calm`.
        self.fill_with(start, x, with_boxes, |x, boxes, bits| {
            if boxes.is_empty() {
                return Some(plane_answer_bits(x, v, planes, epsilon, bits));
            }
            for (j, b) in boxes.iter().enumerate() {
                if broads[..count].iter().any(|p| p.box_may_touch(b.lo, b.hi)) {
                    let (first, end) = (j * BOX, ((j + 1) * BOX).min(x.len()));
                    let mut word = [0];
                    plane_answer_bits(&x[first..end], &v[first..end], planes, epsilon, &mut word);
                    bits[first / 64] |= word[0] << (first % 64);
                }
            }
            None
        });
        true
    }

    /// Every position was calm when the part was summed up.
    #[must_use]
    pub fn calm(&self) -> bool {
        self.calm
    }

    /// The boxes with the particles each holds.
    pub(super) fn boxes_mut(
        &mut self,
    ) -> impl Iterator<Item = (std::ops::Range<usize>, &mut Aabb)> + '_ {
        let (start, end) = (self.start, self.end);
        (self.boxes.iter_mut().enumerate())
            .map(move |(j, b)| (start + j * BOX..(start + (j + 1) * BOX).min(end), b))
    }
}

thread_local! {
    /// A thread's summary in the making (swapped with the shared one, so no step allocates).
    static MAKING: RefCell<PartBounds> = RefCell::new(PartBounds::default());
}

/// Every part's summary of one body: written by the threads that step the parts, read by the
/// response (module docs).
#[derive(Debug, Default)]
pub struct Prepared {
    parts: Mutex<Vec<PartBounds>>,
}

impl Prepared {
    /// Sums up part `k`, particles `start..start + x.len()` at positions `x` (m) and
    /// velocities `v` (m/s) after a step, for the colliders of `world`
    /// ([`PartBounds::sum_up`]); given the body's `spheres` (as the last response left them)
    /// and the step `dt` (s), with the boxes of the spheres' broad phase, and then the part's
    /// particles pushed out of those spheres as this step's response would push them, when
    /// they are all kinematic (`spheres::push_part`; the response records the pushes instead
    /// of making them, or undoes them).
    pub fn prepare<'a>(
        &self,
        world: impl Into<World<'a>>,
        k: usize,
        start: usize,
        x: &mut [DVec3],
        v: &mut [DVec3],
        spheres: Option<(&[DynamicSphere], f64)>,
    ) {
        let world = world.into();
        MAKING.with(|making| {
            let making = &mut *making.borrow_mut();
            making.sum_up(world, start, x, Some(v), spheres.is_some());
            if let Some((spheres, dt)) = spheres {
                push_part(&world, spheres, dt, making, x, v);
            }
            making.fresh = true;
            let mut parts = self.parts.lock().unwrap_or_else(PoisonError::into_inner);
            if parts.len() <= k {
                parts.resize_with(k + 1, PartBounds::default);
            }
            std::mem::swap(&mut parts[k], making);
        });
    }

    /// The summaries of the step just taken, when they cover particles `0..n` part after part
    /// (else `None`: the response scans itself); either way every summary is used up.
    pub fn take(&self, n: usize) -> Option<Taken<'_>> {
        let mut parts = self.parts.lock().unwrap_or_else(PoisonError::into_inner);
        let mut end = 0;
        let mut count = 0;
        for p in parts.iter() {
            if end == n || !p.fresh || p.start != end {
                break;
            }
            end = p.end;
            count += 1;
        }
        for p in parts.iter_mut() {
            p.fresh = false;
        }
        (end == n && count > 0).then_some(Taken { parts, count })
    }

    /// Undoes the pushes the parts made and no response took (`spheres::push_part`): the
    /// positions (m) and velocities (m/s) of the body as they were before them. For a
    /// response that found the summaries incomplete ([`Prepared::take`]).
    pub fn undo_pushes(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        let mut parts = self.parts.lock().unwrap_or_else(PoisonError::into_inner);
        for p in parts.iter_mut().filter(|p| p.pushed_here) {
            p.pushed_here = false;
            for &(i, x_old, v_old) in p.pushed.iter().rev() {
                (x[i as usize], v[i as usize]) = (x_old, v_old);
            }
        }
    }
}

/// The summaries [`Prepared::take`] found complete.
pub struct Taken<'a> {
    parts: MutexGuard<'a, Vec<PartBounds>>,
    count: usize,
}

impl Taken<'_> {
    /// The parts in order.
    pub fn parts(&mut self) -> &mut [PartBounds] {
        &mut self.parts[..self.count]
    }

    /// Every position was calm when the parts were summed up.
    #[must_use]
    pub fn calm(&self) -> bool {
        self.parts[..self.count].iter().all(|p| p.calm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Aabb::of` gives the box that including every point in turn gives, bit for bit, with
    /// NaN coordinates anywhere (first, middle, last, several axes) and signed zeros.
    #[test]
    fn the_box_of_points_is_the_box_grown_point_by_point() {
        let bits = |v: DVec3| v.to_array().map(f64::to_bits);
        for points in cases() {
            let mut grown = Aabb {
                lo: DVec3::INFINITY,
                hi: DVec3::NEG_INFINITY,
            };
            for &p in &points {
                grown.include(p);
            }
            let of = Aabb::of(&points);
            assert_eq!(bits(of.lo), bits(grown.lo), "{points:?}");
            assert_eq!(bits(of.hi), bits(grown.hi), "{points:?}");
        }
    }

    /// The fast boxes (`fast::bounds`, every eighth point in one of eight running boxes) hold
    /// the same values as `Aabb::of` of each box's points (`==`: a zero's sign aside), with NaN
    /// and infinite coordinates anywhere, boxes of 8, 16 and 32 points and a last box that is
    /// not full.
    #[test]
    fn the_fast_boxes_are_the_boxes_of_their_points() {
        for points in cases() {
            // Longer lists: the case's points repeated, moved a little each time.
            let mut long = Vec::new();
            for k in 0..5 {
                long.extend(
                    points
                        .iter()
                        .map(|&p| p + DVec3::splat(0.125 * f64::from(k))),
                );
            }
            for len in [8, 16, 32] {
                let mut fast = Vec::new();
                boxes(&long, len, &mut fast, |lo, hi| Aabb { lo, hi });
                assert_eq!(fast.len(), long.len().div_ceil(len));
                for (b, chunk) in fast.iter().zip(long.chunks(len)) {
                    let of = Aabb::of(chunk);
                    assert_eq!(b.lo, of.lo, "{chunk:?}");
                    assert_eq!(b.hi, of.hi, "{chunk:?}");
                }
            }
        }
    }

    /// A summary's particles near planes (`fast::bounds::plane_bits`, eight at a time) are
    /// those `near_any` (one by one, `Broad::may_touch`) marks, and its `calm` is every
    /// position's `calm`: points on a grid through two planes, a hair from their bounds, NaN,
    /// infinite and huge coordinates, counts that are not whole words or chunks, with and
    /// without boxes.
    #[test]
    fn the_planes_summary_is_the_scan_of_every_particle() {
        let planes = [
            crate::physics::collide::Collider::Plane {
                point: DVec3::new(0.0, -0.5, 0.0),
                normal: DVec3::new(0.3, 1.0, -0.2).normalize(),
            },
            crate::physics::collide::Collider::Plane {
                point: DVec3::new(0.25, 0.0, 0.0),
                normal: DVec3::X,
            },
        ];
        let broads: Vec<Broad> = planes.iter().map(|c| c.broad(0.01)).collect();
        let mut x: Vec<DVec3> = (0..203)
            .map(|i| {
                let f = f64::from(i);
                DVec3::new(0.013 * f - 1.0, (0.37 * f).sin(), 0.5 - 0.007 * f)
            })
            .collect();
        x.push(DVec3::new(0.25 + 0.01 - 1e-12, 3.0, 0.0));
        for (count, poison) in [
            (64, None),
            (197, None),
            (204, Some(DVec3::new(f64::NAN, 0.0, 0.0))),
            (150, Some(DVec3::new(0.0, f64::INFINITY, 0.0))),
            (9, Some(DVec3::new(0.0, 0.0, -2e50))),
        ] {
            let mut x = x[..count].to_vec();
            if let Some(p) = poison {
                x[count / 2] = p;
            }
            let scan = near_any(&broads, &x);
            let expected: Vec<u32> = (0..x.len() as u32)
                .filter(|&i| scan[i as usize / 64] >> (i % 64) & 1 == 1)
                .collect();
            for with_boxes in [false, true] {
                let mut part = PartBounds::default();
                part.fill(&broads, 100, &x, with_boxes);
                let near: Vec<u32> = part.near.iter().map(|&i| i - 100).collect();
                assert_eq!(near, expected, "{count} {poison:?}");
                assert_eq!(part.calm, x.iter().all(|p| calm(*p)), "{count} {poison:?}");
                if count > 64 {
                    assert!(
                        !near.is_empty() && near.len() < x.len(),
                        "{count}: {near:?}"
                    );
                }
            }
        }
    }

    /// With velocities, a summary's `near` is exactly the particles for which the response
    /// itself (`respond`, with a climb that costs nothing) changes something for some
    /// collider: a plane, a sphere and a bowl, points on both sides of each surface and within
    /// its band, moving in, out and along it (`v·N` of both signs and zero, φ = 0 exactly),
    /// NaN and infinite coordinates; and it holds some but not all of the bounds' particles.
    #[test]
    fn the_summary_with_velocities_keeps_the_particles_the_response_answers() {
        use crate::physics::collide::{Collider, ContactParams, response::respond};
        let colliders = [
            Collider::Plane {
                point: DVec3::new(0.0, -0.5, 0.0),
                normal: DVec3::Y,
            },
            Collider::Sphere {
                center: DVec3::new(0.6, 0.1, 0.0),
                radius: 0.3,
            },
            Collider::Bowl {
                center: DVec3::new(-0.4, 0.3, 0.1),
                radius: 0.5,
                rim_height: 0.3,
            },
        ];
        let params = ContactParams::course_2021();
        let world = World {
            colliders: &colliders,
            contact: &params,
            gravity: DVec3::new(0.0, -9.81, 0.0),
            inv_mass: &[],
            springs: &[],
            incident: &[],
            incident_start: &[],
        };
        let mut x = Vec::new();
        let mut v = Vec::new();
        for i in 0u32..600 {
            let f = f64::from(i);
            // Heights around the plane (some exactly on it) and points around the sphere and
            // the bowl's inside.
            let y = if i % 7 == 0 {
                -0.5
            } else {
                -0.52 + 0.0007 * f64::from(i % 60)
            };
            x.push(DVec3::new(
                (0.37 * f).sin(),
                y + 0.9 * f64::from(i % 3 == 1),
                (0.11 * f).cos(),
            ));
            let speed = [0.0, -0.3, 0.3, -1e-9, 2.0][(i % 5) as usize];
            v.push(DVec3::new(
                0.1 * (0.5 * f).cos(),
                speed,
                0.2 * (0.3 * f).sin(),
            ));
        }
        x[17] = DVec3::new(f64::NAN, -0.5, 0.0);
        x[33] = DVec3::new(0.0, f64::NEG_INFINITY, 0.0);
        v[34] = DVec3::new(f64::NAN, 0.0, 0.0);
        let answered = |i: usize| {
            colliders.iter().any(|c| {
                let (mut xi, mut vi) = (x[i], v[i]);
                respond(c, 0.0, &params, &|_, _| 0.0, &mut xi, &mut vi).is_some()
            })
        };
        let start = 40;
        let expected: Vec<u32> = (0..x.len())
            .filter(|&i| answered(i))
            .map(|i| (start + i) as u32)
            .collect();
        let mut bounds = PartBounds::default();
        bounds.sum_up(world, start, &x, None, false);
        let mut part = PartBounds::default();
        part.sum_up(world, start, &x, Some(&v), false);
        assert_eq!(part.near, expected);
        assert!(!expected.is_empty() && expected.len() < bounds.near.len());
        assert!(expected.iter().all(|i| bounds.near.contains(i)));
    }

    /// Kinematic spheres' pushes made part by part (`spheres::push_part`, then the response
    /// records them) leave the particles, the spheres and the records bit for bit as the
    /// response's own pushes over the whole body: two moving spheres over 300 particles (some
    /// inside both, some pinned, NaN), split into one, two and three parts at any particle.
    /// Where the parts must not push (a sphere that is not kinematic, a velocity of -0), or
    /// pushed with spheres other than the step's (the response then undoes their pushes), the
    /// same too.
    #[test]
    fn pushes_made_part_by_part_are_the_responses_pushes() {
        use crate::physics::collide::{Bodies, Changes, ContactParams, advance_spheres};
        use crate::physics::collide::{DynamicSphere, collide_spheres_prepared};
        let bits = |v: &[DVec3]| -> Vec<u64> {
            v.iter()
                .flat_map(|p| p.to_array().map(f64::to_bits))
                .collect()
        };
        let sphere_bits = |s: &[DynamicSphere]| -> Vec<u64> {
            s.iter()
                .flat_map(|s| [s.center.to_array(), s.velocity.to_array()])
                .flatten()
                .map(f64::to_bits)
                .collect()
        };
        let params = ContactParams::course_2021();
        let n = 300;
        let inv_mass: Vec<f64> = (0..n)
            .map(|i| if i % 37 == 5 { 0.0 } else { 40.0 })
            .collect();
        let world = World {
            colliders: &[],
            contact: &params,
            gravity: DVec3::new(0.0, -9.81, 0.0),
            inv_mass: &inv_mass,
            springs: &[],
            incident: &[],
            incident_start: &[],
        };
        let x0: Vec<DVec3> = (0..n)
            .map(|i| {
                let f = i as f64;
                DVec3::new(
                    0.9 * (0.37 * f).sin(),
                    0.5 * (0.11 * f).cos(),
                    0.01 * f - 1.5,
                )
            })
            .collect();
        // A NaN particle makes a sphere NaN (its push is 0 · NaN): the parts' spheres then
        // differ from the step's, and the response pushes itself.
        let mut poisoned = x0.clone();
        poisoned[77] = DVec3::new(f64::NAN, 0.0, 0.0);
        let v0: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(0.1, -0.3 * (0.7 * i as f64).cos(), 0.0))
            .collect();
        let kinematic = vec![
            DynamicSphere::kinematic(DVec3::new(0.0, 0.0, -0.5), 0.6, DVec3::new(0.2, 0.1, 0.0)),
            DynamicSphere::kinematic(DVec3::new(0.3, 0.1, 0.2), 0.5, DVec3::new(0.0, 0.0, 0.3)),
        ];
        let mut falling = kinematic.clone();
        falling[1] = DynamicSphere::new(DVec3::new(0.3, 0.1, 0.2), 0.5);
        let mut signed = kinematic.clone();
        signed[0].velocity.z = -0.0;
        let dt = 1e-3;
        // (positions, spheres of the step, spheres the parts are given)
        let cases = [
            (&x0, kinematic.clone(), kinematic.clone()),
            (&x0, falling.clone(), falling),
            (&x0, signed.clone(), signed),
            (&x0, kinematic.clone(), vec![kinematic[1], kinematic[0]]),
            (&poisoned, kinematic.clone(), kinematic.clone()),
        ];
        for (case, (x0, spheres, given)) in cases.iter().enumerate() {
            // The response over the whole body.
            let (mut x, mut v, mut s) = ((*x0).clone(), v0.clone(), spheres.clone());
            let mut x_prev = vec![DVec3::ZERO; n];
            let mut expected = Changes::default();
            let mut bodies = Bodies {
                x: &mut x,
                v: &mut v,
                x_prev: &mut x_prev,
                history_valid: false,
                spheres: &mut s,
            };
            advance_spheres(world, bodies.reborrow(), dt);
            collide_spheres_prepared(world, bodies, dt, Some(&mut expected), None);
            expected.finish(n);
            let pushed_some = expected.particles.len();
            assert!(
                pushed_some > 10 && pushed_some < n / 2,
                "{case}: {pushed_some}"
            );
            for cuts in [vec![0, n], vec![0, 150, n], vec![0, 41, 200, n]] {
                let (mut xp, mut vp, mut sp) = ((*x0).clone(), v0.clone(), spheres.clone());
                let mut parts: Vec<PartBounds> = Vec::new();
                for w in cuts.windows(2) {
                    let (a, b) = (w[0], w[1]);
                    let mut part = PartBounds::default();
                    part.sum_up(world, a, &xp[a..b], Some(&vp[a..b]), true);
                    push_part(&world, given, dt, &mut part, &mut xp[a..b], &mut vp[a..b]);
                    if case == 0 {
                        // The parts' pushes are taken as they are (their spheres the step's).
                        assert!(part.pushed_here, "{cuts:?}");
                        assert_eq!(sphere_bits(&part.spheres), sphere_bits(&s), "{cuts:?}");
                    }
                    parts.push(part);
                }
                let mut changes = Changes::default();
                let mut bodies = Bodies {
                    x: &mut xp,
                    v: &mut vp,
                    x_prev: &mut x_prev,
                    history_valid: false,
                    spheres: &mut sp,
                };
                advance_spheres(world, bodies.reborrow(), dt);
                collide_spheres_prepared(world, bodies, dt, Some(&mut changes), Some(&mut parts));
                changes.finish(n);
                assert_eq!(bits(&xp), bits(&x), "{case} {cuts:?}");
                assert_eq!(bits(&vp), bits(&v), "{case} {cuts:?}");
                assert_eq!(sphere_bits(&sp), sphere_bits(&s), "{case} {cuts:?}");
                let records = |c: &Changes| -> Vec<(u32, Vec<u64>)> {
                    (c.particles.iter())
                        .map(|&(i, x, v)| (i, bits(&[x, v])))
                        .collect()
                };
                assert_eq!(records(&changes), records(&expected), "{case} {cuts:?}");
            }
        }
        // Not kinematic or -0: no push.
        let mut part = PartBounds::default();
        let (mut x, mut v) = (x0.clone(), v0.clone());
        part.sum_up(world, 0, &x, Some(&v), true);
        push_part(&world, &cases[2].2, dt, &mut part, &mut x, &mut v);
        assert!(!part.pushed_here && bits(&x) == bits(&x0));
        push_part(&world, &cases[1].2, dt, &mut part, &mut x, &mut v);
        assert!(!part.pushed_here && bits(&x) == bits(&x0));
        push_part(&world, &cases[0].2, dt, &mut part, &mut x, &mut v);
        assert!(part.pushed_here && !part.pushed.is_empty() && bits(&x) != bits(&x0));
    }

    /// Planes alone (`fast::bounds::plane_answer_bits`, eight at a time): a summary's `near`
    /// is exactly the particles for which the response itself (`respond`) changes something
    /// for some plane, and the same as the bounds' set filtered one by one (`responds_within`);
    /// `calm` is every position's. One and two planes (one tilted), points on both sides and
    /// in the band (φ = 0 exactly), `v·N` of both signs and zero (and -0), NaN, infinite and
    /// huge coordinates and velocities, counts that are not whole chunks, with and without
    /// boxes; a NaN band (whose bounds hold fewer) goes the one-by-one way.
    #[test]
    fn the_planes_answers_are_the_responses_answers() {
        use crate::physics::collide::{ContactParams, response::respond};
        let planes = [
            Collider::Plane {
                point: DVec3::new(0.0, -0.5, 0.0),
                normal: DVec3::Y,
            },
            Collider::Plane {
                point: DVec3::new(0.25, 0.0, 0.1),
                normal: DVec3::new(0.3, -1.0, 0.2).normalize(),
            },
        ];
        let mut x = Vec::new();
        let mut v = Vec::new();
        for i in 0u32..333 {
            let f = f64::from(i);
            let y = if i % 7 == 0 {
                -0.5
            } else {
                -0.52 + 0.0007 * f64::from(i % 60)
            };
            x.push(DVec3::new((0.37 * f).sin(), y, (0.11 * f).cos()));
            let speed = [0.0, -0.3, 0.3, -1e-9, 2.0, -0.0][(i % 6) as usize];
            v.push(DVec3::new(
                0.1 * (0.5 * f).cos(),
                speed,
                0.2 * (0.3 * f).sin(),
            ));
        }
        x[17] = DVec3::new(f64::NAN, -0.5, 0.0);
        x[33] = DVec3::new(0.0, f64::NEG_INFINITY, 0.0);
        x[40] = DVec3::new(0.0, -0.5, 3e50);
        v[34] = DVec3::new(f64::NAN, 0.0, 0.0);
        v[35] = DVec3::new(0.0, f64::INFINITY, 0.0);
        for (colliders, epsilon) in [
            (&planes[..1], 0.01),
            (&planes[..], 0.01),
            (&planes[..], 0.0),
            (&planes[..], f64::NAN),
        ] {
            let params = ContactParams {
                epsilon,
                ..ContactParams::course_2021()
            };
            let world = World {
                colliders,
                contact: &params,
                gravity: DVec3::new(0.0, -9.81, 0.0),
                inv_mass: &[],
                springs: &[],
                incident: &[],
                incident_start: &[],
            };
            for count in [333, 64, 41, 9] {
                let (x, v) = (&x[..count], &v[..count]);
                let answered = |i: usize| {
                    colliders.iter().any(|c| {
                        let (mut xi, mut vi) = (x[i], v[i]);
                        respond(c, 0.0, &params, &|_, _| 0.0, &mut xi, &mut vi).is_some()
                    })
                };
                let start = 40;
                let expected: Vec<u32> = (0..count)
                    .filter(|&i| answered(i))
                    .map(|i| (start + i) as u32)
                    .collect();
                // The bounds' set filtered one by one, as without the planes' pass.
                let broads: Vec<Broad> = colliders.iter().map(|c| c.broad(epsilon)).collect();
                let mut filtered = PartBounds::default();
                filtered.fill(&broads, start, x, false);
                (filtered.near).retain(|&i| {
                    let k = i as usize - start;
                    (colliders.iter().zip(&broads))
                        .any(|(c, b)| responds_within(b, c, &params, x[k], v[k]))
                });
                for with_boxes in [false, true] {
                    let mut part = PartBounds::default();
                    part.sum_up(world, start, x, Some(v), with_boxes);
                    let case = format!("{} planes, ε {epsilon}, {count}", colliders.len());
                    if !epsilon.is_nan() {
                        assert_eq!(part.near, expected, "{case}");
                    }
                    assert_eq!(part.near, filtered.near, "{case}");
                    assert_eq!(part.calm, x.iter().all(|p| calm(*p)), "{case}");
                }
                if count > 64 && epsilon > 0.0 {
                    assert!(!expected.is_empty() && expected.len() < count);
                }
            }
        }
    }

    /// Points with NaN or infinite coordinates anywhere (first, middle, last, several axes),
    /// signed zeros and values across the range of f64.
    fn cases() -> Vec<Vec<DVec3>> {
        let nan = f64::NAN;
        let base = [
            DVec3::new(0.5, -0.0, 2.0),
            DVec3::new(-1.5, 0.0, 2.0),
            DVec3::new(3.0, 1e-300, -7.25),
            DVec3::new(0.0, -4.0, 1e300),
            DVec3::new(-2.0, 5.0, 0.25),
            DVec3::new(1.0, -0.0, -8.0),
            DVec3::new(0.75, 2.0, 3.0),
        ];
        let mut cases: Vec<Vec<DVec3>> = vec![Vec::new(), base.to_vec(), base[..3].to_vec()];
        for at in 0..base.len() {
            for poison in [
                DVec3::new(nan, 1.0, 1.0),
                DVec3::new(1.0, nan, nan),
                DVec3::splat(nan),
                DVec3::new(1.0, f64::INFINITY, f64::NEG_INFINITY),
            ] {
                let mut points = base.to_vec();
                points[at] = poison;
                cases.push(points);
            }
        }
        cases
    }
}
