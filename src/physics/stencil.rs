//! The stencil form of a lattice's springs: the same forces as the spring list, computed for
//! throughput on every core.
//!
//! # Theory
//!
//! **Stencil.** In a lattice (the jelly cube, the cloth, a rope) every spring joins particle `p` to
//! particle `p + δ` for one of a few index offsets `δ`, and all springs of one offset share their
//! stiffness `k` and damping `k_d`. Grouping the springs by offset (a "stencil") turns the force
//! loop into passes over contiguous arrays with no scattered writes. Spring `(p, p + δ)` pushes
//! its first end with `+f_δ[p]` and its second end with `-f_δ[p]`, so the net spring force on
//! particle `q` is
//!
//! ```text
//! F[q] = Σ_δ f_δ[q]  -  Σ_δ f_δ[q - δ]          (a term is 0 where the spring does not exist)
//!        "q is a first end"  "q is a second end"
//! ```
//! where the force of one spring is that of [`super::springs`]:
//! `f = (k (L - L0) + k_d (v_b - v_a)·n) n`, `n = (x_b - x_a)/L`, in N.
//!
//! **Tiles and rings.** The particles are visited in chunks of eight (`LANES`, one AVX-512
//! register of f64) and tiles of 64 (`TILE`). For each tile:
//!
//! ```text
//! pass 1, each chunk p of the tile:  load x[p..p+8], v[p..p+8] once;  plus = 0
//!         each offset δ:             f_δ[p..p+8] (8 springs at once) → ring_δ;  plus += f_δ
//! pass 2, each chunk q of the tile:  minus = Σ_δ ring_δ[q-δ..q-δ+8]
//!                                    F[q..q+8] = plus[q] - minus,  then the output
//! ```
//! Pass 1 reads `x[p+δ..p+δ+8]` as contiguous loads, and its iterations are independent, so
//! the processor overlaps them; the first ends and the sum of the forces that start at `p`
//! stay in registers across the offsets. A spring's force is needed a second time, at its
//! second end `δ` particles later, so it is kept in a ring buffer per offset holding the last
//! `R ≥ δ + TILE + 8` forces (`R` a power of two, index `p mod R`, plus a copy of the first
//! eight after the end so that eight values can always be read at once). The whole working set
//! stays in the core's caches however large the lattice is. Positions and velocities are first
//! copied into one contiguous `f64` array per component (structure of arrays; with AVX-512 eight
//! particles at a time by two-register permutes).
//!
//! **To the end of the step in the same pass.** Pass 2 finishes each chunk with what the caller
//! asked for ([`Output`]): the spring force; the total force with weight, drag and the
//! colliders' contact force ([`Dynamics`]); the acceleration `f/m`; or a whole stage of an
//! integrator ([`Update`]): the semi-implicit Euler step `v' = v + dt a`, `x' = x + dt v'`, an
//! Euler stage `x' = x_b + h v`, `v' = v_b + h a` from a base state (explicit Euler, the
//! midpoint and predictor–corrector stages, RK4's first three stages), or RK4's weighted sum.
//! So [`super::forces::forces`], [`super::forces::accelerations`] and every explicit method's
//! stages need no further pass over the particles, and that work is split between the threads
//! too. Each output does the same operations in the same order as the textbook loop it
//! replaces, so the numbers are the same bit for bit (tested for every method).
//!
//! **Contact in the same pass.** The contact force depends on the total of the other forces on
//! the particle, which pass 2 has in registers. A chunk is tested against each collider in its
//! registers first (a broad phase without square roots: a plane's signed distance, a sphere's
//! or bowl's squared distance, a floor's height, each with a relative margin of 10⁻⁹ so that it
//! never rejects a particle the exact test would accept); only particles that may touch go
//! through the scalar contact code of [`super::collide`], with the same operations as
//! [`super::collide::contact_forces`].
//!
//! **Dissipated power in the same pass.** When asked ([`Stencil::write`] with a power buffer),
//! pass 1 also computes each damper's power `k_d ((v_b - v_a)·n)²` (two more multiplications
//! per spring) and pass 2 adds the drag `c |v|²` and the contact power of each particle
//! (see [`super::energy::dissipated_power`]); each chunk writes its eight partial sums, and the
//! caller adds them in chunk order, so the total does not depend on the split between threads.
//!
//! **One reciprocal square root.** The length and the direction need `L = √(d·d)` and `1/L`.
//! A 512-bit square root or division keeps the divider busy for about 13–16 cycles (measured on
//! the benchmark machine; Intel Intrinsics Guide, `VSQRTPD`, `VDIVPD`), as long as the twenty
//! other operations of a spring together. With AVX-512F the processor also offers an estimate
//! `y₀ ≈ 1/√a` with relative error below 2⁻¹⁴ (`VRSQRT14PD`, about 1.6 cycles per vector),
//! which Newton–Raphson on `g(y) = 1/y² - a` refines:
//!
//! ```text
//! e      = 1 - a y_k²                    relative residual (one fused multiply-add)
//! y_k+1  = y_k + ½ y_k e                 error ε_k+1 ≈ 1.5 ε_k²: 2⁻¹⁴ → 2⁻²⁷ → 2⁻⁵³
//! 1/L    = y₂,   L = a · y₂              (a = d·d)
//! ```
//! Two steps reach the last bit or two of an f64 (relative error ≈ 1e-16, against 2.2e-16 for
//! one rounding), cheaper than one division. The result is not always the correctly rounded
//! `1/√a`.
//!
//! **Three kernels** ([`Kernel`]), chosen at run time for the CPU: `Portable` (plain Rust,
//! `sqrt` then `1/L`), `Avx2` (the same operations on 256-bit registers, so the same bits) and
//! `Avx512` (the reciprocal square root above, with fused multiply-adds). Runs are
//! bit-identical run to run on one machine, but a machine with AVX-512 and one without give
//! results that differ in the last bits of a force (about 1e-16 relative; after the peer
//! workloads' N steps their checksums differ by at most 2e-13 relative, on cloth64, and all
//! agree with the C++ references to 1.1e-10; `examples/kernel_checksums.rs` prints them). Measured on the benchmark machine (2-core Xeon, one thread, jelly cube): about
//! 2.1 ns per spring slot with AVX-512, 2.9 ns with AVX2, 7.5 ns portable (SSE2).
//!
//! The sums run in a different order than the spring-list loop, so forces agree with
//! [`super::forces`] to rounding (about 1e-15 relative), not bit for bit; a test checks it.
//!
//! References: the "stencil" formulation of finite-difference codes (Datta et al., "Stencil
//! Computation Optimization and Auto-tuning on State-of-the-Art Multicore Architectures",
//! SC 2008); Intel Intrinsics Guide, `_mm512_rsqrt14_pd`, `_mm512_fmadd_pd`,
//! <https://www.intel.com/content/www/us/en/docs/intrinsics-guide/>; C. Lomont, "Fast Inverse
//! Square Root", Purdue University technical report, 2003 (the Newton step for `1/√a`);
//! WORKLOADS.md (the peer benchmark's lattices and their spring order).

use std::cell::RefCell;
use std::sync::Mutex;

use glam::DVec3;

use super::collide::{Collider, ContactParams, contact_force};
#[cfg(target_arch = "x86_64")]
use super::lanes::{Avx2, Avx512};
use super::lanes::{LANES, Lanes, Plain, from_lanes, lanes, to_lanes};
use super::pool::Pool;
use super::springs::Spring;

/// At most this many offset groups: more would make the passes slower than the spring list.
const MAX_GROUPS: usize = 32;

/// The stencil form pays off when at least this share of the `(group, p)` slots hold a spring.
const MIN_DENSITY: f64 = 0.5;

/// Below this many springs the spring list is as fast: the stencil's passes have fixed costs.
const MIN_SPRINGS: usize = 32;

/// Particles per tile of the streaming loop (a multiple of `LANES`): the springs of a tile are
/// computed before their forces are gathered (see `range_body`).
const TILE: usize = 64;

/// At most this many parts (threads) per pass.
pub const MAX_PARTS: usize = 16;

