//! Conservation laws and invariants of the force model and the integrators.

use crate::common;

use common::Rng;
use glam::DVec3;
use springlab::physics::{
    Method, MethodParams, Model, Spring, SpringKind, State, Workspace, forces,
};
use springlab::scene::builder::{Builder, RopeSpec, rope};
use springlab::scene::{self};
use springlab::simulation::Simulation;

/// A random system of `n` particles and `m` springs (some of zero rest length), no gravity.
/// A vector with each component uniform in `[-r, r)`.
fn random_vector(rng: &mut Rng, r: f64) -> DVec3 {
    DVec3::new(rng.range(-r, r), rng.range(-r, r), rng.range(-r, r))
}

fn random_system(rng: &mut Rng, n: usize, m: usize) -> (Model, State) {
    let x: Vec<DVec3> = (0..n).map(|_| random_vector(rng, 2.0)).collect();
    let v: Vec<DVec3> = (0..n).map(|_| random_vector(rng, 1.0)).collect();
    let springs = (0..m)
        .map(|i| {
            let a = (rng.range(0.0, n as f64) as u32).min(n as u32 - 1);
            let b = (a + 1 + rng.range(0.0, (n - 1) as f64) as u32) % n as u32;
            Spring {
                a,
                b,
                rest_length: if i % 7 == 0 { 0.0 } else { rng.range(0.1, 3.0) },
                stiffness: rng.range(1.0, 1000.0),
                damping: rng.range(0.0, 10.0),
                kind: SpringKind::Struct,
            }
        })
        .collect();
    let mass = (0..n).map(|_| rng.range(0.5, 2.0)).collect();
    let model = Model::new(mass, &vec![false; n], springs, DVec3::ZERO, 0.0);
    (model, State::new(x, v))
}

#[test]
fn internal_forces_sum_to_zero() {
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    for trial in 0..20 {
        let (model, state) = random_system(&mut rng, 30, 80);
        let mut f = vec![DVec3::ZERO; 30];
        forces(&model, &state.x, &state.v, &mut f);
        let total: DVec3 = f.iter().copied().sum();
        let scale: f64 = f.iter().map(|f| f.length()).sum();
        assert!(
            total.length() <= 1e-12 * scale,
            "trial {trial}: net internal force {total}"
        );
        // Newton's third law also for the moments: Σ x × f = 0 for central forces.
        let torque: DVec3 = state.x.iter().zip(&f).map(|(x, f)| x.cross(*f)).sum();
        let torque_scale: f64 = state
            .x
            .iter()
            .zip(&f)
            .map(|(x, f)| x.length() * f.length())
            .sum();
        assert!(
            torque.length() <= 1e-12 * torque_scale,
            "trial {trial}: net torque {torque}"
        );
    }
}

#[test]
fn a_zero_length_spring_gives_no_nan() {
    let p = DVec3::new(0.5, 0.5, 0.5);
    let springs = vec![Spring {
        a: 0,
        b: 1,
        rest_length: 0.0,
        stiffness: 100.0,
        damping: 1.0,
        kind: SpringKind::Struct,
    }];
    let model = Model::new(
        vec![1.0, 1.0],
        &[false, false],
        springs,
        DVec3::new(0.0, -9.8, 0.0),
        0.0,
    );
    for method in Method::ALL {
        let mut state = State::new(vec![p, p], vec![DVec3::X, DVec3::ZERO]);
        let mut work = Workspace::new();
        for _ in 0..10 {
            method.step(
                &model,
                &mut state,
                0.01,
                &MethodParams::default(),
                &mut work,
            );
        }
        assert!(
            state.x.iter().chain(&state.v).all(|v| v.is_finite()),
            "{method} produced NaN"
        );
    }
}

