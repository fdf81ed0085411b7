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
//! register of f64) and tiles of 32 (`TILE`). For each tile:
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
//! eight after the end so that eight values can always be read at once). Pass 2 goes offset by
//! offset, the tile's chunks side by side (each chunk still adds the offsets in their order).
//! A chunk `q - δ` straddles two whole chunks of the ring when `δ` is not a multiple of eight;
//! with AVX-512 pass 2 loads those whole chunks, aligned (each shared by two neighbouring
//! chunks of the tile), and joins each pair with one two-register permute (a funnel), so no
//! load crosses a cache line and the ring needs no copy after its end (measured, one thread,
//! interleaved: 4–6 % faster on the jelly cube and the 128×128 cloth than unaligned loads and
//! the copy). The whole working set stays in the core's caches however large the lattice is. Positions and velocities are
//! copied into one contiguous `f64` array per component (structure of arrays; with AVX-512 eight
//! particles at a time by two-register permutes) as the loop goes, each tile's second ends just
//! before its pass 1, so that they are still in the first-level cache when the springs read them
//! (measured on the 128×128 cloth, one thread: 3–4 % faster than copying the whole range first;
//! the jelly cube, whose copy fits that cache, as fast).
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
//! caller adds them in chunk order, so the total does not depend on the split between threads
//! (a pass on one part adds them itself as it goes, in that order: [`Stencil::write_with_power`]).
//!
//! **One reciprocal square root.** The length and the direction need `L = √(d·d)` and `1/L`.
//! A 512-bit square root or division keeps the divider busy for about 13–16 cycles (measured on
//! the benchmark machine; Intel Intrinsics Guide, `VSQRTPD`, `VDIVPD`), as long as the twenty
//! other operations of a spring together. With AVX-512F the processor also offers an estimate
//! `y₀ ≈ 1/√a` with relative error below 2⁻¹⁴ (`VRSQRT14PD`, about 1.6 cycles per vector).
//! With `e = 1 - a y₀²` the exact value is `1/√a = y₀ (1 - e)^(-1/2)`, whose series is cut after
//! the cubic term:
//!
//! ```text
//! e      = 1 - a y₀²                             relative residual, |e| < 2⁻¹³
//! 1/L    = y₀ + y₀ e (½ + e (⅜ + e 5⁄16))        truncation error (35/128) e⁴ < 2⁻⁵³
//! L      = a · (1/L)                             (a = d·d)
//! ```
//! Six operations (multiplications and fused multiply-adds, Horner form), where the two
//! Newton–Raphson steps `y ← y + ½ y (1 - a y²)` that reach the same accuracy take eight; the
//! result is within a rounding or two of an f64 (relative error ≈ 1e-16, against 2.2e-16 for one
//! rounding), cheaper than one division, but not always the correctly rounded `1/√a`.
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
//! Square Root", Purdue University technical report, 2003 (refining an estimate of `1/√a`);
//! `docs/workloads.md` (the peer benchmark's lattices and their spring order).

pub mod ceiling;
mod contacts;
mod kernels;
mod passes;
mod small;
mod team;

use std::cell::RefCell;
use std::sync::Mutex;

use glam::DVec3;

#[cfg(target_arch = "x86_64")]
use super::lanes::{Avx2, Avx512};
use super::lanes::{LANES, Lanes, Plain, lanes};
use super::pool::Pool;
use crate::physics::collide::{Broad, Collider, ContactParams};
use crate::physics::springs::Spring;
use kernels::range_portable;
#[cfg(target_arch = "x86_64")]
use kernels::{range_avx2, range_avx512};
use passes::{Part, PowerMode, SCRATCH, Scratch, outputs_for, take};
pub use team::{Crew, PartFn, Pass, TeamPower, TeamUpdate};

/// At most this many offset groups: more would make the passes slower than the spring list.
const MAX_GROUPS: usize = 32;

/// The stencil form pays off when at least this share of the `(group, p)` slots hold a spring.
const MIN_DENSITY: f64 = 0.5;

/// Below this many springs the spring list is as fast: the stencil's passes have fixed costs.
const MIN_SPRINGS: usize = 32;

/// Particles per tile of the streaming loop (a multiple of `LANES`): the springs of a tile are
/// computed before their forces are gathered (see `range_body`). Measured with
/// `examples/perf_ab.rs`, one thread, builds alternated: 32 steps the 128×128 cloth about 3 %
/// faster than 64 and the jelly as fast (16 no better, 128 clearly slower); every ring
/// (`δ + TILE + LANES` forces, rounded up to a power of two) is smaller too.
const TILE: usize = 32;

