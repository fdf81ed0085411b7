//! The integrators against exact solutions: convergence orders and stability limits on the
//! harmonic oscillator `x(t) = 1 + A cos(ω t)`, ω = √(k/m) = 10 rad/s.

use crate::common;

use common::{fitted_order, oscillator, oscillator_x};
use springlab::physics::Method;

const OMEGA: f64 = 10.0;

/// |x_sim(1 s) - x_exact(1 s)| for time step `dt`.
fn error_at_one_second(method: Method, dt: f64) -> f64 {
    let mut sim = oscillator(method, &["verlet_damping=0", "iterations=0"]);
    sim.set_dt(dt);
    let steps = (1.0 / dt).round() as u64;
    sim.run(steps, |_| {});
    assert!(sim.diverged.is_none(), "{method} diverged at dt {dt}");
    let exact = 1.0 + 0.1 * (OMEGA * 1.0).cos();
    (oscillator_x(&sim) - exact).abs()
}

fn measured_order(method: Method) -> f64 {
    // dt·ω = 0.05 down to 0.00625: small enough that every method is in its asymptotic regime.
    let dt0 = 0.005;
    let points: Vec<(f64, f64)> = (0..4)
        .map(|i| {
            let dt = dt0 / f64::from(1 << i);
            (dt, error_at_one_second(method, dt))
        })
        .collect();
    let order = fitted_order(&points);
    eprintln!("{method}: errors {points:?} -> order {order:.3}");
    order
}

#[test]
fn convergence_orders_match_theory() {
    let expected = [
        (Method::ExplicitEuler, 1.0),
        (Method::SemiImplicitEuler, 1.0),
        (Method::ImplicitEuler, 1.0),
        (Method::PredictorCorrector, 1.0),
        (Method::Midpoint, 2.0),
        (Method::Verlet, 2.0),
        (Method::VelocityVerlet, 2.0),
        (Method::Rk4, 4.0),
    ];
    for (method, order) in expected {
        let measured = measured_order(method);
        assert!(
            (measured - order).abs() <= 0.15,
            "{method}: measured order {measured:.3}, expected {order} ± 0.15"
        );
    }
}

/// Initial stretch (m): small, so that a growth of 10⁵ still leaves the spring in its linear
/// range (|x - L0| < L0; beyond, the particle would pass through the pin).
const AMPLITUDE: f64 = 1e-6;

/// Runs the undamped oscillator at `dt·ω = z` for `steps` steps and returns the largest
/// |x - L0| seen divided by the initial amplitude, stopping once it passes 10⁵.
fn amplitude_growth(method: Method, z: f64, steps: u64) -> f64 {
    let mut sim = oscillator(
        method,
        &["amplitude=1e-6", "verlet_damping=0", "iterations=0"],
    );
    sim.set_dt(z / OMEGA);
    let mut max = 0.0f64;
    for _ in 0..steps {
        sim.step();
        max = max.max((oscillator_x(&sim) - 1.0).abs() / AMPLITUDE);
        if max > 1e5 || sim.diverged.is_some() {
            return f64::INFINITY;
        }
    }
    max
}

#[test]
fn semi_implicit_euler_and_verlet_are_stable_below_two_and_grow_above() {
    for method in [Method::SemiImplicitEuler, Method::Verlet] {
        // Below the limit the orbit is an ellipse: bounded by 1/√(1 - (z/2)²) ≈ 7.1 at z = 1.98.
        let stable = amplitude_growth(method, 1.98, 5_000);
        assert!(stable < 10.0, "{method} at dt·ω = 1.98 grew by {stable}");
        // Above it one eigenvalue has modulus ≈ 1.33: growth by orders of magnitude.
        let growing = amplitude_growth(method, 2.02, 5_000);
        assert!(
            growing.is_infinite(),
            "{method} at dt·ω = 2.02 grew only by {growing}"
        );
    }
}

#[test]
fn rk4_is_stable_below_two_root_two_and_grows_above() {
    let stable = amplitude_growth(Method::Rk4, 2.80, 5_000);
    assert!(stable <= 1.0 + 1e-9, "RK4 at dt·ω = 2.80 grew by {stable}");
    let growing = amplitude_growth(Method::Rk4, 2.86, 5_000);
    assert!(
        growing.is_infinite(),
        "RK4 at dt·ω = 2.86 grew only by {growing}"
    );
}

