//! Many semi-implicit Euler steps of a small lattice in one call, with the particles kept in
//! the structure-of-arrays form between the steps.
//!
//! A rope of 64 particles has 63 springs: one pass of the streaming loop ([`super::passes`])
//! is a few hundred nanoseconds, and much of it is fixed cost: the copy of the positions and
//! velocities into the structure of arrays and back, the rings, the tile loop. Here the copy is
//! made once for all the steps of a call, and the springs' forces go to one flat array per
//! offset group (the whole lattice is one tile):
//!
//! ```text
//! copy x, v in (structure of arrays, zero past the last particle)
//! each step:  pass 1, each chunk p, each group δ with p < starts:
//!                 f_δ[p..p+8] → F_δ[δ + p..];   plus[p] = (0 + f_δ₁) + f_δ₂ + …
//!             pass 2, each chunk q:  minus = 0 + F_δ₁[q..q+8] + F_δ₂[q..q+8] + …
//!                 F = plus - minus;  f = (m g - c v) + F;  a = f · (1/m)
//!                 v' = v + dt a;  x' = x + dt v'          (in place: pass 1 is done)
//! copy x, v out
//! ```
//! where `F_δ` holds `δ` zeros before the first spring (a particle `q < δ` ends no spring of
//! that offset). These are the operations of the streaming loop with
//! [`Update::SemiImplicitEuler`], with the same kernels, in the same order, so the numbers are
//! the same bit for bit as that many single steps (tested). Only for small lattices without
//! colliders or per-step projections (see [`Stencil::semi_implicit_euler_steps`]). With energy
//! accounting ([`Stencil::semi_implicit_euler_steps_with_power`]) pass 1 also keeps each chunk's
//! damper power and pass 2 adds the drag, into one step's power buffer as the streaming loop
//! writes it, summed after each step (the same bits; the one-pass AVX-512 loop below computes
//! the same chunk values and sums them in the same order).
//!
//! # One pass per step (AVX-512, at most six offset groups)
//!
//! The two passes above are the textbook form, and what the portable and AVX2 kernels run.
//! With AVX-512 (`fused_avx512`, below the seam at the end of the file) each step is a single
//! pass over the chunks, the same operations on the same values:
//!
//! ```text
//! each step, each chunk c (particles 8c..8c+8), in order:
//!     own    = x, v of chunk c                                  (6 registers, old values)
//!     each group δ = 8k + r with 8c < starts:
//!         second = lanes r.. of chunks c+k, c+k+1 (one permute per component; old values:
//!                  chunks after c are not written yet this step)
//!         f_δ[c] = springs(own, second);   plus = (0 + f_δ₁[c]) + f_δ₂[c] + …
//!     minus  = 0 + (lanes 8-r.. of f_δ₁[c-k-1], f_δ₁[c-k]) + …  (forces ending in chunk c,
//!              all computed already: they start δ particles earlier)
//!     F = plus - minus;  f = (m g - c v) + F;  a = f · (1/m);  v' = v + dt a;  x' = x + dt v'
//!     store x', v' into chunk c
//!     with power:  P += (0 + P_δ₁[c] + P_δ₂[c] + …) + c |v|² (free particles)
//! with power, after the last chunk:  the step's power = the sum of P's lanes
//! ```
//! where `f_δ[c]` is zero for a chunk before the first (`c < 0`) or past the group's springs,
//! `P_δ[c]` (W) the dampers' power of those springs, `P` (W, per lane, zero at the start of
//! the step) the dampers and drag of the chunks so far: the chunk values of the two passes'
//! power buffer, added in the order of [`Stencil::sum_power`].
//! Four things make this faster than the two passes (on the 64-particle rope of `rope-se`
//! about 150 ns a step instead of about 310, measured with `examples/rope_micro.rs`):
//! - The springs' second ends and the forces that end in a chunk are lane permutations
//!   (`VPERMT2PD`) of whole chunks already in registers or just stored, instead of loads that
//!   straddle two chunks written a moment earlier: such a load cannot take its value from the
//!   pending stores and waits until they reach the cache.
//! - For `δ < 8` (the rope: `δ = 1`) the forces that end in chunk `c` come from chunks `c - 1`
//!   and `c`, both still in registers: nothing is stored. Larger offsets keep a short history
//!   per group (aligned lines of eight values).
//! - The state is one aligned line per component and chunk (a load is one cache line), and
//!   what does not change between steps is computed once per call: the weight `m g`, `1/m`
//!   with zeros past the last particle, the permutation indices.
//! - The group count is a compile-time constant (`G` = 1 to 6), so the loop over groups is
//!   unrolled and each group's constants stay in registers.
//!
//! The kernel's arithmetic is that of [`springs_avx512`] (both call `spring_lanes_avx512`, which
//! takes both ends in registers) and every sum keeps its order, so the results are the same bits as the
//! single steps (tested for 1 to 6 groups, offsets below, equal to and above a chunk, sizes
//! that are not a multiple of eight, pinned particles; seven groups take the two passes).

