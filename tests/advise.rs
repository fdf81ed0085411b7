//! `springlab study resolution` and `springlab advise` against independent truths: the rope's
//! continuum solution (wave equation with gravity), free fall, the first touch of a falling
//! sphere, the oscillator's exact solution, the measured (perturbation-growth) stability limit,
//! and `springlab run`'s own positions.

use crate::common;
use common::{json, springlab};

use std::f64::consts::PI;

use glam::DVec3;
use serde_json::Value;
use springlab::budget::Limits;
use springlab::physics::Method;
use springlab::scene;
use springlab::study::advise;
use springlab::study::convergence::fitted_slope;
use springlab::study::observe::{self, Observable, Value as Obs};
use springlab::study::resolution::{self, Kinds, Refinement, ResolutionOptions};
use springlab::study::stability::{self, StabilityOptions};

fn stderr_of_failure(args: &[&str]) -> String {
    let out = springlab(args);
    assert!(!out.status.success(), "expected failure for {args:?}");
    assert!(out.stdout.is_empty(), "nothing on stdout for {args:?}");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn sets(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| (*s).to_string()).collect()
}

// ---------------------------------------------------------------------------------------------
// Refinement

#[test]
fn every_level_keeps_the_body_total_mass_and_scales_its_springs_by_the_dimension() {
    // (scene, levels, exponent p of k ∝ h^p)
    for (name, levels, p) in [
        ("jelly-bowl", [3i64, 6, 10, 14], 1.0),
        ("cloth-sphere", [5, 13, 25, 31], 0.0),
        ("rope", [2, 3, 9, 33], -1.0),
    ] {
        let r = Refinement::require(name, &[]).expect("refinable");
        let own = r.scene(r.base, Kinds::All, &Limits::DEFAULT).expect("own");
        // The scene's own level is the scene, bit for bit.
        assert_eq!(own, scene::load(name, &[]).expect("scene"), "{name}");
        let total = |s: &scene::Scene| s.bodies[0].model.mass.iter().sum::<f64>();
        let spacing = |n: i64| 1.0 / (n - 1) as f64;
        for n in levels {
            let level = r.scene(n, Kinds::All, &Limits::DEFAULT).expect("level");
            assert!(
                (total(&level) / total(&own) - 1.0).abs() < 1e-12,
                "{name} n = {n}: mass {} against {}",
                total(&level),
                total(&own)
            );
            let k = level.bodies[0].model.springs()[0].stiffness;
            let k0 = own.bodies[0].model.springs()[0].stiffness;
            let expected = (spacing(n) / spacing(r.base)).powf(p);
            assert!(
                (k / k0 / expected - 1.0).abs() < 1e-12,
                "{name} n = {n}: k/k0 = {} against h^{p} ratio {expected}",
                k / k0
            );
            let d = level.bodies[0].model.springs()[0].damping;
            let d0 = own.bodies[0].model.springs()[0].damping;
            if d0 > 0.0 {
                assert!((d / d0 / expected - 1.0).abs() < 1e-12, "{name}: dampers");
            }
        }
    }
    // The rope's pinned node stays at its place along the rope: the first; an end pinned at
    // node 2 of 3 is the last node of 9.
    let r = Refinement::require("rope", &sets(&["pinned=[0,2]"])).expect("rope");
    let nine = r.scene(9, Kinds::All, &Limits::DEFAULT).expect("9 nodes");
    let pinned: Vec<usize> = (0..9)
        .filter(|&i| nine.bodies[0].model.is_pinned(i))
        .collect();
    assert_eq!(pinned, vec![0, 8]);
}