#[test]
fn explicit_euler_energy_grows_at_every_dt() {
    for z in [1e-3, 1e-2, 0.1, 0.5, 1.0] {
        let mut sim = oscillator(Method::ExplicitEuler, &["amplitude=1e-6"]);
        sim.set_dt(z / OMEGA);
        let mut last = sim.energy().total;
        // 20 steps grow the amplitude at most 2^10 times: still linear.
        for _ in 0..20 {
            sim.step();
            let e = sim.energy().total;
            // Exact factor per step: |1 + i dt ω|² = 1 + (dt ω)².
            assert!(e > last, "explicit Euler energy did not grow at dt·ω = {z}");
            let ratio = e / last;
            assert!(
                (ratio - (1.0 + z * z)).abs() < 1e-6 * (1.0 + z * z),
                "ratio {ratio} at z {z}"
            );
            last = e;
        }
    }
}

#[test]
fn implicit_euler_is_stable_at_dt_omega_100_and_loses_energy() {
    let mut sim = oscillator(Method::ImplicitEuler, &[]);
    sim.set_dt(100.0 / OMEGA);
    let mut last = sim.energy().total;
    for _ in 0..1_000 {
        sim.step();
        let e = sim.energy().total;
        assert!(e <= last, "implicit Euler energy rose from {last} to {e}");
        last = e;
    }
    assert!(sim.diverged.is_none());
    // Exact factor per step on the amplitude: 1/|1 - i dt ω| = 1/√(1 + 10⁴).
    assert!(
        last < 1e-12,
        "energy after 1000 steps at dt·ω = 100: {last}"
    );
}