/// Split the work between threads only with at least this many spring slots per thread
/// (about 1.5 µs of work): measured with `examples/stencil_micro.rs`, two parts already win on
/// a 24×24 cloth (3 500 slots: 6.5 → 3.7 µs per call) and on a 16×16 cloth (1 500 slots:
/// 2.7 → 1.8 µs) when the second core is free, but lose on the 64-node rope (0.3 → 0.4 µs).
const MIN_SLOTS_PER_PART: usize = 1024;

/// The instructions that compute the springs (see the module docs). All give the same forces
/// to about 1e-16 relative; each is deterministic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Plain Rust: `sqrt`, then one division `1/L`. Runs everywhere.
    Portable,
    /// The same operations on AVX2 registers (x86-64): the same results bit for bit.
    Avx2,
    /// AVX-512F (x86-64): reciprocal square root estimate, two Newton steps and fused
    /// multiply-adds.
    Avx512,
}

impl Kernel {
    /// Every kernel, slowest first.
    pub const ALL: [Kernel; 3] = [Kernel::Portable, Kernel::Avx2, Kernel::Avx512];

    /// True when this CPU can run the kernel.
    #[must_use]
    pub fn is_available(self) -> bool {
        match self {
            Kernel::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => std::arch::is_x86_feature_detected!("avx512f"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The fastest kernel this CPU can run.
    #[must_use]
    pub fn best() -> Kernel {
        Kernel::ALL
            .into_iter()
            .rev()
            .find(|k| k.is_available())
            .unwrap_or(Kernel::Portable)
    }
}

/// Everything besides the springs that acts on a particle: weight, drag and the colliders'
/// contact force, as in [`super::forces::forces`]:
///
/// ```text
/// f_q = (m_q g - c v_q) + F_springs[q]        then the contact force of the colliders
/// a_q = f_q · (1/m_q)
/// ```
/// where `m` is in kg, `g` in m/s², `c` the drag coefficient in N·s/m, `v` in m/s.
#[derive(Clone, Copy, Debug)]
pub struct Dynamics<'a> {
    /// Masses `m` (kg).
    pub mass: &'a [f64],
    /// Inverse masses `1/m` (1/kg, 0 for pinned particles).
    pub inv_mass: &'a [f64],
    /// Gravitational acceleration `g` (m/s²).
    pub gravity: DVec3,
    /// Drag coefficient `c` (N·s/m).
    pub drag: f64,
    /// Static colliders (empty: no contact force).
    pub colliders: &'a [Collider],
    /// Their contact coefficients.
    pub contact: &'a ContactParams,
}

/// A per-particle rule applied to positions and velocities (m, m/s) at the end of a step, such
/// as the benchmark's contact projections: it must treat every particle on its own, so that
/// applying it to any split of the particles gives the same result.
pub type After<'a> = &'a (dyn Fn(&mut [DVec3], &mut [DVec3]) + Sync);

/// What the stencil writes for each particle `q`, given its spring force `F_springs[q]` (N),
/// into the outputs `outs` of [`Stencil::write`]. Every variant does the same operations in
/// the same order as the textbook loop it replaces, so the numbers are the same.
#[derive(Clone, Copy)]
pub enum Output<'a> {
    /// Adds the spring force: `outs[0][q] += F_springs[q]`.
    Add,
    /// The total force `f_q` of [`Dynamics`] (N) into `outs[0]`.
    Forces(Dynamics<'a>),
    /// The acceleration `a_q = f_q / m_q` (m/s²) into `outs[0]`.
    Accelerations(Dynamics<'a>),
    /// Nothing but the dissipated power (a power buffer is required).
    Power(Dynamics<'a>),
    /// A stage of an integrator (see [`Update`]) with the accelerations `a` of
    /// [`Output::Accelerations`]; then `after`, if given, on the new positions and velocities.
    Step {
        /// Weight, drag, contact and masses.
        dynamics: Dynamics<'a>,
        /// What the stage writes.
        update: Update<'a>,
        /// Applied to the new positions and velocities of each tile once they are written.
        after: Option<After<'a>>,
    },
}

/// What a stage writes, from the input `(x, v)` of the pass and its accelerations `a` (m/s²).
/// Positions go to `outs[0]`, velocities to `outs[1]`. Outputs that are not written in place
/// must not be the inputs themselves: other threads still read those.
#[derive(Clone, Copy)]
pub enum Update<'a> {
    /// Semi-implicit Euler: `v' = v + dt a`, then `x' = x + dt v'` (`dt` in s).
    SemiImplicitEuler {
        /// Time step (s).
        dt: f64,
    },
    /// An Euler stage from a base state `(x_b, v_b)`: `x' = x_b + h v`, `v' = v_b + h a`, and
    /// `a` itself into `outs[2]` when that is not empty (`h` in s).
    Euler {
        /// Stage length (s).
        h: f64,
        /// Where `(x_b, v_b)` come from.
        base: Base<'a>,
    },
    /// RK4's last stage, in place: with `(x_n, v_n)` in `outs[0]`, `outs[1]` on entry,
    /// `x' = x_n + sixth (v_n + 2 v_2 + 2 v_3 + v)` and
    /// `v' = v_n + sixth (a_1 + 2 a_2 + 2 a_3 + a)` (`sixth = dt/6` in s).
    Rk4 {
        /// `dt/6` (s).
        sixth: f64,
        /// The slopes `a_1`, `a_2`, `a_3` of the first three stages (m/s²).
        a: [&'a [DVec3]; 3],
        /// The velocities `v_2`, `v_3` of stages 2 and 3 (m/s).
        v: [&'a [DVec3]; 2],
    },
}

/// The base state of an [`Update::Euler`] stage.
#[derive(Clone, Copy)]
pub enum Base<'a> {
    /// The pass's own input `(x, v)`.
    Input,
    /// Other positions and velocities (m, m/s), read only.
    Slices(&'a [DVec3], &'a [DVec3]),
    /// `outs[0]` and `outs[1]` as they are on entry (updated in place).
    InPlace,
}

/// The springs of one index offset `δ`, all with the same stiffness and damping.
#[derive(Clone, Debug, PartialEq)]
struct Group {
    /// `b - a` for every spring of the group.
    delta: usize,
    /// Stiffness `k` (N/m).
    stiffness: f64,
    /// Damping `k_d` (N·s/m).
    damping: f64,
    /// Number of possible first ends: `particles - delta`.
    starts: usize,
    /// Rest length of the spring starting at `p` (m); 0 where there is none. Padded with zeros
    /// to a whole number of chunks.
    rest_length: Vec<f64>,
    /// Bit `l` of byte `c` is set when a spring starts at `p = 8 c + l` (zero in the padding).
    present: Vec<u8>,
    /// Length `R` of the group's force ring (a power of two, at least `delta + LANES`).
    ring: usize,
    /// Where the group's ring starts in [`Scratch::ring`]: three components of `R + LANES`
    /// values each (the last `LANES` mirror the first, so a chunk can be read across the wrap).
    ring_offset: usize,
}

/// A lattice's springs grouped by index offset (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Stencil {
    particles: usize,
    groups: Vec<Group>,
    /// The largest offset `δ`.
    reach: usize,
    /// Length of all the groups' rings together (f64 values).
    ring_len: usize,
    /// The instructions used for the springs.
    kernel: Kernel,
    /// `work[j]` = spring slots in chunks `0..j` (for splitting the work between threads).
    work: Vec<usize>,
    /// The work of the spring slots a thread recomputes when its range does not start at
    /// particle 0, in own slots.
    halo_work: usize,
}

impl Stencil {
    /// The stencil form of `springs` over `particles` particles, or `None` when the springs are
    /// not a lattice worth it (too few springs, too many offsets, too sparse, or two springs
    /// with the same start and offset). Springs without stiffness and damping exert no force
    /// and are left out.
    #[must_use]
    pub fn detect(particles: usize, springs: &[Spring]) -> Option<Stencil> {
        let mut groups: Vec<Group> = Vec::new();
        // Springs without stiffness and damping exert no force (pure distance constraints).
        let elastic = springs
            .iter()
            .filter(|s| s.stiffness != 0.0 || s.damping != 0.0);
        if elastic.clone().count() < MIN_SPRINGS {
            return None;
        }
        for s in elastic {
            // Orient every spring from its lower index: swapping the ends negates d, n and the
            // relative velocity, so the force on the lower end is exactly the same number.
            let (a, b) = if s.a < s.b {
                (s.a as usize, s.b as usize)
            } else {
                (s.b as usize, s.a as usize)
            };
            let delta = b - a;
            if delta == 0 {
                return None;
            }
            let g = match groups.iter().position(|g| {
                g.delta == delta && g.stiffness == s.stiffness && g.damping == s.damping
            }) {
                Some(g) => g,
                None => {
                    if groups.len() == MAX_GROUPS || groups.iter().any(|g| g.delta == delta) {
                        // Too many offsets, or one offset with two coefficient sets.
                        return None;
                    }
                    let starts = particles - delta;
                    let padded = starts.next_multiple_of(LANES);
                    groups.push(Group {
                        delta,
                        stiffness: s.stiffness,
                        damping: s.damping,
                        starts,
                        rest_length: vec![0.0; padded],
                        present: vec![0; padded / LANES],
                        ring: (delta + TILE + LANES).next_power_of_two(),
                        ring_offset: 0,
                    });
                    groups.len() - 1
                }
            };
            let group = &mut groups[g];
            let bit = 1u8 << (a % LANES);
            if group.present[a / LANES] & bit != 0 {
                return None;
            }
            group.present[a / LANES] |= bit;
            group.rest_length[a] = s.rest_length;
        }
        let slots: usize = groups.iter().map(|g| g.starts).sum();
        let count: usize = groups
            .iter()
            .map(|g| {
                g.present
                    .iter()
                    .map(|b| b.count_ones() as usize)
                    .sum::<usize>()
            })
            .sum();
        if (count as f64) < MIN_DENSITY * slots as f64 {
            return None;
        }
        // Visit offsets in increasing order: neighbouring streams, better locality; and the
        // groups a chunk has (`p < starts`) are then always a prefix of the list.
        groups.sort_by_key(|g| g.delta);
        let mut ring_len = 0;
        for g in &mut groups {
            g.ring_offset = ring_len;
            ring_len += 3 * (g.ring + LANES);
        }
        let chunks = particles.div_ceil(LANES);
        let mut work = Vec::with_capacity(chunks + 1);
        work.push(0);
        for j in 0..chunks {
            let here = groups.iter().filter(|g| j * LANES < g.starts).count();
            work.push(work[j] + here * LANES);
        }
        // A halo slot costs pass 1 only, about two thirds of an own slot (pass 1, pass 2 and the
        // output; measured on the jelly cube with `examples/stencil_micro.rs`).
        let halo_slots: usize = groups
            .iter()
            .map(|g| (g.delta.div_ceil(LANES) + 1) * LANES)
            .sum();
        let halo_work = halo_slots * 2 / 3;
        Some(Stencil {
            particles,
            reach: groups.iter().map(|g| g.delta).max().unwrap_or(0),
            groups,
            ring_len,
            kernel: Kernel::best(),
            work,
            halo_work,
        })
    }

    /// Number of offset groups.
    #[must_use]
    pub fn group_count(&self) -> usize {
        self.groups.len()
    }

    /// Number of spring slots (springs and the gaps between them that the passes compute as
    /// zeros): the work of one pass.
    #[must_use]
    pub fn slots(&self) -> usize {
        self.work.last().copied().unwrap_or(0)
    }

    /// The instructions that compute the springs ([`Kernel::best`] unless changed).
    #[must_use]
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// The same stencil computing with `kernel`.
    ///
    /// # Panics
    /// If this CPU cannot run `kernel` (see [`Kernel::is_available`]).
    #[must_use]
    pub fn with_kernel(mut self, kernel: Kernel) -> Stencil {
        assert!(kernel.is_available(), "{kernel:?} is not available here");
        self.kernel = kernel;
        self
    }

    /// Sets the stiffness and damping of every spring (used when a lesson changes them for all
    /// springs at once).
    pub fn set_coefficients(&mut self, stiffness: f64, damping: f64) {
        for g in &mut self.groups {
            g.stiffness = stiffness;
            g.damping = damping;
        }
    }

    /// The number of parts (threads) worth using with a pool of `threads` threads: one per
    /// `MIN_SLOTS_PER_PART` spring slots, at most `threads` and [`MAX_PARTS`].
    #[must_use]
    pub fn parallel_parts(&self, threads: usize) -> usize {
        (self.slots() / MIN_SLOTS_PER_PART).clamp(1, threads.clamp(1, MAX_PARTS))
    }

    /// The length of the power buffer of [`Stencil::write`]: two values per particle, rounded
    /// up to whole chunks.
    #[must_use]
    pub fn power_len(&self) -> usize {
        2 * self.particles.next_multiple_of(LANES)
    }

    /// The dissipated power in a buffer written by [`Stencil::write`]: `(dampers and drag,
    /// contact)` (W), added chunk by chunk in a fixed order (so the same for any split).
    #[must_use]
    pub fn sum_power(power: &[f64]) -> (f64, f64) {
        let mut sums = [[0.0; LANES]; 2];
        for chunk in power.chunks_exact(2 * LANES) {
            for (sum, part) in sums.iter_mut().zip(chunk.chunks_exact(LANES)) {
                for (s, p) in sum.iter_mut().zip(part) {
                    *s += p;
                }
            }
        }
        let total = |s: [f64; LANES]| s.iter().sum::<f64>();
        (total(sums[0]), total(sums[1]))
    }

    /// Adds the spring forces (N) at positions `x` and velocities `v` to `f`, on as many
    /// threads of [`Pool::global`] as pay off.
    ///
    /// # Panics
    /// If the slices are shorter than the stencil's particle count.
    pub fn add_forces(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        self.write(x, v, [f, &mut [], &mut []], &mut [], Output::Add);
    }

    /// [`Stencil::add_forces`] with the particles split into `parts` ranges (at most
    /// [`MAX_PARTS`]), run in parallel where the global pool has free threads. The result is
    /// bit-identical for every `parts` (see the module docs).
    ///
    /// # Panics
    /// If the slices are shorter than the stencil's particle count.
    pub fn add_forces_in_parts(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], parts: usize) {
        self.write_in_parts(x, v, [f, &mut [], &mut []], &mut [], Output::Add, parts);
    }

    /// Writes `output` (see [`Output`] and [`Update`] for which of `outs` each writes; the
    /// others may be empty) for every particle at positions `x` (m) and velocities `v` (m/s),
    /// on as many threads of [`Pool::global`] as pay off. When `power` is not empty (at least
    /// [`Stencil::power_len`] long; only with [`Dynamics`]), it receives the dissipated power of
    /// each chunk, which [`Stencil::sum_power`] adds up.
    ///
    /// # Panics
    /// If a slice the output needs is shorter than the stencil's particle count.
    pub fn write(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        outs: [&mut [DVec3]; 3],
        power: &mut [f64],
        output: Output,
    ) {
        let parts = self.parallel_parts(Pool::global().threads());
        self.write_in_parts(x, v, outs, power, output, parts);
    }

    /// [`Stencil::write`] with the particles split into `parts` ranges (at most
    /// [`MAX_PARTS`]); the result is bit-identical for every `parts`.
    ///
    /// # Panics
    /// If a slice the output needs is shorter than the stencil's particle count.
    pub fn write_in_parts(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        outs: [&mut [DVec3]; 3],
        power: &mut [f64],
        output: Output,
        parts: usize,
    ) {
        let n = self.particles;
        let (x, v) = (&x[..n], &v[..n]);
        let [o0, o1, o2] = outs;
        // The outputs this variant writes, cut to n particles; the others to nothing.
        let (count, optional) = output.outputs();
        let outs = [
            cut(o0, count > 0, n),
            cut(o1, count > 1, n),
            cut(o2, optional && !o2.is_empty(), n),
        ];
        output.check(n);
        let power = if power.is_empty() {
            power
        } else {
            assert!(
                !matches!(output, Output::Add),
                "the dissipated power needs the dynamics"
            );
            &mut power[..self.power_len()]
        };
        let parts = parts.clamp(1, MAX_PARTS);
        if parts == 1 {
            let mut part = Part { outs, power };
            SCRATCH.with(|s| self.range(&mut s.borrow_mut(), x, v, 0, n, &mut part, &output));
            return;
        }
        let bounds = self.split(parts);
        // Each part gets its own pieces of the outputs (disjoint: no thread writes another's
        // values).
        let [mut r0, mut r1, mut r2] = outs;
        let mut rest_power = power;
        let pieces: [Mutex<Part>; MAX_PARTS] = std::array::from_fn(|k| {
            let len = if k < parts {
                bounds[k + 1] - bounds[k]
            } else {
                0
            };
            let outs = [take(&mut r0, len), take(&mut r1, len), take(&mut r2, len)];
            // Two values per particle, whole chunks: the last part takes the padding too.
            let power_len = if k + 1 == parts {
                rest_power.len()
            } else {
                (2 * len).min(rest_power.len())
            };
            debug_assert!(power_len <= rest_power.len());
            let (power, others) = std::mem::take(&mut rest_power).split_at_mut(power_len);
            rest_power = others;
            Mutex::new(Part { outs, power })
        });
        Pool::global().run(parts, &|k| {
            let mut part = pieces[k]
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            let (q0, q1) = (bounds[k], bounds[k + 1]);
            SCRATCH.with(|s| self.range(&mut s.borrow_mut(), x, v, q0, q1, &mut part, &output));
        });
    }

    /// Boundaries `0 = b_0 ≤ b_1 ≤ … ≤ b_parts = n` of the particle ranges, multiples of
    /// `LANES` (except `n`), such that every part does about the same work: part 0 its own
    /// slots, every other part its own slots plus its halo.
    ///
    /// With `W` slots in all and a halo worth `H` slots, each part does
    /// `X = (W + (parts-1) H) / parts`; part 0 ends where the slot count reaches `X`, part `k`
    /// where it reaches `k X - (k-1) H`.
    fn split(&self, parts: usize) -> [usize; MAX_PARTS + 1] {
        let n = self.particles;
        let total = self.slots();
        let each = (total + (parts - 1) * self.halo_work) / parts;
        let mut bounds = [n; MAX_PARTS + 1];
        bounds[0] = 0;
        for k in 1..parts {
            let target = (k * each).saturating_sub((k - 1) * self.halo_work);
            let chunk = self.work.partition_point(|&w| w < target);
            bounds[k] = (chunk * LANES).clamp(bounds[k - 1], n);
        }
        bounds
    }

    /// Writes `output` for particles `q0..q1` into `part` (`part.outs[k][i]` is particle
    /// `q0 + i`).
    #[allow(clippy::too_many_arguments)]
    fn range(
        &self,
        s: &mut Scratch,
        x: &[DVec3],
        v: &[DVec3],
        q0: usize,
        q1: usize,
        part: &mut Part,
        output: &Output,
    ) {
        let power = !part.power.is_empty();
        match (self.kernel, power) {
            #[cfg(target_arch = "x86_64")]
            (Kernel::Avx512, false) => {
                // SAFETY: `with_kernel` and `Kernel::best` only choose `Avx512` on a CPU that
                // supports AVX-512F.
                unsafe { range_avx512::<false>(self, s, x, v, q0, q1, part, output) }
            }
            #[cfg(target_arch = "x86_64")]
            (Kernel::Avx512, true) => {
                // SAFETY: as above.
                unsafe { range_avx512::<true>(self, s, x, v, q0, q1, part, output) }
            }
            #[cfg(target_arch = "x86_64")]
            (Kernel::Avx2, false) => {
                // SAFETY: `with_kernel` and `Kernel::best` only choose `Avx2` on a CPU that
                // supports AVX2.
                unsafe { range_avx2::<false>(self, s, x, v, q0, q1, part, output) }
            }
            #[cfg(target_arch = "x86_64")]
            (Kernel::Avx2, true) => {
                // SAFETY: as above.
                unsafe { range_avx2::<true>(self, s, x, v, q0, q1, part, output) }
            }
            (_, false) => range_portable::<false>(self, s, x, v, q0, q1, part, output),
            (_, true) => range_portable::<true>(self, s, x, v, q0, q1, part, output),
        }
    }
}

/// One offset group as implicit Euler's lattice system reads it (see
/// `integrators::implicit_lattice`).
pub(crate) struct GroupView<'a> {
    /// The offset `δ` of its springs `(p, p + δ)`.
    pub delta: usize,
    /// Possible first ends `0..starts`.
    pub starts: usize,
    /// Stiffness `k` (N/m).
    pub stiffness: f64,
    /// Damping `k_d` (N·s/m).
    pub damping: f64,
    /// Rest length of the spring starting at `p` (m), padded with zeros to whole chunks.
    pub rest_length: &'a [f64],
    /// Bit `p % 8` of byte `p / 8`: a spring starts at `p`.
    pub present: &'a [u8],
}

impl Stencil {
    /// Number of particles.
    #[must_use]
    pub fn particles(&self) -> usize {
        self.particles
    }

