//! Many passes in one job of the worker pool: a "team" of threads that runs pass after pass
//! (the stages of many steps) over the same split of the particles into parts, and waits for
//! the others only at the boundary between two passes.
//!
//! [`Stencil::write`] is one job of the pool per pass: the caller publishes it, the workers pick
//! it up, and the caller waits until every part has finished. On the jelly cube a pass is about
//! 8–11 µs per thread (see "what a pass costs"), and that hand-over costs a microsecond or two
//! of it. A team hands over once, for all the passes of `n` steps:
//!
//! ```text
//! pass s:  claim a part of pass s, run it; again while one is left (see "stealing")
//!          wait until every part of pass s is done                     (a barrier)
//! ```
//! where running part `k` of a pass reads the buffers the previous passes wrote (the
//! neighbouring parts' particles too, within the stencil's reach) and writes only part `k`'s
//! particles of the pass's outputs. The barrier makes that safe: while any part of pass `s`
//! runs, every part of pass `s - 1` is done (so the inputs are complete) and none of pass
//! `s + 1` has started (so no one writes what pass `s` reads, provided a pass never reads its
//! own outputs, which [`Crew::pass`] checks).
//!
//! **The same numbers.** Each part of a pass is computed exactly once, as the same pass of
//! [`Stencil::write`] computes it with the same split, whichever thread runs it; so `n` steps in
//! a team are bit for bit `n` single steps, for any number of parts and threads (tested).
//!
//! **Dissipated power.** A pass may name a slot for its dissipated power
//! ([`Stencil::team_with_power`], [`Pass::power`]), in a ring of `R` slots (slot `p` at
//! `p mod R`), and the team sums it as [`Stencil::sum_power`] does, so that slot `p`'s total is
//! the pass's power bit for bit (energy accounting in many steps at once,
//! `Simulation::advance`). That sum goes group by group (1 024 particles, `POWER_GROUP`
//! chunks): each group's chunks in order from zero, then the groups' sums in order. A part
//! sums every group that starts in it in registers as it computes the chunks and stores each
//! group's lane sums in the slot (`PowerMode::Groups`); its chunks before its first group end
//! a group the previous part began, so their values go to the slot's chunks, as
//! [`Stencil::write_in_parts`] cuts its power buffer. Then:
//!
//! ```text
//! pass s:  run part k; then, to the running sums of the slot written k passes ago (pass s - k),
//!          add its chunks of part k to the open group, and for each group that starts in
//!          part k close the open one and open it with the part's sums of it
//!                                                            (part 0: this pass's slot, from 0)
//! ```
//! Part `k`'s share of a slot is added after part `k - 1`'s (one pass earlier, behind a
//! barrier) and before part `k + 1`'s: the order of one sum over the whole slot, whichever
//! thread adds it. A slot is read until `parts - 1` passes after it was written, so a ring of
//! `parts` slots is never overwritten before it is summed; the sums of the team's last passes
//! are finished after it. Before the groups every part but the first wrote all its chunks'
//! values to the ring and added them a pass later: on a 128×128 cloth at two threads, 2.5 µs
//! of stores to lines outside the caches and 0.6 µs of additions per pass on that thread (of
//! 65–70 µs). Now a part writes at most a group's chunks there (a slot still has room for every
//! chunk, and one sum per group: 0.5 MB for two slots of the 128×128 cloth).
//!
//! **A serial stage.** Between two passes the body may call [`Crew::serial`]: the first thread
//! to come runs a function on whole buffers (the collision response after a step, which reads
//! any particle and may scale every velocity), the others wait for it as at a barrier, and the
//! team goes on with the next pass without handing the work back to the pool. What that
//! function would ask of every particle, each thread can answer for its own part right after a
//! pass ([`Crew::pass_then`]: the thread that wrote the part, while it is in its cache), so that
//! the serial stage reads one summary per part instead; and what it would do to each particle
//! on its own, each thread can do to its part (the serial stage then records it).
//!
//! **Stealing.** Every thread of the team has a home part, which it claims first in every pass
//! (so a part's particles stay in one core's cache from pass to pass). A thread that has
//! finished its part and finds another part of the pass still unclaimed after a few
//! microseconds takes it: its owner has been paused by the operating system (a busy machine)
//! and may not run again for milliseconds. Until the owner is back, its part is taken at once.
//! So a team never waits for a thread that is not running, and on a busy machine it runs at the
//! speed of the threads that are (at worst one), where a fixed part per thread would stall.
//! Parts with no thread of their own (more parts than threads) are taken at once.
//!
//! **The barrier** is a counter per part (each on its own cache line): whoever finishes part
//! `k` of pass `s` stores `s + 1` there, and a pass is done when every counter has reached it.
//! A part is claimed by a compare-and-swap of another counter per part from `s` to `s + 1`, so
//! exactly one thread runs it. A thread that panics raises a flag that makes the others stop
//! waiting, so the job always ends.
//!
//! **What a pass costs** (jelly cube, semi-implicit Euler, a team of two on a 2-vCPU AMD EPYC
//! Zen 5 virtual machine with AVX-512; each thread's time stamps per pass, measured with
//! temporary instrumentation): each part takes 8.0–9.9 µs and the pass 8.3–10.0 µs, of which
//! the barrier's hand-over (the last `done` store until the waiting thread sees it) is 60–100
//! ns. At other times the same machine hands over in 265–295 ns, each part takes 10.1–12.2 µs
//! and the pass 11.0–12.5 µs: the host has then placed the two virtual CPUs on cores farther
//! apart, and a part's halo comes from the other core's cache (the boundary's lines go back and
//! forth every pass). That is the two rates of `springlab bench jelly-se` on two threads (about
//! 105–110k and 86–91k steps/s on a quiet machine); the same part, run while the other thread
//! is not running, takes 8.3–8.6 µs in both. Stealing plays no part in it: while both threads
//! run, a home part is taken by the other thread at most about once in 2 000 passes; steals
//! come in runs of 100–1 000 passes, while the operating system has paused the owner (a busy
//! machine).
//! Prefetching the halo at the start of a part did not pay (1 % faster when the cores are far
//! apart, 2–4 % slower when they are near).
//!
//! References: M. Herlihy, N. Shavit, *The Art of Multiprocessor Programming*, 2nd ed., Morgan
//! Kaufmann 2020, §16 (work stealing) and §17 (barriers); Datta et al., SC 2008 (see the parent
//! module), on time-stepping stencils with one thread per subdomain.

