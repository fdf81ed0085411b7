//! Results do not depend on the number of threads: 1, 2, 3, 4 and 8 threads (more than this
//! machine's cores: the extra workers oversubscribe it, which changes only the speed) give the
//! same positions and velocities bit for bit on the lattice workloads, with the explicit, RK4
//! and implicit methods.
//!
//! Many steps in one call (`Method::steps`, which runs them as one team of threads on a large
//! lattice) give the same bits as one step at a time, the simulator's collision response between
//! a team's steps too, and so is the dissipated power a team sums while it runs; a team's
//! misuse and a panicking part end with a panic, never a hang.
//!
//! Only one test of this file touches the process-wide pool, on purpose: it sizes the pool
//! through `SPRINGLAB_THREADS` before anything starts it, which no other test may race.

use springlab::bench::{Run, Workload};
use springlab::physics::Method;
use springlab::physics::pool::{MAX_THREADS, Pool, THREADS_ENV, threads_for};

fn bits(s: &springlab::State) -> Vec<u64> {
    s.x.iter()
        .chain(&s.v)
        .flat_map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

#[test]
fn lattice_runs_are_bit_identical_for_1_2_3_4_and_8_threads() {
    // SAFETY: the only test of this binary, so no other thread reads the environment now.
    unsafe { std::env::set_var(THREADS_ENV, "8") };
    let pool = Pool::global();
    assert_eq!(pool.threads(), 8, "{THREADS_ENV}=8 sizes the pool");
    // Odd step counts: a team that alternates between two pairs of buffers ends in the second.
    let cases = [
        (Workload::JellySe, Method::SemiImplicitEuler, 201),
        (Workload::JellyRk4, Method::Rk4, 61),
        (Workload::Cloth64Se, Method::SemiImplicitEuler, 101),
        (Workload::Cloth64Se, Method::Midpoint, 50),
        (Workload::JellySe, Method::ImplicitEuler, 20),
    ];
    for (w, method, steps) in cases {
        let run = |threads: usize| {
            pool.set_threads(threads);
            let mut r = Run::with_method(w, method);
            r.advance(steps);
            bits(&r.state)
        };
        let one = run(1);
        for threads in [2, 3, 4, 8] {
            assert!(
                run(threads) == one,
                "{w} with {method}: {threads} threads differ from 1"
            );
        }
        // One step per call, on two threads: the same bits as all steps in one call.
        pool.set_threads(2);
        let mut r = Run::with_method(w, method);
        for _ in 0..steps {
            r.step();
        }
        assert!(
            bits(&r.state) == one,
            "{w} with {method}: step by step differs"
        );
    }
    a_landing_cube_is_the_same_on_any_number_of_threads(pool);
    pool.set_threads(8);
    a_team_fails_loudly();
    a_teams_power_is_the_single_passes_power();
}

/// `Simulation::advance` with the plane's response between two steps of its fused chunks (a
/// team's serial stage; on one thread, after each step of the loop) gives the single steps'
/// bits, and the same energy taken out, on 1, 2, 3 and 8 threads: the jelly cube lands on its
/// plane and rests there.
fn a_landing_cube_is_the_same_on_any_number_of_threads(pool: &Pool) {
    use springlab::simulation::Simulation;
    let sim = || {
        let sets = ["offset=[0, -4.9, 0]".to_string()];
        let mut scene = springlab::scene::load("cube-plane", &sets).expect("built-in scene");
        scene.set_method(Method::SemiImplicitEuler);
        let mut sim = Simulation::new(scene);
        sim.set_dt(1e-3);
        sim
    };
    let all_bits = |s: &Simulation| -> Vec<u64> { s.states().flat_map(bits).collect() };
    pool.set_threads(2);
    let mut single = sim();
    for _ in 0..300 {
        single.step();
    }
    assert!(single.dissipated().contacts > 0.0, "the cube landed");
    for threads in [1, 2, 3, 8] {
        pool.set_threads(threads);
        let mut fused = sim();
        fused.advance(300);
        assert_eq!(fused.fused_steps(), 300, "{threads} threads: fused steps");
        assert!(
            all_bits(&fused) == all_bits(&single),
            "{threads} threads: states"
        );
        assert_eq!(
            fused.dissipated().total.to_bits(),
            single.dissipated().total.to_bits(),
            "{threads} threads: energy taken out"
        );
    }
}

/// A pass that reads its own output, a thread that panics before its first pass, and a part
/// that panics while the other threads wait for it at the barrier: each ends in a panic of the
/// caller, never a hang, and teams still work afterwards.
fn a_team_fails_loudly() {
    use glam::DVec3;
    use springlab::physics::stencil::After;
    use std::panic::{AssertUnwindSafe, catch_unwind};
    let r = Run::new(Workload::JellySe);
    let stencil = r.model.stencil().expect("a lattice").clone();
    let dynamics = r.model.dynamics(true);
    let pass = |s: usize, after: Option<After<'static>>| step_pass(s, dynamics, after);
    let (mut x, mut v) = (r.state.x.clone(), r.state.v.clone());
    let (mut x2, mut v2) = (x.clone(), v.clone());
    // The last particle is in the last part; a rule that fails on it fails that part.
    fn marked(x: &mut [DVec3], _: &mut [DVec3]) {
        assert!(x.iter().all(|p| p.x < 1e29), "the marked particle");
    }
    for parts in [2, 3] {
        let mut buffers = [&mut x[..], &mut v[..], &mut x2[..], &mut v2[..]];
        let own_output = catch_unwind(AssertUnwindSafe(|| {
            stencil.team(parts, &mut buffers, &|crew| {
                let mut p = pass(0, None);
                p.outs[1] = Some(1);
                crew.pass(&p);
            });
        }));
        assert!(own_output.is_err(), "a pass that reads its own output");
        let late_panic = catch_unwind(AssertUnwindSafe(|| {
            stencil.team(parts, &mut buffers, &|crew| {
                assert!(crew.home() != 1, "thread 1 fails");
                for s in 0..4 {
                    crew.pass(&pass(s, None));
                }
            });
        }));
        assert!(late_panic.is_err(), "a thread that panics");
        buffers[0].last_mut().expect("particles").x = 1e30;
        let part_panic = catch_unwind(AssertUnwindSafe(|| {
            stencil.team(parts, &mut buffers, &|crew| {
                for s in 0..4 {
                    crew.pass(&pass(s, Some(&marked)));
                }
            });
        }));
        assert!(part_panic.is_err(), "a part that panics");
    }
    // Teams still work: four steps in a team, against four single steps.
    let (mut x, mut v) = (r.state.x.clone(), r.state.v.clone());
    let mut buffers = [&mut x[..], &mut v[..], &mut x2[..], &mut v2[..]];
    stencil.team(2, &mut buffers, &|crew| {
        for s in 0..4 {
            crew.pass(&pass(s, None));
        }
    });
    let mut state = r.state.clone();
    let mut work = springlab::physics::Workspace::new();
    let params = springlab::physics::MethodParams::default();
    for _ in 0..4 {
        Method::SemiImplicitEuler.step(&r.model, &mut state, 1e-4, &params, &mut work);
    }
    assert!(x == state.x && v == state.v);
}

/// The power of a pass from its buffer (two columns of eight values per chunk) as its formula
/// reads (`Stencil::sum_power`): lane by lane, each group of 128 chunks summed in order from
/// zero, the groups' sums in order from zero, then the lanes in order.
fn grouped_power(power: &[f64], contact: bool) -> (f64, f64) {
    let column = |c: usize| {
        let mut total = [0.0; 8];
        for group in power.chunks(16 * 128) {
            let mut sums = [0.0; 8];
            for chunk in group.chunks_exact(16) {
                for (s, p) in sums.iter_mut().zip(&chunk[8 * c..8 * c + 8]) {
                    *s += p;
                }
            }
            for (t, s) in total.iter_mut().zip(sums) {
                *t += s;
            }
        }
        total.iter().sum::<f64>()
    };
    (column(0), if contact { column(1) } else { 0.0 })
}

/// A team's power totals (its ring of slots, each summed part by part in later passes) are
/// bit for bit `Stencil::sum_power` of the power buffer of the same pass run alone
/// (`Stencil::write`), which is its formula (`grouped_power`), for 1, 2, 3 and 5 parts and
/// more passes than the ring has slots, without colliders and with a plane the body moves into
/// (a contact column to sum); the states too. So are the totals of
/// `Stencil::write_with_power_in_parts` (one part sums them in registers as the pass goes and
/// writes no buffer). On the jelly cube (1 000 particles: one group, the plain sum chunk after
/// chunk) and on the 128×128 cloth (16 groups, parts cut inside groups).
fn a_teams_power_is_the_single_passes_power() {
    for workload in [Workload::JellySe, Workload::Cloth128Se] {
        a_teams_power_is_the_single_passes_power_on(workload);
    }
}

fn a_teams_power_is_the_single_passes_power_on(workload: Workload) {
    use glam::DVec3;
    use springlab::physics::collide::Collider;
    use springlab::physics::stencil::{Output, Stencil, TeamPower, Update};
    let mut r = Run::new(workload);
    let stencil = r.model.stencil().expect("a lattice").clone();
    // The body moving down through a plane a little above its lowest layer, each particle a
    // little differently (so that every damper takes power).
    let lowest = r.state.x.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    for (i, v) in r.state.v.iter_mut().enumerate() {
        let wobble = 0.01 * (0.7 * i as f64).sin();
        *v = DVec3::new(0.1 + wobble, -0.5 - wobble, 0.05);
    }
    for contact in [false, true] {
        if contact {
            r.model.contact = springlab::physics::collide::ContactParams::course_2021();
            r.model.colliders = vec![Collider::Plane {
                point: DVec3::new(0.0, lowest + 0.004, 0.0),
                normal: DVec3::Y,
            }];
        }
        let dynamics = r.model.dynamics(true);
        let steps = 7;
        // Step by step: each pass's power buffer summed.
        let (mut x, mut v) = (r.state.x.clone(), r.state.v.clone());
        let mut want = Vec::new();
        let mut grouped_differs = false;
        let mut power = vec![0.0; stencil.power_len()];
        for _ in 0..steps {
            let (mut x1, mut v1) = (x.clone(), v.clone());
            let output = Output::Step {
                dynamics,
                update: Update::SemiImplicitEuler { dt: 1e-4 },
                after: None,
            };
            stencil.write(&x, &v, [&mut x1, &mut v1, &mut []], &mut power, output);
            want.push(Stencil::sum_power(&power, contact));
            let formula = grouped_power(&power, contact);
            let last = want.last().expect("a total");
            assert_eq!(
                [formula.0.to_bits(), formula.1.to_bits()],
                [last.0.to_bits(), last.1.to_bits()],
                "{workload}: the power's formula, contact {contact}"
            );
            // The plain sum, chunk after chunk: the same with one group (so the groups
            // changed nothing up to 1 024 particles), not always with more.
            let mut plain = [0.0; 8];
            for chunk in power.chunks_exact(16) {
                for (s, p) in plain.iter_mut().zip(&chunk[..8]) {
                    *s += p;
                }
            }
            let plain = plain.iter().sum::<f64>();
            if stencil.particles() <= 1024 {
                assert_eq!(plain.to_bits(), last.0.to_bits());
            }
            grouped_differs |= plain.to_bits() != last.0.to_bits();
            // The totals summed as the pass goes (one part: in registers, no buffer
            // written; more: the buffer summed), the same bits and states.
            for parts in [1, 2, 3] {
                let (mut x3, mut v3) = (x.clone(), v.clone());
                let mut buffer = vec![f64::NAN; stencil.power_len()];
                let outs = [&mut x3[..], &mut v3[..], &mut []];
                let total =
                    stencil.write_with_power_in_parts(&x, &v, outs, &mut buffer, output, parts);
                let last = want.last().expect("a total");
                assert_eq!(
                    [total.0.to_bits(), total.1.to_bits()],
                    [last.0.to_bits(), last.1.to_bits()],
                    "{workload}, {parts} parts, contact {contact}"
                );
                assert!(x3 == x1 && v3 == v1, "{workload}, {parts} parts: states");
                assert_eq!(buffer.iter().all(|p| p.is_nan()), parts == 1);
            }
            (x, v) = (x1, v1);
        }
        assert_eq!(
            want.iter().any(|p| p.1 != 0.0),
            contact,
            "the plane's contact power"
        );
        assert!(
            want.iter().all(|p| p.0 > 0.0),
            "{workload}: the dampers' power"
        );
        assert_eq!(
            grouped_differs,
            stencil.particles() > 1024,
            "{workload}: the groups' sum against the plain one"
        );
        for parts in [1, 2, 3, 5] {
            let (mut x0, mut v0) = (r.state.x.clone(), r.state.v.clone());
            let (mut x2, mut v2) = (x0.clone(), v0.clone());
            let mut buffers = [&mut x0[..], &mut v0[..], &mut x2[..], &mut v2[..]];
            let mut ring = vec![f64::NAN; stencil.power_ring_len(parts)];
            let mut totals = vec![(f64::NAN, f64::NAN); steps];
            let power = TeamPower {
                ring: &mut ring,
                totals: &mut totals,
                contact,
            };
            stencil.team_with_power(parts, &mut buffers, power, &|crew| {
                for s in 0..steps {
                    let mut pass = step_pass(s, dynamics, None);
                    pass.power = Some(s);
                    crew.pass(&pass);
                }
            });
            let bits = |p: &[(f64, f64)]| -> Vec<[u64; 2]> {
                p.iter().map(|p| [p.0.to_bits(), p.1.to_bits()]).collect()
            };
            assert_eq!(
                bits(&totals),
                bits(&want),
                "{workload}, {parts} parts, contact {contact}"
            );
            // An odd count of steps ends in the second pair of buffers.
            assert!(x2 == x && v2 == v, "{workload}, {parts} parts: states");
            // A part sums the groups that start in it in registers: no chunk's values from
            // the first group's start on are written to the ring (part 0 starts there, and
            // its chunk 0 is always one), only the groups' sums after the chunks' values.
            let slots = ring.chunks(stencil.power_slot_len());
            assert!(
                slots
                    .clone()
                    .all(|slot| slot[..16].iter().all(|p| p.is_nan())),
                "{workload}, {parts} parts: part 0's chunks written to the ring"
            );
            assert!(
                slots
                    .take(steps)
                    .all(|slot| !slot[stencil.power_len()].is_nan()),
                "{workload}, {parts} parts: no group's sums"
            );
        }
    }
}

/// Step `s` of semi-implicit Euler in a team whose buffers 0, 1 and 2, 3 hold two states.
fn step_pass<'a>(
    s: usize,
    dynamics: springlab::physics::stencil::Dynamics<'a>,
    after: Option<springlab::physics::stencil::After<'a>>,
) -> springlab::physics::stencil::Pass<'a> {
    use springlab::physics::stencil::{Pass, TeamUpdate};
    let (from, to) = if s.is_multiple_of(2) { (0, 2) } else { (2, 0) };
    Pass {
        x: from,
        v: from + 1,
        outs: [Some(to), Some(to + 1), None],
        dynamics,
        update: TeamUpdate::SemiImplicitEuler { dt: 1e-4 },
        after,
        power: None,
    }
}

#[test]
fn pool_size_comes_from_the_machine_unless_overridden() {
    assert_eq!(threads_for(None, Some(12)), 12);
    assert_eq!(threads_for(None, None), 1);
    assert_eq!(threads_for(Some(" 3 "), Some(12)), 3);
    assert_eq!(threads_for(Some("1"), Some(12)), 1);
    // Not a whole number ≥ 1: the machine's count.
    assert_eq!(threads_for(Some("0"), Some(4)), 4);
    assert_eq!(threads_for(Some("many"), Some(4)), 4);
    assert_eq!(threads_for(Some("100000"), Some(4)), MAX_THREADS);
    assert_eq!(threads_for(None, Some(1000)), MAX_THREADS);
}