/// The dissipated power of a pass is summed in groups of this many chunks (1 024 particles),
/// lane by lane: each group's chunks in order from zero, then the groups' sums in order from
/// zero ([`Stencil::sum_power`]). A part of a team sums every group that starts inside it in
/// registers and stores that one sum; only its chunks before its first group (the end of a
/// group the previous part began) wait in the ring for the previous part's sum. One group
/// (up to 1 024 particles) is the plain sum chunk after chunk.
pub(super) const POWER_GROUP: usize = 128;

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
    /// AVX-512F (x86-64): reciprocal square root estimate, one fourth-order refinement and fused
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

    /// The kernel every new model computes with: the one [`KERNEL_ENV`] names, when it names one
    /// this CPU can run (see [`Kernel::from_env`]), else the fastest this CPU can run.
    #[must_use]
    pub fn best() -> Kernel {
        static CHOSEN: std::sync::OnceLock<Kernel> = std::sync::OnceLock::new();
        *CHOSEN.get_or_init(|| {
            Kernel::from_environment()
                .ok()
                .flatten()
                .unwrap_or_else(Kernel::fastest)
        })
    }

    /// [`Kernel::from_env`] of this process's [`KERNEL_ENV`] (the command line checks it once
    /// at start, so that a bad value is an error, not a silent fallback).
    ///
    /// # Errors
    /// As [`Kernel::from_env`].
    pub fn from_environment() -> Result<Option<Kernel>, String> {
        Kernel::from_env(std::env::var(KERNEL_ENV).ok().as_deref())
    }

    /// The fastest kernel this CPU can run.
    #[must_use]
    pub fn fastest() -> Kernel {
        Kernel::ALL
            .into_iter()
            .rev()
            .find(|k| k.is_available())
            .unwrap_or(Kernel::Portable)
    }

    /// The kernel a value of [`KERNEL_ENV`] names: `None` when unset or empty; `exact` is the
    /// fastest of the kernels with correctly rounded `sqrt` and `1/L` (AVX2, else portable), whose
    /// results are the same bits on every x86-64 machine. An unknown name, or a kernel this CPU
    /// cannot run, is an error naming the choices.
    ///
    /// # Errors
    /// The message names the value, what is wrong and the accepted values.
    pub fn from_env(value: Option<&str>) -> Result<Option<Kernel>, String> {
        let Some(value) = value.map(str::trim).filter(|v| !v.is_empty()) else {
            return Ok(None);
        };
        let kernel = match value.to_ascii_lowercase().as_str() {
            "portable" => Kernel::Portable,
            "avx2" => Kernel::Avx2,
            "avx512" => Kernel::Avx512,
            "exact" if Kernel::Avx2.is_available() => Kernel::Avx2,
            "exact" => Kernel::Portable,
            _ => {
                return Err(format!(
                    "{KERNEL_ENV}={value}: not a spring kernel; expected exact, portable, avx2 or avx512"
                ));
            }
        };
        if kernel.is_available() {
            Ok(Some(kernel))
        } else {
            Err(format!(
                "{KERNEL_ENV}={value}: this CPU cannot run the {kernel:?} kernel; expected exact or portable{}",
                if Kernel::Avx2.is_available() {
                    ", avx2"
                } else {
                    ""
                }
            ))
        }
    }
}

/// The environment variable that chooses the spring kernel ([`Kernel::from_env`]), for example
/// `exact` to get the same bits on a machine with AVX-512 as on one without.
pub const KERNEL_ENV: &str = "SPRINGLAB_KERNEL";

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
    /// values each (the last `LANES` mirror the first, so a chunk can be read across the wrap;
    /// unused by the AVX-512 kernel, which reads whole chunks and funnels them).
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
        // A halo slot costs pass 1 and its share of the window's copy, about five sixths of an
        // own slot (pass 1, pass 2 and the output): measured as each part's CPU time per pass in
        // a team of two on the jelly cube, where two thirds left the second part 0.5–0.9 µs of
        // 21 µs longer than the first, and one whole slot 0.9 µs shorter.
        let halo_slots: usize = groups
            .iter()
            .map(|g| (g.delta.div_ceil(LANES) + 1) * LANES)
            .sum();
        let halo_work = halo_slots * 5 / 6;
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
    /// contact)` (W), added in a fixed order, group by group (so the same for any split).
    /// `contact`: the pass had colliders ([`Dynamics::colliders`]). Without, the pass writes
    /// no contact values (they would all be `+0`, whose sum is `+0`): the contact power is
    /// `+0` and only the dampers' half of the buffer is read.
    ///
    /// ```text
    /// G_g = ((0 + c_{g,0}) + c_{g,1}) + …      the chunks of group g, in order
    /// P   = ((0 + G_0) + G_1) + …              the groups, in order
    /// total = P_0 + P_1 + … + P_7              P's lanes, in order
    /// ```
    /// where `c_{g,i}` is the `i`-th chunk of group `g` (eight lanes, W; [`POWER_GROUP`]
    /// chunks a group), each sum lane by lane, the dampers' and the contact column apart.
    #[must_use]
    pub fn sum_power(power: &[f64], contact: bool) -> (f64, f64) {
        let mut total = [[0.0; LANES]; 2];
        for group in power.chunks(2 * LANES * POWER_GROUP) {
            let mut sums = [[0.0; LANES]; 2];
            Self::add_power(&mut sums, group, contact);
            Self::close_group(&mut total, &sums);
        }
        Self::power_total(&total, contact)
    }

    /// `total += group`, lane by lane (both columns): a group's sums added to the groups'.
    pub(super) fn close_group(total: &mut [[f64; LANES]; 2], group: &[[f64; LANES]; 2]) {
        for (t, g) in total.iter_mut().zip(group) {
            for (t, g) in t.iter_mut().zip(g) {
                *t += g;
            }
        }
    }

    /// The values after the chunks' in a slot of a team's ring: each group's sums.
    pub(super) fn groups_len(&self) -> usize {
        2 * LANES * self.particles.div_ceil(LANES).div_ceil(POWER_GROUP)
    }

    /// The last sum of [`Stencil::sum_power`]: its lane sums added in lane order.
    pub(super) fn lanes_total(sums: &[f64; LANES]) -> f64 {
        sums.iter().sum()
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
        // The outputs this variant writes, cut to n particles; the others to nothing.
        let outs = outputs_for(&output, outs, n);
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
            let mut part = Part {
                outs,
                power,
                groups: &mut [],
            };
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
            Mutex::new(Part {
                outs,
                power,
                groups: &mut [],
            })
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
        let power = !part.power.is_empty() || s.power_mode != PowerMode::Buffer;
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