use std::cell::Cell;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

#[allow(clippy::wildcard_imports)]
use super::*;

/// At most this many buffers in a team.
pub const MAX_BUFFERS: usize = 12;

/// How long a thread that has finished its part waits for the owner of another unclaimed part
/// before it takes that part itself (a running owner claims it within a fraction of this).
const PATIENCE: Duration = Duration::from_micros(5);

/// How long a thread spins at the barrier before it starts giving its time slice away.
const SPIN: Duration = Duration::from_micros(50);

/// Spins at a barrier before a waiting thread first reads the clock: most waits end within
/// them (a pass's parts end within a microsecond or two of each other), and reading the clock
/// on a virtual machine costs as much as many spins (measured: 3 % of a two-thread jelly
/// cube's samples in `clock_gettime`, from a clock read at the start of every wait).
const QUIET_SPINS: u32 = 256;

/// How long a thread has waited at a barrier after `spins` spins: nothing for the first
/// [`QUIET_SPINS`], then the time since the clock was first read (into `start`).
fn waited(start: &mut Option<Instant>, spins: u32) -> Duration {
    if spins < QUIET_SPINS {
        return Duration::ZERO;
    }
    start.get_or_insert_with(Instant::now).elapsed()
}

/// The running sums of one slot of the power ring (module docs): per lane, the dampers' and
/// the contacts' values added so far (of the closed groups, and of the open one), the logical
/// slot, and the next part.
#[derive(Clone, Copy, Default)]
struct Running {
    /// The sums of the slot's closed groups (`P` of `Stencil::sum_power`).
    closed: [[f64; LANES]; 2],
    /// The sums of its open group (`G`).
    open: [[f64; LANES]; 2],
    slot: usize,
    next: usize,
}

