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
//! pass 1, each offset δ, each chunk p of the tile:  f_δ[p..p+8]  (8 springs at once) → ring_δ
//! pass 2, each chunk q of the tile:                 plus  = Σ_δ ring_δ[q..q+8]
//!                                                   minus = Σ_δ ring_δ[q-δ..q-δ+8]
//!                                                   F[q..q+8] += plus - minus
//! ```
//! Pass 1 reads `x[p..p+8]` and `x[p+δ..p+δ+8]` as contiguous loads, and its iterations are
//! independent, so the processor overlaps them. A spring's force is needed twice, for both its
//! ends, `δ` particles apart, so it is kept in a ring buffer per offset holding the last
//! `R ≥ δ + TILE + 8` forces (`R` a power of two, index `p mod R`, plus a copy of the first eight
//! after the end so that eight values can always be read at once). The whole working set stays
//! in the core's caches however large the lattice is. Positions and velocities are first copied
//! into one contiguous `f64` array per component (structure of arrays).
//!
//! **To the end of the step in the same pass.** Pass 2 finishes each chunk with what the caller
//! asked for ([`Output`]): the spring force, the total force with weight and drag, the
//! acceleration `f/m`, or a whole semi-implicit Euler step `v' = v + dt a`, `x' = x + dt v'`. So
//! [`super::forces::forces`], [`super::forces::accelerations`] and the semi-implicit Euler step
//! need no further pass over the particles, and that work is split between the threads too.
//! Each output does the same operations in the same order as the plain loop it replaces, so
//! the numbers are the same.
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
//! `docs/workloads.md` (the peer benchmark's lattices and their spring order).

use std::cell::RefCell;
use std::sync::Mutex;

use glam::DVec3;

use super::pool::Pool;
use super::springs::Spring;

/// Springs computed together: one AVX-512 register of f64 (two AVX2 registers).
const LANES: usize = 8;

/// At most this many offset groups: more would make the passes slower than the spring list.
const MAX_GROUPS: usize = 32;

/// The stencil form pays off when at least this share of the `(group, p)` slots hold a spring.
const MIN_DENSITY: f64 = 0.5;

/// Below this many springs the spring list is as fast: the stencil's passes have fixed costs.
const MIN_SPRINGS: usize = 32;

/// Particles per tile of the streaming loop (a multiple of `LANES`): the springs of a tile are
/// computed before their forces are gathered (see `range_body`).
const TILE: usize = 64;

/// At most this many parts (threads) per force evaluation.
const MAX_PARTS: usize = 8;

/// Split the work between threads only with at least this many spring slots per thread
/// (about 3 µs of work): measured with `examples/stencil_micro.rs`, two parts already win on a
/// 24×24 cloth (3 500 slots: 7.7 → 4.7 µs per call) and on a 16×16 cloth (1 500 slots:
/// 3.4 → 2.4 µs) when the second core is free, but lose on the 64-node rope (0.3 → 0.6 µs);
/// the margin keeps small lattices on one thread when the machine is busy.
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