#[test]
fn pinned_particles_never_move_under_any_method() {
    for method in Method::ALL {
        let sets = vec![
            "nodes=8".to_string(),
            "pinned=[0, 7]".to_string(),
            "damping=0.5".to_string(),
        ];
        let mut scene = scene::load("rope", &sets).expect("rope");
        // Give the free nodes a kick so every method has something to do.
        for v in scene.bodies[0].state.v.iter_mut().skip(1).take(6) {
            *v = DVec3::new(0.3, 1.0, -0.2);
        }
        scene.set_method(method);
        let before = scene.bodies[0].state.x.clone();
        let mut sim = Simulation::new(scene);
        sim.set_dt(0.002);
        sim.run(500, |_| {});
        let after = &sim.scene.bodies[0].state;
        assert_eq!(after.x[0], before[0], "{method} moved pinned node 0");
        assert_eq!(after.x[7], before[7], "{method} moved pinned node 7");
        assert_eq!(after.v[0], DVec3::ZERO);
        assert_ne!(after.x[3], before[3], "{method} did not move a free node");
    }
}

#[test]
fn rope_constructor_spaces_nodes_evenly_with_springs_between_neighbours() {
    let start = DVec3::new(1.0, 2.0, -0.5);
    let end = DVec3::new(-3.0, 0.5, 2.5);
    let spec = RopeSpec {
        start,
        end,
        nodes: 11,
        node_mass: 0.25,
        stiffness: 40.0,
        damping: 0.1,
        pinned: vec![0, 10],
    };
    let mut b = Builder::new();
    b.particle(DVec3::splat(9.0), 1.0); // an earlier particle: the rope must index after it
    let first = rope(&mut b, &spec);
    assert_eq!(first, 1);
    let (model, state) = b.build(DVec3::ZERO, 0.0);
    let x = &state.x[1..];
    assert_eq!(x.len(), 11);
    assert_eq!(x[0], start);
    assert!((x[10] - end).length() < 1e-15);
    let spacing = (end - start).length() / 10.0;
    for i in 0..10 {
        assert!(
            ((x[i + 1] - x[i]).length() - spacing).abs() < 1e-12,
            "gap {i}"
        );
        // Evenly spaced along the straight line from start to end.
        let expected = start + (end - start) * (i as f64 / 10.0);
        assert!((x[i] - expected).length() < 1e-14);
    }
    assert_eq!(model.springs().len(), 10);
    for (i, s) in model.springs().iter().enumerate() {
        assert_eq!((s.a, s.b), (1 + i as u32, 2 + i as u32));
        assert!((s.rest_length - spacing).abs() < 1e-12);
        assert_eq!((s.stiffness, s.damping), (40.0, 0.1));
    }
    assert!(model.is_pinned(1) && model.is_pinned(11) && !model.is_pinned(2));
    assert_eq!(model.mass[5], 0.25);
}

#[test]
fn explicit_euler_diverges_on_the_rope_while_semi_implicit_and_verlet_stay_bounded() {
    let run = |method: Method, steps: u64| {
        let mut scene = scene::load("rope", &[]).expect("rope");
        scene.set_method(method);
        let mut sim = Simulation::new(scene);
        let mut max_speed = 0.0f64;
        sim.run(steps, |s| {
            for v in s.velocities() {
                max_speed = max_speed.max(v.length());
            }
        });
        (sim, max_speed)
    };
    let (euler, _) = run(Method::ExplicitEuler, 10_000);
    let d = euler
        .diverged
        .as_ref()
        .expect("explicit Euler must diverge on the rope");
    assert!(
        d.step > 10 && d.step < 10_000,
        "diverged at step {}",
        d.step
    );
    assert!((d.time - d.step as f64 / 64.0).abs() < 1e-12);
    assert!(d.max_speed > 1000.0);
    for method in [Method::SemiImplicitEuler, Method::Verlet] {
        let (sim, max_speed) = run(method, 10_000);
        assert!(sim.diverged.is_none(), "{method} diverged");
        assert_eq!(sim.steps, 10_000);
        // Free fall of a 4 m rope from rest cannot exceed √(2 g h) ≈ 12.5 m/s at its tip
        // (h ≤ 8 m); energy conservation bounds the speed of a bounded method.
        assert!(max_speed < 20.0, "{method}: max speed {max_speed} m/s");
    }
}

#[test]
fn the_same_run_twice_is_bit_identical() {
    let run = || {
        let mut scene = scene::load("ropes", &["nodes=12".to_string()]).expect("ropes");
        scene.bodies[0].method = Method::ImplicitEuler;
        let mut sim = Simulation::new(scene);
        sim.run(3_000, |_| {});
        let mut report = sim.report(0.0);
        report.wall_seconds = 0.0;
        serde_json::to_string(&report).expect("json")
    };
    assert_eq!(run(), run());
}