/// One pass of a team: [`Output::Step`] at positions `buffers[x]` and velocities `buffers[v]`
/// into `buffers[outs[..]]`, with buffers named by their index in the call of
/// [`Stencil::team`].
#[derive(Clone, Copy)]
pub struct Pass<'a> {
    /// Positions (m) read by the pass.
    pub x: usize,
    /// Velocities (m/s) read by the pass.
    pub v: usize,
    /// Where the stage's positions, velocities and (for [`TeamUpdate::Euler`], optionally)
    /// accelerations go.
    pub outs: [Option<usize>; 3],
    /// Weight, drag, contact and masses.
    pub dynamics: Dynamics<'a>,
    /// What the stage writes.
    pub update: TeamUpdate,
    /// Applied to each tile's new positions and velocities.
    pub after: Option<After<'a>>,
    /// Where the pass's dissipated power goes: total `k` of [`Stencil::team_with_power`]
    /// (its values in slot `k mod R` of the ring, module docs); `None` computes none. Passes
    /// with power name the slots `0, 1, 2, …` in order.
    pub power: Option<usize>,
}

/// What [`Crew::pass_then`] calls after each part: part `k`, its first particle `q0`, its new
/// positions (m) and velocities (m/s), which it may change (the part's own).
pub type PartFn<'a> = &'a (dyn Fn(usize, usize, &mut [DVec3], &mut [DVec3]) + Sync);

/// [`Update`] with buffers named by index (see [`Pass`]).
#[derive(Clone, Copy, Debug)]
pub enum TeamUpdate {
    /// [`Update::SemiImplicitEuler`] with step `dt` (s).
    SemiImplicitEuler {
        /// Time step (s).
        dt: f64,
    },
    /// [`Update::Euler`] with the base `(x_b, v_b)` the pass's input (`None`) or two buffers.
    Euler {
        /// Stage length (s).
        h: f64,
        /// The buffers of `x_b` and `v_b`, or the input.
        base: Option<[usize; 2]>,
    },
    /// [`Update::Rk4`]: the slopes `a_1..a_3` and velocities `v_2`, `v_3` from buffers.
    Rk4 {
        /// `dt/6` (s).
        sixth: f64,
        /// The buffers of `a_1`, `a_2`, `a_3`.
        a: [usize; 3],
        /// The buffers of `v_2`, `v_3`.
        v: [usize; 2],
    },
}

impl TeamUpdate {
    /// The buffers this update reads besides the pass's input and its own outputs.
    fn reads(&self) -> impl Iterator<Item = usize> + Clone {
        let list: [Option<usize>; 5] = match *self {
            TeamUpdate::SemiImplicitEuler { .. } | TeamUpdate::Euler { base: None, .. } => {
                [None; 5]
            }
            TeamUpdate::Euler {
                base: Some([x, v]), ..
            } => [Some(x), Some(v), None, None, None],
            TeamUpdate::Rk4 { a, v, .. } => {
                [Some(a[0]), Some(a[1]), Some(a[2]), Some(v[0]), Some(v[1])]
            }
        };
        list.into_iter().flatten()
    }
}

/// A buffer shared by the threads of a team: a pointer and a length, valid while
/// [`Stencil::team`] runs (it holds the exclusive borrow).
#[derive(Clone, Copy)]
struct Shared {
    ptr: *mut DVec3,
    len: usize,
}

/// A counter on a cache line of its own (so that threads do not slow each other down by
/// writing neighbouring counters).
#[repr(align(64))]
#[derive(Default)]
struct Padded(AtomicU64);

/// The team's power ring: a pointer, valid while [`Stencil::team_with_power`]
/// runs (it holds the exclusive borrow).
#[derive(Clone, Copy)]
struct SharedPower {
    ptr: *mut f64,
}

/// Where the team writes each slot's power total: a pointer and a length, valid while
/// [`Stencil::team_with_power`] runs (it holds the exclusive borrow).
#[derive(Clone, Copy)]
struct SharedTotals {
    ptr: *mut (f64, f64),
    len: usize,
}