use super::kernels::springs_exact;
#[cfg(target_arch = "x86_64")]
use super::kernels::{spring_lanes_avx512, springs_avx512};
use super::passes::{Forces, Window, load_padded, semi_implicit_euler, weight_drag_springs};
#[allow(clippy::wildcard_imports)]
use super::*;
use crate::physics::lanes::first_lanes;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{
    __m512d, __m512i, _CMP_LT_OQ, _mm512_add_pd, _mm512_cmp_pd_mask, _mm512_load_pd,
    _mm512_loadu_pd, _mm512_loadu_si512, _mm512_maskz_mov_pd, _mm512_mul_pd,
    _mm512_permutex2var_pd, _mm512_set1_pd, _mm512_setzero_pd, _mm512_store_pd, _mm512_sub_pd,
};

/// Up to this many particles a lattice is "small": its state stays in the first-level cache,
/// and one thread does the whole pass (see `MIN_SLOTS_PER_PART`).
pub(super) const SMALL_PARTICLES: usize = 256;

/// The arrays of a call (reused, so calls do not allocate).
#[derive(Default)]
pub(super) struct SmallScratch {
    x: [Vec<f64>; 3],
    v: [Vec<f64>; 3],
    /// `plus[c]`: the forces of the springs starting at each particle (N).
    plus: [Vec<f64>; 3],
    /// Per group: its springs' forces, after `δ` zeros (N), three components.
    forces: Vec<[Vec<f64>; 3]>,
    /// `spring_power[c]`: the dampers' power of the springs starting in chunk `c` (W).
    spring_power: Vec<f64>,
    /// One step's power buffer, as [`Stencil::write`] fills it (W).
    power: Vec<f64>,
    /// Each step's `(dampers and drag, contact)` power (W), when asked.
    powers: Vec<(f64, f64)>,
}

thread_local! {
    static SMALL: RefCell<SmallScratch> = RefCell::new(SmallScratch::default());
}

impl Stencil {
    /// `steps` semi-implicit Euler steps of `dt` seconds (see [`Update::SemiImplicitEuler`]) of
    /// the positions `x` (m) and velocities `v` (m/s) under `dynamics`, in one call: the same
    /// numbers bit for bit as `steps` calls of [`Stencil::write`] with
    /// [`Output::Step`] (`after` none) each followed by swapping in the outputs.
    ///
    /// Returns false, and changes nothing, unless the lattice is small (at most 256 particles,
    /// `SMALL_PARTICLES`) and `dynamics` has no colliders.
    ///
    /// # Panics
    /// If a slice is shorter than the stencil's particle count.
    pub fn semi_implicit_euler_steps(
        &self,
        x: &mut [DVec3],
        v: &mut [DVec3],
        dynamics: &Dynamics,
        dt: f64,
        steps: u64,
    ) -> bool {
        self.semi_implicit_euler_steps_with_power(x, v, dynamics, dt, steps, None)
    }