/// A deformed, moving copy of a workload's lattice, with one pair of particles on top of each
/// other (a zero-length spring).
fn shaken(workload: springlab::bench::Workload, rng: &mut Rng) -> (Model, State) {
    let (model, mut state) = springlab::bench::setup(workload);
    for (x, v) in state.x.iter_mut().zip(state.v.iter_mut()) {
        *x += random_vector(rng, 0.02);
        *v = random_vector(rng, 1.0);
    }
    state.x[1] = state.x[0];
    (model, state)
}

#[test]
fn the_stencil_form_gives_the_spring_list_forces() {
    use springlab::bench::Workload;
    use springlab::physics::stencil::Kernel;
    let mut rng = Rng(0x57e9_c11a_0000_0042);
    for workload in [Workload::JellySe, Workload::Cloth64Se] {
        let (model, state) = shaken(workload, &mut rng);
        assert!(
            model.uses_stencil(),
            "{} should use the stencil",
            workload.name()
        );
        let list = model.clone().without_stencil();
        let n = state.len();
        let mut slow = vec![DVec3::ZERO; n];
        forces(&list, &state.x, &state.v, &mut slow);
        let scale = slow.iter().map(|f| f.length()).fold(0.0, f64::max);
        for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
            let stencil = model
                .stencil()
                .expect("a stencil")
                .clone()
                .with_kernel(kernel);
            let mut fast = vec![DVec3::ZERO; n];
            stencil.add_forces(&state.x, &state.v, &mut fast);
            for (i, (a, b)) in fast.iter().zip(&slow).enumerate() {
                // `slow` includes gravity; the stencil adds the springs only.
                let b = *b - model.mass[i] * model.gravity;
                assert!(a.is_finite(), "{} {kernel:?}: NaN at {i}", workload.name());
                assert!(
                    (*a - b).length() <= 1e-12 * scale,
                    "{} {kernel:?}: particle {i}: {a} vs {b}",
                    workload.name()
                );
            }
        }
    }
}

#[test]
fn fused_accelerations_are_the_forces_over_the_masses_bit_for_bit() {
    use springlab::bench::Workload;
    use springlab::physics::accelerations;
    let mut rng = Rng(0xacce_1000_0000_0007);
    for workload in [Workload::JellySe, Workload::Cloth64Se, Workload::RopeSe] {
        let (mut model, state) = shaken(workload, &mut rng);
        model.drag = 0.25;
        assert!(model.uses_stencil(), "{}", workload.name());
        let n = state.len();
        let (mut f, mut a) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        forces(&model, &state.x, &state.v, &mut f);
        accelerations(&model, &state.x, &state.v, &mut a);
        for i in 0..n {
            let expected = f[i] * model.inv_mass[i];
            assert!(
                a[i].to_array().map(f64::to_bits) == expected.to_array().map(f64::to_bits),
                "{} particle {i}: {} vs {expected}",
                workload.name(),
                a[i]
            );
        }
    }
}

#[test]
fn the_fused_semi_implicit_euler_step_is_the_textbook_step_bit_for_bit() {
    use springlab::bench::Workload;
    use springlab::physics::accelerations;
    let mut rng = Rng(0x5e5e_0000_0000_0009);
    for workload in [Workload::JellySe, Workload::Cloth64Se, Workload::RopeSe] {
        let (mut model, state) = shaken(workload, &mut rng);
        model.drag = 0.25;
        let dt = 1e-4;
        // v' = v + dt a(x, v), x' = x + dt v', written out.
        let mut a = vec![DVec3::ZERO; state.len()];
        accelerations(&model, &state.x, &state.v, &mut a);
        let v_new: Vec<DVec3> = state.v.iter().zip(&a).map(|(v, a)| *v + dt * *a).collect();
        let x_new: Vec<DVec3> = state
            .x
            .iter()
            .zip(&v_new)
            .map(|(x, v)| *x + dt * *v)
            .collect();
        let mut fused = state.clone();
        Method::SemiImplicitEuler.step(
            &model,
            &mut fused,
            dt,
            &MethodParams::default(),
            &mut Workspace::new(),
        );
        let bits = |p: &[DVec3]| {
            p.iter()
                .flat_map(|p| p.to_array().map(f64::to_bits))
                .collect::<Vec<u64>>()
        };
        assert!(
            bits(&fused.v) == bits(&v_new),
            "{} velocities",
            workload.name()
        );
        assert!(
            bits(&fused.x) == bits(&x_new),
            "{} positions",
            workload.name()
        );
    }
}