/// The team's shared state: the stencil, the split, the buffers and the counters.
struct Common<'b> {
    stencil: &'b Stencil,
    /// Part `k` is particles `bounds[k]..bounds[k + 1]`.
    bounds: [usize; MAX_PARTS + 1],
    parts: usize,
    /// Threads of the team: parts `0..homes` have one of their own.
    homes: usize,
    buffers: [Shared; MAX_BUFFERS],
    count: usize,
    /// The ring of power slots (each [`Stencil::power_slot_len`] values), `ring` of them.
    power: SharedPower,
    ring: usize,
    /// Each slot's `(dampers and drag, contact)` power (W) once summed.
    totals: SharedTotals,
    /// The passes have colliders (a contact column to sum, [`Stencil::sum_power`]).
    contact: bool,
    /// The running sums of each slot of the ring.
    running: [std::cell::UnsafeCell<Running>; MAX_PARTS],
    /// `claimed[k]`: passes of part `k` some thread has taken.
    claimed: [Padded; MAX_PARTS],
    /// `done[k]`: passes of part `k` finished.
    done: [Padded; MAX_PARTS],
    /// Serial stages ([`Crew::serial`]) some thread has taken, and those finished.
    serial_claimed: Padded,
    serial_done: Padded,
    /// Set when a thread panicked: the others stop waiting.
    abort: AtomicBool,
    _borrow: PhantomData<&'b mut [DVec3]>,
}

// SAFETY: the raw pointers and the running sums are only dereferenced in `Common::run_part`,
// `Common::add_power` (each slot's sums by one part at a time, parts in successive passes) and
// `Crew::serial` (which has the buffers to itself between two passes), under the barrier
// discipline of the module docs (whole reads of buffers no one writes during the pass, writes
// only of the running part's own disjoint piece); the rest is `Sync`.
unsafe impl Sync for Common<'_> {}