#[test]
fn leaving_out_a_kind_removes_exactly_its_springs() {
    let r = Refinement::require("jelly-bowl", &sets(&["n=4"])).expect("jelly");
    let count = |kinds| {
        let s = r.scene(4, kinds, &Limits::DEFAULT).expect("scene");
        springlab::scene::lattice::count_kinds(s.bodies[0].model.springs())
    };
    let [st, sh, be] = count(Kinds::All);
    // A 4×4×4 lattice: 3·4²·3 struct, 6·4·3² + 4·3³ shear, 3·4²·2 bend.
    assert_eq!((st, sh, be), (144, 324, 96));
    assert_eq!(count(Kinds::NoBend), [144, 324, 0]);
    assert_eq!(count(Kinds::NoShear), [144, 0, 96]);
    let rope = Refinement::require("rope", &[]).expect("rope");
    assert!(!rope.has_kind(Kinds::NoBend) && !rope.has_kind(Kinds::NoShear));
}

// ---------------------------------------------------------------------------------------------
// Observables against closed forms

#[test]
fn a_falling_cube_has_the_free_fall_centroid_and_no_compression() {
    // Before it lands (t = 0.5 s < 1.43 s) every particle feels the same gravity: the springs
    // stay at rest length, the centroid falls g t²/2 exactly (RK4 integrates a constant
    // acceleration exactly), the volume does not change.
    let scene = scene::load("cube-plane", &sets(&["n=3"])).expect("cube");
    let c0 = scene.bodies[0].state.centroid();
    let m = observe::measure(&scene, Method::Rk4, 1e-3, 500);
    let o = m.observation.expect("no divergence");
    let Obs::Point(c) = o.components[0].value else {
        panic!("centroid first")
    };
    let expected = c0 + DVec3::new(0.0, -0.5 * 9.8 * 0.25, 0.0);
    assert!(
        DVec3::from_array(c).distance(expected) < 1e-12,
        "{c:?} vs {expected}"
    );
    let Obs::Length(compression) = o.components[1].value else {
        panic!("compression second")
    };
    assert!(compression.abs() < 1e-12, "compression {compression}");
}

#[test]
fn the_compression_is_the_volume_lost_as_an_edge() {
    // The outer faces enclose the cube's volume whatever its resolution, position or turn:
    // 4³ m³ at rest, 0.9 · 4³ squeezed by a tenth along y, unchanged by a rotation or a shear.
    for n in ["3", "6"] {
        let scene = scene::load("jelly-bowl", &sets(&[&format!("n={n}")])).expect("jelly");
        let b = &scene.bodies[0];
        let volume = |f: &dyn Fn(DVec3) -> DVec3| {
            let x: Vec<DVec3> = b.state.x.iter().map(|&p| f(p)).collect();
            observe::block_volume(&b.model, &x).expect("a block")
        };
        let c = b.state.centroid();
        assert!((volume(&|p| p) - 64.0).abs() < 1e-9);
        assert!((volume(&|p| c + (p - c) * DVec3::new(1.0, 0.9, 1.0)) - 57.6).abs() < 1e-9);
        let turn = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        assert!((volume(&|p| turn * p) - 64.0).abs() < 1e-9);
        assert!((volume(&|p| p + DVec3::new(0.3 * p.y, 0.0, 0.0)) - 64.0).abs() < 1e-9);
    }
    let rope = scene::load("rope", &[]).expect("rope");
    assert!(observe::block_volume(&rope.bodies[0].model, &rope.bodies[0].state.x).is_none());
}