#[test]
fn the_avx2_kernel_gives_the_portable_forces_bit_for_bit() {
    use springlab::bench::Workload;
    use springlab::physics::stencil::Kernel;
    if !Kernel::Avx2.is_available() {
        return;
    }
    let mut rng = Rng(0xa7b2_0000_0000_0003);
    let (model, state) = shaken(Workload::JellySe, &mut rng);
    let run = |kernel| {
        let stencil = model
            .stencil()
            .expect("a stencil")
            .clone()
            .with_kernel(kernel);
        let mut f = vec![DVec3::ZERO; state.len()];
        stencil.add_forces(&state.x, &state.v, &mut f);
        f.iter()
            .flat_map(|f| f.to_array().map(f64::to_bits))
            .collect::<Vec<u64>>()
    };
    assert!(run(Kernel::Avx2) == run(Kernel::Portable));
}

#[test]
fn the_stencil_forces_are_bit_identical_for_any_number_of_threads() {
    use springlab::bench::Workload;
    use springlab::physics::stencil::Kernel;
    let mut rng = Rng(0xb17_1de7_0000_0001);
    for workload in [Workload::JellySe, Workload::Cloth64Se, Workload::Cloth128Se] {
        let (model, state) = shaken(workload, &mut rng);
        let n = state.len();
        for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
            let stencil = model
                .stencil()
                .expect("a stencil")
                .clone()
                .with_kernel(kernel);
            let run = |parts: usize| {
                let mut f = vec![DVec3::ZERO; n];
                stencil.add_forces_in_parts(&state.x, &state.v, &mut f, parts);
                f.iter()
                    .flat_map(|f| f.to_array().map(f64::to_bits))
                    .collect::<Vec<u64>>()
            };
            let one = run(1);
            for parts in [2, 3, 5] {
                assert!(
                    run(parts) == one,
                    "{} {kernel:?}: {parts} parts differ from 1",
                    workload.name()
                );
            }
        }
    }
}

#[test]
fn random_springs_and_short_ropes_use_the_spring_list_and_long_ropes_the_stencil() {
    let mut rng = Rng(7);
    let (model, _) = random_system(&mut rng, 300, 400);
    assert!(!model.uses_stencil(), "random springs are not a lattice");
    let rope = |nodes: usize| {
        let scene = scene::load("rope", &[format!("nodes={nodes}")]).expect("rope");
        scene.bodies[0].model.uses_stencil()
    };
    assert!(!rope(12), "11 springs: the list is as fast");
    assert!(rope(64), "63 springs: a chain is a lattice with one offset");
    // Springs without stiffness and damping exert no force: no stencil for them.
    let (verlet, _) = springlab::bench::setup(springlab::bench::Workload::RopeVerlet);
    assert!(
        !verlet.uses_stencil(),
        "pure constraints need no force loop"
    );
}

/// The colliders of the fused-pass tests: a plane through the middle of the shaken lattice, a
/// sphere, a bowl and the 2023 floor with a hole, placed so that each touches some particles.
fn test_colliders(state: &State) -> Vec<springlab::physics::collide::Collider> {
    use springlab::physics::collide::Collider;
    let n = state.len() as f64;
    let centre = state.x.iter().fold(DVec3::ZERO, |a, b| a + *b) / n;
    let far = state
        .x
        .iter()
        .map(|x| (*x - centre).length())
        .fold(0.0, f64::max);
    vec![
        Collider::plane(
            centre + DVec3::new(0.0, 0.03, 0.0),
            DVec3::new(0.1, 1.0, 0.0),
        ),
        Collider::sphere(centre + DVec3::new(0.5 * far, 0.0, 0.0), 0.4 * far),
        Collider::bowl(
            centre + DVec3::new(0.0, 0.6 * far, 0.0),
            0.9 * far,
            centre.y,
        ),
        Collider::hole_plane(
            centre - DVec3::new(0.0, 0.1 * far, 0.0),
            DVec3::Y,
            centre - DVec3::new(0.3 * far, 0.1 * far, 0.0),
            0.5 * far,
        ),
    ]
}

