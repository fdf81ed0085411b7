//! Implicit Euler's linear system on a lattice: the matrix of `implicit_euler` with its spring
//! blocks stored by offset group as structure of arrays, so that the assembly and the product
//! `A p` run eight springs at a time (AVX-512 or AVX2 where the CPU has them), and the
//! conjugate-gradient vectors stored as structure of arrays too.
//!
//! On a lattice every spring joins `p` and `p + δ` for one of a few offsets `δ`
//! (`physics::stencil`). With `B_δ[p] = dt D_s + dt² K_s` the symmetric 3×3 block of the spring
//! `(p, p + δ)` (zero where there is none, kg), the product of the textbook's `System::apply`
//! is, per particle `q`,
//!
//! ```text
//! (A p)_q = (m_q + dt c) p_q + Σ_δ [ B_δ[q] (p_q - p_{q+δ})  -  B_δ[q-δ] (p_{q-δ} - p_q) ]
//! ```
//! where `p` is a velocity change (m/s), `m` the mass (kg) and `c` the drag (N·s/m). Each chunk of
//! eight particles gathers its own terms (a spring's block product is computed for each of its
//! two ends), so no chunk writes another's values and the loops have no scattered stores. The
//! diagonal blocks and the right-hand side are gathered the same way from the springs' blocks
//! and their `dt² K_s (v_b - v_a)`. The arrays carry a zero margin of at least the largest `δ`
//! before and after the particles, so the chunks near either end need no special case.
//!
//! Without colliders the assembly also sums the force `f_n` (weight, drag and the springs' forces
//! from the lengths and directions the blocks need), so the step has no force pass of its own;
//! with colliders `f_n` comes from `forces` (the contact forces depend on the total). The
//! conjugate-gradient loop does one pass for `A p` (with `pᵀ A p` summed in it) and one for the
//! updates of `Δv`, `r`, `z = P⁻¹ r` and their dot products, then the new direction. The
//! constraint impulses need `(A Δv - b)_i` only at the constrained particles: their rows alone
//! ([`Lattice::row_residual`]). The energy guard's elastic energy is summed by offset group too
//! ([`Lattice::elastic_energy`]).
//!
//! The sums run in another order than the spring-list loops, so the matrix and the solution
//! agree with the textbook system to rounding, not bit for bit (the solve stops at the same
//! relative residual).
//!
//! **The blocks as four numbers.** Each spring's block is a multiple of the identity plus a
//! rank-one term along the spring,
//!
//! ```text
//! B = dt D_s + dt² K_s = (dt k_d + dt² k (1 - t)) n nᵀ + dt² k t I = c I + u uᵀ
//! c = dt² k t,   u = √(dt k_d + dt² k (1 - t)) n,   t = max(0, 1 - L0/L)
//! B d = c d + (u·d) u
//! ```
//! where `c` is in kg, `u` in √kg and `d` any velocity (m/s); the square root is real because
//! `k, k_d ≥ 0` and `0 ≤ t < 1` ([`usable`]). So a block is stored as four numbers instead of
//! its six entries: the product reads two thirds of the block data it read before (145 kB
//! instead of 217 kB for the 25 × 25 cloth, more than the first-level cache holds), and its
//! loads, not its arithmetic, set its speed: a variant with a fifth fewer operations and a few
//! more loads (the diagonal blocks summed once) was 6 % slower. Measured on 3 s of
//! `cloth-spheres` at dt = 5 ms: one product 2.8 µs → 2.25 µs, the run 14 % less time
//! (docs/performance.md). The matrix is the same to rounding.
//!
//! **The seam of the hot loops.** The product, the conjugate-gradient update passes and the
//! assembly's loops read and write through addresses taken once before each loop, without a
//! bounds check per load: each function asserts once, at its top, that every array has the
//! length the indices need (`front + q ± δ` with `δ ≤ front`, plus `LANES`). With a check per
//! load (an index comparison, and each array's address loaded again after every store), `perf`
//! put about 30 % of the conjugate gradients' samples on index arithmetic; without, 3 s of
//! `cloth-spheres` take about 9 % less CPU time (docs/performance.md). The arithmetic is unchanged, so the results are the same
//! bit for bit (a test compares the product with the same formula written with checked loads).
//! The blocks of one offset group are one array (entry `e` at `e len + p`), one address per
//! group in the product.
//!
//! **Aligned arrays.** Every array starts a 64-byte cache line ([`Aligned`]) and every length
//! and margin is a multiple of `LANES`, so the chunk at a particle index is one line, one
//! aligned load (the blocks and `p` at the chunk itself; those at `q ± δ` still span two
//! lines). A `Vec<f64>` starts wherever the allocator puts it, usually mid-line, and then every
//! load spans two. Measured (one thread, interleaved, 4 rounds, medians of CPU time):
//! implicit Euler on `jelly-bowl` at dt = 0.545 s for 190 steps 2.04 s → 1.84 s, on
//! `cube-plane` at dt = 0.05 s for 1000 steps 3.24 s → 2.91 s. The values are the same bits.