/// What the stencil writes for each particle `q`, given its spring force `F_springs[q]` (N).
#[derive(Clone, Copy, Debug)]
pub enum Output<'a> {
    /// Adds the spring force: `f[q] += F_springs[q]`.
    Add,
    /// The total force with weight and drag, `f[q] = (m_q g - c v_q) + F_springs[q]` (N), or,
    /// when `inv_mass` is given, the acceleration `a[q] = f[q] · (1/m_q)` (m/s²). The same
    /// operations in the same order as [`super::forces::forces`] and
    /// [`super::forces::accelerations`] without the stencil (so the same numbers), done by each
    /// thread for its own particles, eight at a time, instead of in separate passes.
    Total {
        /// Masses `m` (kg).
        mass: &'a [f64],
        /// Gravitational acceleration `g` (m/s²).
        gravity: DVec3,
        /// Drag coefficient `c` (N·s/m).
        drag: f64,
        /// Inverse masses `1/m` (1/kg, 0 for pinned particles), for accelerations.
        inv_mass: Option<&'a [f64]>,
    },
    /// One semi-implicit Euler step: with `a[q]` the acceleration of [`Output::Total`],
    /// `v'[q] = v[q] + dt a[q]` goes to the first output and `x'[q] = x[q] + dt v'[q]` to the
    /// second (the operations of `semi_implicit_euler::step`, so the same numbers). The
    /// outputs must not be `x` and `v` themselves: other threads still read those.
    SemiImplicitEuler {
        /// Masses `m` (kg).
        mass: &'a [f64],
        /// Gravitational acceleration `g` (m/s²).
        gravity: DVec3,
        /// Drag coefficient `c` (N·s/m).
        drag: f64,
        /// Inverse masses `1/m` (1/kg, 0 for pinned particles).
        inv_mass: &'a [f64],
        /// Time step (s).
        dt: f64,
    },
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
    /// 1 where a spring starts at `p`, 0 where none does (and in the padding).
    present: Vec<f64>,
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
                        present: vec![0.0; padded],
                        ring: (delta + TILE + LANES).next_power_of_two(),
                        ring_offset: 0,
                    });
                    groups.len() - 1
                }
            };
            let group = &mut groups[g];
            if group.present[a] != 0.0 {
                return None;
            }
            group.present[a] = 1.0;
            group.rest_length[a] = s.rest_length;
        }
        let slots: usize = groups.iter().map(|g| g.starts).sum();
        let count: usize = groups
            .iter()
            .map(|g| g.present.iter().sum::<f64>() as usize)
            .sum();
        if (count as f64) < MIN_DENSITY * slots as f64 {
            return None;
        }
        // Visit offsets in increasing order: neighbouring streams, better locality.
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

    /// The number of parts (threads) worth using with a pool of `threads` threads: 1 for small
    /// lattices (see `MIN_SLOTS_PER_PART`).
    #[must_use]
    pub fn parallel_parts(&self, threads: usize) -> usize {
        let slots = self.work.last().copied().unwrap_or(0);
        (slots / MIN_SLOTS_PER_PART).clamp(1, threads.clamp(1, MAX_PARTS))
    }

    /// Adds the spring forces (N) at positions `x` and velocities `v` to `f`, on as many
    /// threads of [`Pool::global`] as pay off.
    ///
    /// # Panics
    /// If the slices are shorter than the stencil's particle count.
    pub fn add_forces(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        self.write(x, v, f, &mut [], Output::Add);
    }

    /// [`Stencil::add_forces`] with the particles split into `parts` ranges (at most 8), run
    /// in parallel where the global pool has free threads. The result is bit-identical for
    /// every `parts` (see the module docs).
    ///
    /// # Panics
    /// If the slices are shorter than the stencil's particle count.
    pub fn add_forces_in_parts(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], parts: usize) {
        self.write_in_parts(x, v, f, &mut [], Output::Add, parts);
    }

    /// Writes `output` (see [`Output`]) for every particle into `out` (and, for
    /// [`Output::SemiImplicitEuler`], the new positions into `out2`; otherwise `out2` is not
    /// used and may be empty), on as many threads of [`Pool::global`] as pay off.
    ///
    /// # Panics
    /// If the slices (or the masses of `output`) are shorter than the stencil's particle count.
    pub fn write(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        out: &mut [DVec3],
        out2: &mut [DVec3],
        output: Output,
    ) {
        let parts = self.parallel_parts(Pool::global().threads());
        self.write_in_parts(x, v, out, out2, output, parts);
    }

    /// [`Stencil::write`] with the particles split into `parts` ranges (at most 8); the result
    /// is bit-identical for every `parts`.
    ///
    /// # Panics
    /// If the slices (or the masses of `output`) are shorter than the stencil's particle count.
    pub fn write_in_parts(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        out: &mut [DVec3],
        out2: &mut [DVec3],
        output: Output,
        parts: usize,
    ) {
        let n = self.particles;
        let (x, v, out) = (&x[..n], &v[..n], &mut out[..n]);
        let out2 = match output {
            Output::Total { mass, inv_mass, .. } => {
                assert!(mass.len() >= n && inv_mass.is_none_or(|w| w.len() >= n));
                &mut out2[..0]
            }
            Output::SemiImplicitEuler { mass, inv_mass, .. } => {
                assert!(mass.len() >= n && inv_mass.len() >= n);
                &mut out2[..n]
            }
            Output::Add => &mut out2[..0],
        };
        let parts = parts.clamp(1, MAX_PARTS);
        if parts == 1 {
            SCRATCH.with(|s| self.range(&mut s.borrow_mut(), x, v, 0, n, out, out2, &output));
            return;
        }
        let bounds = self.split(parts);
        // Each part gets its own slices of the outputs (disjoint: no thread writes another's
        // values).
        let (mut rest, mut rest2) = (out, out2);
        let outputs: [Mutex<(&mut [DVec3], &mut [DVec3])>; MAX_PARTS] = std::array::from_fn(|k| {
            let len = if k < parts {
                bounds[k + 1] - bounds[k]
            } else {
                0
            };
            let (mine, others) = std::mem::take(&mut rest).split_at_mut(len);
            rest = others;
            let len2 = len.min(rest2.len());
            let (mine2, others2) = std::mem::take(&mut rest2).split_at_mut(len2);
            rest2 = others2;
            Mutex::new((mine, mine2))
        });
        Pool::global().run(parts, &|k| {
            let mut mine = outputs[k]
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            let (out, out2) = &mut *mine;
            let (q0, q1) = (bounds[k], bounds[k + 1]);
            SCRATCH.with(|s| self.range(&mut s.borrow_mut(), x, v, q0, q1, out, out2, &output));
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
        let total = self.work.last().copied().unwrap_or(0);
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

    /// Writes `output` for particles `q0..q1` into `out` and `out2` (`out[i]` is particle
    /// `q0 + i`; `out2` is empty unless the output needs it).
    #[allow(clippy::too_many_arguments)]
    fn range(
        &self,
        s: &mut Scratch,
        x: &[DVec3],
        v: &[DVec3],
        q0: usize,
        q1: usize,
        out: &mut [DVec3],
        out2: &mut [DVec3],
        output: &Output,
    ) {
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => {
                // SAFETY: `with_kernel` and `Kernel::best` only choose `Avx512` on a CPU that
                // supports AVX-512F.
                unsafe { range_avx512(self, s, x, v, q0, q1, out, out2, output) }
            }
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => {
                // SAFETY: `with_kernel` and `Kernel::best` only choose `Avx2` on a CPU that
                // supports AVX2.
                unsafe { range_avx2(self, s, x, v, q0, q1, out, out2, output) }
            }
            _ => range_body(
                self,
                s,
                x,
                v,
                q0,
                q1,
                out,
                out2,
                output,
                // A closure, not the function item: the item would be called through a shim
                // that is not inlined.
                #[inline(always)]
                #[allow(clippy::redundant_closure)]
                |g, first, w, i, p| springs_exact::<Plain>(g, first, w, i, p),
            ),
        }
    }
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

/// `LANES` values of `values` from index `i`.
#[inline(always)]
fn lanes(values: &[f64], i: usize) -> &[f64; LANES] {
    values[i..i + LANES]
        .try_into()
        .expect("a slice of LANES values")
}

/// `LANES` f64 computed together, and the few operations the streaming loop needs on them.
/// Two implementations: [`Plain`] (an array; the compiler vectorises what it can) and, on
/// x86-64, [`Avx512`] (one AVX-512 register).
trait Lanes: Copy {
    /// All lanes zero.
    fn zero() -> Self;
    /// `LANES` values.
    fn load(values: &[f64; LANES]) -> Self;
    /// Writes the lanes to `out`.
    fn store(self, out: &mut [f64; LANES]);
    /// Lane-wise `self + other`.
    fn add(self, other: Self) -> Self;
    /// Lane-wise `self - other`.
    fn sub(self, other: Self) -> Self;
    /// Lane-wise `self · other`.
    fn mul(self, other: Self) -> Self;
    /// `value` in every lane.
    fn splat(value: f64) -> Self;
    /// The same lanes with lanes `0..k` set to zero.
    fn clear_below(self, k: usize) -> Self;
    /// Lane-wise square root (correctly rounded, IEEE 754).
    fn sqrt(self) -> Self;
    /// Lane-wise `self / other` (correctly rounded).
    fn div(self, other: Self) -> Self;
    /// `self` in the lanes where `condition > 0`, zero elsewhere (also where it is NaN).
    fn where_positive(self, condition: Self) -> Self;
}

/// [`Lanes`] as a plain array.
#[derive(Clone, Copy)]
struct Plain([f64; LANES]);

impl Lanes for Plain {
    #[inline(always)]
    fn zero() -> Plain {
        Plain([0.0; LANES])
    }
    #[inline(always)]
    fn load(values: &[f64; LANES]) -> Plain {
        Plain(*values)
    }
    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        *out = self.0;
    }
    #[inline(always)]
    fn add(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] + other.0[l]))
    }
    #[inline(always)]
    fn sub(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] - other.0[l]))
    }
    #[inline(always)]
    fn mul(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] * other.0[l]))
    }
    #[inline(always)]
    fn splat(value: f64) -> Plain {
        Plain([value; LANES])
    }
    #[inline(always)]
    fn clear_below(self, k: usize) -> Plain {
        Plain(std::array::from_fn(|l| if l < k { 0.0 } else { self.0[l] }))
    }
    #[inline(always)]
    fn sqrt(self) -> Plain {
        Plain(self.0.map(f64::sqrt))
    }
    #[inline(always)]
    fn div(self, other: Plain) -> Plain {
        Plain(std::array::from_fn(|l| self.0[l] / other.0[l]))
    }
    #[inline(always)]
    fn where_positive(self, condition: Plain) -> Plain {
        Plain(std::array::from_fn(|l| {
            if condition.0[l] > 0.0 { self.0[l] } else { 0.0 }
        }))
    }
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
/// chunk of springs. Inlined into one copy per instruction set.
///
/// Every call `springs(g, w, i, p)` has `p` a multiple of `LANES`, `p < g.starts` and
/// `i = p - base` with `i + g.delta + LANES <= len`: the `LANES` springs starting at `p` and
/// both their ends are inside the window and inside `g`'s padded arrays.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn range_body<V: Lanes>(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    out: &mut [DVec3],
    out2: &mut [DVec3],
    output: &Output,
    // The `LANES` springs of a group starting at window index `i` (particle `p`), given the
    // positions and velocities of their first ends.
    springs: impl Fn(&Group, &[V; 6], &Window, usize, usize) -> Forces<V>,
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
    for (i, (x, v)) in x[base..base + real]
        .iter()
        .zip(&v[base..base + real])
        .enumerate()
    {
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
            let f = springs(g, &w.first_ends(p - base), &w, p - base, p);
            ring_store(ring, g, p, f);
        }
    }
    for t0 in (q0..q1).step_by(TILE) {
        let t1 = (t0 + TILE).min(q1);
        // Pass 1, group by group: the springs that start in the tile, into the rings. The
        // iterations are independent, so the processor overlaps them.
        for g in &st.groups {
            for p in (t0..t1.min(g.starts)).step_by(LANES) {
                let f = springs(g, &w.first_ends(p - base), &w, p - base, p);
                ring_store(ring, g, p, f);
            }
        }
        // Pass 2, chunk by chunk: + the springs that start here, - those that end here (they
        // started δ earlier). The ring of δ holds at least the last δ + TILE + LANES forces.
        for q in (t0..t1).step_by(LANES) {
            // Two sums, so that the processor can add both at once: the springs that start
            // here and those that end here (they started δ earlier).
            let (mut plus, mut minus) = ([V::zero(); 3], [V::zero(); 3]);
            for g in &st.groups {
                if q < g.starts {
                    let f: Forces<V> = ring_load(ring, g, q);
                    for (total, part) in plus.iter_mut().zip(f) {
                        *total = total.add(part);
                    }
                }
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
                plus[0].sub(minus[0]),
                plus[1].sub(minus[1]),
                plus[2].sub(minus[2]),
            ];
            let count = (q1 - q).min(LANES);
            let i = q - base;
            let out = &mut out[q - q0..q - q0 + count];
            match *output {
                Output::Add => {
                    let old = to_lanes::<V>(out);
                    from_lanes(
                        [old[0].add(sum[0]), old[1].add(sum[1]), old[2].add(sum[2])],
                        out,
                    );
                }
                Output::Total {
                    mass,
                    gravity,
                    drag,
                    inv_mass,
                } => {
                    let m = load_padded::<V>(mass, q, count);
                    let total = weight_drag_springs(m, gravity, drag, components(w.v, i), sum);
                    match inv_mass {
                        Some(inv_mass) => {
                            let w = load_padded::<V>(inv_mass, q, count);
                            from_lanes([total[0].mul(w), total[1].mul(w), total[2].mul(w)], out);
                        }
                        None => from_lanes(total, out),
                    }
                }
                Output::SemiImplicitEuler {
                    mass,
                    gravity,
                    drag,
                    inv_mass,
                    dt,
                } => {
                    let m = load_padded::<V>(mass, q, count);
                    let v: [V; 3] = components(w.v, i);
                    let total = weight_drag_springs(m, gravity, drag, v, sum);
                    let inv = load_padded::<V>(inv_mass, q, count);
                    let dt = V::splat(dt);
                    // v' = v + dt a, a = f w; then x' = x + dt v'.
                    let v_new = [
                        v[0].add(dt.mul(total[0].mul(inv))),
                        v[1].add(dt.mul(total[1].mul(inv))),
                        v[2].add(dt.mul(total[2].mul(inv))),
                    ];
                    let x: [V; 3] = components(w.x, i);
                    let x_new = [
                        x[0].add(dt.mul(v_new[0])),
                        x[1].add(dt.mul(v_new[1])),
                        x[2].add(dt.mul(v_new[2])),
                    ];
                    from_lanes(v_new, out);
                    from_lanes(x_new, &mut out2[q - q0..q - q0 + count]);
                }
            }
        }
    }
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

