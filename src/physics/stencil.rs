//! The stencil form of a lattice's springs: the same forces as the spring list, computed for
//! throughput.
//!
//! # Theory
//!
//! In a lattice (the jelly cube, the cloth, a rope) every spring joins particle `p` to particle
//! `p + δ` for one of a few index offsets `δ`, and all springs of one offset share their
//! stiffness `k` and damping `k_d`. Grouping the springs by offset turns the force loop into a
//! few passes over contiguous arrays, with no scattered writes:
//!
//! ```text
//! pass 1, for each offset δ and each p:      f_δ[p] = spring force on p from p + δ   (or 0)
//! pass 2, for each particle q:               F[q]   = m_q g - c v_q
//!                                                     + Σ_δ f_δ[q]        (q is the first end)
//!                                                     - Σ_δ f_δ[q - δ]    (q is the second end)
//! ```
//! where the force of one spring is that of [`super::springs`]:
//! `f = (k (L - L0) + k_d (v_b - v_a)·n) n`, `n = (x_b - x_a)/L`, in N.
//!
//! Pass 1 reads `x[p]` and `x[p + δ]` as two contiguous streams, so the compiler turns it into
//! vector instructions (four or eight springs at once). Where no spring joins `p` and `p + δ`
//! (the lattice's border) the stiffness and damping are multiplied by zero. Pass 2 adds the
//! pieces in one fixed order per particle, so the result does not depend on how the particles
//! are split between threads: runs are bit-identical.
//!
//! The sums run in a different order than the spring-list loop, so forces agree with
//! [`super::forces`] to rounding (about 1e-15 relative), not bit for bit; a test checks it.
//!
//! References: the "stencil" formulation of finite-difference codes (e.g. Datta et al., "Stencil
//! Computation Optimization and Auto-tuning on State-of-the-Art Multicore Architectures", SC 2008);
//! WORKLOADS.md (the peer benchmark's lattices and their spring order).

use std::cell::RefCell;

use glam::DVec3;

use super::springs::Spring;

/// The springs of one index offset `δ`, all with the same stiffness and damping.
#[derive(Clone, Debug, PartialEq)]
struct Group {
    /// `b - a` for every spring of the group.
    delta: usize,
    /// Stiffness `k` (N/m).
    stiffness: f64,
    /// Damping `k_d` (N·s/m).
    damping: f64,
    /// Rest length of the spring starting at `p` (m); 0 where there is none.
    rest_length: Vec<f64>,
    /// 1 where a spring starts at `p`, 0 where none does.
    present: Vec<f64>,
}

/// A lattice's springs grouped by index offset (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Stencil {
    particles: usize,
    groups: Vec<Group>,
}

/// At most this many offset groups: more would make the passes slower than the spring list.
const MAX_GROUPS: usize = 32;

/// The stencil form pays off when at least this share of the `(group, p)` slots hold a spring.
const MIN_DENSITY: f64 = 0.5;

/// Below this many springs the spring list is as fast: the stencil's passes have fixed costs.
const MIN_SPRINGS: usize = 256;