    /// The largest offset `δ`.
    #[must_use]
    pub fn reach(&self) -> usize {
        self.reach
    }

    /// The offset groups, in increasing `δ`.
    pub(crate) fn group_views(&self) -> impl Iterator<Item = GroupView<'_>> {
        self.groups.iter().map(|g| GroupView {
            delta: g.delta,
            starts: g.starts,
            stiffness: g.stiffness,
            damping: g.damping,
            rest_length: &g.rest_length,
            present: &g.present,
        })
    }
}

impl Output<'_> {
    /// How many of `outs` this output writes (always the first ones), and whether `outs[2]`
    /// is optional (written when not empty).
    fn outputs(&self) -> (usize, bool) {
        match self {
            Output::Add | Output::Forces(_) | Output::Accelerations(_) => (1, false),
            Output::Power(_) => (0, false),
            Output::Step {
                update: Update::Euler { .. },
                ..
            } => (2, true),
            Output::Step { .. } => (2, false),
        }
    }

    /// Panics when a slice this output reads is shorter than `n`.
    fn check(&self, n: usize) {
        let dynamics = match self {
            Output::Add => return,
            Output::Forces(d) | Output::Accelerations(d) | Output::Power(d) => d,
            Output::Step {
                dynamics, update, ..
            } => {
                match update {
                    Update::SemiImplicitEuler { .. }
                    | Update::Euler {
                        base: Base::Input, ..
                    } => {}
                    Update::Euler {
                        base: Base::InPlace,
                        ..
                    } => {}
                    Update::Euler {
                        base: Base::Slices(x, v),
                        ..
                    } => assert!(x.len() >= n && v.len() >= n, "base state too short"),
                    Update::Rk4 { a, v, .. } => assert!(
                        a.iter().chain(v).all(|s| s.len() >= n),
                        "RK4 slopes too short"
                    ),
                }
                dynamics
            }
        };
        assert!(
            dynamics.mass.len() >= n && dynamics.inv_mass.len() >= n,
            "masses too short"
        );
    }
}

