//! Issue 26 items 2 and 3: the usable dt beside the stable one, and the damped theory
//! linearised where the scene hangs.
//!
//! Truths: a pendulum (one free mass on a spring hanging from a pinned point) has, at its
//! equilibrium `L = L0 + m g / k`, the transverse frequency `√(g/L)` twice and the longitudinal
//! `√(k/m)`; an along-spring damper damps only the longitudinal mode (`μ = k_d/m`). Explicit
//! Euler multiplies an undamped mode by `|1 + i ω dt| > 1` at every dt. The usable dt is
//! defined by the energy residual `|E + D - E0| ≤ 1 % |E0|`, re-measured here over 10 s.

use crate::common;
use common::json;

use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::Simulation;
use springlab::study::Stability;
use springlab::study::stability::{self, StabilityOptions};
use springlab::study::theory::{self, equilibrium};

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn a_hanging_pendulum_has_its_textbook_frequencies_and_dampings() {
    let (m, k, d, g, l0): (f64, f64, f64, f64, f64) = (2.0, 300.0, 5.0, 9.8, 4.0);
    let sets = [
        "nodes=2".to_string(),
        format!("mass={m}"),
        format!("stiffness={k}"),
        format!("damping={d}"),
        format!("gravity={g}"),
    ];
    let scene = scene::load("rope", &sets).expect("built-in");
    let body = &scene.bodies[0];
    let (spectrum, report) =
        equilibrium::spectrum_at_equilibrium(&body.model, &body.state).expect("it hangs");
    let length = l0 + m * g / k;
    let pendulum = (g / length).sqrt();
    let spring = (k / m).sqrt();
    assert!(
        report.force_ratio <= equilibrium::FORCE_TOLERANCE,
        "{report:?}"
    );
    let mut omegas: Vec<(f64, f64)> = spectrum.modes.iter().map(|m| (m.omega, m.mu)).collect();
    omegas.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(omegas.len(), 3, "{omegas:?}");
    for (omega, mu) in &omegas[..2] {
        assert!(
            relative(*omega, pendulum) < 1e-9,
            "{omega} against √(g/L) = {pendulum}"
        );
        assert!(mu.abs() < 1e-9, "a pendulum mode is not damped: μ = {mu}");
    }
    assert!(
        relative(omegas[2].0, spring) < 1e-9,
        "{:?} against {spring}",
        omegas[2]
    );
    assert!(
        relative(omegas[2].1, d / m) < 1e-9,
        "{:?} against k_d/m",
        omegas[2]
    );
    assert!(relative(report.omega_min, pendulum) < 1e-9);
    // At rest (horizontal, rest length) the pendulum modes are not there at all.
    let at_rest = theory::spectrum(&body.model, &body.state, spring);
    assert_eq!(at_rest.modes.len(), 1, "{:?}", at_rest.modes);
    // So explicit Euler is conditional at rest and unstable at every dt where it hangs.
    let ee = Method::ExplicitEuler;
    assert_eq!(
        theory::limit(ee, &body.params, &at_rest).stability,
        "conditional"
    );
    assert_eq!(theory::limit(ee, &body.params, &spectrum).stability, "none");
    // RK4 stays conditional there, limited by the stiffest mode: 2√2/ω on the imaginary axis
    // is above the damped spring mode's limit, so the binding mode is one of the two.
    let rk4 = theory::limit(Method::Rk4, &body.params, &spectrum);
    assert_eq!(rk4.stability, "conditional", "{rk4:?}");
}

#[test]
fn the_damped_ropes_explicit_euler_is_classed_by_the_hanging_equilibrium() {
    let (scene, _) =
        stability::load_scene("rope", &["damping=2".to_string()]).expect("built-in scene");
    let options = StabilityOptions {
        methods: vec![Method::ExplicitEuler, Method::SemiImplicitEuler],
        ..StabilityOptions::default()
    };
    let r = stability::stability(&scene, &options, &mut |_, _| {}).expect("study");
    assert!(r.equilibrium.is_some(), "{}", r.equilibrium_spectrum);
    let ee = &r.methods[0];
    // At rest the linear test finds a limit (the "conditional, 2e-2 s") ...
    assert_eq!(ee.linear_stability, Stability::Conditional, "{ee:?}");
    // ... but where the rope hangs its pendulum modes are undamped: none.
    let at_eq = ee
        .equilibrium_theory
        .as_ref()
        .expect("theory at the equilibrium");
    assert_eq!(at_eq.stability, "none");
    assert_eq!(ee.stability, Stability::None);
    assert!(ee.classed_by_equilibrium);
    assert_eq!(ee.max_stable_dt, None);
    // Semi-implicit Euler is stable on undamped modes: not overruled.
    let se = &r.methods[1];
    assert_eq!(se.stability, Stability::Conditional, "{se:?}");
    assert!(!se.classed_by_equilibrium);
}

/// `|E + D - E0|` at its largest over `seconds` of `scene` with `method` at `dt` (J), and E0:
/// sampled every 10 steps (the residual is a sum of smooth per-step terms; the steps between
/// samples go through the fused multi-step passes). With `stop_above`, the run stops at the
/// first sample whose residual exceeds it.
fn largest_residual(
    scene: &scene::Scene,
    method: Method,
    dt: f64,
    seconds: f64,
    stop_above: Option<f64>,
) -> (f64, f64) {
    let mut scene = scene.clone();
    scene.set_method(method);
    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    sim.set_accounting(true);
    let mut worst = 0.0f64;
    let steps = (seconds / dt).round() as u64;
    let mut done = 0;
    while done < steps {
        let n = 10.min(steps - done);
        sim.run(n, |_| {});
        done += n;
        assert!(sim.diverged.is_none(), "{method} diverged at dt = {dt}");
        worst = worst.max(sim.energy_residual().abs());
        if stop_above.is_some_and(|limit| worst > limit) {
            break;
        }
    }
    (worst, sim.energy_initial())
}