#[test]
fn a_rising_sphere_touches_the_cloth_when_it_reaches_the_nearest_particle() {
    // Without gravity the 2024 cloth (n = 6: no particle at the centre) stays where it is, at
    // y = 1; the sphere of radius 1 rises from the origin at 1 m/s. The nearest particles are
    // at (±0.4, 1, ±0.4), within the band ε = 0.01 of the sphere when
    // (1 - t)² + 0.32 ≤ 1.01², at t = 1 - √(1.01² - 0.32).
    let scene = scene::load(
        "cloth-sphere",
        &sets(&["n=6", "gravity=0", "sphere_velocity=[0,1,0]"]),
    )
    .expect("cloth");
    let expected = 1.0 - (1.01f64 * 1.01 - 0.32).sqrt();
    let dt = 1e-4;
    let m = observe::measure(&scene, Method::SemiImplicitEuler, dt, 2000);
    let o = m.observation.expect("no divergence");
    let contact = o
        .components
        .iter()
        .find(|c| c.name == "contact time")
        .expect("a contact time");
    let Obs::Time(Some(t)) = contact.value else {
        panic!("touched within 0.2 s")
    };
    assert!(
        t >= expected - 1e-9 && t < expected + dt + 1e-9,
        "contact at {t} s, the geometry says {expected} s"
    );
    // The sag stays 0 until then: nothing else moves the cloth.
    let early = observe::measure(&scene, Method::SemiImplicitEuler, dt, 1500);
    let sag = &early.observation.expect("runs").components[0];
    assert_eq!(sag.name, "sag");
    assert!(sag.headline().abs() < 1e-12, "{}", sag.headline());
    // With n = 5 a particle sits on the sphere's top from the start: no contact time.
    let draped = scene::load("cloth-sphere", &sets(&["n=5"])).expect("cloth");
    let names: Vec<String> = Observable::of(&draped)
        .names()
        .into_iter()
        .map(|n| n.0)
        .collect();
    assert_eq!(names, vec!["sag".to_string()]);
}

#[test]
fn accounting_does_not_change_the_motion() {
    // advise runs its halvings with the accounting on and compares their motion with runs
    // made without it, for every method it considers: the same bits at every sample instant.
    let scene = scene::load("jelly-bowl", &sets(&["n=3"])).expect("jelly");
    for method in advise::DEFAULT_METHODS {
        let a = observe::measure(&scene, method, 1e-3, 400);
        let b = observe::measure_accounted(&scene, method, 1e-3, 400);
        assert_eq!(a.observation, b.observation, "{method}");
        assert_eq!(a.snapshots, b.snapshots, "{method}");
        assert_eq!(a.force_evals, b.force_evals, "{method}");
        assert!(a.energy_residual.is_none() && b.energy_residual.is_some());
    }
}

// ---------------------------------------------------------------------------------------------
// The rope's resolution study against the continuum

/// The end of a vertical elastic rope (length L, mass M, EA), fixed at the top and released at
/// rest length under gravity: `u_tt = c² u_xx + g`, `u(0) = 0`, `u_x(L) = 0`, `c² = EA L/M`.
/// Modal solution: `u(L, t) = u_s(L) - Σ b_j sin(k_j L) cos(c k_j t)` with the static stretch
/// `u_s = (g/c²)(L x - x²/2) = Σ b_j sin(k_j x)`, `k_j = (2j - 1)π/(2L)`,
/// `b_j = (2/L)(g/c²)/k_j³`.
fn continuum_end(t: f64) -> f64 {
    let (l, m, ea, g) = (2.0f64, 3.0f64, 100.0f64, 9.8f64);
    let c2 = ea * l / m;
    let mut u = g / c2 * l * l / 2.0;
    for j in 1..20_000 {
        let k = (2 * j - 1) as f64 * PI / (2.0 * l);
        let b = 2.0 / l * g / c2 / (k * k * k);
        u -= b * (k * l).sin() * (c2.sqrt() * k * t).cos();
    }
    -l - u
}

