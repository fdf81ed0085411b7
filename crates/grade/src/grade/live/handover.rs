//! The lesson's own steps handed to the reference: where the lesson's simulation steps the same
//! body with the same method, dt and model as the comparison's reference, the reference's
//! thread takes the lesson's state after step `n` instead of computing step `n` a second time.
//!
//! ```text
//! lesson (drawing thread)   after each step n:  offer (n, x_n, v_n)    a copy, into a queue of
//!                                                                      at most QUEUE_BYTES
//! reference (its thread)    step n:  the lesson's (n, x_n, v_n) if queued and trusted,
//!                                    else its own step from n - 1 (as without a hand-over)
//! trusted   when the first offer's body has the comparison's model, method and dt, after
//!           VERIFY steps computed both ways with the same bits (and again at every RECHECK-th
//!           step); one difference, another lesson generation or another energy baseline (an
//!           edit: every editing key rebases the energy accounting) ends the hand-over for good
//! ```
//!
//! So the reference's body is the one it would compute itself, bit for bit: the lesson's
//! `Simulation::step` on a lattice with an explicit method is `Method::step` followed by the
//! same collision response (`collide::resolve_logged`) as the reference's step
//! (`tests/homework_live.rs` checks it on lesson 5's jelly for every explicit method), and the
//! verification refuses the hand-over where it is not (an edited model, another method). The
//! queue is bounded: a step the queue had no room for, or that the lesson took before the
//! comparison started, the reference computes itself.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use glam::DVec3;

use super::{Assignment, Integrator, Setup};
use crate::physics::Model;
use crate::simulation::Simulation;

/// Bytes the queue holds: 64 MiB, 1398 steps of the 1000-particle jelly (48 KB a step), so
/// that a comparison behind the lesson by that much still finds the lesson's steps.
const QUEUE_BYTES: usize = 64 << 20;
/// Steps computed both ways before the lesson's states are trusted.
pub(super) const VERIFY: u64 = 8;
/// After that, every this many steps one is computed both ways again.
pub(super) const RECHECK: u64 = 1024;

/// One step of the lesson's body.
pub(super) struct Offered {
    /// The lesson's step count after it.
    pub(super) step: u64,
    /// Positions (m).
    pub(super) x: Vec<DVec3>,
    /// Velocities (m/s).
    pub(super) v: Vec<DVec3>,
}

#[derive(Default)]
struct Queue {
    states: VecDeque<Offered>,
    /// Buffers taken back, reused by the next offers.
    spare: Vec<Offered>,
    /// The lesson's generation and energy baseline (bits) at the first offer.
    tag: Option<(u64, u64)>,
    /// What the first offer's body must have: the setup's model, its trait method and dt
    /// (bits); dropped once checked.
    expected: Option<Box<(Model, Assignment, Integrator, u64)>>,
}

struct Inner {
    body: usize,
    particles: usize,
    queue: Mutex<Queue>,
    /// Set for good: the comparison ended, or the lesson's steps are not the reference's.
    off: AtomicBool,
    /// Steps the reference took from the lesson.
    taken: AtomicU64,
}

/// The lesson's side of the hand-over (module docs): cheap to clone; the lesson run calls
/// [`Handover::offer`] after each step.
#[derive(Clone)]
pub struct Handover {
    inner: Arc<Inner>,
}

impl std::fmt::Debug for Handover {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Handover")
            .field("body", &self.inner.body)
            .field("off", &self.inner.off.load(Ordering::Relaxed))
            .finish_non_exhaustive()
    }
}

impl Handover {
    /// A hand-over for `setup`'s body, when the lesson's step can be the reference's: a
    /// lattice (jelly, cloth) stepped by an explicit method (implicit Euler's energy guard in
    /// the lesson retakes steps the reference takes once; the rope's types differ).
    pub(super) fn for_setup(setup: &Setup) -> Option<Handover> {
        let explicit = matches!(
            setup.integrator,
            Integrator::ExplicitEuler | Integrator::Midpoint | Integrator::Rk4
        );
        let lattice = setup.assignment != Assignment::Rope;
        (explicit && lattice).then(|| Handover {
            inner: Arc::new(Inner {
                body: setup.body,
                particles: setup.model.particle_count(),
                queue: Mutex::new(Queue {
                    expected: Some(Box::new((
                        setup.model.clone(),
                        setup.assignment,
                        setup.integrator,
                        setup.dt.to_bits(),
                    ))),
                    ..Queue::default()
                }),
                off: AtomicBool::new(false),
                taken: AtomicU64::new(0),
            }),
        })
    }