fn bits(p: &[DVec3]) -> Vec<u64> {
    p.iter()
        .flat_map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn contact_in_the_fused_pass_is_the_scalar_contact_bit_for_bit() {
    use springlab::bench::Workload;
    use springlab::physics::collide::{ContactParams, contact_forces};
    use springlab::physics::forces::applied_forces;
    let mut rng = Rng(0xc0_77ac_7000_0001);
    for workload in [Workload::JellySe, Workload::Cloth64Se] {
        let (model, state) = shaken(workload, &mut rng);
        let colliders = test_colliders(&state);
        let model = model.with_colliders(colliders, ContactParams::course_2023());
        let n = state.len();
        let (mut fused, mut plain) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        forces(&model, &state.x, &state.v, &mut fused);
        applied_forces(&model, &state.x, &state.v, &mut plain);
        let before = plain.clone();
        contact_forces(&model, &state.x, &state.v, &mut plain);
        let touched = plain.iter().zip(&before).filter(|(a, b)| a != b).count();
        assert!(touched > n / 20, "{workload}: only {touched} contacts");
        assert!(bits(&fused) == bits(&plain), "{workload}");
    }
}

#[test]
fn every_method_fused_into_the_stencil_is_its_textbook_loop_bit_for_bit() {
    use springlab::bench::Workload;
    use springlab::physics::collide::ContactParams;
    let mut rng = Rng(0xf05e_d000_0000_0015);
    for workload in [Workload::JellySe, Workload::Cloth64Se, Workload::RopeSe] {
        let (mut model, state) = shaken(workload, &mut rng);
        model.drag = 0.25;
        for contact in [false, true] {
            let model = if contact {
                let colliders = test_colliders(&state);
                model
                    .clone()
                    .with_colliders(colliders, ContactParams::course_2021())
            } else {
                model.clone()
            };
            for method in Method::ALL {
                let run = |textbook: bool| {
                    let mut s = state.clone();
                    let mut work = Workspace::new();
                    work.account = true;
                    work.textbook = textbook;
                    let mut dissipated = 0.0;
                    for _ in 0..3 {
                        // CG to 1e-10 of |b|, so that the two paths' solves agree closely.
                        let params = MethodParams {
                            cg_tolerance: 1e-10,
                            ..MethodParams::default()
                        };
                        method.step(&model, &mut s, 1e-4, &params, &mut work);
                        dissipated += work.dissipated.dampers_and_drag;
                    }
                    (s, dissipated)
                };
                let ((fused, d_fused), (textbook, d_textbook)) = (run(false), run(true));
                let label = format!("{workload} {method} contact {contact}");
                if method == Method::ImplicitEuler {
                    // Its lattice path sums the same system in another order; the solves
                    // agree to their tolerance (1e-10 of |b|).
                    let scale = textbook.v.iter().map(|v| v.length()).fold(0.0, f64::max);
                    for (a, b) in fused.v.iter().zip(&textbook.v) {
                        assert!((*a - *b).length() <= 1e-8 * scale, "{label}: {a} vs {b}");
                    }
                } else {
                    assert!(bits(&fused.x) == bits(&textbook.x), "{label}: positions");
                    assert!(bits(&fused.v) == bits(&textbook.v), "{label}: velocities");
                }
                assert!(
                    (d_fused - d_textbook).abs() <= 1e-12 * d_textbook.abs().max(1e-300),
                    "{label}: dissipated {d_fused} vs {d_textbook}"
                );
                assert!(d_fused > 0.0, "{label}: no damper or drag power");
            }
        }
    }
}

#[test]
fn the_fused_dissipated_power_is_the_spring_list_power() {
    use springlab::bench::Workload;
    use springlab::physics::collide::ContactParams;
    let mut rng = Rng(0x90e7_0000_0000_0001);
    for workload in [Workload::JellySe, Workload::Cloth64Se] {
        let (mut model, state) = shaken(workload, &mut rng);
        model.drag = 0.25;
        let colliders = test_colliders(&state);
        let model = model.with_colliders(colliders, ContactParams::course_2021());
        // Explicit Euler integrates P(x_n, v_n): one step from the same state compares the
        // power of the stencil's pass with the spring list's loop.
        let dissipated = |model: &Model| {
            let mut s = state.clone();
            let mut work = Workspace::new();
            work.account = true;
            Method::ExplicitEuler.step(model, &mut s, 1e-3, &MethodParams::default(), &mut work);
            work.dissipated
        };
        let (fused, list) = (
            dissipated(&model),
            dissipated(&model.clone().without_stencil()),
        );
        assert!(
            list.dampers_and_drag > 0.0 && list.contact_forces > 0.0,
            "{workload}"
        );
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-11 * b.abs();
        assert!(
            close(fused.dampers_and_drag, list.dampers_and_drag),
            "{workload}: dampers {} vs {}",
            fused.dampers_and_drag,
            list.dampers_and_drag
        );
        assert!(
            close(fused.contact_forces, list.contact_forces),
            "{workload}: contact {} vs {}",
            fused.contact_forces,
            list.contact_forces
        );
    }
}

/// A model built afresh from `model`'s particles and colliders with the springs `springs`.
fn rebuilt_with(model: &Model, springs: Vec<Spring>) -> Model {
    let pinned: Vec<bool> = (0..model.particle_count())
        .map(|i| model.is_pinned(i))
        .collect();
    Model::new(
        model.mass.clone(),
        &pinned,
        springs,
        model.gravity,
        model.drag,
    )
    .with_colliders(model.colliders.clone(), model.contact)
}

#[test]
fn editing_springs_through_the_model_keeps_its_caches_right() {
    use springlab::bench::Workload;
    let mut rng = Rng(0x5e7_5a1e_0000_0012);
    for workload in [Workload::JellySe, Workload::Cloth64Se, Workload::RopeSe] {
        let (model, state) = shaken(workload, &mut rng);
        let n = state.len();
        let forces_of = |m: &Model| {
            let mut f = vec![DVec3::ZERO; n];
            forces(m, &state.x, &state.v, &mut f);
            bits(&f)
        };
        // Stiffer springs: the same forces as a model built with them.
        let mut stiffer = model.clone();
        stiffer.scale_stiffness(2.0);
        let doubled: Vec<Spring> = model
            .springs()
            .iter()
            .map(|s| Spring {
                stiffness: 2.0 * s.stiffness,
                ..*s
            })
            .collect();
        assert_eq!(stiffer.springs(), doubled.as_slice());
        let fresh = rebuilt_with(&model, doubled);
        assert_eq!(stiffer.uses_stencil(), fresh.uses_stencil());
        assert_eq!(
            forces_of(&stiffer),
            forces_of(&fresh),
            "{}",
            workload.name()
        );
        assert_ne!(
            forces_of(&stiffer),
            forces_of(&model),
            "{}",
            workload.name()
        );
        // Springs that exert no force (rigid rods): the force loop skips them, like a model
        // built with them, and the projection order is the fresh model's.
        let mut rods = model.clone();
        rods.update_springs(|s| {
            s.stiffness = 0.0;
            s.damping = 0.0;
        });
        let fresh = rebuilt_with(&model, rods.springs().to_vec());
        assert_eq!(forces_of(&rods), forces_of(&fresh), "{}", workload.name());
        assert!(
            rods.spring_colours().eq(fresh.spring_colours()),
            "{}",
            workload.name()
        );
        for i in 0..n {
            assert_eq!(rods.springs_at(i), fresh.springs_at(i));
        }
    }
}

/// A jittered `nx × ny` grid lattice (`nx` odd, particle count not a multiple of 8) whose
/// springs join `p` to `p + δ` for δ = 1, 2, nx - 1, nx, nx + 1, 2 nx and 3 nx + 5: a reach
/// larger than the stencil's tiles (32 particles) and several of them, and rows whose ends have no spring of
/// δ = 1, 2 (lanes without a spring). The groups δ = 1 and 2 nx have one rest length each
/// (the lattice spacing, twice it), the others the distance at the start times 0.9–1.1;
/// velocities are random.
fn jittered_lattice(rng: &mut Rng, nx: usize, ny: usize) -> (Vec<Spring>, Vec<DVec3>, Vec<DVec3>) {
    let n = nx * ny;
    let h = 0.1;
    let x: Vec<DVec3> = (0..n)
        .map(|p| {
            let (i, j) = ((p % nx) as f64, (p / nx) as f64);
            DVec3::new(
                i * h + rng.range(-0.02, 0.02),
                j * h + rng.range(-0.02, 0.02),
                rng.range(-0.05, 0.05),
            )
        })
        .collect();
    let v: Vec<DVec3> = (0..n).map(|_| random_vector(rng, 1.0)).collect();
    let offsets = [1, 2, nx - 1, nx, nx + 1, 2 * nx, 3 * nx + 5];
    let mut springs = Vec::new();
    for (k, &delta) in offsets.iter().enumerate() {
        for a in 0..n - delta {
            // Leave out the springs that would wrap around a row, as a cloth does.
            if (delta == 1 || delta == 2) && a % nx + delta >= nx {
                continue;
            }
            let b = a + delta;
            let rest_length = match delta {
                1 => h,
                d if d == 2 * nx => 2.0 * h,
                _ => (x[b] - x[a]).length() * rng.range(0.9, 1.1),
            };
            springs.push(Spring {
                a: a as u32,
                b: b as u32,
                rest_length,
                stiffness: 100.0 * (k + 1) as f64,
                damping: 0.5 + k as f64,
                kind: SpringKind::Struct,
            });
        }
    }
    (springs, x, v)
}

#[test]
fn the_streaming_stencil_is_its_sum_in_offset_order_bit_for_bit_across_tiles_and_threads() {
    use springlab::physics::stencil::{Kernel, Stencil};
    let mut rng = Rng(0x5eed_c107_0000_0004);
    for (nx, ny) in [(37, 11), (23, 29)] {
        let (springs, x, v) = jittered_lattice(&mut rng, nx, ny);
        let n = x.len();
        let stencil = Stencil::detect(n, &springs).expect("a lattice");
        assert_eq!(stencil.group_count(), 7);
        assert!(
            stencil.reach() > 64,
            "reach {} within one tile",
            stencil.reach()
        );
        // The module's formula F[q] = Σ_δ f_δ[q] - Σ_δ f_δ[q - δ], each sum from zero in
        // increasing δ, with the textbook spring force (`Spring::force_on_a`, which the exact
        // kernel computes with the same operations).
        let mut by_start: Vec<&Spring> = springs.iter().collect();
        by_start.sort_by_key(|s| (s.b - s.a, s.a));
        let mut plus = vec![DVec3::ZERO; n];
        let mut minus = vec![DVec3::ZERO; n];
        for s in &by_start {
            let f = s.force_on_a(&x, &v);
            plus[s.a as usize] += f;
            minus[s.b as usize] += f;
        }
        let textbook: Vec<DVec3> = plus
            .iter()
            .zip(&minus)
            .map(|(p, m)| DVec3::ZERO + (*p - *m))
            .collect();
        let portable = stencil.clone().with_kernel(Kernel::Portable);
        for parts in [1, 2, 3, 5] {
            let mut f = vec![DVec3::ZERO; n];
            portable.add_forces_in_parts(&x, &v, &mut f, parts);
            assert!(
                bits(&f) == bits(&textbook),
                "{nx}×{ny}, {parts} parts: not the textbook sum"
            );
        }
        // The other kernels: the same bits for every split (AVX-512 differs from the exact
        // kernel in the last bits, see the stencil's docs).
        for kernel in Kernel::ALL.into_iter().filter(|k| k.is_available()) {
            let stencil = stencil.clone().with_kernel(kernel);
            let run = |parts| {
                let mut f = vec![DVec3::ZERO; n];
                stencil.add_forces_in_parts(&x, &v, &mut f, parts);
                f
            };
            let one = run(1);
            for (a, b) in one.iter().zip(&textbook) {
                assert!(
                    (*a - *b).length() <= 1e-12 * (1.0 + b.length()),
                    "{kernel:?}"
                );
            }
            for parts in [2, 3, 5] {
                assert!(bits(&run(parts)) == bits(&one), "{kernel:?}, {parts} parts");
            }
        }
    }
}
