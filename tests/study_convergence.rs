//! `springlab study convergence` and `work-precision` through the binary.

use crate::common;
use common::{json, springlab};

fn orders(v: &serde_json::Value) -> Vec<(String, Option<f64>)> {
    v["methods"]
        .as_array()
        .expect("methods")
        .iter()
        .map(|m| {
            (
                m["method"].as_str().unwrap_or("").to_string(),
                m["order"].as_f64(),
            )
        })
        .collect()
}

#[test]
fn oscillator_orders_against_the_exact_solution() {
    let v = json(&["study", "convergence", "oscillator", "--json"]);
    assert_eq!(v["reference"], "exact");
    assert_eq!(v["reference_error"], 0.0);
    let expected = [
        ("explicit-euler", 1.0),
        ("semi-implicit-euler", 1.0),
        ("midpoint", 2.0),
        ("rk4", 4.0),
        ("implicit-euler", 1.0),
        ("verlet", 2.0),
    ];
    let got = orders(&v);
    for (name, order) in expected {
        let (_, measured) = got.iter().find(|(m, _)| m == name).expect("method present");
        let measured = measured.expect("an order");
        assert!((measured - order).abs() <= 0.15, "{name}: {measured}");
    }
    // Four dt levels per method, halving, each with its cost.
    let rk4 = &v["methods"][3];
    let points = rk4["points"].as_array().expect("points");
    assert_eq!(points.len(), 4);
    assert_eq!(points[0]["force_evals"], 800);
    assert_eq!(points[1]["force_evals"], 1600);
    assert!(
        (points[0]["dt"].as_f64().unwrap() / points[1]["dt"].as_f64().unwrap() - 2.0).abs() < 1e-12
    );
}

#[test]
fn rope_work_precision_uses_an_rk4_reference_with_its_error() {
    let v = json(&[
        "study",
        "work-precision",
        "rope",
        "--methods",
        "semi-implicit-euler,rk4",
        "--repeats",
        "1",
        "--json",
    ]);
    assert!(v["reference"].as_str().unwrap().starts_with("rk4 dt="));
    assert!(v["reference_error"].as_f64().unwrap() < 1e-10);
    let got = orders(&v);
    assert_eq!(got.len(), 2);
    assert!((got[0].1.unwrap() - 1.0).abs() < 0.15);
    assert!((got[1].1.unwrap() - 4.0).abs() < 0.15);
    // More accuracy costs more force evaluations: cost doubles with each halving of dt.
    let pts = v["methods"][1]["points"].as_array().unwrap();
    assert_eq!(pts.len(), 6);
    for w in pts.windows(2) {
        assert_eq!(
            w[1]["force_evals"].as_u64().unwrap(),
            2 * w[0]["force_evals"].as_u64().unwrap()
        );
        assert!(w[1]["error"].as_f64().unwrap() < w[0]["error"].as_f64().unwrap());
    }
}

#[test]
fn the_same_study_twice_gives_the_same_errors() {
    let strip = |mut v: serde_json::Value| {
        for m in v["methods"].as_array_mut().unwrap() {
            for p in m["points"].as_array_mut().unwrap() {
                p["wall_seconds"] = 0.into();
            }
        }
        for p in v["verlet_companion"]["verlet"]["points"]
            .as_array_mut()
            .unwrap()
        {
            p["wall_seconds"] = 0.into();
        }
        v
    };
    let args = ["study", "convergence", "rope", "--json"];
    assert_eq!(strip(json(&args)), strip(json(&args)));
}

#[test]
fn bad_study_input_gets_a_message() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["study", "convergence", "rope", "--dt", "0"],
            "--dt 0: expected a time step in seconds > 0",
        ),
        (
            &["study", "convergence", "rope", "--time", "-1"],
            "--time -1: expected a duration in seconds > 0",
        ),
        (
            &["study", "convergence", "rope", "--levels", "1"],
            "--levels 1: expected at least 2 time steps",
        ),
        (
            &["study", "convergence", "rope", "--methods", "euler"],
            "unknown method `euler`",
        ),
        (
            &["study", "work-precision", "nosuch"],
            "unknown scene `nosuch`",
        ),
    ];
    for (args, message) in cases {
        let out = springlab(args);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(message), "{args:?}: {err}");
    }
}

