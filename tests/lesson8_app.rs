//! Lesson 8 runs the study's bodies in the app: step 2's cloth is the resolution study's level
//! n = 9 and step 3's the same level without bend springs (the same `--set` values as
//! `Refinement::sets_for`, the study's method and dt), and their sags at the study's time equal
//! the recorded study's within 1 mm; the chart's mark (`observed_view::recorded`) is that
//! recorded value. Step 4 runs advise's recommendation (method and dt as recorded).

use springlab::lesson;
use springlab::physics::Method;
use springlab::study::observe;
use springlab::study::resolution::{Kinds, Refinement};
use springlab::tui::observed_view;

fn lesson_8() -> lesson::Lesson {
    lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.number == 8)
        .expect("lesson 8")
}

fn recorded(name: &str) -> serde_json::Value {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/studies")
        .join(name);
    serde_json::from_str(&std::fs::read_to_string(path).expect("recorded study")).expect("json")
}

#[test]
fn lesson_8_step_2_is_the_resolution_studys_level_9() {
    study_level(1, Kinds::All, "all");
}

#[test]
fn lesson_8_step_3_is_level_9_without_bend_springs() {
    study_level(2, Kinds::NoBend, "no-bend");
}

#[test]
fn lesson_8_step_4_runs_advises_recommendation() {
    let l = lesson_8();
    let step = &l.steps[3];
    let a = recorded("advise-jelly-bowl.json");
    let best = &a["candidates"][a["recommended"].as_u64().expect("recommended") as usize];
    assert_eq!(step.scene, a["scene"].as_str().expect("scene"));
    assert!(step.params.is_empty(), "the scene's own resolution");
    assert_eq!(best["n"].as_i64(), Some(10), "jelly-bowl's own n");
    assert_eq!(best["kinds"], "all");
    assert_eq!(step.method.map(|m| m.name()), best["method"].as_str());
    assert_eq!(step.dt, best["dt"].as_f64(), "advise's dt, not the scene's");
    // The chart's mark is the converged reference the advice was measured against.
    let mark = observed_view::recorded(step).expect("a recorded reference");
    let reference = &a["reference"]["observation"]["components"];
    assert_eq!(mark.time, 2.5);
    assert_eq!(mark.values[0], reference[0]["value"][1].as_f64());
    assert_eq!(mark.values[1], reference[1]["value"].as_f64());
}

/// Step `index` of lesson 8 is the resolution study's level n = 9 with `kinds`, and its sag at
/// the study's time is the recorded one within 1 mm.
fn study_level(index: usize, kinds: Kinds, name: &str) {
    let l = lesson_8();
    let step = &l.steps[index];
    let refinement = Refinement::require(&step.scene, &[]).expect("cloth-sphere refines");
    let mut want = refinement.sets_for(9, kinds);
    let mut have = step.params.clone();
    want.sort();
    have.sort();
    // The same values, however printed.
    let parse = |sets: &[String]| -> Vec<(String, f64)> {
        sets.iter()
            .map(|s| {
                let (k, v) = s.split_once('=').expect("key=value");
                (k.to_string(), v.parse::<f64>().expect("a number"))
            })
            .collect()
    };
    assert_eq!(parse(&have), parse(&want), "the study's level 9");

    let report = recorded("resolution-cloth-sphere.json");
    let run = report["runs"]
        .as_array()
        .expect("runs")
        .iter()
        .find(|r| r["n"] == 9 && r["kinds"] == name)
        .expect("level 9");
    let dt = run["run"]["dt"].as_f64().expect("dt");
    assert_eq!(step.method, Some(Method::Rk4));
    assert_eq!(run["run"]["method"], "rk4");
    assert_eq!(step.dt, Some(dt));
    let time = report["time"].as_f64().expect("time");
    let recorded = run["run"]["observation"]["components"][0]["value"]
        .as_f64()
        .expect("sag");
    let scene = step.build_scene().expect("builds");
    let steps = (time / dt).round() as u64;
    let m = observe::measure(&scene, Method::Rk4, dt, steps);
    let observation = m.observation.expect("the run does not diverge");
    let sag = observation.components[0].headline();
    assert_eq!(observation.components[0].name, "sag");
    assert!(
        (sag - recorded).abs() < 1e-3,
        "sag {sag} m, the study's {recorded} m"
    );
    let mark = observed_view::recorded(step).expect("the chart's mark");
    assert_eq!(mark.time, time);
    assert_eq!(
        mark.values,
        vec![Some(recorded)],
        "the mark is the recording's"
    );
}
