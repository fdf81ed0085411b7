//! `springlab run` and `springlab scenes` through the real binary.

use crate::common;
use common::{json, springlab};

fn stderr_of_failure(args: &[&str]) -> String {
    let out = springlab(args);
    assert!(!out.status.success(), "expected failure for {args:?}");
    assert!(out.stdout.is_empty(), "nothing on stdout for {args:?}");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn oscillator_rk4_json_follows_the_contract() {
    let v = json(&[
        "run",
        "oscillator",
        "--method",
        "rk4",
        "--dt",
        "0.01",
        "--time",
        "10",
        "--json",
    ]);
    assert_eq!(v["scene"], "oscillator");
    assert_eq!(v["method"], "rk4");
    assert_eq!(v["dt"], 0.01);
    assert_eq!(v["steps"], 1000);
    assert_eq!(v["time"], 10.0);
    assert_eq!(v["particles"], 2);
    assert_eq!(v["springs"], 1);
    assert_eq!(v["force_evals"], 4000);
    assert!(v["diverged"].is_null());
    assert!(v["wall_seconds"].as_f64().expect("wall") >= 0.0);
    let x = v["positions"][1][0].as_f64().expect("x1");
    // RK4's own error at dt·ω = 0.1 over 10 s is 4.8e-6 m (see tests/integrators.rs).
    assert!((x - (1.0 + 0.1 * 100f64.cos())).abs() < 5e-6, "x = {x}");
    let e = &v["energy"];
    let sum = e["kinetic"].as_f64().unwrap()
        + e["gravity"].as_f64().unwrap()
        + e["elastic"].as_f64().unwrap();
    assert!((sum - e["total"].as_f64().unwrap()).abs() < 1e-15);
    // Energy ½ k A² = 0.5 J, which RK4 loses only slowly.
    assert!((e["total"].as_f64().unwrap() - 0.5).abs() < 1e-4);
    assert_eq!(v["velocities"].as_array().unwrap().len(), 2);
}

#[test]
fn two_runs_print_identical_json_but_for_the_wall_time() {
    let args = [
        "run", "ropes", "--set", "nodes=16", "--time", "20", "--json",
    ];
    let mut a = json(&args);
    let mut b = json(&args);
    a["wall_seconds"] = 0.into();
    b["wall_seconds"] = 0.into();
    assert_eq!(a, b);
    assert_eq!(a["method"], "semi-implicit-euler,verlet");
    assert_eq!(a["particles"], 32);
}

#[test]
fn explicit_euler_rope_reports_divergence_with_exit_code_zero() {
    let v = json(&[
        "run",
        "rope",
        "--method",
        "explicit-euler",
        "--steps",
        "10000",
        "--json",
    ]);
    let d = &v["diverged"];
    let step = d["step"].as_u64().expect("diverged.step");
    assert!(step < 10_000);
    assert_eq!(v["steps"].as_u64(), Some(step));
    assert!(d["max_speed"].as_f64().unwrap() > 1000.0);
    assert!((d["time"].as_f64().unwrap() - step as f64 / 64.0).abs() < 1e-12);
    assert!(d["reason"].as_str().unwrap().contains("1000 m/s"));
}

#[test]
fn csv_has_a_header_and_one_row_per_recorded_step() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let path = dir.join("osc.csv");
    let out = springlab(&[
        "run",
        "oscillator",
        "--steps",
        "100",
        "--csv",
        path.to_str().unwrap(),
        "--csv-every",
        "10",
    ]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "step,time,kinetic,gravity,elastic,total,dissipated,residual,x0,y0,z0,x1,y1,z1"
    );
    assert_eq!(lines.len(), 1 + 11, "header, step 0 and every 10th step");
    let last: Vec<f64> = lines[11].split(',').map(|c| c.parse().unwrap()).collect();
    assert_eq!(last[0], 100.0);
    assert!((last[1] - 1.0).abs() < 1e-12);
    // total = kinetic + gravity + elastic on every row
    assert!((last[2] + last[3] + last[4] - last[5]).abs() < 1e-12);
    // The undamped oscillator dissipates nothing; the residual is RK4's energy error,
    // E_n - E_0 = (|R(0.1 i)|^(2n) - 1) E_0 with |R|² = 1 - z⁶/72 + z⁸/576, z = 0.1.
    let first: Vec<f64> = lines[1].split(',').map(|c| c.parse().unwrap()).collect();
    assert_eq!(last[6], 0.0);
    let z: f64 = 0.1;
    let r2 = 1.0 - z.powi(6) / 72.0 + z.powi(8) / 576.0;
    let expected = (r2.powi(100) - 1.0) * first[5];
    assert!(
        (last[7] - expected).abs() < 1e-6 * expected.abs(),
        "residual {} expected {expected}",
        last[7]
    );
}