    /// [`Stencil::semi_implicit_euler_steps`], and, when `powers` is given, the dissipated
    /// power at the start of each step appended to it: `(dampers and drag, contact)` (W), the
    /// values [`Stencil::sum_power`] gives for the power buffer [`Stencil::write`] fills in the
    /// same step (the same bits: the same chunk values, summed in the same order).
    ///
    /// # Panics
    /// If a slice is shorter than the stencil's particle count.
    pub fn semi_implicit_euler_steps_with_power(
        &self,
        x: &mut [DVec3],
        v: &mut [DVec3],
        dynamics: &Dynamics,
        dt: f64,
        steps: u64,
        powers: Option<&mut Vec<(f64, f64)>>,
    ) -> bool {
        let n = self.particles;
        if n > SMALL_PARTICLES || !dynamics.colliders.is_empty() {
            return false;
        }
        let (x, v) = (&mut x[..n], &mut v[..n]);
        assert!(
            dynamics.mass.len() >= n && dynamics.inv_mass.len() >= n,
            "masses too short"
        );
        let mut powers = powers;
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `with_kernel` and `Kernel::best` only choose `Avx512` on a CPU that supports
        // AVX-512F.
        if self.kernel == Kernel::Avx512
            && unsafe { fused_steps(self, dynamics, x, v, dt, steps, powers.as_deref_mut()) }
        {
            return true;
        }
        SMALL.with(|s| {
            let s = &mut *s.borrow_mut();
            s.load(self, x, v);
            match powers {
                None => small_steps::<false>(self, s, dynamics, dt, steps),
                Some(powers) => {
                    s.power.clear();
                    s.power.resize(self.power_len(), 0.0);
                    s.powers = std::mem::take(powers);
                    small_steps::<true>(self, s, dynamics, dt, steps);
                    *powers = std::mem::take(&mut s.powers);
                }
            }
            s.store(x, v);
        });
        true
    }
}

/// `steps` steps of `small_body` with the kernel of the stencil's instruction set.
fn small_steps<const POWER: bool>(
    st: &Stencil,
    s: &mut SmallScratch,
    dynamics: &Dynamics,
    dt: f64,
    steps: u64,
) {
    match st.kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `with_kernel` and `Kernel::best` only choose `Avx512` on a CPU that
        // supports AVX-512F.
        Kernel::Avx512 => unsafe { steps_avx512::<POWER>(st, s, dynamics, dt, steps) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above, AVX2.
        Kernel::Avx2 => unsafe { steps_avx2::<POWER>(st, s, dynamics, dt, steps) },
        _ => small_body::<Plain, POWER>(
            st,
            s,
            dynamics,
            dt,
            steps,
            #[inline(always)]
            #[allow(clippy::redundant_closure)]
            |g, first, w, i, p| springs_exact::<Plain>(g, first, w, i, p),
        ),
    }
}

impl SmallScratch {
    /// Sizes the arrays for `st` and copies `x`, `v` in (zero past the last particle).
    fn load(&mut self, st: &Stencil, x: &[DVec3], v: &[DVec3]) {
        let n = st.particles;
        // As the streaming loop's window: the springs' second ends up to `n + reach`.
        let len = n.next_multiple_of(LANES) + st.reach;
        for c in self.x.iter_mut().chain(&mut self.v) {
            c.clear();
            c.resize(len, 0.0);
        }
        for c in &mut self.plus {
            c.clear();
            c.resize(n.next_multiple_of(LANES), 0.0);
        }
        self.forces.resize_with(st.groups.len(), Default::default);
        for (g, f) in st.groups.iter().zip(&mut self.forces) {
            for c in f {
                c.clear();
                c.resize(g.delta + n.next_multiple_of(LANES), 0.0);
            }
        }
        for (i, (p, u)) in x.iter().zip(v).enumerate() {
            (self.x[0][i], self.x[1][i], self.x[2][i]) = (p.x, p.y, p.z);
            (self.v[0][i], self.v[1][i], self.v[2][i]) = (u.x, u.y, u.z);
        }
    }

