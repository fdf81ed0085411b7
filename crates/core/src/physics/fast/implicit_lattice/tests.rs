use glam::DVec3;

use super::solve::{apply, group_block};
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
    let mut a: Soa = std::array::from_fn(|_| Aligned::zeros(sys.len));
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
    let mut out_ref: Soa = std::array::from_fn(|_| Aligned::zeros(sys.len));
    let sum_ref = apply_checked::<Plain>(&sys, &p, &mut out_ref);
    // Margins zero, as `resize` leaves them; NaN where the product must write.
    let mut out: Soa = std::array::from_fn(|_| Aligned::zeros(sys.len));
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
        let (iterations, residual, converged) = sys.solve(
            &[],
            1e-10,
            1000,
            false,
            None,
            &mut crate::physics::fast::implicit_constraint::SphereRows::default(),
        );
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

#[test]
fn every_array_of_the_system_starts_a_cache_line_and_a_clone_keeps_the_values() {
    let (sys, _) = assembled();
    let starts = |a: &Aligned| (a.as_ptr() as usize).is_multiple_of(64) && a.len() == sys.len;
    let vectors = [
        &sys.x, &sys.v, &sys.rhs, &sys.dv, &sys.r, &sys.p, &sys.ap, &sys.z,
    ];
    assert!(vectors.iter().all(|soa| soa.iter().all(starts)));
    assert!(sys.diag_inv.iter().all(starts) && starts(&sys.mass) && starts(&sys.free));
    for g in &sys.groups {
        assert!(g.kv.iter().all(starts));
        assert!((g.b.as_ptr() as usize).is_multiple_of(64) && g.b.len() == BLOCK * sys.len);
    }
    // The rows of a group's blocks start lines too (`len` is a multiple of LANES).
    assert_eq!(sys.len % LANES, 0);
    let copy = sys.clone();
    assert!(copy.diag_inv.iter().all(starts));
    for (a, b) in copy.diag_inv.iter().zip(&sys.diag_inv) {
        assert!(
            a.iter()
                .zip(b.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }
    assert!(sys.diag_inv[0].iter().any(|&d| d != 0.0));
}