impl Common<'_> {
    /// Takes part `k` of pass `s` if no thread has: true for exactly one caller.
    fn claim(&self, k: usize, s: u64) -> bool {
        self.claimed[k]
            .0
            .compare_exchange(s, s + 1, Ordering::AcqRel, Ordering::Relaxed)
            .is_ok()
    }

    /// True when every part of pass `s` is done.
    fn pass_done(&self, s: u64) -> bool {
        self.done[..self.parts]
            .iter()
            .all(|d| d.0.load(Ordering::Acquire) > s)
    }

    /// Runs part `k` of `pass` (the `s`-th pass), claimed by this thread, then `then` on the
    /// part's new positions and velocities, adds part `k` of slot `sum` to its running sums
    /// ([`Common::add_power`]), and marks it done.
    fn run_part(&self, k: usize, s: u64, pass: &Pass, then: Option<PartFn>, sum: Option<usize>) {
        let n = self.stencil.particles;
        let (q0, q1) = (self.bounds[k], self.bounds[k + 1]);
        // SAFETY (all reads and pieces below): `Crew::pass` checked that the outputs are
        // distinct from each other and from every buffer the pass reads; by the barrier no
        // thread writes a buffer during a pass that reads it; each part writes only its own
        // particles q0..q1 (disjoint between parts, and each part of a pass runs once); every
        // buffer holds at least n ≥ q1 values (checked by `Stencil::team`).
        let read = |i: usize| -> &[DVec3] {
            let b = self.buffers[i];
            unsafe { std::slice::from_raw_parts(b.ptr, b.len) }
        };
        let piece = |o: Option<usize>| -> &mut [DVec3] {
            match o {
                Some(i) => unsafe {
                    std::slice::from_raw_parts_mut(self.buffers[i].ptr.add(q0), q1 - q0)
                },
                None => &mut [],
            }
        };
        let update = match pass.update {
            TeamUpdate::SemiImplicitEuler { dt } => Update::SemiImplicitEuler { dt },
            TeamUpdate::Euler { h, base } => Update::Euler {
                h,
                base: match base {
                    None => Base::Input,
                    Some([x, v]) => Base::Slices(read(x), read(v)),
                },
            },
            TeamUpdate::Rk4 { sixth, a, v } => Update::Rk4 {
                sixth,
                a: a.map(read),
                v: v.map(read),
            },
        };
        let output = Output::Step {
            dynamics: pass.dynamics,
            update,
            after: pass.after,
        };
        output.check(n);
        // The part's pieces of the pass's power slot: of its chunks' values, as
        // `Stencil::write_in_parts` cuts them (two values per particle from 2 q0, the last part
        // to the end, padding), and of the groups' sums, those of the groups that start in it.
        let (power, groups): (&mut [f64], &mut [f64]) = match pass.power {
            Some(slot) => {
                let len = self.stencil.power_len();
                let end = if k + 1 == self.parts { len } else { 2 * q1 };
                let group = 2 * LANES * POWER_GROUP;
                let (g0, g1) = ((2 * q0).div_ceil(group), end.div_ceil(group));
                let at = slot % self.ring * self.stencil.power_slot_len();
                // SAFETY: as above; the ring holds `ring` slots (checked by
                // `Stencil::team_with_power`), the parts' pieces of a slot are disjoint (a group
                // starts in one part), and no slot being summed is written (`Crew::pass_then`
                // checked).
                unsafe {
                    (
                        std::slice::from_raw_parts_mut(
                            self.power.ptr.add(at + 2 * q0),
                            end - 2 * q0,
                        ),
                        std::slice::from_raw_parts_mut(
                            self.power.ptr.add(at + len + 2 * LANES * g0),
                            2 * LANES * (g1 - g0),
                        ),
                    )
                }
            }
            None => (&mut [], &mut []),
        };
        let mut part = Part {
            outs: pass.outs.map(piece),
            power,
            groups,
        };
        let (x, v) = (&read(pass.x)[..n], &read(pass.v)[..n]);
        SCRATCH.with(|scratch| {
            let scratch = &mut scratch.borrow_mut();
            if pass.power.is_some() {
                scratch.power_mode = PowerMode::Groups;
            }
            self.stencil
                .range(scratch, x, v, q0, q1, &mut part, &output);
            // (An empty range returns before it takes the mode.)
            scratch.power_mode = PowerMode::Buffer;
        });
        if let Some(then) = then {
            let [xs, vs, _] = &mut part.outs;
            then(k, q0, xs, vs);
        }
        if let Some(slot) = sum {
            self.add_power(k, slot);
        }
        self.done[k].0.store(s + 1, Ordering::Release);
    }

    /// Adds part `k`'s share of power slot `slot` to the slot's running sums (module docs),
    /// as [`Stencil::sum_power`] adds them; after the last part, the slot's total. Part `k`'s
    /// chunks are those from the first whole chunk at or after `bounds[k]` to the next part's
    /// first: those before the first group that starts in it continue the open group, chunk
    /// by chunk (from the ring); each group that starts in it closes the open one and opens
    /// with the sums the part made of it (`PowerMode::Groups`).
    fn add_power(&self, k: usize, slot: usize) {
        let len = self.stencil.power_len();
        // The part's first chunk (the parts' pieces of the ring, `run_part`).
        let first = |k: usize| match k {
            0 => 0,
            k if k == self.parts => len / (2 * LANES),
            k => self.bounds[k].div_ceil(LANES).min(len / (2 * LANES)),
        };
        let (c0, c1) = (first(k), first(k + 1));
        let lead = c0.next_multiple_of(POWER_GROUP).min(c1);
        let at = slot % self.ring * self.stencil.power_slot_len();
        // SAFETY: slot `slot % ring` of the ring was written by a pass every part of which is
        // done (a barrier ago), and no pass writes it until its last part is added
        // (`Crew::pass_then` checked); its running sums are touched by one part at a time, the
        // parts in successive passes, each behind a barrier.
        let (values, groups, running) = unsafe {
            let ring = self.power.ptr.add(at);
            (
                std::slice::from_raw_parts(ring.add(2 * LANES * c0), 2 * LANES * (lead - c0)),
                std::slice::from_raw_parts(ring.add(len), self.stencil.groups_len()),
                &mut *self.running[slot % self.ring].get(),
            )
        };
        if k == 0 {
            *running = Running {
                slot,
                ..Running::default()
            };
        }
        assert!(
            running.slot == slot && running.next == k,
            "power summed out of order"
        );
        Stencil::add_power(&mut running.open, values, self.contact);
        for g in c0.div_ceil(POWER_GROUP)..c1.div_ceil(POWER_GROUP) {
            if g > 0 {
                Stencil::close_group(&mut running.closed, &running.open);
            }
            let sums = &groups[2 * LANES * g..2 * LANES * (g + 1)];
            for (open, column) in running.open.iter_mut().zip(sums.chunks_exact(LANES)) {
                open.copy_from_slice(column);
            }
        }
        running.next = k + 1;
        if k + 1 == self.parts {
            if c1 > 0 {
                Stencil::close_group(&mut running.closed, &running.open);
            }
            self.finish_power(slot, running);
        }
    }

    /// Slot `slot`'s total from its running sums, once its last part is added.
    fn finish_power(&self, slot: usize, running: &Running) {
        assert!(slot < self.totals.len, "no power total {slot}");
        // SAFETY: inside the totals (checked); each slot's total is written once.
        unsafe { *self.totals.ptr.add(slot) = Stencil::power_total(&running.closed, self.contact) };
    }
}