use glam::DVec3;

use super::implicit_constraint::{Constraint, Rows, SphereRows};
#[cfg(test)]
use crate::physics::lanes::Plain;
use crate::physics::lanes::{
    LANES, Lanes, first_lanes, lanes, load_chunk, load_padded, store_chunk,
};
use crate::physics::stencil::{Kernel, Stencil};

/// Whether the lattice system can hold `stencil`'s springs: every group's stiffness and
/// damping are at least zero, so that each block is `c I + u uᵀ` with real `u` (module docs,
/// "The blocks as four numbers"; scenes never have other springs, and the spring-list path
/// takes any that do).
pub(crate) fn usable(stencil: &Stencil) -> bool {
    stencil
        .group_views()
        .all(|g| g.stiffness >= 0.0 && g.damping >= 0.0)
}

/// The blocks of one offset group.
#[derive(Clone, Debug, Default)]
struct Blocks {
    delta: usize,
    /// `B_δ[p] = c I + u uᵀ` as its four numbers `c` (kg) and `u` (√kg), entry `e` (c, u_x,
    /// u_y, u_z) at index `e len + front + p` (one array, so that the product needs one address
    /// per group; module docs, "The blocks as four numbers").
    b: Aligned,
    /// `dt² K_s (v_b - v_a)` (N·s) at index `front + p`.
    kv: [Aligned; 3],
}

/// Where the assembly's forces `f_n` come from.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Forces<'a> {
    /// Computed elsewhere (N), per particle.
    Given(&'a [DVec3]),
    /// Weight `m g` and drag `-c v` with `gravity` (m/s²), and the springs' forces summed by the
    /// assembly: `f_a = (k (L - L0) + k_d (v_b - v_a)·n) n`, `f_b = -f_a`.
    Springs { gravity: DVec3 },
}

/// What the assembly reads per particle: masses (kg), inverse masses (1/kg; zero when pinned),
/// the drag (N·s/m), positions (m), velocities (m/s) and where `f_n` comes from.
struct Particles<'a> {
    mass: &'a [f64],
    inv_mass: &'a [f64],
    drag: f64,
    x: &'a [DVec3],
    v: &'a [DVec3],
    forces: Forces<'a>,
}

/// Three components as structure of arrays, indexed `front + particle`.
type Soa = [Aligned; 3];

/// The numbers stored per spring block: `c` and the three components of `u`.
const BLOCK: usize = 4;

/// The assembled system `A Δv = b` of one step and the conjugate-gradient vectors.
#[derive(Clone, Debug, Default)]
pub(crate) struct Lattice {
    /// Particles.
    n: usize,
    /// Zero margin before particle 0 (a multiple of `LANES`, at least the largest offset).
    front: usize,
    /// Length of every array.
    len: usize,
    kernel: Option<Kernel>,
    groups: Vec<Blocks>,
    /// The springs' elastic energy at the last assembly's positions (J).
    start_elastic: f64,
    /// The inverse diagonal blocks (xx, xy, xz, yy, yz, zz; 1/kg); zero in the margins.
    diag_inv: [Aligned; 6],
    /// `m + dt c` (kg); zero in the margins.
    mass: Aligned,
    /// 1 for a free particle, 0 for a pinned one and in the margins.
    free: Aligned,
    /// Positions (m) and velocities (m/s) of the step's start.
    x: Soa,
    v: Soa,
    /// The right-hand side `b = dt f_n + dt² ∂f/∂x v_n` (N·s).
    rhs: Soa,
    /// Δv (m/s) and the CG vectors r, p, A p, z.
    dv: Soa,
    r: Soa,
    p: Soa,
    ap: Soa,
    z: Soa,
}