/// The first `len` values of `rest` (all of them when shorter), which keeps the others.
fn take<'a>(rest: &mut &'a mut [DVec3], len: usize) -> &'a mut [DVec3] {
    let len = len.min(rest.len());
    let (mine, others) = std::mem::take(rest).split_at_mut(len);
    *rest = others;
    mine
}

/// `o[..n]` when `keep`, else `o[..0]`.
fn cut(o: &mut [DVec3], keep: bool, n: usize) -> &mut [DVec3] {
    if keep { &mut o[..n] } else { &mut o[..0] }
}

/// One part's pieces of the outputs: `outs[k][i]` and `power[2 i..]` belong to the part's
/// particle `q0 + i`.
struct Part<'o> {
    outs: [&'o mut [DVec3]; 3],
    power: &'o mut [f64],
}

/// Scratch buffers of one thread (reused, so steps do not allocate).
#[derive(Default)]
struct Scratch {
    /// Positions `x`, `y`, `z` of the particles `base..` (m), zero past the last particle.
    x: [Aligned; 3],
    /// Velocities (m/s), the same layout.
    v: [Aligned; 3],
    /// Every group's force ring (N), see [`Group::ring_offset`].
    ring: Aligned,
}

/// A buffer of f64 whose used part starts at a 64-byte boundary, so that a chunk of `LANES`
/// values at a multiple of `LANES` is one cache line (a load that straddles two lines costs
/// two).
#[derive(Default)]
struct Aligned(Vec<f64>);