impl Stencil {
    /// The stencil form of `springs` over `particles` particles, or `None` when the springs are
    /// not a lattice worth it (too few springs, too many offsets, too sparse, or two springs
    /// with the same start and offset).
    #[must_use]
    pub fn detect(particles: usize, springs: &[Spring]) -> Option<Stencil> {
        if springs.len() < MIN_SPRINGS {
            return None;
        }
        let mut groups: Vec<Group> = Vec::new();
        for s in springs {
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
                    groups.push(Group {
                        delta,
                        stiffness: s.stiffness,
                        damping: s.damping,
                        rest_length: vec![0.0; particles - delta],
                        present: vec![0.0; particles - delta],
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
        let slots: usize = groups.iter().map(|g| g.present.len()).sum();
        if (springs.len() as f64) < MIN_DENSITY * slots as f64 {
            return None;
        }
        // Visit offsets in increasing order: neighbouring streams, better locality.
        groups.sort_by_key(|g| g.delta);
        Some(Stencil { particles, groups })
    }

    /// Number of offset groups.
    #[must_use]
    pub fn group_count(&self) -> usize {
        self.groups.len()
    }

    /// Sets the stiffness and damping of every spring (used when a lesson changes them for all
    /// springs at once).
    pub fn set_coefficients(&mut self, stiffness: f64, damping: f64) {
        for g in &mut self.groups {
            g.stiffness = stiffness;
            g.damping = damping;
        }
    }

    /// Adds the spring forces (N) at positions `x` and velocities `v` to `f`.
    ///
    /// # Panics
    /// If the slices are shorter than the stencil's particle count.
    pub fn add_forces(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        SCRATCH.with(|scratch| {
            let mut scratch = scratch.borrow_mut();
            self.add_forces_with(&mut scratch, x, v, f);
        });
    }

    fn add_forces_with(&self, s: &mut Scratch, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        let n = self.particles;
        s.resize(n, self.groups.len());
        // Struct of arrays: one contiguous f64 stream per component.
        for (i, (x, v)) in x[..n].iter().zip(&v[..n]).enumerate() {
            s.x[0][i] = x.x;
            s.x[1][i] = x.y;
            s.x[2][i] = x.z;
            s.v[0][i] = v.x;
            s.v[1][i] = v.y;
            s.v[2][i] = v.z;
        }
        // Pass 1: the force of every spring, offset by offset.
        for (g, out) in self.groups.iter().zip(s.f.iter_mut()) {
            spring_pass(g, &s.x, &s.v, out);
        }
        // Pass 2: each particle gathers its springs in a fixed order (+ as first end, - as second).
        gather_pass(&self.groups, &s.f, &mut s.sum);
        let [sx, sy, sz] = &s.sum;
        for (i, f) in f[..n].iter_mut().enumerate() {
            *f += DVec3::new(sx[i], sy[i], sz[i]);
        }
    }
}

/// Scratch buffers of the stencil passes (per thread; reused, so steps do not allocate).
#[derive(Default)]
struct Scratch {
    x: [Vec<f64>; 3],
    v: [Vec<f64>; 3],
    f: Vec<[Vec<f64>; 3]>,
    sum: [Vec<f64>; 3],
}

impl Scratch {
    fn resize(&mut self, n: usize, groups: usize) {
        if self.x[0].len() != n {
            for c in self
                .x
                .iter_mut()
                .chain(self.v.iter_mut())
                .chain(self.sum.iter_mut())
            {
                *c = vec![0.0; n];
            }
            self.f.clear();
        }
        while self.f.len() < groups {
            self.f.push([vec![0.0; n], vec![0.0; n], vec![0.0; n]]);
        }
    }
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Pass 2: `sum[q] = Σ_δ f_δ[q] - Σ_δ f_δ[q - δ]`, component by component.
fn gather_pass(groups: &[Group], pieces: &[[Vec<f64>; 3]], sum: &mut [Vec<f64>; 3]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked on the line above.
            unsafe { gather_pass_avx2(groups, pieces, sum) };
            return;
        }
    }
    gather_pass_body(groups, pieces, sum);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gather_pass_avx2(groups: &[Group], pieces: &[[Vec<f64>; 3]], sum: &mut [Vec<f64>; 3]) {
    gather_pass_body(groups, pieces, sum);
}

#[inline(always)]
fn gather_pass_body(groups: &[Group], pieces: &[[Vec<f64>; 3]], sum: &mut [Vec<f64>; 3]) {
    for c in sum.iter_mut() {
        c.fill(0.0);
    }
    for (g, piece) in groups.iter().zip(pieces) {
        let m = g.present.len();
        for (total, part) in sum.iter_mut().zip(piece) {
            let part = &part[..m];
            // The spring's first end p receives +f ...
            let first = &mut total[..m];
            for i in 0..m {
                first[i] += part[i];
            }
            // ... and its second end p + δ receives -f.
            let second = &mut total[g.delta..g.delta + m];
            for i in 0..m {
                second[i] -= part[i];
            }
        }
    }
}

/// Pass 1 for one offset group, with the widest vector instructions this CPU has.
fn spring_pass(g: &Group, x: &[Vec<f64>; 3], v: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked on the line above.
            unsafe { spring_pass_avx2(g, x, v, out) };
            return;
        }
    }
    spring_pass_body(g, x, v, out);
}

/// The same loop compiled for AVX2: four springs per instruction. No fused multiply-add is
/// formed (Rust never contracts), so the result is bit-identical to the portable loop.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn spring_pass_avx2(g: &Group, x: &[Vec<f64>; 3], v: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
    spring_pass_body(g, x, v, out);
}

#[inline(always)]
fn spring_pass_body(g: &Group, x: &[Vec<f64>; 3], v: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
    let m = g.present.len();
    let d = g.delta;
    // Equal-length slices: the compiler drops the bounds checks and vectorises.
    let (xa, ya, za) = (&x[0][..m], &x[1][..m], &x[2][..m]);
    let (xb, yb, zb) = (&x[0][d..d + m], &x[1][d..d + m], &x[2][d..d + m]);
    let (vxa, vya, vza) = (&v[0][..m], &v[1][..m], &v[2][..m]);
    let (vxb, vyb, vzb) = (&v[0][d..d + m], &v[1][d..d + m], &v[2][d..d + m]);
    let (rest, present) = (&g.rest_length[..m], &g.present[..m]);
    let [fx, fy, fz] = out;
    let (fx, fy, fz) = (&mut fx[..m], &mut fy[..m], &mut fz[..m]);
    for i in 0..m {
        // d = x_b - x_a, L = |d|
        let (dx, dy, dz) = (xb[i] - xa[i], yb[i] - ya[i], zb[i] - za[i]);
        let length = (dx * dx + dy * dy + dz * dz).sqrt();
        // n = d / L; a zero-length spring has no direction and no force.
        let inv = if length > 0.0 { 1.0 / length } else { 0.0 };
        let (nx, ny, nz) = (dx * inv, dy * inv, dz * inv);
        // Hooke k (L - L0) plus the damper k_d (v_b - v_a)·n, zero where there is no spring.
        let rel = (vxb[i] - vxa[i]) * nx + (vyb[i] - vya[i]) * ny + (vzb[i] - vza[i]) * nz;
        let tension = present[i] * (g.stiffness * (length - rest[i]) + g.damping * rel);
        fx[i] = tension * nx;
        fy[i] = tension * ny;
        fz[i] = tension * nz;
    }
}
