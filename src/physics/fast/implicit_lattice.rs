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

use glam::DVec3;

use super::implicit_constraint::Constraint;
#[cfg(target_arch = "x86_64")]
use crate::physics::lanes::{Avx2, Avx512};
use crate::physics::lanes::{
    LANES, Lanes, Plain, first_lanes, lanes, load_chunk, load_padded, store_chunk,
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
    b: Vec<f64>,
    /// `dt² K_s (v_b - v_a)` (N·s) at index `front + p`.
    kv: [Vec<f64>; 3],
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
type Soa = [Vec<f64>; 3];

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
    diag_inv: [Vec<f64>; 6],
    /// `m + dt c` (kg); zero in the margins.
    mass: Vec<f64>,
    /// 1 for a free particle, 0 for a pinned one and in the margins.
    free: Vec<f64>,
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
        let zeros = vec![0.0; len];
        let soa = || [zeros.clone(), zeros.clone(), zeros.clone()];
        self.n = n;
        self.front = front;
        self.len = len;
        self.groups = stencil
            .group_views()
            .map(|g| Blocks {
                delta: g.delta,
                b: vec![0.0; BLOCK * len],
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
    /// zero, with the constrained particles' normal components prescribed. Returns the
    /// iterations, the final relative residual and whether it reached `tolerance`.
    pub(crate) fn solve(
        &mut self,
        constraints: &[Constraint],
        tolerance: f64,
        max_iterations: u32,
        warm: bool,
        start: Option<&[DVec3]>,
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
        solve_on(kernel, self, constraints, tolerance, max_iterations, warm)
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
fn block<V: Lanes>(b: &[Vec<f64>; 6], i: usize) -> [V; 6] {
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

/// The particles that `x + dt (v + Δv)` puts inside one of the spheres `ends` (centre in m,
/// radius in m), in order, into `out`: eight particles at a time, with the same arithmetic as
/// the contact search's test (`|x̃ - c|² < r²`, in `implicit_euler::nearest_contact`), so that
/// the search needs to look only at these. `x` (m), `v` and `dv` (m/s) have one entry per
/// particle.
pub(crate) fn inside_spheres(
    kernel: Kernel,
    x: &[DVec3],
    v: &[DVec3],
    dv: &[DVec3],
    dt: f64,
    ends: &[(DVec3, f64)],
    out: &mut Vec<usize>,
) {
    assert!(v.len() == x.len() && dv.len() == x.len());
    out.clear();
    inside_on(kernel, x, v, dv, dt, ends, out);
}

#[inline(always)]
fn inside_body<V: Lanes>(
    x: &[DVec3],
    v: &[DVec3],
    dv: &[DVec3],
    dt: f64,
    ends: &[(DVec3, f64)],
    out: &mut Vec<usize>,
) {
    let dt_v = V::splat(dt);
    for q in (0..x.len()).step_by(LANES) {
        let count = (x.len() - q).min(LANES);
        let (xq, vq, dq) = (
            load_chunk::<V>(&x[q..], count),
            load_chunk::<V>(&v[q..], count),
            load_chunk::<V>(&dv[q..], count),
        );
        let end = [
            xq[0].add(dt_v.mul(vq[0].add(dq[0]))),
            xq[1].add(dt_v.mul(vq[1].add(dq[1]))),
            xq[2].add(dt_v.mul(vq[2].add(dq[2]))),
        ];
        let mut inside = 0u8;
        for &(center, radius) in ends {
            let d = [
                end[0].sub(V::splat(center.x)),
                end[1].sub(V::splat(center.y)),
                end[2].sub(V::splat(center.z)),
            ];
            let distance2 = d[0].mul(d[0]).add(d[1].mul(d[1])).add(d[2].mul(d[2]));
            inside |= distance2.less_than(V::splat(radius * radius));
        }
        let mut bits = inside & first_lanes(count);
        while bits != 0 {
            out.push(q + bits.trailing_zeros() as usize);
            bits &= bits - 1;
        }
    }
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

/// `out = A p` (see the module docs), zero at pinned particles and in the margins; returns
/// `p·out` (the conjugate-gradient step's `pᵀ A p`, summed in the same pass).
///
/// The conjugate gradients spend most of their time here, so the loop reads its arrays through
/// addresses taken once before it, without a bounds check per load: the checks are made once,
/// for the whole loop, by the asserts at the top (every index is `front + q ± δ` with
/// `δ ≤ front` and `front + q + δ + LANES ≤ len`). The arithmetic is the formula's, in its
/// order: a test compares it bit for bit with the same product written with checked loads.
#[inline(always)]
fn apply<V: Lanes>(sys: &Lattice, p: &Soa, out: &mut Soa) -> f64 {
    let (front, len, end) = (
        sys.front,
        sys.len,
        sys.front + sys.n.next_multiple_of(LANES),
    );
    assert!(p.iter().chain(out.iter()).all(|a| a.len() == len));
    assert!(sys.mass.len() == len && sys.free.len() == len && end + front + LANES <= len);
    assert!(
        sys.groups
            .iter()
            .all(|g| g.delta <= front && g.b.len() == BLOCK * len)
    );
    let p = [p[0].as_ptr(), p[1].as_ptr(), p[2].as_ptr()];
    let out = [
        out[0].as_mut_ptr(),
        out[1].as_mut_ptr(),
        out[2].as_mut_ptr(),
    ];
    let (mass, free) = (sys.mass.as_ptr(), sys.free.as_ptr());
    let mut p_out = V::zero();
    for i in (front..end).step_by(LANES) {
        // SAFETY (every load and store below): `i - δ ≥ 0` and `i + δ + LANES ≤ len` for every
        // group's δ, and every array has `len` values (the asserts above); `out` is not `p`.
        unsafe {
            let pq = raw_triple::<V>(p, i);
            let m: V = raw(mass, i);
            let mut acc = [m.mul(pq[0]), m.mul(pq[1]), m.mul(pq[2])];
            for g in &sys.groups {
                let b = g.b.as_ptr();
                let ahead = raw_triple::<V>(p, i + g.delta);
                let behind = raw_triple::<V>(p, i - g.delta);
                let y1 = block_mul(
                    raw_block::<V>(b, len, i),
                    [
                        pq[0].sub(ahead[0]),
                        pq[1].sub(ahead[1]),
                        pq[2].sub(ahead[2]),
                    ],
                );
                let y2 = block_mul(
                    raw_block::<V>(b, len, i - g.delta),
                    [
                        behind[0].sub(pq[0]),
                        behind[1].sub(pq[1]),
                        behind[2].sub(pq[2]),
                    ],
                );
                for c in 0..3 {
                    acc[c] = acc[c].add(y1[c]).sub(y2[c]);
                }
            }
            let free: V = raw(free, i);
            let y = [acc[0].mul(free), acc[1].mul(free), acc[2].mul(free)];
            p_out = p_out
                .add(pq[0].mul(y[0]))
                .add(pq[1].mul(y[1]))
                .add(pq[2].mul(y[2]));
            for c in 0..3 {
                y[c].store(&mut *out[c].add(i).cast::<[f64; LANES]>());
            }
        }
    }
    sum_lanes(p_out)
}

/// The addresses of a vector's three components.
fn soa_ptrs(a: &Soa) -> [*const f64; 3] {
    [a[0].as_ptr(), a[1].as_ptr(), a[2].as_ptr()]
}

/// `LANES` values from `a + i`.
///
/// # Safety
/// `a + i .. a + i + LANES` must be inside one array of `f64`.
#[inline(always)]
unsafe fn raw<V: Lanes>(a: *const f64, i: usize) -> V {
    // SAFETY: as the caller promises; `[f64; LANES]` has the alignment of `f64`.
    V::load(unsafe { &*a.add(i).cast::<[f64; LANES]>() })
}

/// The three components at `i` of a vector whose components start at `a`.
///
/// # Safety
/// As [`raw`], for each component.
#[inline(always)]
unsafe fn raw_triple<V: Lanes>(a: [*const f64; 3], i: usize) -> [V; 3] {
    // SAFETY: as the caller promises.
    unsafe { [raw(a[0], i), raw(a[1], i), raw(a[2], i)] }
}

/// The four numbers `c, u` at `i` of a group's blocks (entry `e` at `b + e len`).
///
/// # Safety
/// As [`raw`], for each entry.
#[inline(always)]
unsafe fn raw_block<V: Lanes>(b: *const f64, len: usize, i: usize) -> [V; BLOCK] {
    // SAFETY: as the caller promises.
    unsafe {
        [
            raw(b, i),
            raw(b, len + i),
            raw(b, 2 * len + i),
            raw(b, 3 * len + i),
        ]
    }
}

/// The four numbers at `i` of a group's blocks (entry `e` at index `e len + i`), checked.
#[cfg(test)]
fn group_block<V: Lanes>(b: &[f64], len: usize, i: usize) -> [V; BLOCK] {
    [
        at(b, i),
        at(b, len + i),
        at(b, 2 * len + i),
        at(b, 3 * len + i),
    ]
}

/// The conjugate-gradient step's pass after the product: `Δv += α p`, `r -= α S A p`,
/// `z = P⁻¹ r`; returns `|r|²` and `r·z` (summed in lanes, in a fixed order). `dv_r_z` are Δv,
/// r and z. Reads through addresses without a bounds check per load, like [`apply`].
#[inline(always)]
fn descend<V: Lanes>(
    sys: &Lattice,
    alpha: f64,
    dv_r_z: [&mut Soa; 3],
    p: &Soa,
    ap: &Soa,
) -> (f64, f64) {
    let (len, end) = (sys.len, sys.front + sys.n.next_multiple_of(LANES));
    let [dv, r, z] = dv_r_z;
    assert!(
        [&*dv, &*r, &*z, p, ap]
            .iter()
            .all(|a| a.iter().all(|c| c.len() == len))
    );
    assert!(sys.diag_inv.iter().all(|d| d.len() == len) && end <= len);
    let ptrs = |a: &mut Soa| [a[0].as_mut_ptr(), a[1].as_mut_ptr(), a[2].as_mut_ptr()];
    let (dv, r, z) = (ptrs(dv), ptrs(r), ptrs(z));
    let p = [p[0].as_ptr(), p[1].as_ptr(), p[2].as_ptr()];
    let ap = [ap[0].as_ptr(), ap[1].as_ptr(), ap[2].as_ptr()];
    let d = &sys.diag_inv;
    let d = [
        d[0].as_ptr(),
        d[1].as_ptr(),
        d[2].as_ptr(),
        d[3].as_ptr(),
        d[4].as_ptr(),
        d[5].as_ptr(),
    ];
    let alpha = V::splat(alpha);
    let (mut rr, mut rz) = (V::zero(), V::zero());
    for i in (sys.front..end).step_by(LANES) {
        // SAFETY: `i + LANES ≤ end ≤ len`, and every array has `len` values (asserts above).
        unsafe {
            let mut rn = [V::zero(); 3];
            for c in 0..3 {
                let next = raw::<V>(dv[c], i).add(alpha.mul(raw(p[c], i)));
                next.store(&mut *dv[c].add(i).cast::<[f64; LANES]>());
                rn[c] = raw::<V>(r[c], i).sub(alpha.mul(raw(ap[c], i)));
                rn[c].store(&mut *r[c].add(i).cast::<[f64; LANES]>());
            }
            let block = [
                raw(d[0], i),
                raw(d[1], i),
                raw(d[2], i),
                raw(d[3], i),
                raw(d[4], i),
                raw(d[5], i),
            ];
            let y = sym_mul::<V>(&block, rn);
            for c in 0..3 {
                y[c].store(&mut *z[c].add(i).cast::<[f64; LANES]>());
            }
            rr = rr
                .add(rn[0].mul(rn[0]))
                .add(rn[1].mul(rn[1]))
                .add(rn[2].mul(rn[2]));
            rz = rz
                .add(rn[0].mul(y[0]))
                .add(rn[1].mul(y[1]))
                .add(rn[2].mul(y[2]));
        }
    }
    (sum_lanes(rr), sum_lanes(rz))
}

/// The new direction `p = z + β p`, without a bounds check per load, like [`apply`].
#[inline(always)]
fn redirect<V: Lanes>(sys: &Lattice, beta: f64, z: &Soa, p: &mut Soa) {
    let (len, end) = (sys.len, sys.front + sys.n.next_multiple_of(LANES));
    assert!(z.iter().chain(p.iter()).all(|a| a.len() == len) && end <= len);
    let beta = V::splat(beta);
    for (p, z) in p.iter_mut().zip(z) {
        let (p, z) = (p.as_mut_ptr(), z.as_ptr());
        for i in (sys.front..end).step_by(LANES) {
            // SAFETY: `i + LANES ≤ end ≤ len` values in both arrays (assert above).
            unsafe {
                let next = raw::<V>(z, i).add(beta.mul(raw(p, i)));
                next.store(&mut *p.add(i).cast::<[f64; LANES]>());
            }
        }
    }
}

/// The sum of the lanes of `v`, in a fixed order.
#[inline(always)]
fn sum_lanes<V: Lanes>(v: V) -> f64 {
    let mut values = [0.0; LANES];
    v.store(&mut values);
    values.iter().sum()
}

/// `Σ a·b` over all particles, in lanes, added in a fixed order.
#[inline(always)]
fn dot<V: Lanes>(sys: &Lattice, a: &Soa, b: &Soa) -> f64 {
    let mut sum = V::zero();
    for q in (0..sys.n.next_multiple_of(LANES)).step_by(LANES) {
        let i = sys.front + q;
        for c in 0..3 {
            sum = sum.add(at::<V>(&a[c], i).mul(at(&b[c], i)));
        }
    }
    let mut values = [0.0; LANES];
    sum.store(&mut values);
    values.iter().sum()
}

/// `z = P⁻¹ r` with the inverse diagonal blocks.
#[inline(always)]
fn precondition<V: Lanes>(sys: &Lattice, r: &Soa, z: &mut Soa) {
    for q in (0..sys.n.next_multiple_of(LANES)).step_by(LANES) {
        let i = sys.front + q;
        let y = sym_mul(&block::<V>(&sys.diag_inv, i), triple(r, i));
        put_triple(z, i, y);
    }
}

/// `S v`: removes the constrained normal components.
fn filter(front: usize, constraints: &[Constraint], v: &mut Soa) {
    for c in constraints {
        let k = front + c.i;
        let n = c.normal;
        let along = v[0][k] * n.x + v[1][k] * n.y + v[2][k] * n.z;
        v[0][k] -= along * n.x;
        v[1][k] -= along * n.y;
        v[2][k] -= along * n.z;
    }
}

/// The textbook's preconditioned conjugate gradients on the lattice system.
#[inline(always)]
fn solve_body<V: Lanes>(
    sys: &mut Lattice,
    constraints: &[Constraint],
    tolerance: f64,
    max_iterations: u32,
    warm: bool,
) -> (u32, f64, bool) {
    let (front, n) = (sys.front, sys.n);
    let chunks = || {
        (0..n.next_multiple_of(LANES))
            .step_by(LANES)
            .map(|q| front + q)
    };
    let mut dv = std::mem::take(&mut sys.dv);
    let mut r = std::mem::take(&mut sys.r);
    let mut p = std::mem::take(&mut sys.p);
    let mut ap = std::mem::take(&mut sys.ap);
    let mut z = std::mem::take(&mut sys.z);
    // Δv starts at z_0: the prescribed normal velocity changes, elsewhere zero or a warm
    // start; a warm start whose residual is not below |b| is dropped for zero.
    let mut warm = warm;
    let b_norm2 = loop {
        if !warm {
            for c in &mut dv {
                c.fill(0.0);
            }
        }
        for c in constraints {
            let k = front + c.i;
            let n = c.normal;
            let along = dv[0][k] * n.x + dv[1][k] * n.y + dv[2][k] * n.z;
            dv[0][k] += (c.dv_n - along) * n.x;
            dv[1][k] += (c.dv_n - along) * n.y;
            dv[2][k] += (c.dv_n - along) * n.z;
        }
        // r = S (b - A z_0), pinned rows zero; |b|² over the free particles.
        let _ = apply::<V>(sys, &dv, &mut ap);
        let mut b2 = V::zero();
        for i in chunks() {
            let free: V = at(&sys.free, i);
            // Written out, not with `map`: its closure would not be inlined (nor the AVX-512
            // operations inside it).
            let [b0, b1, b2_] = triple::<V>(&sys.rhs, i);
            let b = [b0.mul(free), b1.mul(free), b2_.mul(free)];
            let a = triple::<V>(&ap, i);
            b2 = b2
                .add(b[0].mul(b[0]))
                .add(b[1].mul(b[1]))
                .add(b[2].mul(b[2]));
            put_triple(&mut r, i, [b[0].sub(a[0]), b[1].sub(a[1]), b[2].sub(a[2])]);
        }
        let b_norm2 = {
            let mut values = [0.0; LANES];
            b2.store(&mut values);
            values.iter().sum::<f64>()
        };
        filter(front, constraints, &mut r);
        if warm && dot::<V>(sys, &r, &r) >= b_norm2 {
            warm = false;
            continue;
        }
        break b_norm2;
    };
    let mut outcome = (0, f64::NAN, false);
    if b_norm2.is_finite() {
        let tol2 = (tolerance * tolerance * b_norm2).max(f64::MIN_POSITIVE);
        precondition::<V>(sys, &r, &mut p);
        filter(front, constraints, &mut p);
        let mut rz = dot::<V>(sys, &r, &p);
        let mut r_norm2 = dot::<V>(sys, &r, &r);
        let mut iterations = 0;
        while r_norm2 > tol2 && iterations < max_iterations {
            // p ⊥ N at the constrained particles, so pᵀ S A p = pᵀ A p: the product's own sum.
            let p_ap = apply::<V>(sys, &p, &mut ap);
            filter(front, constraints, &mut ap);
            if p_ap.is_nan() || p_ap <= 0.0 {
                break;
            }
            // One pass: Δv += α p, r -= α S A p, |r|², z = P⁻¹ r and r·z (r = S r, so
            // r·S z = r·z: the filter of z can follow).
            let (r2, rz_new) = descend::<V>(sys, rz / p_ap, [&mut dv, &mut r, &mut z], &p, &ap);
            r_norm2 = r2;
            filter(front, constraints, &mut z);
            redirect::<V>(sys, rz_new / rz, &z, &mut p);
            rz = rz_new;
            iterations += 1;
        }
        let residual = if b_norm2 > 0.0 {
            (r_norm2 / b_norm2).sqrt()
        } else {
            0.0
        };
        outcome = (iterations, residual, r_norm2.is_finite() && r_norm2 <= tol2);
    }
    (sys.dv, sys.r, sys.p, sys.ap, sys.z) = (dv, r, p, ap, z);
    outcome
}

/// `$name(kernel, args…)`: the body generic over [`Lanes`] on `kernel`'s registers, through an
/// AVX-512 and an AVX2 instance, each compiled with its target feature so that the inlined
/// body runs on those registers. `kernel` must be one this CPU has, as a stencil's kernel
/// ([`Stencil::kernel`]) and [`Kernel::best`] are.
macro_rules! on_kernel {
    ($name:ident, $body:ident, ($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        #[allow(clippy::too_many_arguments)]
        fn $name(kernel: Kernel, $($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f")]
            #[allow(clippy::too_many_arguments)]
            fn avx512($($arg: $ty),*) -> $ret {
                $body::<Avx512>($($arg),*)
            }

            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            #[allow(clippy::too_many_arguments)]
            fn avx2($($arg: $ty),*) -> $ret {
                $body::<Avx2>($($arg),*)
            }

            match kernel {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the caller passes a kernel this CPU has (macro docs).
                Kernel::Avx512 => unsafe { avx512($($arg),*) },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as above.
                Kernel::Avx2 => unsafe { avx2($($arg),*) },
                _ => $body::<Plain>($($arg),*),
            }
        }
    };
}

on_kernel!(
    assemble_on,
    assemble_body,
    (sys: &mut Lattice, stencil: &Stencil, dt: f64, particles: &Particles<'_>) -> ()
);
on_kernel!(
    solve_on,
    solve_body,
    (
        sys: &mut Lattice,
        constraints: &[Constraint],
        tolerance: f64,
        max_iterations: u32,
        warm: bool
    ) -> (u32, f64, bool)
);
on_kernel!(
    inside_on,
    inside_body,
    (
        x: &[DVec3],
        v: &[DVec3],
        dv: &[DVec3],
        dt: f64,
        ends: &[(DVec3, f64)],
        out: &mut Vec<usize>
    ) -> ()
);
on_kernel!(
    advance_on,
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
on_kernel!(
    elastic_on,
    elastic_body,
    (sys: &Lattice, stencil: &Stencil) -> f64
);

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::physics::energy::dissipated_power;
    use crate::physics::forces::Model;
    use crate::physics::particles::State;
    use crate::random::XorShift64Star;
    use crate::scene::builder::Builder;
    use crate::scene::lattice::{ClothSpec, cloth};

    /// `out = A p` and `p·out` as [`apply`] computes them, with a bounds check on every load and
    /// store (the loop as it was written before the checks were hoisted).
    fn apply_checked<V: Lanes>(sys: &Lattice, p: &Soa, out: &mut Soa) -> f64 {
        let mut p_out = V::zero();
        for q in (0..sys.n.next_multiple_of(LANES)).step_by(LANES) {
            let i = sys.front + q;
            let pq = triple::<V>(p, i);
            let m: V = at(&sys.mass, i);
            let mut acc = [m.mul(pq[0]), m.mul(pq[1]), m.mul(pq[2])];
            for g in &sys.groups {
                let ahead = triple::<V>(p, i + g.delta);
                let behind = triple::<V>(p, i - g.delta);
                let y1 = block_mul(
                    group_block::<V>(&g.b, sys.len, i),
                    [
                        pq[0].sub(ahead[0]),
                        pq[1].sub(ahead[1]),
                        pq[2].sub(ahead[2]),
                    ],
                );
                let y2 = block_mul(
                    group_block::<V>(&g.b, sys.len, i - g.delta),
                    [
                        behind[0].sub(pq[0]),
                        behind[1].sub(pq[1]),
                        behind[2].sub(pq[2]),
                    ],
                );
                for c in 0..3 {
                    acc[c] = acc[c].add(y1[c]).sub(y2[c]);
                }
            }
            let free: V = at(&sys.free, i);
            let y = [acc[0].mul(free), acc[1].mul(free), acc[2].mul(free)];
            p_out = p_out
                .add(pq[0].mul(y[0]))
                .add(pq[1].mul(y[1]))
                .add(pq[2].mul(y[2]));
            put_triple(out, i, y);
        }
        sum_lanes(p_out)
    }

    /// The 2022 course cloth (25 × 25, corners pinned, drag 0.3 N·s/m), shaken.
    fn shaken_cloth() -> (Model, State) {
        let mut b = Builder::new();
        cloth(&mut b, &ClothSpec::course_2022());
        let (model, mut state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.3);
        let mut rng = XorShift64Star::new(1);
        let mut noise = || rng.symmetric();
        for (x, v) in state.x.iter_mut().zip(&mut state.v) {
            *x += 0.02 * DVec3::new(noise(), noise(), noise());
            *v = DVec3::new(noise(), noise(), noise());
        }
        (model, state)
    }

    /// The step of the assembled systems below (s).
    const DT: f64 = 0.005;

    /// [`shaken_cloth`], its stencil with `kernel`, and the system assembled for a step of
    /// [`DT`].
    fn assembled_on(kernel: Kernel) -> (Model, State, Stencil, Lattice) {
        let (model, state) = shaken_cloth();
        let stencil = model
            .stencil()
            .expect("a lattice")
            .clone()
            .with_kernel(kernel);
        let mut sys = Lattice::default();
        let forces = Forces::Springs {
            gravity: model.gravity,
        };
        sys.assemble(
            &stencil,
            &model.mass,
            &model.inv_mass,
            model.drag,
            DT,
            &state.x,
            &state.v,
            forces,
        );
        (model, state, stencil, sys)
    }

    /// [`assembled_on`] the fastest kernel here.
    fn assembled() -> (Lattice, Stencil) {
        let (_, _, stencil, sys) = assembled_on(Kernel::best());
        (sys, stencil)
    }

    fn field(sys: &Lattice, seed: u64) -> Soa {
        let mut rng = XorShift64Star::new(seed);
        let mut a: Soa = std::array::from_fn(|_| vec![0.0; sys.len]);
        for a in &mut a {
            for value in &mut a[sys.front..sys.front + sys.n] {
                *value = rng.symmetric();
            }
        }
        a
    }

    fn same_bits(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a == 0.0 && b == 0.0)
    }

    #[test]
    fn the_product_without_bounds_checks_is_the_checked_product_bit_for_bit() {
        let (sys, _) = assembled();
        assert_eq!(sys.groups.len(), 6, "the 2022 cloth has six offsets");
        let p = field(&sys, 1_000_000);
        let mut out_ref: Soa = std::array::from_fn(|_| vec![0.0; sys.len]);
        let sum_ref = apply_checked::<Plain>(&sys, &p, &mut out_ref);
        // Margins zero, as `resize` leaves them; NaN where the product must write.
        let mut out: Soa = std::array::from_fn(|_| vec![0.0; sys.len]);
        for c in &mut out {
            c[sys.front..sys.front + sys.n].fill(f64::NAN);
        }
        let sum = apply::<Plain>(&sys, &p, &mut out);
        assert!(same_bits(sum, sum_ref), "pᵀAp {sum} vs {sum_ref}");
        assert!(sum > 0.0, "A is positive definite: {sum}");
        for c in 0..3 {
            for i in 0..sys.len {
                assert!(
                    same_bits(out[c][i], out_ref[c][i]),
                    "(Ap)[{c}][{i}] {} vs {}",
                    out[c][i],
                    out_ref[c][i]
                );
            }
        }
        // Not all zero: the pinned corners are zero, the rest is not.
        let nonzero = (0..sys.n).filter(|&i| out[0][sys.front + i] != 0.0).count();
        assert_eq!(nonzero, sys.n - 4);
    }

    #[test]
    fn the_solve_leaves_the_residual_it_reports_on_every_kernel() {
        for kernel in Kernel::ALL {
            if !kernel.is_available() {
                continue;
            }
            let (mut sys, stencil) = assembled();
            let stencil = stencil.with_kernel(kernel);
            sys.kernel = Some(stencil.kernel());
            let (iterations, residual, converged) = sys.solve(&[], 1e-10, 1000, false, None);
            assert!(converged && residual <= 1e-10, "{kernel:?}: {residual}");
            assert!((10..1000).contains(&iterations), "{kernel:?}: {iterations}");
            // The residual row by row (each particle's own row of A, as the module docs write
            // it, not the product's pass).
            let (mut r2, mut b2) = (0.0, 0.0);
            for i in (0..sys.n).filter(|&i| sys.free[sys.front + i] != 0.0) {
                let k = sys.front + i;
                let b = DVec3::new(sys.rhs[0][k], sys.rhs[1][k], sys.rhs[2][k]);
                r2 += sys.row_residual(i).length_squared();
                b2 += b.length_squared();
            }
            let measured = (r2 / b2).sqrt();
            assert!(
                measured <= 2e-10,
                "{kernel:?}: |A Δv - b| / |b| = {measured:e}"
            );
        }
    }

    fn available() -> impl Iterator<Item = Kernel> {
        Kernel::ALL.into_iter().filter(|k| k.is_available())
    }

    #[test]
    fn the_assembly_copies_the_particles_and_leaves_the_margins_zero_on_every_kernel() {
        for kernel in available() {
            let (model, state, _, sys) = assembled_on(kernel);
            let n = state.x.len();
            assert_eq!(
                n % LANES,
                1,
                "the last chunk has one particle and seven empty lanes"
            );
            for k in 0..sys.len {
                let Some(i) = k.checked_sub(sys.front).filter(|&i| i < n) else {
                    for a in [&sys.mass, &sys.free, &sys.x[0], &sys.v[2], &sys.rhs[1]] {
                        assert_eq!(a[k], 0.0, "{kernel:?}: margin {k}");
                    }
                    continue;
                };
                let free = if model.inv_mass[i] != 0.0 { 1.0 } else { 0.0 };
                assert!(same_bits(sys.mass[k], model.mass[i] + DT * model.drag));
                assert!(same_bits(sys.free[k], free), "{kernel:?}: particle {i}");
                for c in 0..3 {
                    assert!(same_bits(sys.x[c][k], state.x[i][c]));
                    assert!(same_bits(sys.v[c][k], state.v[i][c]));
                }
            }
        }
    }

    #[test]
    fn the_update_is_the_textbook_update_and_its_power_the_spring_lists_on_every_kernel() {
        let dt = DT;
        for kernel in available() {
            let (model, state, stencil, mut sys) = assembled_on(kernel);
            // A Δv everywhere, the pinned corners too: the update must leave those alone.
            sys.dv = field(&sys, 9);
            let (mut x, mut v) = (state.x.clone(), state.v.clone());
            let power = sys.advance(&stencil, dt, model.drag, true, &mut x, &mut v);
            let mut expected = state.clone();
            for i in 0..x.len() {
                if model.inv_mass[i] != 0.0 {
                    expected.v[i] += sys.dv(i);
                    expected.x[i] += dt * expected.v[i];
                }
                assert!(
                    x[i].to_array()
                        .iter()
                        .zip(expected.x[i].to_array())
                        .all(|(a, b)| same_bits(*a, b))
                );
                assert!(
                    v[i].to_array()
                        .iter()
                        .zip(expected.v[i].to_array())
                        .all(|(a, b)| same_bits(*a, b))
                );
            }
            assert_eq!(x[0], state.x[0], "a pinned corner moved");
            let mut scratch = vec![DVec3::ZERO; x.len()];
            let textbook = dissipated_power(&model, &x, &v, &mut scratch).dampers_and_drag;
            assert!(
                (power - textbook).abs() <= 1e-12 * textbook && textbook > 0.0,
                "{kernel:?}: {power} W vs {textbook} W"
            );
            let without = sys.advance(&stencil, dt, model.drag, false, &mut x, &mut v);
            assert_eq!(without, 0.0);
        }
    }

    #[test]
    fn the_particles_inside_the_spheres_are_the_ones_the_scalar_test_finds_on_every_kernel() {
        let (_, state) = shaken_cloth();
        let dt = DT;
        let mut rng = XorShift64Star::new(3);
        let dv: Vec<DVec3> = (0..state.x.len())
            .map(|_| DVec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()))
            .collect();
        // Four spheres of the course's size on the cloth, one with its centre on a particle's end.
        let end = |i: usize| state.x[i] + dt * (state.v[i] + dv[i]);
        let ends = [
            (end(312), 0.5),
            (DVec3::new(-1.0, 0.1, -1.0), 0.5),
            (DVec3::new(1.2, -0.2, 0.9), 0.3),
            (DVec3::new(0.0, 5.0, 0.0), 0.5),
        ];
        let expected: Vec<usize> = (0..state.x.len())
            .filter(|&i| {
                ends.iter()
                    .any(|&(c, r)| (end(i) - c).length_squared() < r * r)
            })
            .collect();
        assert!(
            expected.len() > 20 && expected.len() < 300,
            "{}",
            expected.len()
        );
        for kernel in available() {
            let mut found = vec![7];
            inside_spheres(kernel, &state.x, &state.v, &dv, dt, &ends, &mut found);
            assert_eq!(found, expected, "{kernel:?}");
        }
    }
}