#[test]
fn bad_input_gets_a_clear_message() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["run", "nosuch"],
            "unknown scene `nosuch`; built-in scenes: oscillator, rope, ropes",
        ),
        (
            &["run", "rope", "--dt", "0"],
            "--dt 0: expected a time step in seconds > 0",
        ),
        (
            &["run", "rope", "--dt", "-1"],
            "--dt -1: expected a time step in seconds > 0",
        ),
        (
            &["run", "rope", "--time", "-3"],
            "--time -3: expected a duration in seconds >= 0",
        ),
        (
            &["run", "rope", "--method", "euler"],
            "unknown method `euler`; expected one of: explicit-euler, semi-implicit-euler",
        ),
        (
            &["run", "ropes", "--method", "rk4,verlet,midpoint"],
            "--method lists 3 methods but scene `ropes` has 2 bodies",
        ),
        (
            &["run", "rope", "--set", "colour=red"],
            "unknown parameter `colour` for scene `rope`; known parameters: nodes, mass",
        ),
        (
            &["run", "rope", "--set", "nodes=1"],
            "`nodes` = 1 is out of range: allowed 2 ..= 1000000",
        ),
        (
            &["run", "rope", "--set", "mass=-1"],
            "`mass` = -1 is out of range: allowed 1e-6 ..= 1e6 (kg)",
        ),
        (
            &["run", "rope", "--set", "mass=heavy"],
            "`mass` = heavy: expected a number 1e-6 ..= 1e6",
        ),
        (
            &["run", "rope", "--set", "pinned=[0, 3]"],
            "`pinned` = 3 is out of range: allowed 0 ..= 2 (the scene has 3 particles)",
        ),
        (
            &["run", "rope", "--set", "start=[1,2]"],
            "`start` = [1,2]: expected a vector [x, y, z]",
        ),
        (
            &["run", "rope", "--set", "nodes"],
            "`nodes`: expected key=value",
        ),
        (
            &["run", "rope", "--set", "verlet_damping=1"],
            "`verlet_damping` = 1 is out of range: allowed 0 ..< 1",
        ),
        (
            &["run", "rope", "--csv", "/nonexistent-dir/x.csv"],
            "cannot write /nonexistent-dir/x.csv: directory /nonexistent-dir does not exist",
        ),
        (
            &[
                "run",
                "rope",
                "--set",
                "start=[0,0,0]",
                "--set",
                "end=[0,0,0]",
            ],
            "`start` and `end` must differ",
        ),
    ];
    for (args, message) in cases {
        let err = stderr_of_failure(args);
        assert!(err.starts_with("springlab: "), "{args:?}: {err}");
        assert!(
            err.contains(message),
            "{args:?}: expected `{message}`, got `{err}`"
        );
    }
}

