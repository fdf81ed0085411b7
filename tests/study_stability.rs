//! `springlab study stability`: the stiffest mode against closed forms and docs/workloads.md, the
//! measured limits against the oscillator's amplification factors, determinism and bad input.

use crate::common;
use common::{json, springlab};

use serde_json::Value;
use springlab::bench::{Workload, setup};
use springlab::physics::Method;
use springlab::scene;
use springlab::simulation::Simulation;
use springlab::study::modes::omega_max_from as omega_from;
use springlab::study::stability::{self, StabilityOptions};
use springlab::study::{Stability, StudyError, omega_max, theory};

fn stderr_of_failure(args: &[&str]) -> String {
    let out = springlab(args);
    assert!(!out.status.success(), "expected failure for {args:?}");
    assert!(out.stdout.is_empty(), "nothing on stdout for {args:?}");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn method<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["methods"]
        .as_array()
        .expect("methods")
        .iter()
        .find(|m| m["method"] == name)
        .unwrap_or_else(|| panic!("no entry for {name}"))
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

// ---------------------------------------------------------------------------------------------
// ω_max

#[test]
fn omega_max_of_the_oscillator_is_root_k_over_m() {
    // Stretched by the default 0.1 m the spring has a transverse stiffness k (1 - L0/L) too;
    // the largest eigenvalue is still the axial k/m = 100 1/s².
    let scene = scene::load("oscillator", &[]).expect("oscillator");
    let body = &scene.bodies[0];
    let e = omega_max(&body.model, &body.state);
    assert!(relative(e.omega, 10.0) < 1e-6, "ω_max = {}", e.omega);
    assert_eq!(e.method, "power iteration");
    assert!(
        e.gershgorin_omega >= e.omega * (1.0 - 1e-12),
        "Gershgorin {} below {}",
        e.gershgorin_omega,
        e.omega
    );
    // Another mass and stiffness: ω = √(k/m) = √(500 / 2).
    let scene = scene::load("oscillator", &["stiffness=500".into(), "mass=2".into()]).unwrap();
    let e = omega_max(&scene.bodies[0].model, &scene.bodies[0].state);
    assert!(
        relative(e.omega, 250f64.sqrt()) < 1e-6,
        "ω_max = {}",
        e.omega
    );
}

#[test]
fn omega_max_of_the_rope_is_the_fixed_free_chain() {
    // At rest the springs have their rest length: only the axial stiffness, a chain of N free
    // masses hanging from a pinned end, λ_j = 4 (k/m) sin²((2j - 1) π / (4N + 2)), j = 1..N.
    for (nodes, stiffness, mass) in [(3, 100.0, 1.0), (10, 100.0, 1.0), (6, 2000.0, 0.5)] {
        let sets = vec![
            format!("nodes={nodes}"),
            format!("stiffness={stiffness}"),
            format!("mass={mass}"),
        ];
        let scene = scene::load("rope", &sets).expect("rope");
        let e = omega_max(&scene.bodies[0].model, &scene.bodies[0].state);
        let n = (nodes - 1) as f64;
        let s = ((2.0 * n - 1.0) * std::f64::consts::PI / (4.0 * n + 2.0)).sin();
        let exact = (4.0 * stiffness / mass * s * s).sqrt();
        assert!(
            relative(e.omega, exact) < 1e-6,
            "{nodes} nodes: ω_max = {}, closed form {exact}",
            e.omega
        );
        assert!(e.gershgorin_omega >= exact, "Gershgorin below ω_max");
    }
    // The default rope: N = 2, ω_max² = 100 (3 + √5)/2 = 261.8, ω_max = 16.18 rad/s.
    let scene = scene::load("rope", &[]).unwrap();
    let e = omega_max(&scene.bodies[0].model, &scene.bodies[0].state);
    assert!(relative(e.omega * e.omega, 50.0 * (3.0 + 5f64.sqrt())) < 1e-9);
}

#[test]
fn omega_max_of_the_w1_jelly_matches_workloads_md() {
    // docs/workloads.md W1: λ_max(M⁻¹K) = 3.37e4 at rest, ω_max = 184 rad/s.
    let (model, state) = setup(Workload::JellySe);
    let e = omega_max(&model, &state);
    assert!(
        relative(e.lambda, 3.37e4) < 0.01,
        "λ_max = {} (1/s²), docs/workloads.md 3.37e4",
        e.lambda
    );
    assert!(relative(e.omega, 184.0) < 0.01, "ω_max = {}", e.omega);
    // The Rayleigh quotient is a lower bound, Gershgorin an upper one.
    assert!(e.gershgorin_lambda >= e.lambda);
    // Deterministic: the same start vector, the same iterations, the same bits.
    assert_eq!(omega_max(&model, &state), e);
    // Warm started from its own converged vector it stops within a few iterations at the
    // same value; from an empty vector it is the cold iteration, bit for bit.
    let mut warm = Vec::new();
    assert_eq!(omega_from(&model, &state, &mut warm), e);
    let again = omega_from(&model, &state, &mut warm);
    assert!(again.iterations < 50, "{again:?}");
    assert!(relative(again.omega, e.omega) < 1e-6, "{again:?}");
}

#[test]
fn omega_max_ignores_pinned_particles_and_needs_stiffness() {
    // Both ends pinned: nothing is free.
    let scene = scene::load("rope", &["nodes=2".into(), "pinned=[0, 1]".into()]).unwrap();
    let e = omega_max(&scene.bodies[0].model, &scene.bodies[0].state);
    assert_eq!(e.omega, 0.0);
    assert_eq!(e.gershgorin_omega, 0.0);
    // A free-free pair of 1 kg masses: ω² = 2k/m (the relative motion), not k/m.
    let scene = scene::load("rope", &["nodes=2".into(), "pinned=[]".into()]).unwrap();
    let e = omega_max(&scene.bodies[0].model, &scene.bodies[0].state);
    assert!(relative(e.omega, 200f64.sqrt()) < 1e-9, "ω = {}", e.omega);
}

// ---------------------------------------------------------------------------------------------
// Measured limits on the oscillator

#[test]
fn oscillator_limits_match_the_amplification_factors() {
    let r = json(&["study", "stability", "oscillator", "--json"]);
    assert_eq!(r["scene"], "oscillator");
    assert_eq!(r["horizon"], 2.0);
    assert_eq!(r["omega_method"], "power iteration");
    assert!(relative(r["omega_max"].as_f64().unwrap(), 10.0) < 1e-9);
    assert!(r["definition"].as_str().unwrap().contains("does not grow"));
    assert!(r["definition"].as_str().unwrap().contains("confirmed"));
    assert_eq!(r["sets"][0], "amplitude=1e-6");
    assert_eq!(r["methods"].as_array().unwrap().len(), Method::ALL.len());

    // Conditional methods: measured dt·ω within 2 % of |R| ≤ 1 on the undamped oscillator, and
    // the damped theory of the scene (no damping) is that same number.
    for (name, theory) in [
        ("semi-implicit-euler", 2.0),
        ("verlet", 2.0),
        ("rk4", 2.0 * 2f64.sqrt()),
        ("predictor-corrector", 1.0),
    ] {
        let m = method(&r, name);
        assert_eq!(m["stability"], "conditional", "{name}");
        let limit = m["limit_dt_omega"].as_f64().expect("limit");
        assert!(
            relative(limit, theory) < 0.02,
            "{name}: measured dt·ω = {limit}, theory {theory}"
        );
        let linear = m["linear_dt_omega"].as_f64().unwrap();
        assert!(relative(linear, theory) < 0.01, "{name}: linear {linear}");
        assert!(limit <= linear * (1.0 + 1e-12), "confirmed above linear");
        assert!(relative(m["theory_dt_omega"].as_f64().unwrap(), theory) < 1e-12);
        let damped = m["damped_theory"]["dt_omega"].as_f64().unwrap();
        assert!(relative(damped, theory) < 1e-9, "{name}: damped {damped}");
        let dt = m["max_stable_dt"].as_f64().unwrap();
        assert!(relative(dt * 10.0, limit) < 1e-12, "{name}: limit = dt·ω");
        assert_eq!(m["theory"], "conditional");
    }
    // Growing at every dt: |R|² = 1 + z² and 1 + z⁴/4.
    for name in ["explicit-euler", "midpoint"] {
        let m = method(&r, name);
        assert_eq!(m["stability"], "none", "{name}");
        assert_eq!(m["linear_stability"], "none", "{name}");
        assert!(m["max_stable_dt"].is_null() && m["limit_dt_omega"].is_null());
        assert_eq!(m["damped_theory"]["stability"], "none");
        // It was probed down to the floor dt·ω = 0.01, and grew there too.
        let last = m["probes"].as_array().unwrap().last().unwrap();
        assert!(relative(last["dt_omega"].as_f64().unwrap(), 0.01) < 1e-9);
        assert_eq!(last["stable"], false);
        assert!(m["confirmations"].as_array().unwrap().is_empty());
    }
    // Stable at dt·ω = 100, linearly and in the confirmation run.
    for name in ["implicit-euler", "xpbd"] {
        let m = method(&r, name);
        assert_eq!(m["stability"], "unconditional", "{name}");
        assert!(m["max_stable_dt"].is_null() && m["theory_dt_omega"].is_null());
        assert!(m["confirmations"][0]["passed"].as_bool().unwrap());
    }
}

#[test]
fn midpoint_growth_at_the_floor_is_its_amplification_factor() {
    // At dt·ω = 0.01 midpoint multiplies the oscillator's perturbation energy by
    // |R|² = 1 + z⁴/4 per step: over the 5000 steps between the two windows,
    // Ē_late / Ē_early = (1 + 2.5e-9)^2000 = 1 + 5e-6, above the 1e-6 threshold.
    let r = json(&[
        "study",
        "stability",
        "oscillator",
        "--methods",
        "midpoint",
        "--json",
    ]);
    let last = method(&r, "midpoint")["probes"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    let growth = last["growth"].as_f64().expect("growth measured");
    let expected = (1.0 + 0.01f64.powi(4) / 4.0).powi(2000);
    assert!(
        ((growth - 1.0) / (expected - 1.0) - 1.0).abs() < 0.05,
        "growth {growth}, expected {expected}"
    );
}

#[test]
fn the_study_is_deterministic() {
    let args = ["study", "stability", "oscillator", "--json"];
    let a = springlab(&args);
    let b = springlab(&args);
    assert!(a.status.success() && b.status.success());
    assert_eq!(a.stdout, b.stdout, "two runs gave different JSON");
    let args = ["study", "stability", "rope", "--json"];
    assert_eq!(springlab(&args).stdout, springlab(&args).stdout);
}

#[test]
fn methods_and_horizon_restrict_the_study() {
    let r = json(&[
        "study",
        "stability",
        "oscillator",
        "--methods",
        " rk4 ,verlet,rk4",
        "--horizon",
        "0.5",
        "--json",
    ]);
    let names: Vec<&str> = r["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["method"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["rk4", "verlet"]);
    assert_eq!(r["horizon"], 0.5);
    // The linear test runs at least 10 000 steps whatever the horizon: the limits hold.
    assert!(
        relative(
            method(&r, "rk4")["limit_dt_omega"].as_f64().unwrap(),
            8f64.sqrt()
        ) < 0.02
    );
}

// ---------------------------------------------------------------------------------------------
// The rope (undamped, gravity): linear limits, free fall, and the confirmation runs

#[test]
fn rope_linear_limits_are_the_theory_and_free_fall_is_not_instability() {
    let r = json(&["study", "stability", "rope", "--json"]);
    let omega = r["omega_max"].as_f64().unwrap();
    assert!(relative(omega, (50.0 * (3.0 + 5f64.sqrt())).sqrt()) < 1e-6);
    for name in ["explicit-euler", "midpoint"] {
        assert_eq!(method(&r, name)["stability"], "none", "{name}");
    }
    for (name, z) in [("semi-implicit-euler", 2.0), ("rk4", 2.0 * 2f64.sqrt())] {
        let m = method(&r, name);
        let linear = m["linear_max_dt"].as_f64().unwrap();
        assert!(
            relative(linear, z / omega) < 0.02,
            "{name}: linear {linear} s, theory {} s",
            z / omega
        );
        assert!(relative(m["theory_dt"].as_f64().unwrap(), z / omega) < 1e-9);
    }
    // Projection makes the rope's springs rods: linearly stable at every dt.
    assert_eq!(method(&r, "verlet")["linear_stability"], "unconditional");
    assert_eq!(method(&r, "implicit-euler")["stability"], "unconditional");
    // Gravity is a constant force: without it the linear limits are the same numbers.
    let weightless = json(&[
        "study",
        "stability",
        "rope",
        "--set",
        "gravity=0",
        "--no-confirm",
        "--json",
    ]);
    for m in r["methods"].as_array().unwrap() {
        let name = m["method"].as_str().unwrap();
        assert_eq!(
            m["linear_dt_omega"],
            method(&weightless, name)["linear_dt_omega"],
            "{name}"
        );
    }
}

/// Every reported limit of `report` (scene `scene`) holds in a run 50 horizons long at 95 % of
/// it: no divergence and no energy that keeps rising above 10 S.
fn fifty_times_longer_at_95_percent(report: &stability::StabilityReport, scene: &scene::Scene) {
    for m in &report.methods {
        let Some(dt) = m.max_stable_dt else {
            continue;
        };
        let dt = 0.95 * dt;
        let steps = (50.0 * report.horizon / dt).ceil() as u64;
        let c = stability::confirm_steps(scene, m.method, dt, steps, report.energy_scale);
        assert!(
            c.passed,
            "{}: {} steps at 0.95 × {} s broke: {:?}",
            m.method,
            steps,
            m.max_stable_dt.unwrap(),
            c.reason
        );
    }
}

#[test]
fn confirmed_limits_hold_fifty_horizons_at_95_percent() {
    // The undamped rope swinging from horizontal: semi-implicit Euler is linearly stable up to
    // dt·ω_max = 2, but the swing pumps its stiff mode (a nonlinear resonance) and the
    // confirmed limit is lower; every confirmed limit then holds in a run 50 horizons long.
    let (rope, _) = stability::load_scene("rope", &[]).unwrap();
    let r = stability::stability(&rope, &StabilityOptions::default(), &mut |_, _| {}).unwrap();
    let se = r
        .methods
        .iter()
        .find(|m| m.method == Method::SemiImplicitEuler)
        .unwrap();
    assert!(se.limit_dt_omega.unwrap() < se.linear_dt_omega.unwrap());
    assert!(se.confirmations.iter().any(|c| !c.passed));
    fifty_times_longer_at_95_percent(&r, &rope);
    // A small cube on the plane (damped, contacts).
    let (cube, _) = stability::load_scene("cube-plane", &["n=3".into()]).unwrap();
    let options = StabilityOptions {
        methods: vec![Method::SemiImplicitEuler, Method::Rk4],
        ..StabilityOptions::default()
    };
    let r = stability::stability(&cube, &options, &mut |_, _| {}).unwrap();
    fifty_times_longer_at_95_percent(&r, &cube);
}

/// `cube-plane` at n = 5 and its stability study for RK4 (default horizon 2 s), computed once
/// for the two tests below: the study's stiffest state is `stability::stiffest(&cube, 2.0)`
/// (the same run, the same samples).
fn cube_and_rk4_study() -> &'static (scene::Scene, stability::StabilityReport) {
    static STUDY: std::sync::OnceLock<(scene::Scene, stability::StabilityReport)> =
        std::sync::OnceLock::new();
    STUDY.get_or_init(|| {
        let (cube, _) = stability::load_scene("cube-plane", &["n=5".into()]).unwrap();
        let options = StabilityOptions {
            methods: vec![Method::Rk4],
            ..StabilityOptions::default()
        };
        assert_eq!(options.horizon, 2.0);
        let r = stability::stability(&cube, &options, &mut |_, _| {}).unwrap();
        (cube, r)
    })
}

#[test]
fn an_impact_stiffens_the_cube_and_free_fall_does_not() {
    // cube-plane at n = 5: the landing on the plane (t ≈ 1.4 s) squeezes the cube, and the
    // stiffest mode of the squeezed cube is stiffer than at rest.
    let (cube, r) = cube_and_rk4_study();
    let body = &cube.bodies[0];
    let at_rest = omega_max(&body.model, &body.state).omega;
    let s = r.stiffest_state.clone();
    assert!(s.ratio > 1.01, "{s:?}");
    assert!(s.time > 1.3 && s.time < 1.7, "{s:?}");
    assert!(relative(s.omega_max / at_rest, s.ratio) < 1e-12, "{s:?}");
    // The warm-started sample is reproduced by a cold power iteration at that instant.
    let mut sim = Simulation::new(cube.clone());
    sim.set_accounting(false);
    sim.run((s.time / s.dt).round() as u64, |_| {});
    let state = sim.states().next().unwrap();
    let cold = omega_max(&body.model, state).omega;
    assert!(relative(cold, s.omega_max) < 1e-3, "{cold} vs {s:?}");
    // Every explicit method's damped theory there is below its theory at rest.
    let spectrum = theory::spectrum(&body.model, state, s.omega_max);
    let rest = theory::spectrum(&body.model, &body.state, at_rest);
    for m in [Method::ExplicitEuler, Method::Midpoint, Method::Rk4] {
        let squeezed = theory::limit(m, &body.params, &spectrum).dt.unwrap();
        let resting = theory::limit(m, &body.params, &rest).dt.unwrap();
        assert!(squeezed < 0.99 * resting, "{m}: {squeezed} vs {resting}");
    }
    // Without the plane the cube falls freely, undeformed: never stiffer than at rest (up to
    // the warm start's further convergence of the same quotient).
    let mut falling = cube.clone();
    falling.bodies[0].model.colliders.clear();
    let f = stability::stiffest(&falling, 2.0).unwrap();
    assert!(f.ratio < 1.0 + 1e-4, "{f:?}");
}

#[test]
fn stiffest_state_is_reported_and_the_scene_limit_lies_between_the_theories() {
    let (_, r) = cube_and_rk4_study();
    assert!(r.stiffest_state.ratio > 1.01, "{:?}", r.stiffest_state);
    let m = &r.methods[0];
    let (scene_dt, linear, rest, squeezed) = (
        m.max_stable_dt.unwrap(),
        m.linear_max_dt.unwrap(),
        m.theory_dt.unwrap(),
        m.stiffest_theory_dt.unwrap(),
    );
    assert!(relative(linear, rest) < 0.01, "{linear} vs {rest}");
    assert!(squeezed < scene_dt && scene_dt <= linear, "{m:?}");
}

#[test]
fn damped_cube_limits_match_the_damped_theory() {
    // n = 3: 27 particles, a dense eigen-solve of all 81 modes; C = (D/K) K exactly.
    let (cube, _) = stability::load_scene("cube-plane", &["n=3".into()]).unwrap();
    let options = StabilityOptions {
        methods: vec![
            Method::ExplicitEuler,
            Method::SemiImplicitEuler,
            Method::Midpoint,
            Method::Rk4,
            Method::PredictorCorrector,
            Method::Verlet,
        ],
        confirm: false,
        ..StabilityOptions::default()
    };
    let r = stability::stability(&cube, &options, &mut |_, _| {}).unwrap();
    assert!(
        r.theory_spectrum.contains("Rayleigh"),
        "{}",
        r.theory_spectrum
    );
    assert!(r.theory_spectrum.contains("dense"), "{}", r.theory_spectrum);
    for m in &r.methods {
        let measured = m.linear_max_dt.expect("conditional");
        let theory = m.theory_dt.expect("theory");
        assert!(
            relative(measured, theory) < 0.01,
            "{}: measured {measured} s, damped theory {theory} s",
            m.method
        );
        // The stiffest mode is overdamped: μ > 2ω, and it binds.
        let b = m.damped_theory.binding.unwrap();
        assert!(b.mu > 2.0 * b.omega && b.stiffest, "{}: {b:?}", m.method);
    }
}

#[test]
fn damped_theory_of_the_course_cube_matches_independent_numbers() {
    // The independent computation for cube-plane (10×10×10, K = 2000, D = 60): explicit
    // Euler 2.048e-3 s, semi-implicit 1.917e-3, predictor–corrector 1.024e-3, RK4 2.852e-3,
    // midpoint 2.048e-3.
    let cube = scene::load("cube-plane", &[]).unwrap();
    let body = &cube.bodies[0];
    let omega = omega_max(&body.model, &body.state).omega;
    let spectrum = theory::spectrum(&body.model, &body.state, omega);
    assert!(!spectrum.dense);
    for (m, expected) in [
        (Method::ExplicitEuler, 2.048e-3),
        (Method::SemiImplicitEuler, 1.917e-3),
        (Method::PredictorCorrector, 1.024e-3),
        (Method::Rk4, 2.852e-3),
        (Method::Midpoint, 2.048e-3),
    ] {
        let t = theory::limit(m, &body.params, &spectrum);
        let dt = t.dt.unwrap();
        assert!(
            relative(dt, expected) < 0.002,
            "{m}: theory {dt} s, independent {expected} s"
        );
        assert!(t.binding.unwrap().stiffest, "{m}");
    }
}

#[test]
fn jacobi_eigenvalues_of_the_fixed_free_chain() {
    // M⁻¹K of a chain of N unit masses and unit springs hanging from a pinned end:
    // λ_j = 4 sin²((2j - 1) π / (4N + 2)), j = 1..N.
    let n = 7;
    let mut a = vec![0.0; n * n];
    for i in 0..n {
        a[i * n + i] = if i + 1 == n { 1.0 } else { 2.0 };
        if i + 1 < n {
            a[i * n + i + 1] = -1.0;
            a[(i + 1) * n + i] = -1.0;
        }
    }
    let values = theory::jacobi_eigenvalues(&mut a, n);
    for (j, v) in values.iter().enumerate() {
        let s = ((2 * j + 1) as f64 * std::f64::consts::PI / (4 * n + 2) as f64).sin();
        assert!((v - 4.0 * s * s).abs() < 1e-12, "λ_{j} = {v}");
    }
}

#[test]
fn text_output_is_a_table() {
    let out = springlab(&["study", "stability", "oscillator", "--methods", "rk4"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("ω_max = 10.000000 rad/s"), "{text}");
    assert!(text.contains("stable means:"), "{text}");
    assert!(text.contains("damped theory:"), "{text}");
    let row = text
        .lines()
        .find(|l| l.starts_with("rk4"))
        .expect("rk4 row");
    assert!(row.contains("conditional") && row.contains("2.8"), "{row}");
    // Quiet when stderr is not a terminal.
    assert!(out.stderr.is_empty());
}

// ---------------------------------------------------------------------------------------------
// The library

#[test]
fn library_study_calls_progress_for_every_probe() {
    let (scene, sets) = stability::load_scene("oscillator", &[]).unwrap();
    assert_eq!(sets, ["amplitude=1e-6"]);
    let options = StabilityOptions {
        methods: vec![Method::PredictorCorrector, Method::ImplicitEuler],
        ..StabilityOptions::default()
    };
    let mut calls = 0;
    let r = stability::stability(&scene, &options, &mut |_, _| calls += 1).unwrap();
    let probes: usize = r.methods.iter().map(|m| m.probes.len()).sum();
    assert_eq!(calls, probes);
    assert_eq!(r.methods[0].stability, Stability::Conditional);
    assert_eq!(r.methods[1].stability, Stability::Unconditional);
    assert_eq!(r.methods[1].probes.len(), 1);
    // The one-call form gives the same limit.
    let dt = stability::max_stable_dt(&scene, Method::PredictorCorrector).unwrap();
    assert_eq!(dt, r.methods[0].max_stable_dt);
    assert_eq!(
        stability::max_stable_dt(&scene, Method::ImplicitEuler).unwrap(),
        None
    );
    assert_eq!(
        stability::max_stable_dt(&scene, Method::ExplicitEuler).unwrap(),
        Some(0.0)
    );
}

#[test]
fn library_rejects_bad_options() {
    let (scene, _) = stability::load_scene("oscillator", &[]).unwrap();
    for horizon in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let options = StabilityOptions {
            horizon,
            ..StabilityOptions::default()
        };
        let e = stability::stability(&scene, &options, &mut |_, _| {}).unwrap_err();
        assert!(matches!(e, StudyError::Horizon(_)), "{e}");
    }
    let options = StabilityOptions {
        methods: vec![],
        ..StabilityOptions::default()
    };
    assert!(matches!(
        stability::stability(&scene, &options, &mut |_, _| {}),
        Err(StudyError::NoMethods)
    ));
    let options = StabilityOptions {
        horizon: 1e12,
        ..StabilityOptions::default()
    };
    let e = stability::stability(&scene, &options, &mut |_, _| {}).unwrap_err();
    assert!(e.to_string().contains("shorter horizon"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// Bad input through the binary

#[test]
fn bad_input_gives_clear_messages() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["study", "stability", "nosuchscene"],
            "unknown scene `nosuchscene`",
        ),
        (
            &["study", "stability", "oscillator", "--methods", "rk5"],
            "unknown method `rk5`; expected one of: explicit-euler",
        ),
        (
            &["study", "stability", "oscillator", "--methods", ","],
            "--methods: expected a comma-separated list of methods",
        ),
        (
            &["study", "stability", "oscillator", "--horizon", "0"],
            "--horizon 0: expected a duration in seconds > 0",
        ),
        (
            &["study", "stability", "oscillator", "--horizon", "-1"],
            "--horizon -1: expected a duration in seconds > 0",
        ),
        (
            &["study", "stability", "oscillator", "--horizon", "nan"],
            "--horizon NaN: expected a duration in seconds > 0",
        ),
        (
            &["study", "stability", "oscillator", "--horizon", "soon"],
            "invalid value 'soon'",
        ),
        (
            &["study", "stability", "oscillator", "--set", "colour=red"],
            "unknown parameter `colour` for scene `oscillator`",
        ),
        (
            &["study", "stability", "oscillator", "--set", "stiffness=0"],
            "has no stiffness on a free particle",
        ),
        (
            &["study", "stability", "missing.toml"],
            "cannot read scene file missing.toml",
        ),
        (&["study", "stability"], "<SCENE>"),
        (
            &["study", "nosuchstudy", "oscillator"],
            "unrecognized subcommand",
        ),
    ];
    for (args, expected) in cases {
        let err = stderr_of_failure(args);
        assert!(
            err.contains(expected),
            "{args:?}: expected `{expected}` in:\n{err}"
        );
        assert!(!err.contains("panicked"), "{args:?} panicked:\n{err}");
    }
}

/// A confirmation run called on its own names `dt·ω_max` with the scene's own `ω_max`: the
/// oscillator's `ω = √(k/m) = √(500/2)` rad/s.
#[test]
fn confirm_steps_reports_dt_omega_of_the_scene() {
    let scene = scene::load("oscillator", &["stiffness=500".into(), "mass=2".into()]).unwrap();
    let dt = 0.01;
    let c = stability::confirm_steps(&scene, Method::Rk4, dt, 100, 1.0);
    let exact = dt * (500.0_f64 / 2.0).sqrt();
    assert!(
        (c.dt_omega - exact).abs() < 1e-9 * exact,
        "dt·ω = {} instead of {exact}",
        c.dt_omega
    );
    assert!(c.passed && c.steps == 100);
}

#[test]
fn velocity_verlet_rope_limit_is_two_over_omega_max() {
    // The undamped rope: the measured linear limit dt·ω within 1 % of 2 (leapfrog's
    // recurrence), and the damped theory the same number.
    let r = json(&[
        "study",
        "stability",
        "rope",
        "--methods",
        "velocity-verlet",
        "--no-confirm",
        "--json",
    ]);
    let m = method(&r, "velocity-verlet");
    assert_eq!(m["stability"], "conditional");
    let linear = m["linear_dt_omega"].as_f64().unwrap();
    assert!(relative(linear, 2.0) < 0.01, "linear dt·ω = {linear}");
    let omega = r["omega_max"].as_f64().unwrap();
    let theory = m["theory_dt"].as_f64().unwrap();
    assert!(
        relative(theory * omega, 2.0) < 1e-9,
        "theory dt·ω = {}",
        theory * omega
    );
}

#[test]
fn one_thread_and_two_give_the_same_study() {
    // The searches run on separate cores, the stiffest state beside them, and the usable-dt
    // search's likely next runs ahead on a free core: every run, verdict and limit must be the
    // ones a single thread computes one after another.
    let args = [
        "study",
        "stability",
        "jelly-bowl",
        "--set",
        "n=3",
        "--methods",
        "semi-implicit-euler,midpoint",
        "--json",
    ];
    let one = common::json_on_threads(&args, "1");
    let two = common::json_on_threads(&args, "2");
    assert_eq!(one, two, "one thread and two differ");
    // The usable search ran (and ran ahead of itself on two threads): every run is reported.
    for m in one["methods"].as_array().expect("methods") {
        let runs = m["usable"]["runs"].as_array().expect("usable runs");
        assert!(runs.len() >= 2, "{m}");
    }
}