impl Lattice {
    /// Sizes the arrays for `stencil` (no allocation when they already fit).
    fn resize(&mut self, stencil: &Stencil) {
        let n = stencil.particles();
        let front = stencil.reach().next_multiple_of(LANES);
        let len = front + n.next_multiple_of(LANES) + front + LANES;
        let groups = stencil.group_count();
        if self.n == n && self.len == len && self.groups.len() == groups {
            return;
        }
        let zeros = Aligned::zeros(len);
        let soa = || [zeros.clone(), zeros.clone(), zeros.clone()];
        self.n = n;
        self.front = front;
        self.len = len;
        self.groups = stencil
            .group_views()
            .map(|g| Blocks {
                delta: g.delta,
                b: Aligned::zeros(BLOCK * len),
                kv: soa(),
            })
            .collect();
        self.diag_inv = std::array::from_fn(|_| zeros.clone());
        self.mass = zeros.clone();
        self.free = zeros.clone();
        (self.x, self.v, self.rhs) = (soa(), soa(), soa());
        (self.dv, self.r, self.p, self.ap, self.z) = (soa(), soa(), soa(), soa(), soa());
    }

    /// Assembles the system of a step of `dt` (s) at `(x, v)` (the textbook's assembly loop, by
    /// offset group; see the module docs). `forces` is either the forces `f_n` (N) computed
    /// elsewhere, or [`Forces::Springs`]: weight and drag, with the spring forces summed here
    /// from the lengths and directions the blocks need anyway (no pass of its own; a model
    /// with colliders needs the other: its contact forces depend on the total).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn assemble(
        &mut self,
        stencil: &Stencil,
        mass: &[f64],
        inv_mass: &[f64],
        drag: f64,
        dt: f64,
        x: &[DVec3],
        v: &[DVec3],
        forces: Forces<'_>,
    ) {
        self.resize(stencil);
        self.kernel = Some(stencil.kernel());
        let n = self.n;
        assert!(mass.len() == n && inv_mass.len() == n && x.len() == n && v.len() == n);
        let particles = Particles {
            mass,
            inv_mass,
            drag,
            x,
            v,
            forces,
        };
        assemble_on(stencil.kernel(), self, stencil, dt, &particles);
    }

    /// Preconditioned conjugate gradients, as the textbook's `System::solve`: writes Δv,
    /// starting from `start` when given, else from the last solve's Δv when `warm`, else from
    /// zero, with the constrained particles' normal components prescribed and the touched
    /// dynamic spheres' rows solved with them (`spheres`). Returns the iterations, the final
    /// relative residual and whether it reached `tolerance`.
    pub(crate) fn solve(
        &mut self,
        constraints: &[Constraint],
        tolerance: f64,
        max_iterations: u32,
        warm: bool,
        start: Option<&[DVec3]>,
        spheres: &mut SphereRows,
    ) -> (u32, f64, bool) {
        if let Some(start) = start {
            for (i, s) in start.iter().enumerate().take(self.n) {
                for c in 0..3 {
                    self.dv[c][self.front + i] = s[c];
                }
            }
        }
        let warm = warm || start.is_some();
        // `assemble` recorded the stencil's kernel.
        let kernel = self.kernel.unwrap_or(Kernel::Portable);
        solve_on(
            kernel,
            self,
            constraints,
            tolerance,
            max_iterations,
            warm,
            spheres,
        )
    }

    /// The inverse diagonal block of particle `i` (1/kg), the preconditioner's.
    pub(crate) fn diag_inv_block(&self, i: usize) -> glam::DMat3 {
        let k = self.front + i;
        let d = |e: usize| self.diag_inv[e][k];
        glam::DMat3::from_cols(
            DVec3::new(d(0), d(1), d(2)),
            DVec3::new(d(1), d(3), d(4)),
            DVec3::new(d(2), d(4), d(5)),
        )
    }

    /// The springs' elastic energy `Σ ½ k (|x_{p+δ} - x_p| - L0)²` (J) at `x` (m): the spring
    /// list's sum ([`crate::physics::energy`]) by offset group, eight springs at a time (equal
    /// to it up to rounding). Uses the position arrays as scratch.
    pub(crate) fn elastic_energy(&mut self, stencil: &Stencil, x: &[DVec3]) -> f64 {
        self.resize(stencil);
        for (i, xi) in x.iter().enumerate().take(self.n) {
            for c in 0..3 {
                self.x[c][self.front + i] = xi[c];
            }
        }
        elastic_on(stencil.kernel(), self, stencil)
    }

    /// The step's update from the solved `Δv` (m/s) on the free particles, into the state `x`
    /// (m) and `v` (m/s) and into the lattice's position and velocity arrays (as
    /// `implicit_euler::advance` writes it, the same numbers):
    ///
    /// ```text
    /// v_{n+1} = v_n + Δv,   x_{n+1} = x_n + dt v_{n+1}
    /// ```
    /// With `power`, returns the power of the springs' dampers and of the drag `c` (N·s/m) at
    /// the new state (W), as [`crate::physics::energy::dissipated_power`] writes it, summed by
    /// offset group (equal to it up to rounding); else zero.
    pub(crate) fn advance(
        &mut self,
        stencil: &Stencil,
        dt: f64,
        drag: f64,
        power: bool,
        x: &mut [DVec3],
        v: &mut [DVec3],
    ) -> f64 {
        assert!(x.len() == self.n && v.len() == self.n);
        // `assemble` recorded the stencil's kernel.
        let kernel = self.kernel.unwrap_or(Kernel::Portable);
        advance_on(kernel, self, stencil, dt, drag, power, x, v)
    }

    /// The springs' elastic energy `Σ ½ k (L - L0)²` (J) at the positions of the last assembly,
    /// summed with the lengths it computed (as [`Lattice::elastic_energy`] sums it).
    pub(crate) fn start_elastic(&self) -> f64 {
        self.start_elastic
    }

    /// Δv of the last solve (m/s), particle `i`.
    pub(crate) fn dv(&self, i: usize) -> DVec3 {
        let k = self.front + i;
        DVec3::new(self.dv[0][k], self.dv[1][k], self.dv[2][k])
    }

    /// Copies Δv into `out` (m/s).
    pub(crate) fn copy_dv(&self, out: &mut [DVec3]) {
        for (i, o) in out.iter_mut().enumerate().take(self.n) {
            *o = self.dv(i);
        }
    }

    /// `(A Δv - b)_i` (N·s) of the last solve for particle `i`, from its row of `A` alone (the
    /// constraint impulses need only the constrained particles' rows; module docs for the row).
    pub(crate) fn row_residual(&self, i: usize) -> DVec3 {
        let k = self.front + i;
        let get = |a: &Soa, j: usize| DVec3::new(a[0][j], a[1][j], a[2][j]);
        // The block `c I + u uᵀ` at index j times d.
        let len = self.len;
        let sym = |b: &[f64], j: usize, d: DVec3| {
            let e = |e: usize| b[e * len + j];
            let u = DVec3::new(e(1), e(2), e(3));
            e(0) * d + u.dot(d) * u
        };
        let p = get(&self.dv, k);
        let mut row = self.mass[k] * p;
        for g in &self.groups {
            row += sym(&g.b, k, p - get(&self.dv, k + g.delta));
            row -= sym(&g.b, k - g.delta, get(&self.dv, k - g.delta) - p);
        }
        self.free[k] * row - get(&self.rhs, k)
    }
}

