//! Tests of the small-lattice path: the same bits as single steps.

use super::*;
use crate::bench::{Workload, setup};
use crate::physics::collide::ContactParams;
use crate::physics::forces::Model;
use crate::physics::particles::State;
use crate::physics::{Method, MethodParams, SpringKind, Workspace};
use crate::scene::builder::Builder;

/// Moves every particle that is not pinned and gives it a velocity (deterministic), so that
/// every spring is stretched and every damper works.
fn shaken(model: &Model, mut state: State) -> State {
    let mut rng = crate::random::XorShift64Star::new(0x5eed);
    let mut next = || rng.unit() - 0.5;
    for ((x, v), &w) in state.x.iter_mut().zip(&mut state.v).zip(&model.inv_mass) {
        let (dx, dv) = (
            DVec3::new(next(), next(), next()),
            DVec3::new(next(), next(), next()),
        );
        if w != 0.0 {
            *x += 0.01 * dx;
            *v = dv;
        }
    }
    state
}

/// A `rows × cols` grid (10 cm apart, 20 g each) with a spring from every particle to its
/// neighbour at each `(row, column)` offset (offset `k`: stiffness `500 + 100 k` N/m), drag
/// 0.3 N·s/m, the particles `pinned` fixed. In particle order (row by row) the offset
/// `(dr, dc)` is the index offset `δ = dr · cols + dc`.
fn grid(rows: i32, cols: i32, offsets: &[(i32, i32)], pinned: &[usize]) -> (Model, State) {
    let mut b = Builder::new();
    for r in 0..rows {
        for c in 0..cols {
            b.particle(
                DVec3::new(f64::from(c) * 0.1, 1.0, f64::from(r) * 0.1),
                0.02,
            );
        }
    }
    for &p in pinned {
        b.pinned[p] = true;
    }
    for (k, (dr, dc)) in offsets.iter().enumerate() {
        for r in 0..rows {
            for c in 0..cols {
                let (qr, qc) = (r + dr, c + dc);
                if (0..rows).contains(&qr) && (0..cols).contains(&qc) {
                    let (p, q) = ((r * cols + c) as u32, (qr * cols + qc) as u32);
                    b.spring(p, q, 500.0 + 100.0 * k as f64, 0.05, SpringKind::Struct);
                }
            }
        }
    }
    let (model, state) = b.build(DVec3::new(0.0, -9.8, 0.0), 0.3);
    let state = shaken(&model, state);
    (model, state)
}

/// Lattices with 1 to 7 offset groups (`(label, groups, model, state)`): the rope of
/// `rope-se` (64 particles); a rope of 37 with bending springs (δ = 1, 2); a 5×10 strip
/// (δ = 1, 10, 11: second ends a chunk and more ahead); a 5×8 cloth (δ = 1, 8, 9, 7: a
/// whole-chunk offset); 7×7 cloths with 5, 6 and 7 offsets (49 particles: a last chunk of
/// one particle); a 16×16 cloth (256 particles, δ up to 17). Some particles pinned.
fn lattices() -> Vec<(&'static str, usize, Model, State)> {
    let (rope, rope_state) = setup(Workload::RopeSe);
    let rope_state = shaken(&rope, rope_state);
    let cloth = [(0, 1), (1, 0), (1, 1), (1, -1), (0, 2), (2, 0), (2, 2)];
    let with = |label, groups, (model, state)| (label, groups, model, state);
    vec![
        ("rope-se", 1, rope, rope_state),
        with("bent rope", 2, grid(1, 37, &[(0, 1), (0, 2)], &[0, 20])),
        with("strip", 3, grid(5, 10, &cloth[..3], &[0, 9])),
        with("5×8 cloth", 4, grid(5, 8, &cloth[..4], &[0])),
        with("7×7, 5 offsets", 5, grid(7, 7, &cloth[..5], &[0, 6])),
        with("7×7, 6 offsets", 6, grid(7, 7, &cloth[..6], &[0, 6])),
        with("7×7, 7 offsets", 7, grid(7, 7, &cloth, &[0, 6])),
        with("16×16 cloth", 4, grid(16, 16, &cloth[..4], &[0, 15])),
    ]
}