#[test]
fn verlet_is_second_order_without_dampers_and_first_order_with_them() {
    let v = json(&["study", "convergence", "oscillator", "--json"]);
    let verlet = orders(&v)
        .into_iter()
        .find(|(m, _)| m == "verlet")
        .and_then(|(_, o)| o)
        .unwrap();
    assert!((verlet - 2.0).abs() <= 0.15, "undamped: {verlet}");
    // The companion row: the same oscillator with a damper k_d = 0.2 √(k m) = 2 N·s/m, against
    // the exact damped solution.
    let c = &v["verlet_companion"];
    assert_eq!(c["damped"], true);
    assert_eq!(c["sets"][0], "damping=2");
    assert_eq!(c["reference"], "exact");
    let damped = c["verlet"]["order"].as_f64().unwrap();
    assert!((damped - 1.0).abs() <= 0.15, "damped: {damped}");
    // Starting from the damped oscillator, the companion switches the damper off.
    let v = json(&[
        "study",
        "convergence",
        "oscillator",
        "--set",
        "damping=2",
        "--methods",
        "verlet,rk4",
        "--json",
    ]);
    assert_eq!(v["verlet_companion"]["damped"], false);
    assert_eq!(v["verlet_companion"]["sets"][0], "damping=0");
    let rk4 = orders(&v)[1].1.unwrap();
    assert!(
        (rk4 - 4.0).abs() <= 0.15,
        "RK4 on the damped oscillator: {rk4}"
    );
    // No Verlet, no companion.
    let v = json(&[
        "study",
        "convergence",
        "oscillator",
        "--methods",
        "rk4",
        "--json",
    ]);
    assert!(v.get("verlet_companion").is_none());
}

/// The order `study convergence` prints for `name` in its table (the line starting with the
/// method's name; the order is the last column).
fn printed_order(args: &[&str], name: &str) -> f64 {
    let out = springlab(args);
    assert!(out.status.success(), "{args:?} failed");
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.split_whitespace().next() == Some(name))
        .unwrap_or_else(|| panic!("no line for {name}:\n{text}"));
    line.split_whitespace()
        .last()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no order at the end of {line:?}"))
}

#[test]
fn velocity_verlet_is_second_order_with_and_without_dampers() {
    // The exact oscillator's solution is the reference: order 2 within 0.05.
    let undamped = printed_order(
        &[
            "study",
            "convergence",
            "oscillator",
            "--methods",
            "velocity-verlet",
        ],
        "velocity-verlet",
    );
    assert!((undamped - 2.0).abs() <= 0.05, "undamped: {undamped}");
    // With a damper k_d = 2 N·s/m the predicted velocity keeps it second order (position
    // Verlet drops to first order here, see above).
    let damped = printed_order(
        &[
            "study",
            "convergence",
            "oscillator",
            "--set",
            "damping=2",
            "--methods",
            "velocity-verlet",
        ],
        "velocity-verlet",
    );
    assert!((damped - 2.0).abs() <= 0.05, "damped: {damped}");
}

/// Verlet's own damping is part of its reference (`study::convergence` module docs, "Verlet's
/// own damping"). The rate r = 0.2 1/s is the drag m r = 0.2 N·s/m; against the exact damped
/// oscillator Verlet, which applies it centred, is second order (before, the undamped reference
/// made it look like order 0.003). A γ per step is a drag γ/dt that grows as dt shrinks, so the
/// runs converge to no solution: no order, and the reason (before: order -0.84).
#[test]
fn verlet_own_damping_is_in_its_reference() {
    let v = json(&[
        "study",
        "convergence",
        "oscillator",
        "--methods",
        "verlet",
        "--set",
        "verlet_damping_rate=0.2",
        "--json",
    ]);
    let verlet = &v["methods"][0];
    let order = verlet["order"].as_f64().expect("an order");
    assert!((order - 2.0).abs() <= 0.05, "order {order}");
    let own = verlet["reference"]
        .as_str()
        .expect("Verlet's own reference");
    assert!(own.starts_with("exact, verlet_damping_rate 0.2"), "{own}");
    // The text output prints the order and Verlet's reference.
    let out = springlab(&[
        "study",
        "convergence",
        "oscillator",
        "--methods",
        "verlet",
        "--set",
        "verlet_damping_rate=0.2",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(&format!("order {order:.3}")), "{text}");
    assert!(
        text.contains("reference: exact, verlet_damping_rate 0.2"),
        "{text}"
    );
    // Other methods do not feel Verlet's rate: RK4 keeps the report's reference and order 4.
    let v = json(&[
        "study",
        "convergence",
        "oscillator",
        "--methods",
        "rk4",
        "--set",
        "verlet_damping_rate=0.2",
        "--json",
    ]);
    assert!(v["methods"][0].get("reference").is_none());
    let rk4 = v["methods"][0]["order"].as_f64().unwrap();
    assert!((rk4 - 4.0).abs() <= 0.15, "rk4 {rk4}");
    // γ per step: no order, and why.
    let v = json(&[
        "study",
        "convergence",
        "oscillator",
        "--methods",
        "verlet",
        "--set",
        "verlet_damping=0.001",
        "--json",
    ]);
    let verlet = &v["methods"][0];
    assert!(verlet["order"].is_null(), "{verlet}");
    assert!(
        verlet["reference"]
            .as_str()
            .unwrap()
            .starts_with("none: verlet_damping"),
        "{verlet}"
    );
    assert!(
        verlet["points"]
            .as_array()
            .unwrap()
            .iter()
            .all(|p| p["fitted"] == false)
    );
}
