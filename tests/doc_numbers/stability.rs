//! docs/stability.md's table and the stiffest states under it are the recorded stability study
//! (`docs/studies/stability-SCENE.json`, written by `scripts/record-stability.sh`), and the
//! recordings are pinned to the code: the rope's whole study is re-run (half a second), and for
//! every scene `ω_max` and each method's damped theory at rest are recomputed. The linear, the
//! stiffest-state and the scene limits of the 10³ cube and the cloth take minutes a scene: they are
//! checked against the theory the test recomputes (linear within 0.1 %, scene limit below the
//! theory at rest), not re-run.

use serde_json::Value;
use springlab::physics::Method;
use springlab::study::{self, theory};

use super::read;

/// The scenes of the table, in its order.
pub const SCENES: [&str; 4] = ["rope", "cube-plane", "jelly-bowl", "cloth-spheres"];

/// Where the generated part of the page begins and ends.
pub const BEGIN: &str = "<!-- recorded: docs/studies/stability-*.json -->";
pub const END: &str = "<!-- /recorded -->";

pub fn recorded(scene: &str) -> Value {
    let text = read(&format!("docs/studies/stability-{scene}.json"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("stability-{scene}.json: {e}"))
}

/// Rust's `{:.4e}`: `1.2361e-1`.
fn seconds(class: &Value, dt: &Value) -> String {
    match dt.as_f64() {
        Some(dt) => format!("{dt:.4e} s"),
        None => class.as_str().expect("class").to_string(),
    }
}

fn versus(a: &Value, b: &Value) -> String {
    match (a.as_f64(), b.as_f64()) {
        (Some(a), Some(b)) => format!(" ({:+.1} %)", 100.0 * (a / b - 1.0)),
        _ => String::new(),
    }
}

fn theory(t: &Value) -> String {
    if t.is_null() {
        return "—".to_string();
    }
    seconds(&t["stability"], &t["dt"])
}

/// The generated part of the page, from the recordings.
pub fn generated() -> String {
    let mut out = String::from(
        "| scene | method | damped theory | linear (vs theory) | theory at the stiffest state | \
         theory hanging | scene (vs theory) |\n|---|---|---|---|---|---|---|\n",
    );
    let mut notes = Vec::new();
    for scene in SCENES {
        let r = recorded(scene);
        for m in r["methods"].as_array().expect("methods") {
            let class = if m["classed_by_equilibrium"] == true {
                " (classed by the hanging theory)"
            } else {
                ""
            };
            out.push_str(&format!(
                "| {scene} | {} | {} | {}{} | {} | {} | {}{}{class} |\n",
                m["method"].as_str().expect("method"),
                theory(&m["damped_theory"]),
                seconds(&m["linear_stability"], &m["linear_max_dt"]),
                versus(&m["linear_max_dt"], &m["theory_dt"]),
                theory(&m["stiffest_theory"]),
                theory(&m["equilibrium_theory"]),
                seconds(&m["stability"], &m["max_stable_dt"]),
                versus(&m["max_stable_dt"], &m["theory_dt"]),
            ));
        }
        let s = &r["stiffest_state"];
        let f = |v: &Value| v.as_f64().expect("number");
        notes.push(format!(
            "- {scene}: ω_max = {:.2} rad/s at rest, {:.2} rad/s ({:+.1} %) at t = {:.3} s of a run \
             with {} at dt = {:e} s",
            f(&r["omega_max"]),
            f(&s["omega_max"]),
            100.0 * (f(&s["ratio"]) - 1.0),
            f(&s["time"]),
            s["method"].as_str().expect("method"),
            f(&s["dt"]),
        ));
    }
    out.push_str("\nThe stiffest states:\n\n");
    out.push_str(&notes.join("\n"));
    out.push('\n');
    out
}

/// The page's generated part.
fn on_the_page(page: &str) -> &str {
    let a = page.find(BEGIN).expect("the begin marker") + BEGIN.len();
    let b = page[a..].find(END).expect("the end marker") + a;
    &page[a..b]
}

fn method(r: &Value, name: &str) -> Value {
    r["methods"]
        .as_array()
        .expect("methods")
        .iter()
        .find(|m| m["method"] == name)
        .unwrap_or_else(|| panic!("{name}"))
        .clone()
}

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-9 * a.abs().max(b.abs()),
        "{what}: recorded {a}, the code gives {b}: run scripts/record-stability.sh"
    );
}

#[test]
fn stability_md_is_the_recorded_study() {
    let page = read("docs/stability.md");
    let expected = generated();
    assert_eq!(
        on_the_page(&page).trim(),
        expected.trim(),
        "docs/stability.md's table is not the recordings': put this between the markers:\n{expected}"
    );
    // The rope's whole study again: the same report (it has no wall-clock fields).
    let now = super::json(&["study", "stability", "rope", "--no-usable", "--json"]);
    assert_eq!(
        now,
        recorded("rope"),
        "the rope's recording differs from the code: run scripts/record-stability.sh"
    );
    // Every scene: ω_max and the damped theory at rest, recomputed.
    let mut shortfall = (0.0f64, String::new(), String::new());
    for scene in SCENES {
        let r = recorded(scene);
        let s = springlab::scene::load(scene, &[]).expect("scene");
        let b = &s.bodies[0];
        let omega = study::omega_max(&b.model, &b.state).omega;
        close(
            r["omega_max"].as_f64().unwrap(),
            omega,
            &format!("{scene} ω_max"),
        );
        let spectrum = theory::spectrum(&b.model, &b.state, omega);
        for m in Method::ALL {
            let t = theory::limit(m, &b.params, &spectrum);
            let rec = method(&r, m.name());
            assert_eq!(
                rec["damped_theory"]["stability"], t.stability,
                "{scene} {m}"
            );
            if let Some(dt) = t.dt {
                close(
                    rec["theory_dt"].as_f64().unwrap(),
                    dt,
                    &format!("{scene} {m} theory"),
                );
                // The linear limit is the theory within 0.1 % (docs/studies.md): the search's
                // bisection tolerance, so up to 0.1 % and a rounding below.
                let linear = rec["linear_max_dt"].as_f64().expect("linear limit");
                assert!(
                    (linear / dt - 1.0).abs() <= 1.001e-3,
                    "{scene} {m}: {linear} vs {dt}"
                );
                if let Some(limit) = rec["max_stable_dt"].as_f64()
                    && scene != "rope"
                {
                    let short = 100.0 * (1.0 - limit / dt);
                    if short > shortfall.0 {
                        shortfall = (short, m.name().to_string(), scene.to_string());
                    }
                }
            }
        }
    }
    // docs/studies.md quotes the rope's linear dt·ω and the largest shortfall of a scene limit.
    let studies = read("docs/studies.md");
    let rope = recorded("rope");
    let z = |m: &str| method(&rope, m)["linear_dt_omega"].as_f64().expect("dt·ω");
    for quote in [
        format!(
            "semi-implicit Euler {:.4} against 2",
            z("semi-implicit-euler")
        ),
        format!("RK4 {:.4} against 2√2", z("rk4")),
        format!(
            "up to {:.0} % for {} on `{}`",
            shortfall.0,
            super::label(&shortfall.1),
            shortfall.2
        ),
    ] {
        assert!(studies.contains(&quote), "docs/studies.md: `{quote}`");
    }
}