/// `LANES` values of `a` from index `i`.
#[inline(always)]
fn at<V: Lanes>(a: &[f64], i: usize) -> V {
    V::load(lanes(a, i))
}

/// The springs from window index `i` to `j` (eight at a time): `d = x_j - x_i` (m) and
/// `L = |d|` (m), from the positions `x` (one array per component).
#[inline(always)]
fn spring_vector<V: Lanes>(x: &Soa, i: usize, j: usize) -> ([V; 3], V) {
    let d = [
        at::<V>(&x[0], j).sub(at(&x[0], i)),
        at::<V>(&x[1], j).sub(at(&x[1], i)),
        at::<V>(&x[2], j).sub(at(&x[2], i)),
    ];
    let length = d[0]
        .mul(d[0])
        .add(d[1].mul(d[1]))
        .add(d[2].mul(d[2]))
        .sqrt();
    (d, length)
}

/// Writes `value` to `a[i..i + LANES]`.
#[inline(always)]
fn put<V: Lanes>(a: &mut [f64], i: usize, value: V) {
    value.store((&mut a[i..i + LANES]).try_into().expect("a chunk"));
}

/// The symmetric block `b` (xx, xy, xz, yy, yz, zz) times `d`.
#[inline(always)]
fn sym_mul<V: Lanes>(b: &[V; 6], d: [V; 3]) -> [V; 3] {
    [
        b[0].mul(d[0]).add(b[1].mul(d[1])).add(b[2].mul(d[2])),
        b[1].mul(d[0]).add(b[3].mul(d[1])).add(b[4].mul(d[2])),
        b[2].mul(d[0]).add(b[4].mul(d[1])).add(b[5].mul(d[2])),
    ]
}