/// One thread of a team, as the body sees it: call [`Crew::pass`] for each pass, the same
/// passes in the same order on every thread.
pub struct Crew<'t> {
    common: &'t Common<'t>,
    /// This thread's home part.
    home: usize,
    /// Passes this thread has been through.
    passes: Cell<u64>,
    /// Serial stages this thread has been through.
    serials: Cell<u64>,
    /// The last pass needed a part whose owner did not come: take such parts at once.
    alone: Cell<bool>,
    /// The power slot of each of the last passes, this one first (module docs).
    written: Cell<[Option<usize>; MAX_PARTS]>,
}

impl Crew<'_> {
    /// This thread's home part (0, 1, …).
    #[must_use]
    pub fn home(&self) -> usize {
        self.home
    }

    /// Runs `pass` over all parts of the particles with the other threads of the team (see the
    /// module docs), and returns when every part of it is done.
    ///
    /// # Panics
    /// If a buffer index is out of range, a pass reads one of its own outputs or writes one
    /// twice, or another thread of the team panicked.
    pub fn pass(&self, pass: &Pass) {
        self.pass_then(pass, None);
    }

    /// [`Crew::pass`], and after each part of it `then(k, q0, x, v)` on the thread that ran
    /// the part, with `x` and `v` the part's new positions and velocities (`outs[0]`,
    /// `outs[1]`, particles `q0..`) while they are in its cache: a summary of each part that a
    /// following [`Crew::serial`] reads instead of scanning every particle itself (the
    /// collision response's broad phase), or a change of each particle that depends on that
    /// particle alone (a kinematic sphere's push). `then` writes only what belongs to part `k`:
    /// no other thread reads the part's new values before the next pass (a pass never reads
    /// its own outputs).
    ///
    /// # Panics
    /// As [`Crew::pass`].
    pub fn pass_then(&self, pass: &Pass, then: Option<PartFn>) {
        let c = self.common;
        let outs = pass.outs;
        let written = outs.iter().flatten();
        for (i, &o) in written.clone().enumerate() {
            assert!(o < c.count, "no buffer {o}");
            assert!(
                written.clone().skip(i + 1).all(|&p| p != o),
                "buffer {o} written twice"
            );
        }
        for r in [pass.x, pass.v].into_iter().chain(pass.update.reads()) {
            assert!(r < c.count, "no buffer {r}");
            assert!(!outs.contains(&Some(r)), "a pass reads its own output {r}");
        }
        let mut written = self.written.get();
        if let Some(slot) = pass.power {
            assert!(c.ring > 0 && slot < c.totals.len, "no power slot {slot}");
            // Not over a slot whose sums are still being added (the last `parts - 1` passes').
            assert!(
                (written[..c.parts - 1].iter().flatten()).all(|&w| w % c.ring != slot % c.ring),
                "power slot {slot} overwrites one not summed yet"
            );
        }
        written.copy_within(..MAX_PARTS - 1, 1);
        written[0] = pass.power;
        self.written.set(written);
        let s = self.passes.get();
        self.passes.set(s + 1);
        if c.claim(self.home, s) {
            c.run_part(self.home, s, pass, then, written[self.home]);
        }
        // Parts without a thread of their own: at once.
        for k in c.homes..c.parts {
            if c.claim(k, s) {
                c.run_part(k, s, pass, then, written[k]);
            }
        }
        let mut start = None;
        let mut stole = false;
        let mut spins = 0u32;
        while !c.pass_done(s) {
            assert!(
                !c.abort.load(Ordering::Relaxed),
                "another thread of the team panicked"
            );
            spins += 1;
            if !spins.is_multiple_of(32) {
                std::hint::spin_loop();
                continue;
            }
            let waited = waited(&mut start, spins);
            if self.alone.get() || waited >= PATIENCE {
                for k in 0..c.homes {
                    if c.claim(k, s) {
                        c.run_part(k, s, pass, then, written[k]);
                        stole = true;
                    }
                }
            }
            if waited >= SPIN {
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
        self.alone.set(stole);
    }
}

impl Crew<'_> {
    /// Runs `f` on the whole of buffers `x` and `v` on one thread of the team, the first to
    /// come, while the others wait; returns when it is done. Called between two passes (every
    /// part of the last pass is done when [`Crew::pass`] returns, and no thread starts the next
    /// one before `f` has finished), so `f` sees the buffers complete and no other thread reads
    /// or writes them meanwhile. Every thread calls it at the same point of the body, as it
    /// calls the passes.
    ///
    /// # Panics
    /// If a buffer index is out of range or `x == v`, or another thread of the team panicked.
    pub fn serial(&self, x: usize, v: usize, f: &(dyn Fn(&mut [DVec3], &mut [DVec3]) + Sync)) {
        let c = self.common;
        assert!(x < c.count && v < c.count && x != v, "no buffers {x}, {v}");
        let s = self.serials.get();
        self.serials.set(s + 1);
        if c.serial_claimed
            .0
            .compare_exchange(s, s + 1, Ordering::AcqRel, Ordering::Relaxed)
            .is_ok()
        {
            let n = c.stencil.particles;
            // SAFETY: two distinct buffers (checked above), each of at least n values (checked
            // by `Stencil::team`); every part of the passes before is done, and the other
            // threads wait below before their next pass, so none reads or writes them now.
            let (xs, vs) = unsafe {
                (
                    std::slice::from_raw_parts_mut(c.buffers[x].ptr, n),
                    std::slice::from_raw_parts_mut(c.buffers[v].ptr, n),
                )
            };
            f(xs, vs);
            c.serial_done.0.store(s + 1, Ordering::Release);
            return;
        }
        let mut start = None;
        let mut spins = 0u32;
        while c.serial_done.0.load(Ordering::Acquire) <= s {
            assert!(
                !c.abort.load(Ordering::Relaxed),
                "another thread of the team panicked"
            );
            spins += 1;
            if spins.is_multiple_of(32) && waited(&mut start, spins) >= SPIN {
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
    }
}

/// Raises the team's abort flag when dropped during a panic.
struct AbortOnPanic<'a>(&'a AtomicBool);

impl Drop for AbortOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Relaxed);
        }
    }
}