impl Aligned {
    /// `len` values starting at a 64-byte boundary; grows the buffer (with zeros) if needed.
    fn get_mut(&mut self, len: usize) -> &mut [f64] {
        if self.0.len() < len + LANES {
            self.0.resize(len + LANES, 0.0);
        }
        // At most LANES - 1 values to the next 64-byte boundary (f64 are 8-byte aligned).
        let offset = self.0.as_ptr().align_offset(64).min(LANES);
        &mut self.0[offset..offset + len]
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// One chunk of spring forces: `[fx, fy, fz]` (N), one spring per lane.
type Forces<V> = [V; 3];

/// The structure-of-arrays copy of the particles `base..base + len` of one range (zero past
/// the last particle): what the kernels read.
struct Window<'a> {
    /// Positions `x`, `y`, `z` (m), each of length `len`.
    x: [&'a [f64]; 3],
    /// Velocities (m/s), each of length `len`.
    v: [&'a [f64]; 3],
}

impl Window<'_> {
    /// Positions and velocities `[x, y, z, v_x, v_y, v_z]` of the `LANES` particles from window
    /// index `i`: the first ends of every group's springs starting there (loaded once per
    /// chunk, not once per group).
    #[inline(always)]
    fn first_ends<V: Lanes>(&self, i: usize) -> [V; 6] {
        // Written out, not with `map`: the closure of `map` would not be inlined, and neither
        // would the AVX-512 loads inside it.
        let [x, y, z] = self.x;
        let [vx, vy, vz] = self.v;
        [
            V::load(lanes(x, i)),
            V::load(lanes(y, i)),
            V::load(lanes(z, i)),
            V::load(lanes(vx, i)),
            V::load(lanes(vy, i)),
            V::load(lanes(vz, i)),
        ]
    }
}

/// The streaming loop of the module docs for particles `q0..q1`, with `springs` computing each
/// chunk of springs (forces, and their dampers' power when `POWER`). Inlined into one copy per
/// instruction set.
///
/// Every call `springs(g, first, w, i, p)` has `p` a multiple of `LANES`, `p < g.starts` and
/// `i = p - base` with `i + g.delta + LANES <= len`: the `LANES` springs starting at `p` and
/// both their ends are inside the window and inside `g`'s padded arrays.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn range_body<V: Lanes, const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
    // The `LANES` springs of a group starting at window index `i` (particle `p`), given the
    // positions and velocities of their first ends: their forces, and their dampers' power.
    springs: impl Fn(&Group, &[V; 6], &Window, usize, usize) -> (Forces<V>, V),
) {
    if q0 >= q1 {
        return;
    }
    let n = st.particles;
    // Structure of arrays for particles base..base + len: the springs starting in the halo
    // (from q0 - reach) up to the chunk that contains q1 - 1, and their second ends.
    let base = q0.saturating_sub(st.reach) / LANES * LANES;
    let len = q1.next_multiple_of(LANES) + st.reach - base;
    let Scratch { x: xs, v: vs, ring } = s;
    let [xs0, xs1, xs2] = xs;
    let [vs0, vs1, vs2] = vs;
    let mut xs = [xs0.get_mut(len), xs1.get_mut(len), xs2.get_mut(len)];
    let mut vs = [vs0.get_mut(len), vs1.get_mut(len), vs2.get_mut(len)];
    let ring = ring.get_mut(st.ring_len);
    let real = n.min(base + len) - base;
    let whole = real / LANES * LANES;
    for i in (0..whole).step_by(LANES) {
        let p = base + i;
        let xc = V::load_vectors(x[p..p + LANES].try_into().expect("a chunk"));
        let vc = V::load_vectors(v[p..p + LANES].try_into().expect("a chunk"));
        for c in 0..3 {
            xc[c].store((&mut xs[c][i..i + LANES]).try_into().expect("a chunk"));
            vc[c].store((&mut vs[c][i..i + LANES]).try_into().expect("a chunk"));
        }
    }
    for (i, (x, v)) in x[base + whole..base + real]
        .iter()
        .zip(&v[base + whole..base + real])
        .enumerate()
    {
        let i = whole + i;
        xs[0][i] = x.x;
        xs[1][i] = x.y;
        xs[2][i] = x.z;
        vs[0][i] = v.x;
        vs[1][i] = v.y;
        vs[2][i] = v.z;
    }
    for c in xs.iter_mut().chain(vs.iter_mut()) {
        c[real..].fill(0.0);
    }
    let w = Window {
        x: [&*xs[0], &*xs[1], &*xs[2]],
        v: [&*vs[0], &*vs[1], &*vs[2]],
    };
    // Halo: the springs that start before q0 and end at q0 or later, into the rings.
    for g in &st.groups {
        let first = q0.saturating_sub(g.delta) / LANES * LANES;
        for p in (first..q0.min(g.starts)).step_by(LANES) {
            let (f, _) = springs(g, &w.first_ends(p - base), &w, p - base, p);
            ring_store(ring, g, p, f);
        }
    }
    const CHUNKS: usize = TILE / LANES;
    for t0 in (q0..q1).step_by(TILE) {
        let t1 = (t0 + TILE).min(q1);
        // Pass 1, chunk by chunk: the springs that start here, offset by offset (the groups
        // a chunk has are a prefix of the list), into the rings, and their sum `plus`.
        let mut plus = [[V::zero(); 3]; CHUNKS];
        let mut spring_power = [V::zero(); CHUNKS];
        for (c, p) in (t0..t1).step_by(LANES).enumerate() {
            let first = w.first_ends::<V>(p - base);
            let mut sum = [V::zero(); 3];
            let mut power = V::zero();
            for g in st.groups.iter().take_while(|g| p < g.starts) {
                let (f, pw) = springs(g, &first, &w, p - base, p);
                ring_store(ring, g, p, f);
                for (total, part) in sum.iter_mut().zip(f) {
                    *total = total.add(part);
                }
                if POWER {
                    power = power.add(pw);
                }
            }
            plus[c] = sum;
            spring_power[c] = power;
        }
        // Pass 2, chunk by chunk: minus the springs that end here (they started δ earlier).
        // The ring of δ holds at least the last δ + TILE + LANES forces.
        for (c, q) in (t0..t1).step_by(LANES).enumerate() {
            let mut minus = [V::zero(); 3];
            for g in &st.groups {
                let mut f: Forces<V> = ring_load(ring, g, q.wrapping_sub(g.delta));
                if q < g.delta {
                    // Near particle 0 the first lanes have no such spring (it would start
                    // before particle 0); their ring slots hold other values.
                    let k = g.delta - q;
                    f = [
                        f[0].clear_below(k),
                        f[1].clear_below(k),
                        f[2].clear_below(k),
                    ];
                }
                for (total, part) in minus.iter_mut().zip(f) {
                    *total = total.add(part);
                }
            }
            let sum = [
                plus[c][0].sub(minus[0]),
                plus[c][1].sub(minus[1]),
                plus[c][2].sub(minus[2]),
            ];
            let i = q - base;
            let chunk = Chunk {
                q,
                at: q - q0,
                count: (q1 - q).min(LANES),
                x: components(w.x, i),
                v: components(w.v, i),
            };
            finish::<V, POWER>(output, &chunk, sum, spring_power[c], part);
        }
        if let Output::Step {
            after: Some(after), ..
        } = output
        {
            let (a, b) = (t0 - q0, t1 - q0);
            let [xo, vo, _] = &mut part.outs;
            after(&mut xo[a..b], &mut vo[a..b]);
        }
    }
}

/// One chunk of particles in pass 2: particle `q` (a multiple of `LANES`) is index `at` of the
/// part's outputs; `count` of its `LANES` particles exist; `x`, `v` are the pass's input.
struct Chunk<V> {
    q: usize,
    at: usize,
    count: usize,
    x: [V; 3],
    v: [V; 3],
}

/// Pass 2's end for one chunk: from the spring forces `sum` (N) to what `output` asks for,
/// and the chunk's dissipated power when `POWER`.
#[inline(always)]
fn finish<V: Lanes, const POWER: bool>(
    output: &Output,
    chunk: &Chunk<V>,
    sum: [V; 3],
    spring_power: V,
    part: &mut Part,
) {
    let Chunk { q, at, count, x, v } = *chunk;
    let d = match *output {
        Output::Add => {
            let out = &mut part.outs[0][at..];
            let old = load_chunk::<V>(out, count);
            let new = [old[0].add(sum[0]), old[1].add(sum[1]), old[2].add(sum[2])];
            store_chunk(new, out, count);
            return;
        }
        Output::Forces(d) | Output::Accelerations(d) | Output::Power(d) => d,
        Output::Step { dynamics, .. } => dynamics,
    };
    // f = (m g - c v) + F_springs, in the order of `forces`; then the contact force.
    let m = load_padded::<V>(d.mass, q, count);
    let mut f = weight_drag_springs(m, d.gravity, d.drag, v, sum);
    let w = load_padded::<V>(d.inv_mass, q, count);
    let free = V::zero().less_than(w);
    let mut contact_power = V::zero();
    if !d.colliders.is_empty() {
        let candidates = free & may_touch(d.colliders, d.contact.epsilon, x);
        if candidates != 0 {
            (f, contact_power) = contact_lanes(&d, x, v, f, candidates);
        }
    }
    if POWER {
        // Drag c |v|² of the free particles, added to the dampers of the springs that start
        // here (see `energy::dissipated_power`).
        let drag = if d.drag == 0.0 {
            V::zero()
        } else {
            let v2 = v[0].mul(v[0]).add(v[1].mul(v[1])).add(v[2].mul(v[2]));
            V::splat(d.drag).mul(v2).select(free)
        };
        let power = &mut part.power[2 * at..2 * at + 2 * LANES];
        let (dampers, contact) = power.split_at_mut(LANES);
        spring_power
            .add(drag)
            .store(dampers.try_into().expect("a chunk"));
        contact_power.store(contact.try_into().expect("a chunk"));
    }
    let a = [f[0].mul(w), f[1].mul(w), f[2].mul(w)];
    match *output {
        Output::Add | Output::Power(_) => {}
        Output::Forces(_) => store_chunk(f, &mut part.outs[0][at..], count),
        Output::Accelerations(_) => store_chunk(a, &mut part.outs[0][at..], count),
        Output::Step { update, .. } => {
            let [xo, vo, ao] = &mut part.outs;
            match update {
                Update::SemiImplicitEuler { dt } => {
                    let dt = V::splat(dt);
                    // v' = v + dt a; then x' = x + dt v'.
                    let v_new = [
                        v[0].add(dt.mul(a[0])),
                        v[1].add(dt.mul(a[1])),
                        v[2].add(dt.mul(a[2])),
                    ];
                    let x_new = [
                        x[0].add(dt.mul(v_new[0])),
                        x[1].add(dt.mul(v_new[1])),
                        x[2].add(dt.mul(v_new[2])),
                    ];
                    store_chunk(x_new, &mut xo[at..], count);
                    store_chunk(v_new, &mut vo[at..], count);
                }
                Update::Euler { h, base } => {
                    let (bx, bv) = match base {
                        Base::Input => (x, v),
                        Base::Slices(bx, bv) => {
                            (load_chunk(&bx[q..], count), load_chunk(&bv[q..], count))
                        }
                        Base::InPlace => {
                            (load_chunk(&xo[at..], count), load_chunk(&vo[at..], count))
                        }
                    };
                    let h = V::splat(h);
                    // x' = x_b + h v;  v' = v_b + h a.
                    let x_new = [
                        bx[0].add(h.mul(v[0])),
                        bx[1].add(h.mul(v[1])),
                        bx[2].add(h.mul(v[2])),
                    ];
                    let v_new = [
                        bv[0].add(h.mul(a[0])),
                        bv[1].add(h.mul(a[1])),
                        bv[2].add(h.mul(a[2])),
                    ];
                    store_chunk(x_new, &mut xo[at..], count);
                    store_chunk(v_new, &mut vo[at..], count);
                    if !ao.is_empty() {
                        store_chunk(a, &mut ao[at..], count);
                    }
                }
                Update::Rk4 {
                    sixth,
                    a: [a1, a2, a3],
                    v: [v2, v3],
                } => {
                    let (xn, vn) = (
                        load_chunk::<V>(&xo[at..], count),
                        load_chunk::<V>(&vo[at..], count),
                    );
                    let (a1, a2, a3) = (
                        load_chunk::<V>(&a1[q..], count),
                        load_chunk::<V>(&a2[q..], count),
                        load_chunk::<V>(&a3[q..], count),
                    );
                    let (v2, v3) = (
                        load_chunk::<V>(&v2[q..], count),
                        load_chunk::<V>(&v3[q..], count),
                    );
                    let (two, sixth) = (V::splat(2.0), V::splat(sixth));
                    // x' = x_n + dt/6 (k1x + 2 k2x + 2 k3x + k4x), k1x = v_n, k4x = v;
                    // v' = v_n + dt/6 (k1v + 2 k2v + 2 k3v + k4v), k4v = a.
                    let weighted =
                        |k1: V, k2: V, k3: V, k4: V| k1.add(two.mul(k2)).add(two.mul(k3)).add(k4);
                    let x_new: [V; 3] = std::array::from_fn(|c| {
                        xn[c].add(sixth.mul(weighted(vn[c], v2[c], v3[c], v[c])))
                    });
                    let v_new: [V; 3] = std::array::from_fn(|c| {
                        vn[c].add(sixth.mul(weighted(a1[c], a2[c], a3[c], a[c])))
                    });
                    store_chunk(x_new, &mut xo[at..], count);
                    store_chunk(v_new, &mut vo[at..], count);
                }
            }
        }
    }
}

/// The chunk's particles (bit `l` for lane `l`) that may touch one of `colliders` (closer than
/// `epsilon`, m, or inside): a test without square roots with a relative margin of 10⁻⁹, so
/// that it never leaves out a particle that [`Collider::contact`] would put within `epsilon`.
#[inline(always)]
fn may_touch<V: Lanes>(colliders: &[Collider], epsilon: f64, x: [V; 3]) -> u8 {
    const MARGIN: f64 = 1e-9;
    let dot = |p: [V; 3], n: DVec3| {
        p[0].mul(V::splat(n.x))
            .add(p[1].mul(V::splat(n.y)))
            .add(p[2].mul(V::splat(n.z)))
    };
    let minus = |p: DVec3| {
        [
            x[0].sub(V::splat(p.x)),
            x[1].sub(V::splat(p.y)),
            x[2].sub(V::splat(p.z)),
        ]
    };
    let squared = |d: [V; 3]| d[0].mul(d[0]).add(d[1].mul(d[1])).add(d[2].mul(d[2]));
    let mut mask = 0u8;
    for collider in colliders {
        mask |= match *collider {
            Collider::Plane { point, normal } => {
                // φ = (x - p)·n < ε, with a margin for rounding.
                let phi = dot(minus(point), normal);
                let scale = point.abs().max_element() + 1.0;
                // NaN: let the exact test decide.
                phi.less_than(V::splat(epsilon + MARGIN * scale)) | phi.nan_lanes()
            }
            Collider::Sphere { center, radius } => {
                // |x - c| - r < ε  ⇔  |x - c|² < (r + ε)².
                let reach = (radius + epsilon).max(0.0);
                let d2 = squared(minus(center));
                d2.less_than(V::splat(reach * reach * (1.0 + MARGIN) + MARGIN)) | d2.nan_lanes()
            }
            Collider::Bowl { center, radius, .. } => {
                // r - |x - c| < ε  ⇔  |x - c|² > (r - ε)² (when r > ε; the rim is left to the
                // exact test).
                let inner = (radius - epsilon).max(0.0);
                let d2 = squared(minus(center));
                !d2.less_than(V::splat(inner * inner * (1.0 - MARGIN)))
            }
            Collider::HolePlane {
                point,
                normal,
                hole_center,
                hole_radius,
            } => {
                // Every contact needs the height h = (x - p)·n < ε; below the floor (h < 0)
                // only the shaft's wall band ρ > R - ε or the solid, so ρ² > (R - ε)².
                let scale = point.abs().max_element() + hole_center.abs().max_element() + 1.0;
                let h = dot(minus(point), normal);
                let low = h.less_than(V::splat(epsilon + MARGIN * scale)) | h.nan_lanes();
                let q = minus(hole_center);
                let along = dot(q, normal);
                let radial = [
                    q[0].sub(along.mul(V::splat(normal.x))),
                    q[1].sub(along.mul(V::splat(normal.y))),
                    q[2].sub(along.mul(V::splat(normal.z))),
                ];
                let rho2 = squared(radial);
                let inner = (hole_radius - epsilon).max(0.0);
                let near_wall = !rho2.less_than(V::splat(inner * inner * (1.0 - MARGIN)));
                let above = !h.less_than(V::splat(-MARGIN * scale));
                low & (above | near_wall)
            }
        };
    }
    mask
}

/// The contact force of `d`'s colliders on the `candidates` lanes of a chunk (positions `x`,
/// velocities `v`, forces before contact `f`), with [`contact_force`], the function of
/// [`super::collide::contact_forces`]: the new forces, and the contact power
/// `-(f_contact)·v` (W) per lane.
#[inline(always)]
fn contact_lanes<V: Lanes>(
    d: &Dynamics,
    x: [V; 3],
    v: [V; 3],
    f: [V; 3],
    candidates: u8,
) -> ([V; 3], V) {
    let unpack = |lanes: [V; 3]| {
        let mut values = [[0.0; LANES]; 3];
        for (c, lane) in lanes.into_iter().enumerate() {
            lane.store(&mut values[c]);
        }
        values
    };
    let (xs, vs, mut fs) = (unpack(x), unpack(v), unpack(f));
    let mut power = [0.0; LANES];
    for l in (0..LANES).filter(|l| candidates & (1 << l) != 0) {
        let at = |a: &[[f64; LANES]; 3]| DVec3::new(a[0][l], a[1][l], a[2][l]);
        let (xl, vl, fl) = (at(&xs), at(&vs), at(&fs));
        if let Some(total) = contact_force(d.colliders, d.contact, xl, vl, fl) {
            // P = -f_contact · v (see `collide::contact_power`).
            power[l] = -(total - fl).dot(vl);
            fs[0][l] = total.x;
            fs[1][l] = total.y;
            fs[2][l] = total.z;
        }
    }
    (
        [V::load(&fs[0]), V::load(&fs[1]), V::load(&fs[2])],
        V::load(&power),
    )
}

/// The `x`, `y`, `z` lanes of window arrays (positions or velocities) from index `i`.
#[inline(always)]
fn components<V: Lanes>(arrays: [&[f64]; 3], i: usize) -> [V; 3] {
    [
        V::load(lanes(arrays[0], i)),
        V::load(lanes(arrays[1], i)),
        V::load(lanes(arrays[2], i)),
    ]
}

/// `(m g - c v) + F_springs` (N), lane by lane, in the order of `forces`.
#[inline(always)]
fn weight_drag_springs<V: Lanes>(m: V, g: DVec3, c: f64, v: [V; 3], spring: [V; 3]) -> [V; 3] {
    let c = V::splat(c);
    [
        m.mul(V::splat(g.x)).sub(c.mul(v[0])).add(spring[0]),
        m.mul(V::splat(g.y)).sub(c.mul(v[1])).add(spring[1]),
        m.mul(V::splat(g.z)).sub(c.mul(v[2])).add(spring[2]),
    ]
}

/// `values[q..q + count]` as lanes, zero past `count`.
#[inline(always)]
fn load_padded<V: Lanes>(values: &[f64], q: usize, count: usize) -> V {
    if count == LANES {
        V::load(lanes(values, q))
    } else {
        // The last chunk of a range that does not end on a multiple of LANES.
        let mut chunk = [0.0; LANES];
        chunk[..count].copy_from_slice(&values[q..q + count]);
        V::load(&chunk)
    }
}

/// The first `count` (at most `LANES`) vectors of `vectors` as lanes `[x, y, z]`, zero past
/// `count`.
#[inline(always)]
fn load_chunk<V: Lanes>(vectors: &[DVec3], count: usize) -> [V; 3] {
    if count == LANES {
        V::load_vectors(vectors[..LANES].try_into().expect("a chunk"))
    } else {
        to_lanes(&vectors[..count])
    }
}

/// Writes lanes `[x, y, z]` into the first `count` (at most `LANES`) vectors of `vectors`.
#[inline(always)]
fn store_chunk<V: Lanes>(lanes: [V; 3], vectors: &mut [DVec3], count: usize) {
    if count == LANES {
        V::store_vectors(lanes, (&mut vectors[..LANES]).try_into().expect("a chunk"));
    } else {
        from_lanes(lanes, &mut vectors[..count]);
    }
}

/// Keeps the forces of the chunk of springs starting at `p` (a multiple of `LANES`) in the
/// ring of `g`: component `c` of particle `p` at `ring_offset + c (R + LANES) + p mod R`.
///
/// # Panics
/// If `ring` is shorter than the stencil's `ring_len` (never: `range_body` sizes it).
#[inline(always)]
fn ring_store<V: Lanes>(ring: &mut [f64], g: &Group, p: usize, f: Forces<V>) {
    let slot = p & (g.ring - 1);
    let stride = g.ring + LANES;
    // One check for all the stores below: the group's three components. Within them,
    // slot + LANES <= R + LANES = stride, and the mirror is the last LANES of a component.
    let ring = &mut ring[g.ring_offset..g.ring_offset + 3 * stride];
    for (c, part) in f.into_iter().enumerate() {
        let at = c * stride + slot;
        debug_assert!(at + LANES <= ring.len());
        // SAFETY: `at + LANES <= 3 * stride = ring.len()` because `c <= 2` and
        // `slot < R`; `Lanes::store` writes exactly LANES values.
        part.store(unsafe { &mut *ring.as_mut_ptr().add(at).cast::<[f64; LANES]>() });
        if slot == 0 {
            // The mirror after the end, so that reads can run across the wrap.
            let mirror = c * stride + g.ring;
            // SAFETY: `mirror + LANES = (c + 1) * stride <= ring.len()`.
            part.store(unsafe { &mut *ring.as_mut_ptr().add(mirror).cast::<[f64; LANES]>() });
        }
    }
}

/// The forces of the `LANES` springs of `g` starting at `p` (any `p`, taken modulo `R`), from
/// the ring.
///
/// # Panics
/// If `ring` is shorter than the stencil's `ring_len` (never: `range_body` sizes it).
#[inline(always)]
fn ring_load<V: Lanes>(ring: &[f64], g: &Group, p: usize) -> Forces<V> {
    let slot = p & (g.ring - 1);
    let stride = g.ring + LANES;
    let ring = &ring[g.ring_offset..g.ring_offset + 3 * stride];
    debug_assert!(2 * stride + slot + LANES <= ring.len());
    // SAFETY: `c * stride + slot + LANES <= 3 * stride = ring.len()` for `c <= 2`, because
    // `slot < R = stride - LANES`; `Lanes::load` reads exactly LANES values.
    let load = |c: usize| unsafe { V::load(&*ring.as_ptr().add(c * stride + slot).cast()) };
    [load(0), load(1), load(2)]
}

/// The springs of one chunk with correctly rounded operations only: `sqrt`, then `1/L`, in the
/// order of [`Spring::force_on_a`](super::springs::Spring::force_on_a) (the result does not
/// depend on the lane type: [`Plain`] and [`Avx2`] give the same bits); and the dampers' power
/// `k_d ((v_b - v_a)·n)²` (W).
#[inline(always)]
fn springs_exact<V: Lanes>(
    g: &Group,
    first: &[V; 6],
    w: &Window,
    i: usize,
    p: usize,
) -> (Forces<V>, V) {
    let j = i + g.delta;
    // d = x_b - x_a, L = |d|
    let dx = V::load(lanes(w.x[0], j)).sub(first[0]);
    let dy = V::load(lanes(w.x[1], j)).sub(first[1]);
    let dz = V::load(lanes(w.x[2], j)).sub(first[2]);
    let length = dx.mul(dx).add(dy.mul(dy)).add(dz.mul(dz)).sqrt();
    // n = d / L; a zero-length spring has no direction and no force.
    let inv = V::splat(1.0).div(length).where_positive(length);
    let (nx, ny, nz) = (dx.mul(inv), dy.mul(inv), dz.mul(inv));
    // Hooke k (L - L0) plus the damper k_d (v_b - v_a)·n, zero where there is no spring.
    let dvx = V::load(lanes(w.v[0], j)).sub(first[3]);
    let dvy = V::load(lanes(w.v[1], j)).sub(first[4]);
    let dvz = V::load(lanes(w.v[2], j)).sub(first[5]);
    let rel = dvx.mul(nx).add(dvy.mul(ny)).add(dvz.mul(nz));
    let rest = V::load(lanes(&g.rest_length, p));
    let hooke = V::splat(g.stiffness).mul(length.sub(rest));
    let damper = V::splat(g.damping).mul(rel);
    let present = g.present[p / LANES];
    let tension = hooke.add(damper).select(present);
    let power = damper.mul(rel).select(present);
    ([tension.mul(nx), tension.mul(ny), tension.mul(nz)], power)
}

/// The streaming loop in plain Rust with the exact springs.
#[allow(clippy::too_many_arguments)]
fn range_portable<const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
) {
    range_body::<Plain, POWER>(
        st,
        s,
        x,
        v,
        q0,
        q1,
        part,
        output,
        // A closure, not the function item: the item would be called through a shim that is
        // not inlined.
        #[inline(always)]
        #[allow(clippy::redundant_closure)]
        |g, first, w, i, p| springs_exact::<Plain>(g, first, w, i, p),
    );
}

