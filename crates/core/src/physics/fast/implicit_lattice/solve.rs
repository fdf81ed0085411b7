//! The conjugate gradients on the lattice system: the product `A p` (with `pᵀ A p` in the same
//! pass), the update passes of `Δv`, `r`, `z = P⁻¹ r` with their dot products, the new direction,
//! the block-Jacobi preconditioner and the constraint filter; reads without a bounds check per
//! load as the parent module's docs ("The seam of the hot loops") describe.

use super::*;

/// `out = A p` (see the module docs), zero at pinned particles and in the margins; returns
/// `p·out` (the conjugate-gradient step's `pᵀ A p`, summed in the same pass).
///
/// The conjugate gradients spend most of their time here, so the loop reads its arrays through
/// addresses taken once before it, without a bounds check per load: the checks are made once,
/// for the whole loop, by the asserts at the top (every index is `front + q ± δ` with
/// `δ ≤ front` and `front + q + δ + LANES ≤ len`). The arithmetic is the formula's, in its
/// order: a test compares it bit for bit with the same product written with checked loads.
#[inline(always)]
pub(super) fn apply<V: Lanes>(sys: &Lattice, p: &Soa, out: &mut Soa) -> f64 {
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
pub(super) fn soa_ptrs(a: &Soa) -> [*const f64; 3] {
    [a[0].as_ptr(), a[1].as_ptr(), a[2].as_ptr()]
}

/// `LANES` values from `a + i`.
///
/// # Safety
/// `a + i .. a + i + LANES` must be inside one array of `f64`.
#[inline(always)]
pub(super) unsafe fn raw<V: Lanes>(a: *const f64, i: usize) -> V {
    // SAFETY: as the caller promises; `[f64; LANES]` has the alignment of `f64`.
    V::load(unsafe { &*a.add(i).cast::<[f64; LANES]>() })
}

/// The three components at `i` of a vector whose components start at `a`.
///
/// # Safety
/// As [`raw`], for each component.
#[inline(always)]
pub(super) unsafe fn raw_triple<V: Lanes>(a: [*const f64; 3], i: usize) -> [V; 3] {
    // SAFETY: as the caller promises.
    unsafe { [raw(a[0], i), raw(a[1], i), raw(a[2], i)] }
}

/// The four numbers `c, u` at `i` of a group's blocks (entry `e` at `b + e len`).
///
/// # Safety
/// As [`raw`], for each entry.
#[inline(always)]
pub(super) unsafe fn raw_block<V: Lanes>(b: *const f64, len: usize, i: usize) -> [V; BLOCK] {
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
pub(super) fn group_block<V: Lanes>(b: &[f64], len: usize, i: usize) -> [V; BLOCK] {
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
pub(super) fn sum_lanes<V: Lanes>(v: V) -> f64 {
    let mut values = [0.0; LANES];
    v.store(&mut values);
    values.iter().sum()
}

/// `Σ a·b` over all particles, in lanes, added in a fixed order.
#[inline(always)]
pub(super) fn dot<V: Lanes>(sys: &Lattice, a: &Soa, b: &Soa) -> f64 {
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
pub(super) fn filter(front: usize, constraints: &[Constraint], v: &mut Soa) {
    for c in constraints {
        let k = front + c.i;
        let n = c.normal;
        let along = v[0][k] * n.x + v[1][k] * n.y + v[2][k] * n.z;
        v[0][k] -= along * n.x;
        v[1][k] -= along * n.y;
        v[2][k] -= along * n.z;
    }
}

/// A structure-of-arrays vector seen as rows (particle `i` at `front + i`), for the sphere rows
/// of the solve ([`SphereRows`]).
struct SoaRows<'a>(usize, &'a mut Soa);

impl Rows for SoaRows<'_> {
    fn add_row(&mut self, i: usize, d: DVec3) {
        let k = self.0 + i;
        self.1[0][k] += d.x;
        self.1[1][k] += d.y;
        self.1[2][k] += d.z;
    }
}

/// Row `i` of a structure-of-arrays vector.
fn soa_row(front: usize, a: &Soa, i: usize) -> DVec3 {
    let k = front + i;
    DVec3::new(a[0][k], a[1][k], a[2][k])
}

/// The textbook's preconditioned conjugate gradients on the lattice system, the touched
/// dynamic spheres' rows with it ([`SphereRows`]).
#[inline(always)]
fn solve_body<V: Lanes>(
    sys: &mut Lattice,
    constraints: &[Constraint],
    tolerance: f64,
    max_iterations: u32,
    warm: bool,
    spheres: &mut SphereRows,
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
            let target = spheres.target(c);
            dv[0][k] += (target - along) * n.x;
            dv[1][k] += (target - along) * n.y;
            dv[2][k] += (target - along) * n.z;
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
        let (b_spheres, r_spheres) = spheres.first_residual(constraints, |i| soa_row(front, &r, i));
        let b_norm2 = b_norm2 + b_spheres;
        filter(front, constraints, &mut r);
        if warm && dot::<V>(sys, &r, &r) + r_spheres >= b_norm2 {
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
        let mut rz = dot::<V>(sys, &r, &p) + spheres.first_direction();
        let mut r_norm2 = dot::<V>(sys, &r, &r) + spheres.first_residual_norm2();
        let tied = spheres.any();
        let mut iterations = 0;
        while r_norm2 > tol2 && iterations < max_iterations {
            // p ⊥ N at the constrained particles, so pᵀ S A p = pᵀ A p: the product's own sum.
            // With spheres in the solve, T p first (the tied particles' normal parts from the
            // spheres' directions), and the spheres' rows of Tᵀ A T p gathered before the filter.
            let mut p_ap;
            if tied {
                spheres.expand(constraints, &mut SoaRows(front, &mut p));
                p_ap = apply::<V>(sys, &p, &mut ap);
                p_ap += spheres.gather(constraints, |i| soa_row(front, &ap, i));
                filter(front, constraints, &mut p);
            } else {
                p_ap = apply::<V>(sys, &p, &mut ap);
            }
            filter(front, constraints, &mut ap);
            if p_ap.is_nan() || p_ap <= 0.0 {
                break;
            }
            // One pass: Δv += α p, r -= α S A p, |r|², z = P⁻¹ r and r·z (r = S r, so
            // r·S z = r·z: the filter of z can follow).
            let alpha = rz / p_ap;
            let (mut r2, mut rz_new) = descend::<V>(sys, alpha, [&mut dv, &mut r, &mut z], &p, &ap);
            if tied {
                let (rr_s, rz_s) =
                    spheres.descend(alpha, constraints, &mut SoaRows(front, &mut dv));
                r2 += rr_s;
                rz_new += rz_s;
            }
            r_norm2 = r2;
            filter(front, constraints, &mut z);
            redirect::<V>(sys, rz_new / rz, &z, &mut p);
            spheres.redirect(rz_new / rz);
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

on_lanes!(
    pub(super) solve_on(kernel),
    solve_body,
    (
        sys: &mut Lattice,
        constraints: &[Constraint],
        tolerance: f64,
        max_iterations: u32,
        warm: bool,
        spheres: &mut SphereRows
    ) -> (u32, f64, bool)
);