impl Stencil {
    /// Runs `body` on a team of threads of the global pool, one per part (at most the pool's
    /// threads; see the module docs), for the particles split into `parts` parts as
    /// [`Stencil::write_in_parts`] splits them; the body calls [`Crew::pass`] for each pass,
    /// which runs all parts of it. The same numbers as the passes one by one with
    /// [`Stencil::write_in_parts`], for any `parts` and however many threads take part.
    ///
    /// # Panics
    /// If there are more than [`MAX_BUFFERS`] buffers, one is shorter than the particle count,
    /// or `body` panics.
    pub fn team(&self, parts: usize, buffers: &mut [&mut [DVec3]], body: &(dyn Fn(&Crew) + Sync)) {
        self.team_with_power(parts, buffers, TeamPower::default(), body);
    }

    /// [`Stencil::team`] with the passes' dissipated power: a pass with [`Pass::power`]
    /// `Some(k)` writes the values [`Stencil::write`] writes into its power buffer into the
    /// ring of `power`, and `power.totals[k]` receives their sum, bit for bit
    /// [`Stencil::sum_power`] of them (module docs).
    ///
    /// # Panics
    /// As [`Stencil::team`]; also when a pass names a total past the end of `power.totals`,
    /// when the ring has fewer than `parts` slots, or when the passes with power do not name
    /// their slots in order.
    pub fn team_with_power(
        &self,
        parts: usize,
        buffers: &mut [&mut [DVec3]],
        power: TeamPower,
        body: &(dyn Fn(&Crew) + Sync),
    ) {
        let parts = parts.clamp(1, MAX_PARTS);
        let ring = (power.ring.len() / self.power_slot_len().max(1)).min(MAX_PARTS);
        assert!(
            power.totals.is_empty() || ring >= parts,
            "a power ring of {ring} slots for {parts} parts"
        );
        assert!(buffers.len() <= MAX_BUFFERS, "too many buffers");
        assert!(
            buffers.iter().all(|b| b.len() >= self.particles),
            "a buffer shorter than the particle count"
        );
        let mut shared = [Shared {
            ptr: std::ptr::null_mut(),
            len: 0,
        }; MAX_BUFFERS];
        for (s, b) in shared.iter_mut().zip(buffers.iter_mut()) {
            *s = Shared {
                ptr: b.as_mut_ptr(),
                len: b.len(),
            };
        }
        let pool = Pool::global();
        let homes = parts.min(pool.threads());
        let common = Common {
            stencil: self,
            bounds: self.split(parts),
            parts,
            homes,
            buffers: shared,
            count: buffers.len(),
            power: SharedPower {
                ptr: power.ring.as_mut_ptr(),
            },
            ring,
            totals: SharedTotals {
                ptr: power.totals.as_mut_ptr(),
                len: power.totals.len(),
            },
            contact: power.contact,
            running: std::array::from_fn(|_| std::cell::UnsafeCell::new(Running::default())),
            claimed: std::array::from_fn(|_| Padded::default()),
            done: std::array::from_fn(|_| Padded::default()),
            serial_claimed: Padded::default(),
            serial_done: Padded::default(),
            abort: AtomicBool::new(false),
            _borrow: PhantomData,
        };
        let common = &common;
        // One job for all the passes; a thread that comes late (or not at all, when another
        // thread is using the pool and the caller runs every home itself) finds the parts done.
        pool.run(homes, &|home| {
            let _abort = AbortOnPanic(&common.abort);
            body(&Crew {
                common,
                home,
                passes: Cell::new(0),
                serials: Cell::new(0),
                alone: Cell::new(false),
                written: Cell::new([None; MAX_PARTS]),
            });
        });
        // The sums of the last passes' slots that the team did not reach, part after part.
        for at in 0..ring {
            // SAFETY: the team is over; this thread alone reads the running sums.
            let Running { slot, next, .. } = unsafe { *common.running[at].get() };
            if next > 0 {
                for k in next..parts {
                    common.add_power(k, slot);
                }
            }
        }
    }