    /// After a step of the lesson's simulation `sim` (its run's `generation`): a copy of the
    /// body's state for the reference, when there is room. Cheap once the hand-over is off.
    pub fn offer(&self, sim: &Simulation, generation: u64) {
        let inner = &self.inner;
        if inner.off.load(Ordering::Relaxed) {
            return;
        }
        let Some(body) = sim.scene.bodies.get(inner.body) else {
            self.end();
            return;
        };
        let (x, v) = (&body.state.x, &body.state.v);
        if x.len() != inner.particles || v.len() != inner.particles || sim.diverged.is_some() {
            self.end();
            return;
        }
        let Ok(mut queue) = inner.queue.lock() else {
            return;
        };
        if let Some(expected) = queue.expected.take() {
            let (model, assignment, integrator, dt) = *expected;
            let method = Integrator::of(assignment, body.method);
            if body.model != model || method != Some(integrator) || sim.dt().to_bits() != dt {
                // Another model (an edit before the comparison started), method or dt.
                drop(queue);
                self.end();
                return;
            }
        }
        let tag = (generation, sim.energy_initial().to_bits());
        if *queue.tag.get_or_insert(tag) != tag {
            // An edit (a new generation, or the energy accounting rebased): not the body the
            // reference steps any more.
            drop(queue);
            self.end();
            return;
        }
        if 48 * inner.particles * queue.states.len() >= QUEUE_BYTES {
            return;
        }
        let mut o = queue.spare.pop().unwrap_or(Offered {
            step: 0,
            x: Vec::new(),
            v: Vec::new(),
        });
        o.step = sim.steps;
        o.x.clear();
        o.x.extend_from_slice(x);
        o.v.clear();
        o.v.extend_from_slice(v);
        queue.states.push_back(o);
    }

    /// Steps the reference took from the lesson so far.
    #[must_use]
    pub fn taken(&self) -> u64 {
        self.inner.taken.load(Ordering::Relaxed)
    }

    /// False once the hand-over ended (module docs).
    #[must_use]
    pub fn is_on(&self) -> bool {
        !self.inner.off.load(Ordering::Relaxed)
    }

    /// Ends the hand-over for good and frees the queue.
    pub(super) fn end(&self) {
        self.inner.off.store(true, Ordering::Relaxed);
        if let Ok(mut queue) = self.inner.queue.lock() {
            queue.states.clear();
            queue.spare.clear();
        }
    }

    /// The lesson's state after step `step`, if queued (older ones are dropped).
    pub(super) fn take(&self, step: u64) -> Option<Offered> {
        if self.inner.off.load(Ordering::Relaxed) {
            return None;
        }
        let mut queue = self.inner.queue.lock().ok()?;
        while queue.states.front().is_some_and(|o| o.step < step) {
            if let Some(old) = queue.states.pop_front() {
                queue.spare.push(old);
            }
        }
        if queue.states.front().is_some_and(|o| o.step == step) {
            queue.states.pop_front()
        } else {
            None
        }
    }

    /// Gives a buffer back for the next offers; `used`: the reference took its state.
    pub(super) fn recycle(&self, o: Offered, used: bool) {
        if used {
            self.inner.taken.fetch_add(1, Ordering::Relaxed);
        }
        if let Ok(mut queue) = self.inner.queue.lock()
            && !self.inner.off.load(Ordering::Relaxed)
            && queue.spare.len() < 4
        {
            queue.spare.push(o);
        }
    }
}

/// True when `a` and `b` hold the same numbers bit for bit.
pub(super) fn same_bits(a: &[DVec3], b: &[DVec3]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| {
            p.x.to_bits() == q.x.to_bits()
                && p.y.to_bits() == q.y.to_bits()
                && p.z.to_bits() == q.z.to_bits()
        })
}