    /// Copies the positions and velocities out.
    fn store(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        for (i, (p, u)) in x.iter_mut().zip(v).enumerate() {
            *p = DVec3::new(self.x[0][i], self.x[1][i], self.x[2][i]);
            *u = DVec3::new(self.v[0][i], self.v[1][i], self.v[2][i]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn steps_avx512<const POWER: bool>(
    st: &Stencil,
    s: &mut SmallScratch,
    d: &Dynamics,
    dt: f64,
    steps: u64,
) {
    small_body::<Avx512, POWER>(
        st,
        s,
        d,
        dt,
        steps,
        #[inline(always)]
        |g, first, w, i, p| {
            // SAFETY: this function only runs on a CPU with AVX-512F, and `small_body` calls
            // with chunks inside the window and the group's arrays.
            unsafe { springs_avx512(g, first, w, i, p) }
        },
    );
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn steps_avx2<const POWER: bool>(
    st: &Stencil,
    s: &mut SmallScratch,
    d: &Dynamics,
    dt: f64,
    steps: u64,
) {
    small_body::<Avx2, POWER>(
        st,
        s,
        d,
        dt,
        steps,
        #[inline(always)]
        #[allow(clippy::redundant_closure)]
        |g, first, w, i, p| springs_exact::<Avx2>(g, first, w, i, p),
    );
}

/// The steps of the module docs, with `springs` computing each chunk of springs (as in
/// `range_body`, whose `i` is `p` here: the window starts at particle 0); with `POWER`, each
/// step's dissipated power too, chunk by chunk as `range_body` computes it (the dampers of the
/// springs starting in the chunk, group by group, then the drag of its free particles; no
/// contact: a small lattice here has no colliders), summed by [`Stencil::sum_power`].
#[inline(always)]
fn small_body<V: Lanes, const POWER: bool>(
    st: &Stencil,
    s: &mut SmallScratch,
    d: &Dynamics,
    dt: f64,
    steps: u64,
    springs: impl Fn(&Group, &[V; 6], &Window, usize, usize) -> (Forces<V>, V),
) {
    let n = st.particles;
    let SmallScratch {
        x: xs,
        v: vs,
        plus,
        forces,
        spring_power,
        power: power_buffer,
        powers,
    } = s;
    if POWER {
        spring_power.clear();
        spring_power.resize(n.next_multiple_of(LANES), 0.0);
    }
    let dt_lanes = V::splat(dt);
    for _ in 0..steps {
        // Pass 1: every spring once, into its group's array, and the sums `plus`.
        {
            let w = Window {
                x: [&xs[0], &xs[1], &xs[2]],
                v: [&vs[0], &vs[1], &vs[2]],
            };
            for p in (0..n).step_by(LANES) {
                let first = w.first_ends::<V>(p);
                let mut sum = [V::zero(); 3];
                let mut power = V::zero();
                for (g, out) in st.groups.iter().zip(forces.iter_mut()) {
                    if p >= g.starts {
                        // The groups a chunk has are a prefix of the list.
                        break;
                    }
                    let (f, pw) = springs(g, &first, &w, p, p);
                    for ((part, total), values) in f.into_iter().zip(&mut sum).zip(out) {
                        part.store(chunk_mut(values, g.delta + p));
                        *total = total.add(part);
                    }
                    if POWER {
                        power = power.add(pw);
                    }
                }
                for (total, values) in sum.into_iter().zip(plus.iter_mut()) {
                    total.store(chunk_mut(values, p));
                }
                if POWER {
                    power.store(chunk_mut(spring_power, p));
                }
            }
        }
        // Pass 2: minus the springs that end here, then the step, in place.
        for q in (0..n).step_by(LANES) {
            let count = (n - q).min(LANES);
            let mut minus = [V::zero(); 3];
            for f in forces.iter() {
                for (total, values) in minus.iter_mut().zip(f) {
                    *total = total.add(V::load(lanes(values, q)));
                }
            }
            let sum = [
                V::load(lanes(&plus[0], q)).sub(minus[0]),
                V::load(lanes(&plus[1], q)).sub(minus[1]),
                V::load(lanes(&plus[2], q)).sub(minus[2]),
            ];
            let x = [
                V::load(lanes(&xs[0], q)),
                V::load(lanes(&xs[1], q)),
                V::load(lanes(&xs[2], q)),
            ];
            let v = [
                V::load(lanes(&vs[0], q)),
                V::load(lanes(&vs[1], q)),
                V::load(lanes(&vs[2], q)),
            ];
            let m = load_padded::<V>(d.mass, q, count);
            let f = weight_drag_springs(m, d.gravity, d.drag, v, sum);
            let w = load_padded::<V>(d.inv_mass, q, count);
            if POWER {
                // As `passes::finish`: the drag c |v|² of the free particles added to the
                // dampers; the contact power is zero.
                let drag = if d.drag == 0.0 {
                    V::zero()
                } else {
                    let free = V::zero().less_than(w);
                    let v2 = v[0].mul(v[0]).add(v[1].mul(v[1])).add(v[2].mul(v[2]));
                    V::splat(d.drag).mul(v2).select(free)
                };
                let dampers = &mut power_buffer[2 * q..2 * q + LANES];
                V::load(lanes(spring_power, q))
                    .add(drag)
                    .store(dampers.try_into().expect("a chunk"));
                // No contact values: `Stencil::sum_power` reads none without colliders.
            }
            let a = [f[0].mul(w), f[1].mul(w), f[2].mul(w)];
            let (x_new, v_new) = semi_implicit_euler(x, v, a, dt_lanes);
            // Past the last particle the window stays zero, as the streaming loop's.
            let keep = first_lanes(count);
            for (new, values) in x_new.into_iter().zip(xs.iter_mut()) {
                new.select(keep).store(chunk_mut(values, q));
            }
            for (new, values) in v_new.into_iter().zip(vs.iter_mut()) {
                new.select(keep).store(chunk_mut(values, q));
            }
        }
        if POWER {
            powers.push(Stencil::sum_power(power_buffer, false));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The fused path (AVX-512, at most `FUSED_GROUPS` offset groups): the same numbers as
// `small_body`, one pass over the chunks per step. See the module docs, "One pass per step".
// ---------------------------------------------------------------------------------------------

/// At most this many offset groups take the fused path (a cloth's six offsets); the groups'
/// constants then stay in registers. More groups take `small_body`.
#[cfg(target_arch = "x86_64")]
const FUSED_GROUPS: usize = 6;

/// `LANES` values on a 64-byte boundary: one cache line, loaded and stored whole.
#[derive(Clone, Copy, Default)]
#[repr(C, align(64))]
struct Line([f64; LANES]);

/// The arrays of the fused path (reused, so calls do not allocate).
#[derive(Default)]
struct FusedScratch {
    /// Per chunk `c`: `[x, y, z, v_x, v_y, v_z]` of particles `8c..8c+8` (m, m/s); zero past
    /// the last particle, including the chunks after the last that the springs' second ends
    /// reach.
    state: Vec<[Line; 6]>,
    /// Per chunk: the weight `m g` (N), as pass 2 computes it (zero past the last particle).
    weight: Vec<[Line; 3]>,
    /// Per chunk: `1/m` (1/kg), zero past the last particle.
    inv_mass: Vec<Line>,
    /// Per group of offset `δ = 8k + r`: the forces of the springs starting in chunk `c` at
    /// index `c + k + 1`, after `k + 1` chunks of zeros (a particle `q < δ` ends no spring).
    history: Vec<Vec<[Line; 3]>>,
}

thread_local! {
    static FUSED: RefCell<FusedScratch> = RefCell::new(FusedScratch::default());
}

impl FusedScratch {
    /// Sizes the arrays for `st` and copies `x`, `v` and the masses in.
    fn load(&mut self, st: &Stencil, d: &Dynamics, x: &[DVec3], v: &[DVec3]) {
        let n = st.particles;
        let chunks = n.div_ceil(LANES);
        // The second ends of the last chunk's springs reach chunk `chunks - 1 + k + 1`.
        let ahead = st.reach / LANES + 1;
        self.state.clear();
        self.state.resize(chunks + ahead, [Line::default(); 6]);
        for (i, (p, u)) in x.iter().zip(v).enumerate() {
            let (c, l) = (i / LANES, i % LANES);
            let line = &mut self.state[c];
            (line[0].0[l], line[1].0[l], line[2].0[l]) = (p.x, p.y, p.z);
            (line[3].0[l], line[4].0[l], line[5].0[l]) = (u.x, u.y, u.z);
        }
        self.weight.clear();
        self.inv_mass.clear();
        for q in (0..n).step_by(LANES) {
            let count = (n - q).min(LANES);
            // As pass 2 of `small_body`: `m g` with the same multiplication, lanes past the last
            // particle from a zero mass.
            let m = load_padded::<Plain>(d.mass, q, count);
            let mut weight = [Line::default(); 3];
            for (line, g) in weight
                .iter_mut()
                .zip([d.gravity.x, d.gravity.y, d.gravity.z])
            {
                m.mul(Plain::splat(g)).store(&mut line.0);
            }
            self.weight.push(weight);
            let mut w = Line::default();
            load_padded::<Plain>(d.inv_mass, q, count).store(&mut w.0);
            self.inv_mass.push(w);
        }
        self.history.resize_with(st.groups.len(), Vec::new);
        for (g, h) in st.groups.iter().zip(&mut self.history) {
            h.clear();
            h.resize(chunks + g.delta / LANES + 1, [Line::default(); 3]);
        }
    }

    /// Copies the positions and velocities out.
    fn store(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        for (i, (p, u)) in x.iter_mut().zip(v).enumerate() {
            let (c, l) = (i / LANES, i % LANES);
            let line = &self.state[c];
            *p = DVec3::new(line[0].0[l], line[1].0[l], line[2].0[l]);
            *u = DVec3::new(line[3].0[l], line[4].0[l], line[5].0[l]);
        }
    }
}

/// The fused steps for a lattice of `G` groups, or false (nothing done) for more groups than
/// `FUSED_GROUPS`; with `powers`, each step's dissipated power appended to it, as
/// [`Stencil::semi_implicit_euler_steps_with_power`] gives it.
///
/// # Safety
/// The CPU must support AVX-512F.
#[cfg(target_arch = "x86_64")]
unsafe fn fused_steps(
    st: &Stencil,
    d: &Dynamics,
    x: &mut [DVec3],
    v: &mut [DVec3],
    dt: f64,
    steps: u64,
    powers: Option<&mut Vec<(f64, f64)>>,
) -> bool {
    if st.groups.is_empty() || st.groups.len() > FUSED_GROUPS {
        return false;
    }
    FUSED.with(|s| {
        let s = &mut *s.borrow_mut();
        s.load(st, d, x, v);
        // SAFETY: the caller guarantees AVX-512F; `load` sized the arrays for `st`.
        unsafe {
            match powers {
                None => fused_groups::<false>(st, s, d, dt, steps, &mut Vec::new()),
                Some(p) => fused_groups::<true>(st, s, d, dt, steps, p),
            }
        }
        s.store(x, v);
    });
    true
}

/// [`fused_avx512`] with the group count `G` of `st` (1 to `FUSED_GROUPS`) as a constant.
///
/// # Safety
/// As [`fused_avx512`].
#[cfg(target_arch = "x86_64")]
#[allow(clippy::too_many_arguments)]
unsafe fn fused_groups<const POWER: bool>(
    st: &Stencil,
    s: &mut FusedScratch,
    d: &Dynamics,
    dt: f64,
    steps: u64,
    powers: &mut Vec<(f64, f64)>,
) {
    // SAFETY: as the caller's.
    unsafe {
        match st.groups.len() {
            1 => fused_avx512::<1, POWER>(st, s, d, dt, steps, powers),
            2 => fused_avx512::<2, POWER>(st, s, d, dt, steps, powers),
            3 => fused_avx512::<3, POWER>(st, s, d, dt, steps, powers),
            4 => fused_avx512::<4, POWER>(st, s, d, dt, steps, powers),
            5 => fused_avx512::<5, POWER>(st, s, d, dt, steps, powers),
            _ => fused_avx512::<6, POWER>(st, s, d, dt, steps, powers),
        }
    }
}

/// The constants of one group in the fused loop.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct FusedGroup {
    /// `k = δ / 8`: the second ends of chunk `c` are in chunks `c + k` and `c + k + 1`.
    k: usize,
    /// Chunks that hold springs: `⌈starts / 8⌉`.
    chunks: usize,
    /// Lane `l` of the second ends: lane `r + l` of chunks `c + k`, `c + k + 1` (`r = δ mod 8`).
    second: __m512i,
    /// Lane `l` of the forces ending in chunk `c`: lane `8 + l - r` of the forces of chunks
    /// `c - k - 1`, `c - k`.
    minus: __m512i,
    stiffness: __m512d,
    damping: __m512d,
}

/// `steps` semi-implicit Euler steps on the arrays of `s`, one pass over the chunks per step
/// (see the module docs, "One pass per step"), for a lattice of exactly `G` groups; with
/// `POWER`, each step's dissipated power pushed to `powers`, as `small_body` computes it: per
/// chunk the dampers of its springs group by group, then the drag of its free particles,
/// added chunk by chunk into per-lane sums, which [`Stencil::sum_power`] adds up (no contact:
/// a small lattice here has no colliders).
///
/// # Safety
/// The CPU must support AVX-512F, `st.groups.len() == G`, and `s` must have been loaded for
/// `st` ([`FusedScratch::load`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn fused_avx512<const G: usize, const POWER: bool>(
    st: &Stencil,
    s: &mut FusedScratch,
    d: &Dynamics,
    dt: f64,
    steps: u64,
    powers: &mut Vec<(f64, f64)>,
) {
    debug_assert_eq!(st.groups.len(), G);
    let n = st.particles;
    let chunks = n.div_ceil(LANES);
    let groups: [FusedGroup; G] = std::array::from_fn(|g| {
        let group = &st.groups[g];
        let r = (group.delta % LANES) as i64;
        let second: [i64; LANES] = std::array::from_fn(|l| r + l as i64);
        let minus: [i64; LANES] = std::array::from_fn(|l| LANES as i64 + l as i64 - r);
        // SAFETY: AVX-512F (this function's target feature); the arrays hold 8 values.
        unsafe {
            FusedGroup {
                k: group.delta / LANES,
                chunks: group.starts.div_ceil(LANES),
                second: _mm512_loadu_si512(second.as_ptr().cast()),
                minus: _mm512_loadu_si512(minus.as_ptr().cast()),
                stiffness: _mm512_set1_pd(group.stiffness),
                damping: _mm512_set1_pd(group.damping),
            }
        }
    });
    let rest: [&[f64]; G] = std::array::from_fn(|g| &st.groups[g].rest_length[..]);
    let present: [&[u8]; G] = std::array::from_fn(|g| &st.groups[g].present[..]);
    // The last chunk's lanes past the last particle stay zero, as in `small_body`.
    let last_keep = if n.is_multiple_of(LANES) {
        u8::MAX
    } else {
        first_lanes(n % LANES)
    };
    let FusedScratch {
        state,
        weight,
        inv_mass,
        history,
    } = s;
    debug_assert!(state.len() > chunks + st.reach / LANES && weight.len() == chunks);
    let state = state.as_mut_ptr();
    let history: [*mut [Line; 3]; G] = std::array::from_fn(|g| history[g].as_mut_ptr());
    // SAFETY (the whole loop): AVX-512F is enabled here. Every index is inside its array as
    // `FusedScratch::load` sized them: `state` has `chunks + reach / 8 + 1` lines and
    // is read at `c + k + 1 <= chunks - 1 + reach / 8 + 1`; `history[g]` has `chunks + k + 1`
    // and is written at `c + k + 1` and read at `c`, `c + 1` (`c < chunks`); a group's
    // `rest_length` and `present` are padded to `chunks_g` chunks and read at `c < chunks_g`.
    unsafe {
        let dt_lanes = _mm512_set1_pd(dt);
        let drag = _mm512_set1_pd(d.drag);
        let zero = _mm512_setzero_pd();
        let line = |p: *const [Line; 6], i: usize| _mm512_load_pd((*p)[i].0.as_ptr());
        // With `POWER`: the lane sums of the last steps, added up a block at a time (off the
        // steps' own work), and the contact power, zero in every lane.
        let mut block = [Line::default(); LANES];
        let mut filled = 0;
        let contact = Stencil::lanes_total(&[0.0; LANES]);
        for step in 0..steps {
            // The forces of the previous chunk, for the groups with δ < 8 (k = 0).
            let mut previous = [[zero; 3]; G];
            // With `POWER`: the step's dampers and drag so far, per lane (W).
            let mut dissipated = zero;
            for c in 0..chunks {
                let own = state.add(c);
                let first: [__m512d; 6] = std::array::from_fn(|i| line(own, i));
                // Pass 1 of the chunk: each group's springs starting here, and their sum.
                let mut plus = [zero; 3];
                let mut current = [[zero; 3]; G];
                let mut dampers = zero;
                for g in 0..G {
                    let group = &groups[g];
                    if c >= group.chunks {
                        // The groups a chunk has are a prefix of the list.
                        break;
                    }
                    let (a, b) = (state.add(c + group.k), state.add(c + group.k + 1));
                    let second: [__m512d; 6] = std::array::from_fn(|i| {
                        _mm512_permutex2var_pd(line(a, i), group.second, line(b, i))
                    });
                    let (f, power) = spring_lanes_avx512(
                        &first,
                        &second,
                        group.stiffness,
                        group.damping,
                        _mm512_loadu_pd(rest[g].as_ptr().add(c * LANES)),
                        *present[g].get_unchecked(c),
                    );
                    if group.k > 0 {
                        let slot = &mut *history[g].add(c + group.k + 1);
                        for (out, value) in slot.iter_mut().zip(f) {
                            _mm512_store_pd(out.0.as_mut_ptr(), value);
                        }
                    }
                    for (total, part) in plus.iter_mut().zip(f) {
                        *total = _mm512_add_pd(*total, part);
                    }
                    current[g] = f;
                    if POWER {
                        dampers = _mm512_add_pd(dampers, power);
                    }
                }
                // Pass 2 of the chunk: minus the springs that end here (they started δ
                // earlier: a lane shift of two chunks of forces), then the step.
                let mut minus = [zero; 3];
                for g in 0..G {
                    let group = &groups[g];
                    let (low, high) = if group.k == 0 {
                        (previous[g], current[g])
                    } else {
                        let (low, high) = (&*history[g].add(c), &*history[g].add(c + 1));
                        (
                            std::array::from_fn(|i| _mm512_load_pd(low[i].0.as_ptr())),
                            std::array::from_fn(|i| _mm512_load_pd(high[i].0.as_ptr())),
                        )
                    };
                    for i in 0..3 {
                        let f = _mm512_permutex2var_pd(low[i], group.minus, high[i]);
                        minus[i] = _mm512_add_pd(minus[i], f);
                    }
                }
                previous = current;
                let weight = &*weight.as_ptr().add(c);
                let w = _mm512_load_pd((*inv_mass.as_ptr().add(c)).0.as_ptr());
                let keep = if c + 1 == chunks { last_keep } else { u8::MAX };
                if POWER {
                    // As `small_body`'s pass 2: the drag c |v|² of the free particles.
                    // Without drag the sum skips the zeros: `dampers` is never -0 (it starts
                    // at +0), so adding +0 changes no bit.
                    if d.drag == 0.0 {
                        dissipated = _mm512_add_pd(dissipated, dampers);
                    } else {
                        let v = [first[3], first[4], first[5]];
                        let v2 = _mm512_add_pd(
                            _mm512_add_pd(_mm512_mul_pd(v[0], v[0]), _mm512_mul_pd(v[1], v[1])),
                            _mm512_mul_pd(v[2], v[2]),
                        );
                        let free = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(zero, w);
                        let drag_power = _mm512_maskz_mov_pd(free, _mm512_mul_pd(drag, v2));
                        dissipated = _mm512_add_pd(dissipated, _mm512_add_pd(dampers, drag_power));
                    }
                }
                let own = &mut *own;
                for i in 0..3 {
                    // F = plus - minus;  f = (m g - c v) + F;  a = f · (1/m)
                    let spring = _mm512_sub_pd(plus[i], minus[i]);
                    let drag_force = _mm512_mul_pd(drag, first[3 + i]);
                    let f = _mm512_add_pd(
                        _mm512_sub_pd(_mm512_load_pd(weight[i].0.as_ptr()), drag_force),
                        spring,
                    );
                    let a = _mm512_mul_pd(f, w);
                    // v' = v + dt a;  x' = x + dt v'
                    let v_new = _mm512_add_pd(first[3 + i], _mm512_mul_pd(dt_lanes, a));
                    let x_new = _mm512_add_pd(first[i], _mm512_mul_pd(dt_lanes, v_new));
                    let (x_new, v_new) = if keep == u8::MAX {
                        (x_new, v_new)
                    } else {
                        (
                            _mm512_maskz_mov_pd(keep, x_new),
                            _mm512_maskz_mov_pd(keep, v_new),
                        )
                    };
                    _mm512_store_pd(own[i].0.as_mut_ptr(), x_new);
                    _mm512_store_pd(own[3 + i].0.as_mut_ptr(), v_new);
                }
            }
            if POWER {
                // `dissipated` is `Stencil::sum_power`'s lane sums of the dampers and drag.
                _mm512_store_pd(block[filled].0.as_mut_ptr(), dissipated);
                filled += 1;
                if filled == LANES || step + 1 == steps {
                    let totals = block[..filled].iter().map(|l| Stencil::lanes_total(&l.0));
                    powers.extend(totals.map(|total| (total, contact)));
                    filled = 0;
                }
            }
        }
    }
}

/// `values[at..at + LANES]` as one chunk.
#[inline(always)]
fn chunk_mut(values: &mut [f64], at: usize) -> &mut [f64; LANES] {
    (&mut values[at..at + LANES]).try_into().expect("a chunk")
}

#[cfg(test)]
mod tests;
