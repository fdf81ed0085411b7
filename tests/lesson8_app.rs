//! Lesson 8 runs the study's bodies in the app: step 2's cloth is the resolution study's level
//! n = 9 (the same `--set` values as `Refinement::sets_for`, the study's method and dt), and
//! its sag at the study's time equals the recorded study's within 1 mm.

use springlab::lesson;
use springlab::physics::Method;
use springlab::study::observe;
use springlab::study::resolution::{Kinds, Refinement};

#[test]
fn lesson_8_step_2_is_the_resolution_studys_level_9() {
    let lessons = lesson::builtin();
    let l = lessons
        .iter()
        .flatten()
        .find(|l| l.number == 8)
        .expect("lesson 8");
    let step = &l.steps[1];
    let refinement = Refinement::require(&step.scene, &[]).expect("cloth-sphere refines");
    let mut want = refinement.sets_for(9, Kinds::All);
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

    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/studies/resolution-cloth-sphere.json");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("recorded study"))
            .expect("json");
    let run = report["runs"]
        .as_array()
        .expect("runs")
        .iter()
        .find(|r| r["n"] == 9 && r["kinds"] == "all")
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
}