#[test]
fn the_rope_converges_at_second_order_to_the_continuum_and_the_study_says_where() {
    // The GAMES101 rope hung vertically (2 m, 3 nodes of 1 kg, k = 100 N/m: EA = 100 N,
    // M = 3 kg) moves only along y: a linear chain. Lumped masses M/N on N nodes with the
    // top one pinned give the chain's frequencies 2√(k/m) sin((2j-1)π/(2(2N-1))), which are
    // the continuum's times 1 - O(h²): second order.
    let user = sets(&["start=[0,0,0]", "end=[0,-2,0]"]);
    let options = ResolutionOptions {
        levels: Some(vec![9, 17, 33, 65, 129, 257]),
        tolerance: 0.005,
        ..ResolutionOptions::default()
    };
    let (refinement, levels, time) = resolution::plan("rope", &user, &options).expect("plan");
    assert_eq!(time, 1.0);
    let planned =
        resolution::runs(&refinement, &levels, &options, time, &Limits::DEFAULT).expect("runs");
    let report =
        resolution::resolution(&refinement, &options, time, &planned, &mut |_, _, _, _| {});
    let exact: Vec<f64> = (1..=observe::SAMPLES)
        .map(|k| continuum_end(k as f64 * time / observe::SAMPLES as f64))
        .collect();
    let mut errors = Vec::new();
    for run in &report.runs {
        let o = run.run.observation.as_ref().expect("no divergence");
        let Obs::Trajectory(t) = &o.components[0].value else {
            panic!("a trajectory")
        };
        assert_eq!(t.len(), exact.len());
        let e = t
            .iter()
            .zip(&exact)
            .map(|(p, y)| (p[1] - y).abs())
            .fold(0.0, f64::max);
        errors.push(((run.n - 1) as f64, e));
    }
    for w in errors.windows(2) {
        assert!(w[1].1 < w[0].1, "error grows: {errors:?}");
    }
    let fit: Vec<(f64, f64)> = errors.iter().map(|&(cells, e)| (1.0 / cells, e)).collect();
    let order = fitted_slope(&fit).expect("an order");
    assert!((1.5..2.6).contains(&order), "order {order}: {errors:?}");
    // Where the study says the answer stops changing, it is within X of the continuum too.
    let from = report.converged_from.expect("converges within the levels");
    let at = errors
        .iter()
        .zip(&report.runs)
        .find(|(_, r)| r.n == from)
        .map(|(e, _)| e.1)
        .expect("a level");
    assert!(
        at <= options.tolerance,
        "stops changing at {from} nodes, {at} m from the continuum"
    );
    // The Richardson limit of the end's height at T (the three finest levels) is the
    // continuum's within its stated uncertainty, at an observed order near 2, and the level
    // from which the study says the answer is within X of that limit is within X of the
    // continuum.
    let l = report.limits[0].as_ref().expect("a limit");
    assert_eq!(l.levels, [65, 129, 257]);
    let truth = continuum_end(time);
    assert!(
        (l.limit - truth).abs() <= l.uncertainty.max(1e-9),
        "limit {} ± {} against {truth}",
        l.limit,
        l.uncertainty
    );
    assert!((1.5..2.6).contains(&l.order), "order {}", l.order);
    // (The limit is of the end's height at T, so that level is compared there.)
    let from = report.within_limit_from.expect("within X of the limit");
    for run in report.runs.iter().filter(|r| r.n >= from) {
        let y = run.run.observation.as_ref().expect("observed").components[0].headline();
        assert!(
            (y - truth).abs() <= options.tolerance,
            "{} nodes: {y} against {truth}",
            run.n
        );
    }
    // The scene's own 3 nodes are not among the levels: no time-step check.
    assert!(report.time_step_check.is_none());
}

// ---------------------------------------------------------------------------------------------
// The binary