/// The block `c I + u uᵀ` given as `[c, u_x, u_y, u_z]` times `d`: `c d + (u·d) u`.
#[inline(always)]
fn block_mul<V: Lanes>(b: [V; BLOCK], d: [V; 3]) -> [V; 3] {
    let [c, u0, u1, u2] = b;
    let along = u0.mul(d[0]).add(u1.mul(d[1])).add(u2.mul(d[2]));
    [
        c.mul(d[0]).add(along.mul(u0)),
        c.mul(d[1]).add(along.mul(u1)),
        c.mul(d[2]).add(along.mul(u2)),
    ]
}

/// The six entries of the block at index `i`.
#[inline(always)]
fn block<V: Lanes>(b: &[Aligned; 6], i: usize) -> [V; 6] {
    [
        at(&b[0], i),
        at(&b[1], i),
        at(&b[2], i),
        at(&b[3], i),
        at(&b[4], i),
        at(&b[5], i),
    ]
}

#[inline(always)]
fn triple<V: Lanes>(a: &Soa, i: usize) -> [V; 3] {
    [at(&a[0], i), at(&a[1], i), at(&a[2], i)]
}

#[inline(always)]
fn put_triple<V: Lanes>(a: &mut Soa, i: usize, value: [V; 3]) {
    for (c, v) in value.into_iter().enumerate() {
        put(&mut a[c], i, v);
    }
}

/// The particles into the lattice's arrays, eight at a time: `m + dt c`, whether free, `x`, `v`
/// and `b = dt f_n` (then `+ dt² ∂f/∂x v_n` from the blocks): `f_n` given, or weight and drag
/// here (and the springs' forces with the blocks). Past the last particle every lane is zero.
#[inline(always)]
fn load_particles<V: Lanes>(sys: &mut Lattice, dt: f64, particles: &Particles<'_>) {
    let Particles {
        mass,
        inv_mass,
        drag,
        x,
        v,
        forces,
    } = *particles;
    let (n, front) = (sys.n, sys.front);
    let (dt_v, drag_v, zero) = (V::splat(dt), V::splat(drag), V::zero());
    for q in (0..n).step_by(LANES) {
        let (i, count) = (front + q, (n - q).min(LANES));
        let m = load_padded::<V>(mass, q, count);
        put(
            &mut sys.mass,
            i,
            m.add(dt_v.mul(drag_v)).select(first_lanes(count)),
        );
        let w = load_padded::<V>(inv_mass, q, count);
        let free = V::splat(1.0).select(zero.less_than(w) | w.less_than(zero));
        put(&mut sys.free, i, free);
        let (xq, vq) = (
            load_chunk::<V>(&x[q..], count),
            load_chunk::<V>(&v[q..], count),
        );
        // Written out, not with `from_fn`: its closure would not be inlined (nor the AVX-512
        // operations inside it).
        let b = match forces {
            Forces::Given(f) => load_chunk::<V>(&f[q..], count),
            Forces::Springs { gravity } => [
                m.mul(V::splat(gravity.x)).sub(drag_v.mul(vq[0])),
                m.mul(V::splat(gravity.y)).sub(drag_v.mul(vq[1])),
                m.mul(V::splat(gravity.z)).sub(drag_v.mul(vq[2])),
            ],
        };
        for c in 0..3 {
            put(&mut sys.x[c], i, xq[c]);
            put(&mut sys.v[c], i, vq[c]);
            put(&mut sys.rhs[c], i, dt_v.mul(b[c]));
        }
    }
}