/// Largest dt·ω in [lo, hi] at which `method` does not grow over 2000 steps (bisection).
fn measured_limit(method: Method, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if amplitude_growth(method, mid, 2_000) <= 1.0 + 1e-9 {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn predictor_corrector_limit_is_dt_omega_one() {
    // |R(i z)|² = 1 - z² + z⁴ for R = 1 + z + z²: stable (and lossy) exactly while z ≤ 1.
    let limit = measured_limit(Method::PredictorCorrector, 0.5, 1.5);
    assert!(
        (limit - 1.0).abs() < 0.01,
        "predictor–corrector limit dt·ω = {limit}"
    );
    // And on a pure decay x' = -λ x it is stable only for dt·λ ≤ 1, half of explicit Euler's 2:
    // covered by the amplification factor 1 + z + z², z = -dt λ, evaluated here for the record.
    let r = |z: f64| 1.0 + z + z * z;
    assert!(r(-1.0).abs() <= 1.0 && r(-1.01).abs() > 1.0);
}

#[test]
fn rk4_matches_its_amplification_factor_on_the_oscillator() {
    // `springlab run oscillator --method rk4 --dt 0.01 --time 10`: x_n - 1 = Re(A R(iθ)^n),
    // R(z) = 1 + z + z²/2 + z³/6 + z⁴/24, θ = dt ω = 0.1, n = 1000.
    let mut sim = oscillator(Method::Rk4, &[]);
    sim.run(1000, |_| {});
    assert_eq!(sim.force_evals, 4000);
    let (theta, mut re, mut im) = (0.1f64, 0.1f64, 0.0f64);
    let (r_re, r_im) = (
        1.0 - theta.powi(2) / 2.0 + theta.powi(4) / 24.0,
        theta - theta.powi(3) / 6.0,
    );
    for _ in 0..1000 {
        (re, im) = (re * r_re - im * r_im, re * r_im + im * r_re);
    }
    let x = oscillator_x(&sim);
    assert!(
        (x - (1.0 + re)).abs() < 1e-12,
        "RK4 x = {x}, theory {}",
        1.0 + re
    );
    // Its distance from the exact solution is RK4's own phase error, 4.8e-6 m at this dt.
    let exact = 1.0 + 0.1 * 100f64.cos();
    assert!((x - exact).abs() < 5e-6, "RK4 error {}", (x - exact).abs());
}

// ---------------------------------------------------------------------------------------------
// Implicit Euler and contacts; the energy accounting

fn run_scene(
    name: &str,
    sets: &[&str],
    method: Method,
    dt: f64,
) -> springlab::simulation::Simulation {
    let sets: Vec<String> = sets.iter().map(|s| (*s).to_string()).collect();
    let mut scene = springlab::scene::load(name, &sets).expect("scene");
    scene.set_method(method);
    let mut sim = springlab::simulation::Simulation::new(scene);
    sim.set_dt(dt);
    sim
}

/// Runs `sim` for `time` s and asserts that the total energy never rises from one step to the
/// next (beyond rounding, 1e-12 of its terms); returns the lowest particle height reached.
fn assert_energy_never_rises(sim: &mut springlab::simulation::Simulation, time: f64) -> f64 {
    let steps = (time / sim.dt()).round() as u64;
    let mut last = sim.energy();
    let mut lowest = f64::INFINITY;
    for _ in 0..steps {
        assert!(sim.step().is_none(), "diverged: {:?}", sim.diverged);
        let e = sim.energy();
        let scale = last.kinetic.abs() + last.gravity.abs() + last.elastic.abs();
        assert!(
            e.total <= last.total + 1e-12 * scale,
            "energy rose from {} J to {} J at t = {} s (dt = {} s)",
            last.total,
            e.total,
            sim.time(),
            sim.dt()
        );
        last = e;
        lowest = sim.positions().map(|p| p.y).fold(lowest, f64::min);
    }
    lowest
}

#[test]
fn implicit_euler_adds_no_energy_over_impacts() {
    // The jelly lands on the edge of the floor's hole at t ≈ 1.5 s and falls into the bowl; at
    // dt = 0.04 s the old post-step projection squeezed its springs and added 65 kJ.
    for dt in [0.01, 0.04, 0.1] {
        let mut sim = run_scene(
            "jelly-bowl",
            &["cg_tolerance=1e-8"],
            Method::ImplicitEuler,
            dt,
        );
        let lowest = assert_energy_never_rises(&mut sim, 2.4);
        assert!(
            lowest < 0.0,
            "dt {dt}: the jelly never went into the hole ({lowest})"
        );
        let solver = sim.solver_report();
        assert!(
            solver.iterations_max > 0 && solver.residual_max <= 1e-8,
            "{solver:?}"
        );
        assert!(
            solver.constrained_max > 0,
            "dt {dt}: no contact reached the solve"
        );
    }
    // The four spheres fall into the cloth (they reach it at t ≈ 0.3 s).
    for dt in [0.005, 0.02] {
        let mut sim = run_scene(
            "cloth-spheres",
            &["cg_tolerance=1e-8"],
            Method::ImplicitEuler,
            dt,
        );
        assert_energy_never_rises(&mut sim, 1.0);
        let sphere = sim.scene.bodies[0].state.spheres[0];
        assert!(
            sphere.center.y < 0.0,
            "dt {dt}: the spheres did not sink into the cloth"
        );
    }
}

#[test]
fn implicit_euler_keeps_the_spheres_contacts_inside_the_solve() {
    // With the energy guard off, the step itself must not add energy while the four spheres
    // press into the cloth (from t ≈ 0.3 s): a projection out of the spheres after the step
    // added up to 2 kJ per step at dt = 5 ms and made the guard halve 277 of 600 steps.
    let mut sim = run_scene("cloth-spheres", &[], Method::ImplicitEuler, 0.005);
    sim.set_energy_guard(false);
    let lowest = assert_energy_never_rises(&mut sim, 1.0);
    assert!(
        lowest < -0.5,
        "the spheres did not carry the cloth down ({lowest})"
    );
    // Guard on: nothing for it to take again.
    let mut sim = run_scene("cloth-spheres", &[], Method::ImplicitEuler, 0.005);
    sim.run(200, |_| {});
    let solver = sim.solver_report();
    assert_eq!((solver.solves, solver.halved_steps), (200, 0), "{solver:?}");
    assert!(
        solver.constrained_max > 0,
        "no sphere contact reached the solve"
    );
}

#[test]
fn the_energy_guard_takes_back_a_linearisation_rise_but_not_a_resting_contacts_lag() {
    // A linearisation error: on jelly-bowl at dt = 0.1 s one unguarded step adds hundreds of J
    // as the jelly squeezes into the hole; guarded, that step is halved and no step adds energy.
    let mut off = run_scene("jelly-bowl", &[], Method::ImplicitEuler, 0.1);
    off.set_energy_guard(false);
    let mut largest_rise = f64::NEG_INFINITY;
    for _ in 0..30 {
        let before = off.energy().total;
        assert!(off.step().is_none(), "{:?}", off.diverged);
        largest_rise = largest_rise.max(off.energy().total - before);
    }
    assert!(largest_rise > 100.0, "no step rose: {largest_rise} J");
    let mut on = run_scene("jelly-bowl", &[], Method::ImplicitEuler, 0.1);
    assert_energy_never_rises(&mut on, 3.0);
    assert!(on.solver_report().halved_steps >= 1);

    // A resting contact: the four spheres lie in the cloth from t ≈ 6 s. With a sphere's
    // reaction added after the solve each such step's energy rose by about 1 J that the next
    // steps took out again, and halving only halved the rate (taking every such step down to
    // 2⁵ substeps cost 63 solves a step). With the spheres' velocities inside the solve the
    // pair moves as one and no step rises, so the guard halves none. Nothing accumulates: over
    // a whole second the energy rises by less than 1 J, and after 6 s it is lower than where it
    // started.
    let mut sim = run_scene("cloth-spheres", &[], Method::ImplicitEuler, 0.005);
    sim.run(1200, |_| {});
    let solves = sim.solver_report().solves;
    let start = sim.energy().total;
    let mut last = start;
    for _ in 0..6 {
        sim.run(200, |_| {});
        let e = sim.energy().total;
        assert!(
            e - last < 1.0,
            "the energy rose from {last} J to {e} J by t = {} s",
            sim.time()
        );
        last = e;
    }
    assert!(
        last < start,
        "the energy rose from {start} J to {last} J over 6 s at rest"
    );
    let per_step = (sim.solver_report().solves - solves) as f64 / 1200.0;
    assert!(per_step <= 5.0, "{per_step} solves a step at rest");
    assert_eq!(
        sim.solver_report().halved_steps,
        0,
        "a resting step rose and was retaken"
    );
}

/// Implicit Euler on `cloth-spheres` at `dt` for 1 s (the spheres press into the cloth from
/// t ≈ 0.3 s) with `sets`: every particle position and sphere centre (m).
fn cloth_spheres_at_one_second(dt: f64, sets: &[&str]) -> Vec<glam::DVec3> {
    let mut sim = run_scene("cloth-spheres", sets, Method::ImplicitEuler, dt);
    sim.run((1.0 / dt).round() as u64, |_| {});
    assert!(sim.diverged.is_none(), "{:?}", sim.diverged);
    let spheres: Vec<glam::DVec3> = sim.scene.bodies[0]
        .state
        .spheres
        .iter()
        .map(|s| s.center)
        .collect();
    sim.positions().chain(spheres).collect()
}

#[test]
fn the_default_cg_tolerance_costs_under_a_tenth_of_the_methods_own_error() {
    // The solve need not be more exact than the step: implicit Euler's own error at dt = 5 ms
    // (against dt/4, a lower bound for a first-order method) must be at least ten times what
    // stopping CG at the default relative residual changes (against 1e-10).
    let largest = |a: &[glam::DVec3], b: &[glam::DVec3]| {
        a.iter()
            .zip(b)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max)
    };
    let default = cloth_spheres_at_one_second(0.005, &[]);
    let tight = cloth_spheres_at_one_second(0.005, &["cg_tolerance=1e-10"]);
    let finer = cloth_spheres_at_one_second(0.00125, &["cg_tolerance=1e-10"]);
    let (solver_error, method_error) = (largest(&default, &tight), largest(&tight, &finer));
    assert!(
        solver_error > 0.0 && 10.0 * solver_error <= method_error,
        "tolerance changes the state by {solver_error} m, the method's error is {method_error} m"
    );
}

#[test]
fn failed_implicit_solves_are_divergences() {
    // An overflowing stiffness (outside the range a user may set, so set in code): the solve
    // is not finite.
    let mut sim = run_scene("rope", &[], Method::ImplicitEuler, 1.0 / 64.0);
    let damping = sim.scene.bodies[0].model.springs()[0].damping;
    sim.scene.bodies[0]
        .model
        .set_spring_coefficients(1e308, damping);
    sim.run(10, |_| {});
    let d = sim.diverged.as_ref().expect("reported");
    assert_eq!(d.step, 1);
    assert!(d.reason.contains("overflowed"), "{}", d.reason);
    // Too few iterations for a 40-node rope hanging straight down (gravity along it).
    let mut sim = run_scene(
        "rope",
        &["nodes=40", "end=[0,-2,0]"],
        Method::ImplicitEuler,
        0.5,
    );
    sim.scene.bodies[0].params.cg_max_iterations = 20;
    sim.step();
    let d = sim.diverged.as_ref().expect("reported");
    assert!(d.reason.contains("did not converge"), "{}", d.reason);
    let report = sim.report(0.0);
    let solver = report.solver.expect("solver statistics");
    assert_eq!(solver.iterations_max, 20);
    assert!(solver.residual_max > 1e-10);
}

/// The largest |E + D - E_0| (J) over `time` s of the damped rope under `method` at `dt`.
fn largest_residual(method: Method, dt: f64, time: f64) -> (f64, f64) {
    let mut sim = run_scene("rope", &["damping=2", "drag=0.1"], method, dt);
    let e0 = sim.energy().total;
    let mut largest = 0.0f64;
    sim.run((time / dt).round() as u64, |s| {
        largest = largest.max(s.energy_residual().abs())
    });
    assert!(sim.diverged.is_none());
    // Something was dissipated: the accounting is not trivially zero.
    assert!(sim.dissipated().dampers_and_drag > 0.1 * e0.abs());
    (largest, e0)
}

#[test]
fn energy_residual_shrinks_with_the_methods_order() {
    // RK4 at a small dt: the residual stays below 1e-6 of E0 over 10 s ...
    let (r, e0) = largest_residual(Method::Rk4, 1.0 / 512.0, 10.0);
    assert!(r < 1e-6 * e0, "RK4 residual {r} J, E0 {e0} J");
    // ... and grows with dt like dt⁴: the dissipated power is integrated with RK4's own stages.
    let points: Vec<(f64, f64)> = [64.0, 128.0, 256.0]
        .iter()
        .map(|n| (1.0 / n, largest_residual(Method::Rk4, 1.0 / n, 10.0).0))
        .collect();
    let fitted = fitted_order(&points);
    assert!(
        (fitted - 4.0).abs() < 0.3,
        "RK4: residual {points:?}, order {fitted}"
    );
}

/// Verlet's error at t = 1 s on the oscillator damped at the rate `mu` (1/s), against
/// u(t) = u0 e^{-γt}(cos ω_d t + γ/ω_d sin ω_d t), γ = μ/2, ω_d = √(ω² - γ²); the damping
/// comes from `sets(dt)`.
fn verlet_damped_error(mu: f64, sets: impl Fn(f64) -> Vec<String>) -> Vec<(f64, f64)> {
    let gamma = 0.5 * mu;
    let wd = (OMEGA * OMEGA - gamma * gamma).sqrt();
    let exact = 1.0 + 0.1 * (-gamma).exp() * (wd.cos() + gamma / wd * wd.sin());
    [0.005, 0.0025, 0.00125, 0.000625]
        .iter()
        .map(|&dt| {
            let owned = sets(dt);
            let sets: Vec<&str> = owned.iter().map(String::as_str).collect();
            let mut sim = oscillator(Method::Verlet, &sets);
            sim.set_dt(dt);
            sim.run((1.0 / dt).round() as u64, |_| {});
            (dt, (oscillator_x(&sim) - exact).abs())
        })
        .collect()
}

#[test]
fn verlet_order_with_dampers_and_with_its_damping_rate() {
    let base = |extra: String| vec!["iterations=0".to_string(), "verlet_damping=0".into(), extra];
    // A spring damper k_d = 2 N·s/m (μ = k_d/m = 2 1/s): the damper sees (x_n - x_{n-1})/dt,
    // half a step late: first order.
    let damper = fitted_order(&verlet_damped_error(2.0, |_| base("damping=2".into())));
    assert!((damper - 1.0).abs() < 0.15, "with a damper: order {damper}");
    // The same damping as Verlet's rate r = 2 1/s, applied with the centred velocity: second
    // order, and the same motion at every dt.
    let rate = fitted_order(&verlet_damped_error(2.0, |_| {
        base("verlet_damping_rate=2".into())
    }));
    assert!((rate - 2.0).abs() < 0.15, "with the rate: order {rate}");
    // GAMES101's factor γ per step, chosen as γ = r dt at each dt to give the same decay
    // rate: first order again.
    let per_step = fitted_order(&verlet_damped_error(2.0, |dt| {
        vec![
            "iterations=0".to_string(),
            format!("verlet_damping={}", 2.0 * dt),
        ]
    }));
    assert!(
        (per_step - 1.0).abs() < 0.15,
        "with γ = r dt: order {per_step}"
    );
}