#[test]
fn study_resolution_prints_where_the_answer_stops_changing() {
    let args = [
        "study",
        "resolution",
        "cloth-sphere",
        "--n",
        "5,7,9",
        "--time",
        "0.3",
        "--set",
        "n=7",
    ];
    let mut with_json = args.to_vec();
    with_json.push("--json");
    let report = json(&with_json);
    let runs = report["runs"].as_array().expect("runs");
    // Three levels with all kinds; without bend and without shear up to the scene's own n = 7.
    assert_eq!(runs.len(), 7);
    assert!(
        runs.iter()
            .filter(|r| r["kinds"] != "all")
            .all(|r| r["n"].as_i64() <= Some(7))
    );
    let all: Vec<&Value> = runs.iter().filter(|r| r["kinds"] == "all").collect();
    assert_eq!(all.len(), 3);
    for r in runs {
        let springs = r["springs"].as_f64().expect("springs");
        let steps = r["run"]["steps"].as_f64().expect("steps");
        assert_eq!(r["springs_steps"].as_f64(), Some(springs * steps));
        let end = r["run"]["dt"].as_f64().expect("dt") * steps;
        assert!((end - 0.3).abs() < 1e-12, "every run ends at T: {end}");
    }
    // converged_from from the successive differences, recomputed here.
    let x = report["tolerance"].as_f64().expect("X");
    let changes: Vec<(i64, f64)> = all
        .iter()
        .filter(|r| !r["change_next"].is_null())
        .map(|r| {
            (
                r["n"].as_i64().expect("n"),
                r["change_next"]["metres"].as_f64().expect("m"),
            )
        })
        .collect();
    let expected = if changes.last().is_some_and(|c| c.1 > x) {
        None
    } else {
        let last_bad = changes.iter().rposition(|c| c.1 > x);
        Some(match last_bad {
            None => changes[0].0,
            Some(i) => all[i + 1]["n"].as_i64().expect("n"),
        })
    };
    assert_eq!(report["converged_from"].as_i64(), expected);
    assert_eq!(all[2]["change_finest"]["metres"].as_f64(), Some(0.0));
    // The text names the definition and the verdict.
    let out = springlab(&args);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("stops changing: the answer stops changing at the first level"));
    assert!(
        text.contains("tolerance X = 0.01 (metres for positions and lengths, seconds for times)")
    );
    assert!(
        text.contains("successive differences: from n = ") || text.contains("still changing: n = "),
        "{text}"
    );
    assert!(
        text.contains("stops changing from n = ")
            || text.contains("not within X = 0.01 of the extrapolated limit"),
        "{text}"
    );
    assert!(text.contains("settled at t = 0.3 s") || text.contains("not settled at t = 0.3 s"));
    assert!(text.contains("bend springs:") && text.contains("shear springs:"));
    assert!(text.contains("time step: halving dt at n = 7"));
}