/// The assembly: the particles' arrays, the springs' blocks and `dt² K_s (v_b - v_a)` group by
/// group, then the diagonal blocks (inverted) and the right-hand side gathered particle by
/// particle.
#[inline(always)]
fn assemble_body<V: Lanes>(
    sys: &mut Lattice,
    stencil: &Stencil,
    dt: f64,
    particles: &Particles<'_>,
) {
    load_particles::<V>(sys, dt, particles);
    let springs = matches!(particles.forces, Forces::Springs { .. });
    let (front, len) = (sys.front, sys.len);
    let dt2 = dt * dt;
    let (one, zero) = (V::splat(1.0), V::zero());
    let mut elastic = 0.0;
    for (blocks, g) in sys.groups.iter_mut().zip(stencil.group_views()) {
        let mut stretch2 = V::zero();
        let (k_dt2, kd_dt) = (V::splat(g.stiffness * dt2), V::splat(g.damping * dt));
        let k_dt = V::splat(g.stiffness * dt);
        // The loop reads and writes through addresses taken here, without a bounds check per
        // load (as `apply`): every index is `front + p (+ δ)` with `p < starts ≤ n`, `δ ≤ front`.
        assert!(g.delta <= front && g.starts <= sys.n);
        assert!(g.rest_length.len() >= g.starts.next_multiple_of(LANES));
        assert!(blocks.b.len() == BLOCK * len && blocks.kv.iter().all(|k| k.len() == len));
        assert!(sys.x.iter().chain(&sys.v).all(|a| a.len() == len));
        let (x, v) = (soa_ptrs(&sys.x), soa_ptrs(&sys.v));
        let (b, rest) = (blocks.b.as_mut_ptr(), g.rest_length.as_ptr());
        let kv = [
            blocks.kv[0].as_mut_ptr(),
            blocks.kv[1].as_mut_ptr(),
            blocks.kv[2].as_mut_ptr(),
        ];
        for p in (0..g.starts).step_by(LANES) {
            // SAFETY (every raw load and store in this loop): the asserts above.
            let (x_i, x_j, v_i, v_j, rest_p) = unsafe {
                let (i, j) = (front + p, front + p + g.delta);
                (
                    raw_triple::<V>(x, i),
                    raw_triple::<V>(x, j),
                    raw_triple::<V>(v, i),
                    raw_triple::<V>(v, j),
                    raw::<V>(rest, p),
                )
            };
            let i = front + p;
            let d = [x_j[0].sub(x_i[0]), x_j[1].sub(x_i[1]), x_j[2].sub(x_i[2])];
            let length = d[0]
                .mul(d[0])
                .add(d[1].mul(d[1]))
                .add(d[2].mul(d[2]))
                .sqrt();
            // n = d / L; a zero-length spring gets no block (as in the textbook loop).
            let keep = g.present[p / LANES] & zero.less_than(length);
            let inv = one.div(length).select(keep);
            let n = [d[0].mul(inv), d[1].mul(inv), d[2].mul(inv)];
            // K = k [n nᵀ + t (I - n nᵀ)], t = max(0, 1 - L0/L); D = k_d n nᵀ;
            // B = dt D + dt² K = (dt k_d + dt² k (1 - t)) n nᵀ + dt² k t I = c I + u uᵀ,
            // c = dt² k t, u = √(dt k_d + dt² k (1 - t)) n (k, k_d ≥ 0: `usable`).
            let t = one.sub(rest_p.mul(inv));
            let t = t.where_positive(t);
            let c_nn = kd_dt.add(k_dt2.mul(one.sub(t)));
            let c_id = k_dt2.mul(t);
            let root = c_nn.sqrt();
            let entries = [c_id, root.mul(n[0]), root.mul(n[1]), root.mul(n[2])];
            for (e, value) in entries.into_iter().enumerate() {
                // SAFETY: see the loop's start.
                unsafe {
                    value
                        .select(keep)
                        .store(&mut *b.add(e * len + i).cast::<[f64; LANES]>())
                };
            }
            // dt² K (v_b - v_a) = dt² k ((1 - t) n (n·dv) + t dv).
            let dv = [v_j[0].sub(v_i[0]), v_j[1].sub(v_i[1]), v_j[2].sub(v_i[2])];
            let along = n[0].mul(dv[0]).add(n[1].mul(dv[1])).add(n[2].mul(dv[2]));
            let s = one.sub(t).mul(along);
            // With `springs`: + dt f_a = dt (k (L - L0) + k_d (v_b - v_a)·n) n, which rows a
            // and b get with the same signs as dt² K (v_b - v_a).
            let f_dt = if springs {
                k_dt.mul(length.sub(rest_p)).add(kd_dt.mul(along))
            } else {
                zero
            };
            for c in 0..3 {
                let kv_c = k_dt2.mul(s.mul(n[c]).add(t.mul(dv[c]))).add(f_dt.mul(n[c]));
                // SAFETY: see the loop's start.
                unsafe {
                    kv_c.select(keep)
                        .store(&mut *kv[c].add(i).cast::<[f64; LANES]>())
                };
            }
            // ½ k (L - L0)², as `elastic_body` sums it.
            let stretch = length.sub(rest_p).select(g.present[p / LANES]);
            stretch2 = stretch2.add(stretch.mul(stretch));
        }
        elastic += 0.5 * g.stiffness * sum_lanes(stretch2);
    }
    sys.start_elastic = elastic;
    // Per particle: A_qq = (m + dt c) I + Σ (B_δ[q] + B_δ[q-δ]); b_q += Σ (kv_δ[q] - kv_δ[q-δ]).
    // Read without a bounds check per load (as `apply`): indices `front + q ± δ`, `δ ≤ front`.
    assert!(
        sys.groups
            .iter()
            .all(|g| g.delta <= front && g.b.len() == BLOCK * len)
    );
    assert!(
        sys.groups
            .iter()
            .all(|g| g.kv.iter().all(|k| k.len() == len))
    );
    for q in (0..sys.n.next_multiple_of(LANES)).step_by(LANES) {
        let i = front + q;
        let m: V = at(&sys.mass, i);
        let mut a = [m, zero, zero, m, zero, m];
        let mut b = triple::<V>(&sys.rhs, i);
        for g in &sys.groups {
            // SAFETY: the asserts above.
            let (here, before, kv_here, kv_before) = unsafe {
                let (blocks, kv) = (g.b.as_ptr(), soa_ptrs(&g.kv));
                (
                    raw_block::<V>(blocks, len, i),
                    raw_block::<V>(blocks, len, i - g.delta),
                    raw_triple::<V>(kv, i),
                    raw_triple::<V>(kv, i - g.delta),
                )
            };
            for block in [here, before] {
                let [c, u0, u1, u2] = block;
                a[0] = a[0].add(c).add(u0.mul(u0));
                a[1] = a[1].add(u0.mul(u1));
                a[2] = a[2].add(u0.mul(u2));
                a[3] = a[3].add(c).add(u1.mul(u1));
                a[4] = a[4].add(u1.mul(u2));
                a[5] = a[5].add(c).add(u2.mul(u2));
            }
            for c in 0..3 {
                b[c] = b[c].add(kv_here[c]).sub(kv_before[c]);
            }
        }
        put_triple(&mut sys.rhs, i, b);
        // The inverse of the symmetric block by cofactors; zero past the last particle.
        let [xx, xy, xz, yy, yz, zz] = a;
        let c_xx = yy.mul(zz).sub(yz.mul(yz));
        let c_xy = xz.mul(yz).sub(xy.mul(zz));
        let c_xz = xy.mul(yz).sub(xz.mul(yy));
        let det = xx.mul(c_xx).add(xy.mul(c_xy)).add(xz.mul(c_xz));
        let real = zero.less_than(m);
        let inv_det = one.div(det).select(real);
        let inverse = [
            c_xx,
            c_xy,
            c_xz,
            xx.mul(zz).sub(xz.mul(xz)),
            xy.mul(xz).sub(xx.mul(yz)),
            xx.mul(yy).sub(xy.mul(xy)),
        ];
        for (d, e) in sys.diag_inv.iter_mut().zip(inverse) {
            put(d, i, e.mul(inv_det));
        }
    }
}

