//! `springlab study stability`: the stiffest mode against closed forms and WORKLOADS.md, the
//! measured limits against the oscillator's amplification factors, determinism and bad input.

use std::process::{Command, Output};

use serde_json::Value;
use springlab::bench::{Workload, setup};
use springlab::physics::Method;
use springlab::scene;
use springlab::study::stability::{self, Criterion, StabilityOptions};
use springlab::study::{Stability, StudyError, omega_max};

fn springlab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(args)
        .output()
        .expect("run springlab")
}

fn json(args: &[&str]) -> Value {
    let out = springlab(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

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
    // WORKLOADS.md W1: λ_max(M⁻¹K) = 3.37e4 at rest, ω_max = 184 rad/s.
    let (model, state) = setup(Workload::JellySe);
    let e = omega_max(&model, &state);
    assert!(
        relative(e.lambda, 3.37e4) < 0.01,
        "λ_max = {} (1/s²), WORKLOADS.md 3.37e4",
        e.lambda
    );
    assert!(relative(e.omega, 184.0) < 0.01, "ω_max = {}", e.omega);
    // The Rayleigh quotient is a lower bound, Gershgorin an upper one.
    assert!(e.gershgorin_lambda >= e.lambda);
    // Deterministic: the same start vector, the same iterations, the same bits.
    assert_eq!(omega_max(&model, &state), e);
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
    assert_eq!(r["criterion"], "growth");
    assert_eq!(r["horizon"], 2.0);
    assert_eq!(r["omega_method"], "power iteration");
    assert!(relative(r["omega_max"].as_f64().unwrap(), 10.0) < 1e-9);
    assert!(r["definition"].as_str().unwrap().contains("no growth"));
    assert_eq!(r["sets"][0], "amplitude=1e-6");
    assert_eq!(r["methods"].as_array().unwrap().len(), Method::ALL.len());

    // Conditional methods: measured dt·ω within 2 % of theory.
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
        assert!(relative(m["theory_dt_omega"].as_f64().unwrap(), theory) < 1e-12);
        let dt = m["max_stable_dt"].as_f64().unwrap();
        assert!(relative(dt * 10.0, limit) < 1e-12, "{name}: limit = dt·ω");
        assert_eq!(m["theory"], "conditional");
    }
    // Growing at every dt: |R|² = 1 + z² and 1 + z⁴/4.
    for name in ["explicit-euler", "midpoint"] {
        let m = method(&r, name);
        assert_eq!(m["stability"], "none", "{name}");
        assert!(m["max_stable_dt"].is_null() && m["limit_dt_omega"].is_null());
        assert!(m["theory_dt_omega"].is_null());
        assert_eq!(m["theory"], "none");
        // It was probed down to the floor dt·ω = 0.01, and grew there too.
        let last = m["probes"].as_array().unwrap().last().unwrap();
        assert!(relative(last["dt_omega"].as_f64().unwrap(), 0.01) < 1e-9);
        assert_eq!(last["stable"], false);
    }
    // Stable at dt·ω = 100.
    for name in ["implicit-euler", "xpbd"] {
        let m = method(&r, name);
        assert_eq!(m["stability"], "unconditional", "{name}");
        assert!(m["max_stable_dt"].is_null() && m["theory_dt_omega"].is_null());
    }
}

#[test]
fn midpoint_growth_at_the_floor_is_its_amplification_factor() {
    // At dt·ω = 0.01 midpoint gains |R|² = 1 + z⁴/4 per step: over the 5000 steps between the
    // two windows, Ē_late / Ē_early = (1 + 2.5e-9)^5000 = 1 + 1.25e-5 exactly (in exact
    // arithmetic), far above the 1e-6 threshold.
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
    let expected = (1.0 + 0.01f64.powi(4) / 4.0).powi(5000);
    assert!(
        ((growth - 1.0) / (expected - 1.0) - 1.0).abs() < 1e-3,
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
    // The growth test runs at least 10 000 steps whatever the horizon: the limits hold.
    assert!(
        relative(
            method(&r, "rk4")["limit_dt_omega"].as_f64().unwrap(),
            8f64.sqrt()
        ) < 0.02
    );
}

#[test]
fn the_rope_uses_the_divergence_criterion() {
    let r = json(&["study", "stability", "rope", "--json"]);
    assert_eq!(r["scene"], "rope");
    assert_eq!(r["criterion"], "divergence");
    assert!(r["sets"].as_array().unwrap().is_empty());
    let omega = r["omega_max"].as_f64().unwrap();
    assert!(relative(omega, (50.0 * (3.0 + 5f64.sqrt())).sqrt()) < 1e-6);
    assert_eq!(method(&r, "implicit-euler")["stability"], "unconditional");
    let se = method(&r, "semi-implicit-euler");
    assert_eq!(se["stability"], "conditional");
    // Every listed probe agrees with the verdict: the largest stable dt was stable, and every
    // probe above the reported limit's bracket was unstable.
    let dt = se["max_stable_dt"].as_f64().unwrap();
    let probes = se["probes"].as_array().unwrap();
    assert!(
        probes
            .iter()
            .any(|p| p["dt"].as_f64() == Some(dt) && p["stable"] == true)
    );
    assert!(
        probes
            .iter()
            .filter(|p| p["dt"].as_f64().unwrap() > dt * 1.001)
            .all(|p| p["stable"] == false && p["diverged_time"].is_f64())
    );
    // Each probe ran at least max(T/dt, 100) steps unless it diverged.
    for p in probes.iter().filter(|p| p["stable"] == true) {
        let steps = p["steps"].as_u64().unwrap();
        let planned = (2.0 / p["dt"].as_f64().unwrap()).ceil().max(100.0) as u64;
        assert_eq!(steps, planned);
    }
}

#[test]
fn text_output_is_a_table() {
    let out = springlab(&["study", "stability", "oscillator", "--methods", "rk4"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("ω_max = 10.000000 rad/s"), "{text}");
    assert!(text.contains("stable means:"), "{text}");
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
fn the_criterion_follows_the_scene() {
    let osc = scene::load("oscillator", &[]).unwrap();
    assert_eq!(Criterion::for_scene(&osc), Criterion::Growth);
    let damped = scene::load("oscillator", &["damping=0.1".into()]).unwrap();
    assert_eq!(Criterion::for_scene(&damped), Criterion::Divergence);
    let rope = scene::load("rope", &[]).unwrap();
    assert_eq!(Criterion::for_scene(&rope), Criterion::Divergence);
    let weightless = scene::load("rope", &["gravity=0".into()]).unwrap();
    assert_eq!(Criterion::for_scene(&weightless), Criterion::Growth);
}

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
            &["study", "stability", "oscillator", "--set", "amplitude=0"],
            "starts at rest",
        ),
        (
            &["study", "stability", "missing.toml"],
            "cannot read scene file missing.toml",
        ),
        (&["study", "stability"], "<SCENE>"),
        (
            &["study", "convergence", "oscillator"],
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