/// The components of up to `LANES` vectors as lanes `[x, y, z]` (zero past the end).
#[inline(always)]
fn to_lanes<V: Lanes>(vectors: &[DVec3]) -> [V; 3] {
    let mut soa = [[0.0; LANES]; 3];
    for (l, p) in vectors.iter().enumerate().take(LANES) {
        soa[0][l] = p.x;
        soa[1][l] = p.y;
        soa[2][l] = p.z;
    }
    [V::load(&soa[0]), V::load(&soa[1]), V::load(&soa[2])]
}

/// Writes lanes `[x, y, z]` into up to `LANES` vectors.
#[inline(always)]
fn from_lanes<V: Lanes>(lanes: [V; 3], vectors: &mut [DVec3]) {
    let mut soa = [[0.0; LANES]; 3];
    lanes[0].store(&mut soa[0]);
    lanes[1].store(&mut soa[1]);
    lanes[2].store(&mut soa[2]);
    for (l, p) in vectors.iter_mut().enumerate().take(LANES) {
        *p = DVec3::new(soa[0][l], soa[1][l], soa[2][l]);
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
/// depend on the lane type: [`Plain`] and [`Avx2`] give the same bits).
#[inline(always)]
fn springs_exact<V: Lanes>(g: &Group, first: &[V; 6], w: &Window, i: usize, p: usize) -> Forces<V> {
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
    let tension = V::load(lanes(&g.present, p)).mul(hooke.add(damper));
    [tension.mul(nx), tension.mul(ny), tension.mul(nz)]
}

/// The streaming loop on AVX2 registers with the exact springs (the same operations as the
/// portable loop, no fused multiply-add: bit-identical results).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
fn range_avx2(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    out: &mut [DVec3],
    out2: &mut [DVec3],
    output: &Output,
) {
    range_body(
        st,
        s,
        x,
        v,
        q0,
        q1,
        out,
        out2,
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
fn range_avx512(
    st: &Stencil,
    s: &mut Scratch,
    x: &[DVec3],
    v: &[DVec3],
    q0: usize,
    q1: usize,
    out: &mut [DVec3],
    out2: &mut [DVec3],
    output: &Output,
) {
    range_body(
        st,
        s,
        x,
        v,
        q0,
        q1,
        out,
        out2,
        output,
        #[inline(always)]
        |g, first, w, i, p| {
            // SAFETY: this function only runs on a CPU with AVX-512F (see `Stencil::range`), and
            // `range_body` calls with chunks inside the window and the group's arrays.
            unsafe { springs_avx512(g, first, w, i, p) }
        },
    );
}

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::__m512d;

/// [`Lanes`] as one AVX-512 register.
///
/// Its methods call AVX-512F instructions without checking the CPU: an `Avx512` value is only
/// ever created by [`springs_avx512`] (an `unsafe fn` whose contract includes AVX-512F) or by
/// the methods of a value that already exists, so their code only runs where AVX-512F was
/// detected.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Avx512(__m512d);

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx512 {
    #[inline(always)]
    fn zero() -> Avx512 {
        // SAFETY: see the type's docs (the streaming loop asks for zero only where it also
        // computes springs, i.e. on a CPU with AVX-512F).
        Avx512(unsafe { std::arch::x86_64::_mm512_setzero_pd() })
    }
    #[inline(always)]
    fn load(values: &[f64; LANES]) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs; `values` is 8 f64, one unaligned 512-bit load.
        Avx512(unsafe { std::arch::x86_64::_mm512_loadu_pd(values.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        // SAFETY: AVX-512F, see the type's docs; `out` is 8 f64, one unaligned 512-bit store.
        unsafe { std::arch::x86_64::_mm512_storeu_pd(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn add(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_add_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn sub(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_sub_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn mul(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_mul_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn splat(value: f64) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_set1_pd(value) })
    }
    #[inline(always)]
    fn clear_below(self, k: usize) -> Avx512 {
        // Keep lanes k.. : bit l of the mask is lane l.
        let keep = (0xFF_u32 << k.min(LANES)) as u8;
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_maskz_mov_pd(keep, self.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_sqrt_pd(self.0) })
    }
    #[inline(always)]
    fn div(self, other: Avx512) -> Avx512 {
        // SAFETY: AVX-512F, see the type's docs.
        Avx512(unsafe { std::arch::x86_64::_mm512_div_pd(self.0, other.0) })
    }
    #[inline(always)]
    fn where_positive(self, condition: Avx512) -> Avx512 {
        use std::arch::x86_64::{_CMP_GT_OQ, _mm512_cmp_pd_mask, _mm512_maskz_mov_pd};
        // SAFETY: AVX-512F, see the type's docs.
        unsafe {
            let zero = std::arch::x86_64::_mm512_setzero_pd();
            let positive = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(condition.0, zero);
            Avx512(_mm512_maskz_mov_pd(positive, self.0))
        }
    }
}

/// [`Lanes`] as two AVX2 registers of four f64 each.
///
/// Its methods call AVX2 instructions without checking the CPU: an `Avx2` value is only ever
/// created inside `range_avx2` (a `target_feature(enable = "avx2")` function, which runs only
/// where AVX2 was detected) or by the methods of a value that already exists.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Avx2([std::arch::x86_64::__m256d; 2]);

#[cfg(target_arch = "x86_64")]
impl Lanes for Avx2 {
    #[inline(always)]
    fn zero() -> Avx2 {
        // SAFETY: AVX2, see the type's docs.
        let zero = unsafe { std::arch::x86_64::_mm256_setzero_pd() };
        Avx2([zero, zero])
    }
    #[inline(always)]
    fn load(values: &[f64; LANES]) -> Avx2 {
        use std::arch::x86_64::_mm256_loadu_pd;
        // SAFETY: AVX2, see the type's docs; two unaligned 256-bit loads of 4 f64 each, inside
        // the 8 values of `values`.
        unsafe {
            Avx2([
                _mm256_loadu_pd(values.as_ptr()),
                _mm256_loadu_pd(values.as_ptr().add(4)),
            ])
        }
    }
    #[inline(always)]
    fn store(self, out: &mut [f64; LANES]) {
        use std::arch::x86_64::_mm256_storeu_pd;
        // SAFETY: AVX2, see the type's docs; two 256-bit stores inside the 8 values of `out`.
        unsafe {
            _mm256_storeu_pd(out.as_mut_ptr(), self.0[0]);
            _mm256_storeu_pd(out.as_mut_ptr().add(4), self.0[1]);
        }
    }
    #[inline(always)]
    fn add(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_add_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_add_pd(self.0[0], other.0[0]),
                _mm256_add_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn sub(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_sub_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_sub_pd(self.0[0], other.0[0]),
                _mm256_sub_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn mul(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_mul_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_mul_pd(self.0[0], other.0[0]),
                _mm256_mul_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn splat(value: f64) -> Avx2 {
        // SAFETY: AVX2, see the type's docs.
        let v = unsafe { std::arch::x86_64::_mm256_set1_pd(value) };
        Avx2([v, v])
    }
    #[inline(always)]
    fn clear_below(self, k: usize) -> Avx2 {
        let mut values = [0.0; LANES];
        self.store(&mut values);
        values[..k.min(LANES)].fill(0.0);
        Avx2::load(&values)
    }
    #[inline(always)]
    fn sqrt(self) -> Avx2 {
        use std::arch::x86_64::_mm256_sqrt_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe { Avx2([_mm256_sqrt_pd(self.0[0]), _mm256_sqrt_pd(self.0[1])]) }
    }
    #[inline(always)]
    fn div(self, other: Avx2) -> Avx2 {
        use std::arch::x86_64::_mm256_div_pd;
        // SAFETY: AVX2, see the type's docs.
        unsafe {
            Avx2([
                _mm256_div_pd(self.0[0], other.0[0]),
                _mm256_div_pd(self.0[1], other.0[1]),
            ])
        }
    }
    #[inline(always)]
    fn where_positive(self, condition: Avx2) -> Avx2 {
        use std::arch::x86_64::{_CMP_GT_OQ, _mm256_and_pd, _mm256_cmp_pd, _mm256_setzero_pd};
        // SAFETY: AVX2, see the type's docs. The comparison gives all-ones lanes where
        // `condition > 0` (false for NaN), and `and` keeps `self` there.
        unsafe {
            let zero = _mm256_setzero_pd();
            let keep = [
                _mm256_cmp_pd::<_CMP_GT_OQ>(condition.0[0], zero),
                _mm256_cmp_pd::<_CMP_GT_OQ>(condition.0[1], zero),
            ];
            Avx2([
                _mm256_and_pd(self.0[0], keep[0]),
                _mm256_and_pd(self.0[1], keep[1]),
            ])
        }
    }
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
) -> Forces<Avx512> {
    use std::arch::x86_64::{
        _CMP_GT_OQ, _mm512_cmp_pd_mask, _mm512_fmadd_pd, _mm512_fmsub_pd, _mm512_fnmadd_pd,
        _mm512_loadu_pd, _mm512_maskz_rsqrt14_pd, _mm512_mul_pd, _mm512_set1_pd, _mm512_setzero_pd,
        _mm512_sub_pd,
    };
    let j = i + g.delta;
    debug_assert!(j + LANES <= w.x[0].len() && p + LANES <= g.present.len());
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
        let damper = _mm512_mul_pd(
            _mm512_set1_pd(g.damping),
            _mm512_fmadd_pd(dvz, dz, _mm512_fmadd_pd(dvy, dy, _mm512_mul_pd(dvx, dx))),
        );
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
        let tension = _mm512_fmadd_pd(
            _mm512_set1_pd(g.stiffness),
            stretch,
            _mm512_mul_pd(damper, y),
        );
        // f = tension n = (tension / L) d, zero where there is no spring (present = 0).
        let scale = _mm512_mul_pd(_mm512_mul_pd(tension, y), load(&g.present, p));
        [
            Avx512(_mm512_mul_pd(dx, scale)),
            Avx512(_mm512_mul_pd(dy, scale)),
            Avx512(_mm512_mul_pd(dz, scale)),
        ]
    }
}