#[test]
fn jelly_bowl_prints_a_usable_dt_and_it_is_usable_for_ten_seconds() {
    let methods = [Method::ExplicitEuler, Method::SemiImplicitEuler];
    let report = json(&[
        "study",
        "stability",
        "jelly-bowl",
        "--set",
        "n=3",
        "--methods",
        "explicit-euler,semi-implicit-euler",
        "--json",
    ]);
    // The course's jelly with 3³ particles instead of 10³: the same bowl, floor, hole and
    // coefficients, a study and three 10 s runs that a test can afford.
    let scene = scene::load("jelly-bowl", &["n=3".to_string()]).expect("built-in");
    for (entry, method) in report["methods"]
        .as_array()
        .expect("methods")
        .iter()
        .zip(methods)
    {
        assert_eq!(entry["method"], method.name());
        let usable = &entry["usable"];
        assert_eq!(usable["fraction"], 0.01);
        let dt = usable["dt"]
            .as_f64()
            .unwrap_or_else(|| panic!("{method}: {usable}"));
        let stable = entry["max_stable_dt"].as_f64().expect("scene dt");
        assert!(
            dt <= stable,
            "{method}: usable {dt} above the scene dt {stable}"
        );
        let (worst, e0) = largest_residual(&scene, method, 0.95 * dt, 10.0, None);
        assert!(
            worst <= 0.01 * e0.abs(),
            "{method} at 0.95 × {dt} s: |residual| reached {worst} J, E0 = {e0} J"
        );
        // Explicit Euler's residual drifts (it pumps every vibration): at twice its usable dt
        // it passes 1 % of E0 within the same 10 s, so the check above fails on a usable dt
        // printed twice too large. (Semi-implicit Euler's residual oscillates; its usable dt
        // is the search's lower bound, and twice it still holds here.)
        if method == Method::ExplicitEuler {
            let (worst, e0) =
                largest_residual(&scene, method, 2.0 * dt, 10.0, Some(0.01 * e0.abs()));
            assert!(
                worst > 0.01 * e0.abs(),
                "{method} at 2 × {dt} s: |residual| stayed at {worst} J, E0 = {e0} J"
            );
        }
    }
}

/// `(method, class, linear dt, scene dt)` as the study printed them before it started from the
/// damped theory's bracket and ran the methods on separate threads (recorded from that build's
/// `study stability SCENE --json`).
type Recorded = (Method, Stability, Option<f64>, Option<f64>);

/// The study of `scene` (with `sets`) against `recorded`: the same classes, the linear limits
/// within twice the bisection tolerance, the scene limits within 1 % (their bisection stops at
/// 0.5 %).
fn same_as_recorded(scene: &str, sets: &[String], recorded: &[Recorded]) {
    let (scene, _) = stability::load_scene(scene, sets).expect("built-in scene");
    let options = StabilityOptions {
        methods: recorded.iter().map(|r| r.0).collect(),
        ..StabilityOptions::default()
    };
    let r = stability::stability(&scene, &options, &mut |_, _| {}).expect("study");
    for (m, (method, class, linear, limit)) in r.methods.iter().zip(recorded) {
        assert_eq!(m.method, *method);
        assert_eq!(m.stability, *class, "{method}");
        let close = |a: Option<f64>, b: Option<f64>, tolerance: f64| match (a, b) {
            (Some(a), Some(b)) => relative(a, b) <= tolerance,
            (a, b) => a == b,
        };
        assert!(
            close(m.linear_max_dt, *linear, 2e-3),
            "{method}: linear {:?} against {linear:?}",
            m.linear_max_dt
        );
        // A scene limit well below the linear one is set by a nonlinear resonance (the undamped
        // rope's swing, module docs of the study), not monotone in dt: the confirmation's path
        // from a start 0.1 % away ends within a few per cent.
        let resonance = matches!((linear, limit), (Some(l), Some(s)) if *s < 0.95 * l);
        let tolerance = if resonance { 5e-2 } else { 1e-2 };
        assert!(
            close(m.max_stable_dt, *limit, tolerance),
            "{method}: scene {:?} against {limit:?}",
            m.max_stable_dt
        );
    }
}

#[test]
fn the_faster_search_finds_the_recorded_limits() {
    use Method::*;
    use Stability::{Conditional as C, None as N, Unconditional as U};
    same_as_recorded(
        "rope",
        &[],
        &[
            (ExplicitEuler, N, None, None),
            (
                SemiImplicitEuler,
                C,
                Some(0.123_512_602),
                Some(0.100_279_791),
            ),
            (Midpoint, N, None, None),
            (Rk4, C, Some(0.174_806_410), Some(0.174_806_410)),
            (ImplicitEuler, U, None, None),
            (
                PredictorCorrector,
                C,
                Some(0.061_803_399),
                Some(0.061_803_399),
            ),
            (Verlet, C, None, Some(0.919_129_907)),
            (VelocityVerlet, C, Some(0.123_512_602), Some(0.103_347_269)),
        ],
    );
    same_as_recorded(
        "cube-plane",
        &["n=3".to_string()],
        &[
            (ExplicitEuler, C, Some(3.131_283e-3), Some(3.131_283e-3)),
            (SemiImplicitEuler, C, Some(2.834_007e-3), Some(2.834_007e-3)),
            (Rk4, C, Some(4.360_771e-3), Some(4.360_771e-3)),
            (
                PredictorCorrector,
                C,
                Some(1.565_641e-3),
                Some(1.565_641e-3),
            ),
            (VelocityVerlet, C, Some(2.967_867e-3), Some(2.967_867e-3)),
        ],
    );
}