fn bits(x: &[DVec3]) -> Vec<[u64; 3]> {
    x.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn many_steps_in_one_call_are_the_single_steps_bit_for_bit() {
    let params = MethodParams::default();
    for (name, groups, model, state) in lattices() {
        for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
            let model = model.clone().with_kernel(kernel);
            let stencil = model.stencil().expect("a lattice");
            let label = format!("{name}, {kernel:?}");
            assert_eq!(stencil.groups.len(), groups, "{label}: groups");
            let mut single = state.clone();
            let mut work = Workspace::new();
            for _ in 0..40 {
                Method::SemiImplicitEuler.step(&model, &mut single, 1e-4, &params, &mut work);
            }
            let mut many = state.clone();
            let dynamics = model.dynamics(true);
            assert!(
                stencil.semi_implicit_euler_steps(&mut many.x, &mut many.v, &dynamics, 1e-4, 40),
                "{label}: not taken"
            );
            assert_eq!(bits(&many.x), bits(&single.x), "{label}: positions");
            assert_eq!(bits(&many.v), bits(&single.v), "{label}: velocities");
            // The same through `Method::steps`, in two calls.
            let mut via = state.clone();
            let mut work = Workspace::new();
            let evals = Method::SemiImplicitEuler
                .steps(&model, &mut via, 1e-4, &params, &mut work, 15)
                + Method::SemiImplicitEuler.steps(&model, &mut via, 1e-4, &params, &mut work, 25);
            assert_eq!(evals, 40);
            assert_eq!(bits(&via.x), bits(&single.x), "{label}: Method::steps");
            assert_eq!(bits(&via.v), bits(&single.v), "{label}: Method::steps");
            // The state moved, and the pinned particles did not.
            assert_ne!(bits(&single.x), bits(&state.x));
            for (i, &w) in model.inv_mass.iter().enumerate() {
                if w == 0.0 {
                    assert_eq!(bits(&single.x[i..=i]), bits(&state.x[i..=i]), "{label}");
                }
            }
        }
    }
}

/// The fused path itself (not `small_body`) takes the lattices of up to `FUSED_GROUPS`
/// groups, with the same bits as single steps of the same kernel; more groups are left to
/// `small_body`.
#[cfg(target_arch = "x86_64")]
#[test]
fn the_fused_path_gives_the_single_steps_bits() {
    if !Kernel::Avx512.is_available() {
        return;
    }
    let params = MethodParams::default();
    for (name, groups, model, state) in lattices() {
        let model = model.with_kernel(Kernel::Avx512);
        let stencil = model.stencil().expect("a lattice");
        let dynamics = model.dynamics(true);
        let mut fused = state.clone();
        // SAFETY: AVX-512F is available (checked above).
        let taken = unsafe {
            fused_steps(
                stencil,
                &dynamics,
                &mut fused.x,
                &mut fused.v,
                1e-4,
                40,
                None,
            )
        };
        assert_eq!(taken, groups <= FUSED_GROUPS, "{name}");
        if !taken {
            assert_eq!(bits(&fused.x), bits(&state.x), "{name}: changed");
            continue;
        }
        let mut single = state.clone();
        let mut work = Workspace::new();
        for _ in 0..40 {
            Method::SemiImplicitEuler.step(&model, &mut single, 1e-4, &params, &mut work);
        }
        assert_eq!(bits(&fused.x), bits(&single.x), "{name}: positions");
        assert_eq!(bits(&fused.v), bits(&single.v), "{name}: velocities");
    }
}