#[test]
fn study_resolution_draws_its_chart() {
    let dir = std::env::temp_dir().join(format!("springlab-resolution-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let png = dir.join("resolution.png");
    let out = springlab(&[
        "study",
        "resolution",
        "rope",
        "--n",
        "3,5,9",
        "--png",
        png.to_str().expect("path"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).expect("the chart");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn advise_recommends_a_verified_configuration_with_its_margin() {
    let x = 0.05;
    let report = json(&[
        "advise",
        "jelly-bowl",
        "--tolerance",
        "0.05",
        "--time",
        "2",
        "--set",
        "n=4",
        "--json",
    ]);
    let i = report["recommended"].as_u64().expect("a recommendation") as usize;
    let c = &report["candidates"][i];
    assert_eq!(c["verdict"], "meets");
    let verification = report["verifications"]
        .as_array()
        .expect("verifications")
        .iter()
        .find(|v| v["candidate"].as_u64() == Some(i as u64))
        .expect("verified");
    assert_eq!(verification["holds"], true);
    assert_eq!(verification["stability"]["passed"], true);
    let e_ref = report["reference"]["error"]["metres"]
        .as_f64()
        .expect("e_ref");
    assert!(e_ref <= x / 4.0, "the reference converged: {e_ref}");
    let over_run = verification["error"]["metres"].as_f64().expect("error");
    assert!(over_run + e_ref <= x, "{over_run} + {e_ref} > {x}");
    let at_t = c["error_at_t"]["metres"].as_f64().expect("error at T");
    let own_run = c["error"]["metres"].as_f64().expect("error");
    assert!(at_t <= own_run, "the run's worst instant includes T");
    let check_at_t = verification["error_at_t"]["metres"]
        .as_f64()
        .expect("check at T");
    assert!(
        check_at_t <= over_run,
        "the check's worst instant includes T"
    );
    // The verification is a run the search did not make: the same configuration at dt/2,
    // within X of the reference too; its change from the candidate is the candidate's own
    // time-step error, which the two errors' difference cannot exceed (triangle inequality).
    let candidate_dt = c["dt"].as_f64().expect("dt");
    assert_eq!(verification["dt"].as_f64(), Some(candidate_dt / 2.0));
    assert_ne!(c["error"], verification["error"]);
    let own = c["error"]["metres"].as_f64().expect("candidate error");
    let change = verification["time_step_change"]["metres"]
        .as_f64()
        .expect("change");
    assert!(change > 0.0, "dt/2 is another run");
    assert!(
        (own - over_run).abs() <= change * (1.0 + 1e-9),
        "|{own} - {over_run}| > {change}"
    );

    // The margin, measured by perturbation growth (not the theory advise used) and by the
    // stability study's theory column.
    let method: Method = c["method"]
        .as_str()
        .expect("method")
        .parse()
        .expect("method");
    let dt = c["dt"].as_f64().expect("dt");
    let n = c["n"].as_i64().expect("n");
    let kinds = match c["kinds"].as_str() {
        Some("all") => Kinds::All,
        Some("no-bend") => Kinds::NoBend,
        _ => Kinds::NoShear,
    };
    let r = Refinement::require("jelly-bowl", &sets(&["n=4"])).expect("jelly");
    let scene = r.scene(n, kinds, &Limits::DEFAULT).expect("scene");
    let study = stability::stability(
        &scene,
        &StabilityOptions {
            methods: vec![method],
            confirm: false,
            ..StabilityOptions::default()
        },
        &mut |_, _| {},
    )
    .expect("study");
    let m = &study.methods[0];
    if let Some(linear) = m.linear_max_dt {
        assert!(
            linear / dt >= 1.5 * (1.0 - 2e-3),
            "measured margin {}",
            linear / dt
        );
    }
    if let Some(theory) = m.damped_theory.dt {
        assert!(
            theory / dt >= 1.5 * (1.0 - 1e-9),
            "theory margin {}",
            theory / dt
        );
    }

    // The error, measured through `springlab run` against a fine RK4 run: the centroid.
    let command = verification["command"].as_str().expect("command");
    let words: Vec<&str> = command.split_whitespace().skip(1).collect();
    let mut run_args = words.clone();
    run_args.push("--json");
    let centroid = |v: &Value| {
        let p = v["positions"].as_array().expect("positions");
        p.iter()
            .map(|q| {
                DVec3::new(
                    q[0].as_f64().expect("x"),
                    q[1].as_f64().expect("y"),
                    q[2].as_f64().expect("z"),
                )
            })
            .sum::<DVec3>()
            / p.len() as f64
    };
    let recommended = json(&run_args);
    let end = recommended["time"].as_f64().expect("time");
    assert!((end - 2.0).abs() < 1e-9, "the command runs to T: {end}");
    let mut fine_args: Vec<String> = vec![
        "run".into(),
        "jelly-bowl".into(),
        "--method".into(),
        "rk4".into(),
        "--dt".into(),
        "5e-5".into(),
        "--time".into(),
        "2".into(),
        "--json".into(),
    ];
    for w in words.windows(2).filter(|w| w[0] == "--set") {
        fine_args.push("--set".into());
        fine_args.push(w[1].to_string());
    }
    let fine = json(&fine_args.iter().map(String::as_str).collect::<Vec<_>>());
    let d = centroid(&recommended).distance(centroid(&fine));
    assert!(d <= x, "centroid {d} m from RK4 at 5e-5 s");
}

#[test]
fn advise_on_the_oscillator_meets_the_exact_solution() {
    // No resolution to choose: methods and steps only. x(t) = 1 + 0.1 cos(10 t).
    let x = 1e-3;
    let report = json(&["advise", "oscillator", "--tolerance", "0.001", "--json"]);
    let i = report["recommended"].as_u64().expect("recommended") as usize;
    let c = &report["candidates"][i];
    assert!(c["n"].is_null(), "no resolution for the oscillator");
    let command = report["verifications"]
        .as_array()
        .expect("verifications")
        .iter()
        .find(|v| v["candidate"].as_u64() == Some(i as u64))
        .expect("verified")["command"]
        .as_str()
        .expect("command")
        .to_string();
    let mut words: Vec<&str> = command.split_whitespace().skip(1).collect();
    words.push("--json");
    let run = json(&words);
    let end = run["positions"][1][0].as_f64().expect("x");
    let exact = 1.0 + 0.1 * (10.0f64 * 1.0).cos();
    assert!((end - exact).abs() <= x, "{end} vs {exact}");
    // Every accepted candidate has a theory margin of at least 1.5.
    for c in report["candidates"].as_array().expect("candidates") {
        if c["verdict"] == "meets" && c["margin_kind"] == "theory" {
            assert!(c["margin"].as_f64().expect("margin") >= 1.5);
        }
    }
}

#[test]
fn bad_input_is_refused_with_what_was_expected() {
    let e = stderr_of_failure(&["study", "resolution", "oscillator"]);
    assert!(e.contains("scene `oscillator` cannot be refined"), "{e}");
    let e = stderr_of_failure(&["study", "resolution", "rope", "--n", "1,3"]);
    assert!(e.contains("nodes = 1: expected whole numbers ≥ 2"), "{e}");
    let e = stderr_of_failure(&["study", "resolution", "rope", "--n", "3"]);
    assert!(e.contains("at least two resolutions"), "{e}");
    let e = stderr_of_failure(&["advise", "rope", "--tolerance", "-1"]);
    assert!(
        e.contains("--tolerance -1: expected a positive number"),
        "{e}"
    );
    let e = stderr_of_failure(&["advise", "rope", "--tolerance", "0.01", "--time", "0"]);
    assert!(e.contains("--time 0: expected a duration"), "{e}");
    let e = stderr_of_failure(&["advise", "rope"]);
    assert!(e.contains("--tolerance"), "{e}");
    let e = stderr_of_failure(&["advise", "oscillator", "--tolerance", "0.1", "--n", "3"]);
    assert!(e.contains("cannot be refined"), "{e}");
    let e = stderr_of_failure(&["study", "resolution", "rope", "--method", "leapfrog"]);
    assert!(e.contains("unknown method `leapfrog`"), "{e}");
}

/// `value` without its `wall_seconds` fields (timings differ between any two runs).
fn without_wall(value: &mut Value) {
    match value {
        Value::Object(map) => {
            map.remove("wall_seconds");
            map.values_mut().for_each(without_wall);
        }
        Value::Array(items) => items.iter_mut().for_each(without_wall),
        _ => {}
    }
}

#[test]
fn advise_on_one_thread_and_two_takes_the_same_decisions() {
    // With two threads the next halvings and the reference chain's next run are computed
    // ahead; the search must take the same decisions and report the same numbers.
    let args = [
        "advise",
        "jelly-bowl",
        "--tolerance",
        "0.05",
        "--time",
        "2",
        "--set",
        "n=4",
        "--methods",
        "semi-implicit-euler,midpoint,rk4",
        "--json",
    ];
    let run = |threads: &str| {
        let mut v = common::json_on_threads(&args, threads);
        without_wall(&mut v);
        v
    };
    let one = run("1");
    assert_eq!(one, run("2"), "one thread and two differ");
    assert!(
        one["candidates"].as_array().expect("candidates").len() >= 3,
        "{one}"
    );
}