/// The streaming loop on AVX2 registers with the exact springs (the same operations as the
/// portable loop, no fused multiply-add: bit-identical results).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
fn range_avx2<const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
) {
    range_body::<Avx2, POWER>(
        st,
        s,
        x,
        v,
        q0,
        q1,
        part,
        output,
        // A closure, not the function item: only a closure is inlined (and with it the AVX2
        // instructions, which cannot be inlined into a function without AVX2).
        #[inline(always)]
        #[allow(clippy::redundant_closure)]
        |g, first, w, i, p| springs_exact::<Avx2>(g, first, w, i, p),
    );
}

/// The streaming loop with the AVX-512 springs.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
fn range_avx512<const POWER: bool>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    part: &mut Part,
    output: &Output,
) {
    range_body::<Avx512, POWER>(
        st,
        s,
        x,
        v,
        q0,
        q1,
        part,
        output,
        #[inline(always)]
        |g, first, w, i, p| {
            // SAFETY: this function only runs on a CPU with AVX-512F (see `Stencil::range`), and
            // `range_body` calls with chunks inside the window and the group's arrays.
            unsafe { springs_avx512(g, first, w, i, p) }
        },
    );
}

/// The springs of one chunk with AVX-512F: `1/L` from the reciprocal square root estimate and
/// two Newton steps (see the module docs), fused multiply-adds.
///
/// Not itself a `target_feature` function, so that the compiler inlines it (a function with
/// more target features than its caller is never inlined); it is only called from
/// `range_avx512`, which has them.
///
/// # Safety
/// The CPU must support AVX-512F, and the window and `g`'s arrays must hold the chunk (see
/// `range_body`): `i + g.delta + LANES` at most the window's length, `p + LANES` at most
/// the length of `g.rest_length` and `g.present`. These are not checked in release builds.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn springs_avx512(
    g: &Group,
    first: &[Avx512; 6],
    w: &Window,
    i: usize,
    p: usize,
) -> (Forces<Avx512>, Avx512) {
    use std::arch::x86_64::{
        _CMP_GT_OQ, _mm512_cmp_pd_mask, _mm512_fmadd_pd, _mm512_fmsub_pd, _mm512_fnmadd_pd,
        _mm512_loadu_pd, _mm512_maskz_mul_pd, _mm512_maskz_rsqrt14_pd, _mm512_mul_pd,
        _mm512_set1_pd, _mm512_setzero_pd, _mm512_sub_pd,
    };
    let j = i + g.delta;
    debug_assert!(j + LANES <= w.x[0].len() && p + LANES <= g.rest_length.len());
    // SAFETY (the intrinsics): the caller guarantees AVX-512F, and that LANES = 8 values exist
    // from every index loaded below (window: `i` and `j = i + δ`; group arrays: `p`), which is
    // what one unaligned 512-bit load reads.
    unsafe {
        let load = |values: &[f64], at: usize| _mm512_loadu_pd(values.as_ptr().add(at));
        // d = x_b - x_a
        let dx = _mm512_sub_pd(load(w.x[0], j), first[0].0);
        let dy = _mm512_sub_pd(load(w.x[1], j), first[1].0);
        let dz = _mm512_sub_pd(load(w.x[2], j), first[2].0);
        // a = d·d = L²
        let a = _mm512_fmadd_pd(dz, dz, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dx, dx)));
        // k_d (v_b - v_a)·d, computed while the square root is refined: (v_b - v_a)·n is
        // this times 1/L.
        let dvx = _mm512_sub_pd(load(w.v[0], j), first[3].0);
        let dvy = _mm512_sub_pd(load(w.v[1], j), first[4].0);
        let dvz = _mm512_sub_pd(load(w.v[2], j), first[5].0);
        let dv_d = _mm512_fmadd_pd(dvz, dz, _mm512_fmadd_pd(dvy, dy, _mm512_mul_pd(dvx, dx)));
        let damper = _mm512_mul_pd(_mm512_set1_pd(g.damping), dv_d);
        // y₀ ≈ 1/√a to 2⁻¹⁴, and 0 where a = 0 (a zero-length spring has no direction, no force).
        let nonzero = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(a, _mm512_setzero_pd());
        let mut y = _mm512_maskz_rsqrt14_pd(nonzero, a);
        let (one, half) = (_mm512_set1_pd(1.0), _mm512_set1_pd(0.5));
        for _ in 0..2 {
            // e = 1 - a y², y ← y + ½ y e (Newton–Raphson for 1/√a).
            let e = _mm512_fnmadd_pd(_mm512_mul_pd(a, y), y, one);
            y = _mm512_fmadd_pd(_mm512_mul_pd(half, y), e, y);
        }
        // L = a / √a = a y; tension = k (L - L0) + k_d (v_b - v_a)·d / L
        let stretch = _mm512_fmsub_pd(a, y, load(&g.rest_length, p));
        let damper_n = _mm512_mul_pd(damper, y);
        let tension = _mm512_fmadd_pd(_mm512_set1_pd(g.stiffness), stretch, damper_n);
        // f = tension n = (tension / L) d, zero where there is no spring.
        let present = g.present[p / LANES];
        let scale = _mm512_maskz_mul_pd(present, tension, y);
        // The damper's power k_d ((v_b - v_a)·n)² = (k_d (v_b - v_a)·n) ((v_b - v_a)·d / L);
        // unused (and not computed) unless the caller asks for the power.
        let power = _mm512_maskz_mul_pd(present, damper_n, _mm512_mul_pd(dv_d, y));
        (
            [
                Avx512(_mm512_mul_pd(dx, scale)),
                Avx512(_mm512_mul_pd(dy, scale)),
                Avx512(_mm512_mul_pd(dz, scale)),
            ],
            Avx512(power),
        )
    }
}