#[test]
fn scenes_lists_every_builtin_with_parameters() {
    let out = springlab(&["scenes"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["oscillator", "rope", "ropes"] {
        assert!(text.lines().any(|l| l.starts_with(name)), "{name} missing");
    }
    assert!(text.contains("stiffness"));
    assert!(text.contains("N/m"));
    // The scenes list their own parameters; the method parameters are listed once, by method.
    let param_lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("    ") && l.contains(" = "))
        .collect();
    for method_param in ["verlet_damping", "iterations", "substeps", "cg_tolerance"] {
        assert!(
            !param_lines
                .iter()
                .any(|l| l.trim_start().starts_with(&format!("{method_param} "))),
            "{method_param} listed as a scene parameter"
        );
    }
    assert!(
        text.contains("  verlet               verlet_damping, verlet_damping_rate, iterations")
    );
    assert!(text.contains("  xpbd                 iterations, substeps"));
    assert!(text.contains("  implicit-euler       cg_tolerance"));
}

#[test]
fn scenes_shows_a_methods_parameters_only_for_that_method() {
    let text = |args: &[&str]| {
        let out = springlab(args);
        assert!(out.status.success(), "{args:?}");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let verlet = text(&["scenes", "rope", "--method", "verlet"]);
    assert!(verlet.contains("verlet parameters (they change only a run with verlet):"));
    assert!(
        verlet.contains("    verlet_damping       = 5e-5"),
        "{verlet}"
    );
    assert!(verlet.contains("    iterations           = 1"), "{verlet}");
    assert!(!verlet.contains("substeps") && !verlet.contains("cg_tolerance"));
    assert!(verlet.contains("  scene parameters:") && verlet.contains("    nodes "));
    // The course cubes run Verlet without projection or damping.
    let jelly = text(&["scenes", "jelly-bowl", "--method", "verlet"]);
    assert!(jelly.contains("    iterations           = 0"), "{jelly}");
    let rk4 = text(&["scenes", "rope", "--method", "rk4"]);
    assert!(rk4.contains("  rk4: no parameters"));
    assert!(!rk4.contains("verlet_damping"));
    let one = text(&["scenes", "jelly-bowl"]);
    assert!(one.contains("default method semi-implicit-euler, dt = 0.001 s, duration 5 s"));
    assert!(one.contains("verlet: verlet_damping = 0, verlet_damping_rate = 0, iterations = 0"));
    let xpbd = text(&["scenes", "--method", "xpbd"]);
    assert_eq!(
        xpbd.matches("  xpbd parameters").count(),
        springlab::scene::BUILTIN.len()
    );
    let out = springlab(&["scenes", "nosuch"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown scene `nosuch`"));
}

/// `SPRINGLAB_KERNEL` chooses the spring kernel; a name that is not a kernel stops the command
/// with a message naming the variable and the choices, and `exact` gives the same `run --json`
/// (wall time aside) as `portable`: both compute `sqrt`, then `1/L`, correctly rounded, where
/// `avx512` does not.
#[test]
fn springlab_kernel_chooses_the_spring_kernel_or_says_what_it_accepts() {
    let run = |kernel: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_springlab"))
            .env("SPRINGLAB_KERNEL", kernel)
            .args(["run", "cube-plane", "--time", "0.2", "--json"])
            .output()
            .expect("springlab")
    };
    let bad = run("fastest");
    assert!(!bad.status.success());
    assert!(bad.stdout.is_empty());
    assert_eq!(
        String::from_utf8_lossy(&bad.stderr),
        "springlab: SPRINGLAB_KERNEL=fastest: not a spring kernel; expected exact, portable, avx2 or avx512\n"
    );
    let without_wall = |out: std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let mut v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
        v.as_object_mut().expect("an object").remove("wall_seconds");
        v
    };
    let exact = without_wall(run("exact"));
    assert_eq!(exact, without_wall(run("portable")));
    // The variable acts: AVX-512's refined reciprocal square root differs in the last bits (and
    // so does the run), or the CPU without it is told so.
    if springlab::physics::stencil::Kernel::Avx512.is_available() {
        assert_ne!(exact, without_wall(run("avx512")));
    } else {
        let refused = run("avx512");
        assert!(!refused.status.success());
        assert!(
            String::from_utf8_lossy(&refused.stderr)
                .contains("this CPU cannot run the Avx512 kernel"),
            "{}",
            String::from_utf8_lossy(&refused.stderr)
        );
    }
}

/// `--no-accounting` takes nothing from the motion: the accounting only watches it, so every
/// position, velocity and energy is the same bits with and without it (scenes on each of the
/// simulator's paths: the lattice's fused chunks with a plane's response, spheres that push a
/// cloth, Verlet's projections on the rope, implicit Euler's energy guard), and only the
/// accounting's own numbers are left out.
#[test]
fn no_accounting_leaves_the_motion_as_it_is() {
    let runs: [&[&str]; 4] = [
        &[
            "cube-plane",
            "--set",
            "n=6",
            "--set",
            "offset=[0,-0.9,0]",
            "--time",
            "0.6",
        ],
        &["cloth-spheres", "--time", "0.3"],
        &["rope", "--method", "verlet", "--time", "2"],
        &["jelly-bowl", "--method", "implicit-euler", "--time", "0.2"],
    ];
    for run in runs {
        let mut args = vec!["run"];
        args.extend_from_slice(run);
        args.push("--json");
        let mut with = json(&args);
        args.push("--no-accounting");
        let mut without = json(&args);
        assert!(with["residual"].is_f64(), "{run:?}: {}", with["residual"]);
        assert!(with["dissipated"]["total"].is_f64(), "{run:?}");
        for key in ["residual", "dissipated", "not_accurate"] {
            assert!(without[key].is_null(), "{run:?}: {key} = {}", without[key]);
            with[key] = serde_json::Value::Null;
        }
        with["wall_seconds"] = 0.into();
        without["wall_seconds"] = 0.into();
        assert!(with["steps"].as_u64().is_some_and(|n| n > 0), "{run:?}");
        assert_eq!(with, without, "{run:?}");
    }
}

#[test]
fn without_accounting_the_csv_leaves_its_columns_empty_and_the_summary_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("osc.csv");
    let out = springlab(&[
        "run",
        "oscillator",
        "--steps",
        "10",
        "--csv",
        path.to_str().unwrap(),
        "--no-accounting",
    ]);
    assert!(out.status.success());
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(
        summary.contains("energy accounting: off (--no-accounting)"),
        "{summary}"
    );
    assert!(!summary.contains("residual"), "{summary}");
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 11, "header and steps 0 to 10");
    for line in &lines[1..] {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), 14, "{line}");
        assert_eq!((cells[6], cells[7]), ("", ""), "{line}");
        let numbers: Vec<f64> = (cells[..6].iter().chain(&cells[8..]))
            .map(|c| c.parse().expect("a number"))
            .collect();
        // total = kinetic + gravity + elastic
        assert!((numbers[2] + numbers[3] + numbers[4] - numbers[5]).abs() < 1e-12);
    }
}