/// The two passes (`small_body` with power, the AVX-512 kernel): the states after `steps`
/// steps and each step's power.
#[cfg(target_arch = "x86_64")]
fn two_passes_with_power(
    stencil: &Stencil,
    dynamics: &Dynamics,
    state: &mut State,
    steps: u64,
) -> Vec<(f64, f64)> {
    let mut s = SmallScratch::default();
    s.load(stencil, &state.x, &state.v);
    s.power.resize(stencil.power_len(), 0.0);
    small_steps::<true>(stencil, &mut s, dynamics, 1e-4, steps);
    s.store(&mut state.x, &mut state.v);
    s.powers
}

/// With power asked, the fused path gives each step's dissipated power with the same bits as
/// the two passes (dampers of every group, the drag of the free particles), and the same
/// states; the drag, and with it the power, is nonzero on every lattice here.
#[cfg(target_arch = "x86_64")]
#[test]
fn the_fused_path_gives_the_two_passes_power_bits() {
    if !Kernel::Avx512.is_available() {
        return;
    }
    let power_bits = |p: &[(f64, f64)]| -> Vec<[u64; 2]> {
        p.iter().map(|(a, b)| [a.to_bits(), b.to_bits()]).collect()
    };
    for (name, groups, model, state) in lattices() {
        let model = model.with_kernel(Kernel::Avx512);
        let stencil = model.stencil().expect("a lattice");
        let dynamics = model.dynamics(true);
        let mut fused = state.clone();
        // Appended after what the vector holds.
        let mut fused_powers = vec![(1.0, 2.0)];
        // SAFETY: AVX-512F is available (checked above).
        let taken = unsafe {
            fused_steps(
                stencil,
                &dynamics,
                &mut fused.x,
                &mut fused.v,
                1e-4,
                40,
                Some(&mut fused_powers),
            )
        };
        assert_eq!(taken, groups <= FUSED_GROUPS, "{name}");
        if !taken {
            assert_eq!(fused_powers, [(1.0, 2.0)], "{name}: changed");
            continue;
        }
        let mut two = state.clone();
        let two_powers = two_passes_with_power(stencil, &dynamics, &mut two, 40);
        assert_eq!(two_powers.len(), 40, "{name}");
        assert_eq!(fused_powers[0], (1.0, 2.0), "{name}: kept");
        assert_eq!(
            power_bits(&fused_powers[1..]),
            power_bits(&two_powers),
            "{name}"
        );
        assert_eq!(bits(&fused.x), bits(&two.x), "{name}: positions");
        assert_eq!(bits(&fused.v), bits(&two.v), "{name}: velocities");
        assert!(
            two_powers.iter().all(|&(d, c)| d > 0.0 && c == 0.0),
            "{name}"
        );
        // Through the seam, the same.
        let mut via = state.clone();
        let mut via_powers = Vec::new();
        assert!(stencil.semi_implicit_euler_steps_with_power(
            &mut via.x,
            &mut via.v,
            &dynamics,
            1e-4,
            40,
            Some(&mut via_powers)
        ));
        assert_eq!(
            power_bits(&via_powers),
            power_bits(&two_powers),
            "{name}: seam"
        );
    }
}

#[test]
fn large_lattices_and_colliders_are_left_to_the_single_steps() {
    let (jelly, mut state) = setup(Workload::JellySe);
    let before = bits(&state.x);
    let stencil = jelly.stencil().expect("a lattice");
    let dynamics = jelly.dynamics(true);
    assert!(!stencil.semi_implicit_euler_steps(&mut state.x, &mut state.v, &dynamics, 1e-4, 3));
    assert_eq!(bits(&state.x), before);
    let (rope, mut state) = setup(Workload::RopeSe);
    let rope = rope.with_colliders(
        vec![Collider::Sphere {
            center: DVec3::new(0.5, 0.5, 0.0),
            radius: 0.2,
        }],
        ContactParams::course_2021(),
    );
    let stencil = rope.stencil().expect("a lattice");
    let dynamics = rope.dynamics(true);
    assert!(!stencil.semi_implicit_euler_steps(&mut state.x, &mut state.v, &dynamics, 1e-4, 3));
    assert_eq!(bits(&state.x), bits(&setup(Workload::RopeSe).1.x));
}