    /// [`Stencil::sum_power`]'s running sums: the chunks of `power` added lane by lane to
    /// `sums` (dampers, contact), chunk after chunk.
    pub(super) fn add_power(sums: &mut [[f64; LANES]; 2], power: &[f64], contact: bool) {
        let columns = if contact { 2 } else { 1 };
        for chunk in power.chunks_exact(2 * LANES) {
            for (sum, part) in sums.iter_mut().zip(chunk.chunks_exact(LANES)).take(columns) {
                for (s, p) in sum.iter_mut().zip(part) {
                    *s += p;
                }
            }
        }
    }

    /// [`Stencil::sum_power`]'s result from its running sums.
    pub(super) fn power_total(sums: &[[f64; LANES]; 2], contact: bool) -> (f64, f64) {
        let contact = if contact {
            Self::lanes_total(&sums[1])
        } else {
            0.0
        };
        (Self::lanes_total(&sums[0]), contact)
    }

    /// The values of a team's power ring ([`TeamPower::ring`]) for `parts` parts.
    #[must_use]
    pub fn power_ring_len(&self, parts: usize) -> usize {
        parts.clamp(1, MAX_PARTS) * self.power_slot_len()
    }

    /// The values of one slot of a team's power ring: its chunks' values
    /// ([`Stencil::power_len`]), then each group's sums.
    #[must_use]
    pub fn power_slot_len(&self) -> usize {
        self.power_len() + self.groups_len()
    }
}

/// The dissipated power of a team's passes ([`Stencil::team_with_power`]).
#[derive(Default)]
pub struct TeamPower<'a> {
    /// The ring of slots the passes write (scratch): whole slots of [`Stencil::power_slot_len`]
    /// values, at least [`Stencil::power_ring_len`] values.
    pub ring: &'a mut [f64],
    /// Total `k`: `(dampers and drag, contact)` (W) of the pass with [`Pass::power`] `Some(k)`.
    pub totals: &'a mut [(f64, f64)],
    /// The passes have colliders ([`Stencil::sum_power`]'s `contact`).
    pub contact: bool,
}