/// `Σ ½ k (L - L0)²` over the groups' springs at the positions in `sys.x`.
#[inline(always)]
fn elastic_body<V: Lanes>(sys: &Lattice, stencil: &Stencil) -> f64 {
    let front = sys.front;
    let mut total = 0.0;
    for g in stencil.group_views() {
        let mut sum = V::zero();
        for p in (0..g.starts).step_by(LANES) {
            let (i, j) = (front + p, front + p + g.delta);
            let (_, length) = spring_vector::<V>(&sys.x, i, j);
            let stretch = length
                .sub(at(g.rest_length, p))
                .select(g.present[p / LANES]);
            sum = sum.add(stretch.mul(stretch));
        }
        total += 0.5 * g.stiffness * sum_lanes(sum);
    }
    total
}

/// [`Lattice::advance`]: the update eight particles at a time, then the dissipated power from
/// the new arrays.
#[inline(always)]
fn advance_body<V: Lanes>(
    sys: &mut Lattice,
    stencil: &Stencil,
    dt: f64,
    drag: f64,
    power: bool,
    x: &mut [DVec3],
    v: &mut [DVec3],
) -> f64 {
    let (n, front) = (sys.n, sys.front);
    let dt_v = V::splat(dt);
    let mut drag_sum = V::zero();
    for q in (0..n).step_by(LANES) {
        let i = front + q;
        let free = V::zero().less_than(at::<V>(&sys.free, i));
        let (dv, mut vq, mut xq) = (
            triple::<V>(&sys.dv, i),
            triple::<V>(&sys.v, i),
            triple::<V>(&sys.x, i),
        );
        for c in 0..3 {
            vq[c] = vq[c].add(dv[c]).blend(vq[c], free);
            xq[c] = xq[c].add(dt_v.mul(vq[c])).blend(xq[c], free);
        }
        put_triple(&mut sys.v, i, vq);
        put_triple(&mut sys.x, i, xq);
        let squared = vq[0].mul(vq[0]).add(vq[1].mul(vq[1])).add(vq[2].mul(vq[2]));
        drag_sum = drag_sum.add(squared.select(free));
        let count = (n - q).min(LANES);
        store_chunk(xq, &mut x[q..], count);
        store_chunk(vq, &mut v[q..], count);
    }
    if !power {
        return 0.0;
    }
    // Σ k_d ((v_b - v_a)·n)², n = d / L, over the springs of nonzero length.
    let mut dampers = 0.0;
    for g in stencil.group_views().filter(|g| g.damping != 0.0) {
        let mut sum = V::zero();
        for p in (0..g.starts).step_by(LANES) {
            let (i, j) = (front + p, front + p + g.delta);
            let (d, length) = spring_vector::<V>(&sys.x, i, j);
            let (vi, vj) = (triple::<V>(&sys.v, i), triple::<V>(&sys.v, j));
            let along = vj[0]
                .sub(vi[0])
                .mul(d[0])
                .add(vj[1].sub(vi[1]).mul(d[1]))
                .add(vj[2].sub(vi[2]).mul(d[2]));
            let keep = g.present[p / LANES] & V::zero().less_than(length);
            let rate = along.div(length).select(keep);
            sum = sum.add(rate.mul(rate));
        }
        dampers += g.damping * sum_lanes(sum);
    }
    dampers + drag * sum_lanes(drag_sum)
}

mod aligned;
mod contacts;
mod solve;
#[cfg(test)]
mod tests;

use aligned::Aligned;
pub(crate) use contacts::inside_spheres;
use solve::{raw, raw_block, raw_triple, soa_ptrs, solve_on, sum_lanes};

on_lanes!(
    assemble_on(kernel),
    assemble_body,
    (sys: &mut Lattice, stencil: &Stencil, dt: f64, particles: &Particles<'_>) -> ()
);
on_lanes!(
    advance_on(kernel),
    advance_body,
    (
        sys: &mut Lattice,
        stencil: &Stencil,
        dt: f64,
        drag: f64,
        power: bool,
        x: &mut [DVec3],
        v: &mut [DVec3]
    ) -> f64
);
on_lanes!(
    elastic_on(kernel),
    elastic_body,
    (sys: &Lattice, stencil: &Stencil) -> f64
);
