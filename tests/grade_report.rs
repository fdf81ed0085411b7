//! Reports: Gradescope's `results.json` fields, the JSON round trip, and the rubric table.

use springlab::grade::{
    Assignment, ClothHomework, DVec3, JellyHomework, Options, Physics, Reference, Report,
    SpringSetup, State, grade_jelly,
};

/// Checks the fields of Gradescope's autograder specification ("Output format"): a numeric
/// `score`, `tests` with `name`, `score`, `max_score`, `output`, `visibility`; the test scores
/// add up to the total.
pub fn validate_gradescope(text: &str, max: f64) -> serde_json::Value {
    let v: serde_json::Value = serde_json::from_str(text).expect("results.json is JSON");
    let score = v["score"].as_f64().expect("score is a number");
    assert_eq!(v["max_score"].as_f64(), Some(max));
    assert!(v["output"].is_string());
    assert!(v["execution_time"].is_number());
    let tests = v["tests"].as_array().expect("tests is an array");
    assert!(!tests.is_empty());
    let mut sum = 0.0;
    let mut max_sum = 0.0;
    for t in tests {
        let name = t["name"].as_str().expect("name is a string");
        let s = t["score"].as_f64().expect("score is a number");
        let m = t["max_score"].as_f64().expect("max_score is a number");
        assert!((0.0..=m).contains(&s), "{name}: {s} of {m}");
        assert!(t["output"].is_string(), "{name}");
        let visibility = t["visibility"].as_str().expect("visibility is a string");
        assert!(
            ["visible", "hidden", "after_due_date", "after_published"].contains(&visibility),
            "{visibility}"
        );
        assert!(["passed", "failed"].contains(&t["status"].as_str().unwrap_or_default()));
        sum += s;
        max_sum += m;
    }
    assert!((sum - score).abs() < 1e-9, "{sum} vs {score}");
    assert!((max_sum - max).abs() < 1e-9);
    v
}

/// The reference with a midpoint step that panics and a spring set-up that forgets bend springs.
struct Partial;

impl JellyHomework for Partial {
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup> {
        let mut s = JellyHomework::springs(&Reference, counts);
        s.retain(|s| s.kind != springlab::grade::SpringKind::Bend);
        s
    }
    fn spring_force(&self, xa: DVec3, xb: DVec3, k: f64, l: f64) -> DVec3 {
        JellyHomework::spring_force(&Reference, xa, xb, k, l)
    }
    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
        JellyHomework::damper_force(&Reference, xa, xb, va, vb, kd)
    }
    fn internal_forces(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        s: &[springlab::grade::Spring],
    ) -> Vec<DVec3> {
        Reference.internal_forces(x, v, s)
    }
    fn plane_collision(
        &self,
        plane: &springlab::grade::Plane,
        p: &mut springlab::grade::Particle,
        c: &springlab::grade::ContactCoefficients,
    ) {
        Reference.plane_collision(plane, p, c);
    }
    fn bowl_collision(
        &self,
        bowl: &springlab::grade::Bowl,
        p: &mut springlab::grade::Particle,
        c: &springlab::grade::ContactCoefficients,
    ) {
        Reference.bowl_collision(bowl, p, c);
    }
    fn explicit_euler(&self, s: &mut State, dt: f64, p: &Physics) {
        JellyHomework::explicit_euler(&Reference, s, dt, p);
    }
    fn implicit_euler(&self, s: &mut State, dt: f64, p: &Physics) {
        JellyHomework::implicit_euler(&Reference, s, dt, p);
    }
    fn midpoint(&self, _: &mut State, _: f64, _: &Physics) {
        panic!("not yet");
    }
    fn rk4(&self, s: &mut State, dt: f64, p: &Physics) {
        JellyHomework::rk4(&Reference, s, dt, p);
    }
}

#[test]
fn gradescope_results_have_the_specified_fields() {
    let report = grade_jelly(Partial, &Options::default());
    let text = serde_json::to_string_pretty(&report.gradescope()).expect("serialises");
    let v = validate_gradescope(&text, 80.0);
    assert_eq!(v["score"].as_f64(), Some(80.0 - 5.0 - 2.5));
    let tests = v["tests"].as_array().expect("tests");
    let midpoint = tests
        .iter()
        .find(|t| t["name"] == "4. integrators: midpoint")
        .expect("a test per item");
    assert_eq!(midpoint["score"].as_f64(), Some(0.0));
    assert!(
        midpoint["output"]
            .as_str()
            .unwrap_or_default()
            .contains("panicked: not yet")
    );
    let springs = &tests[0];
    assert_eq!(springs["score"].as_f64(), Some(10.0));
    assert!(
        springs["output"]
            .as_str()
            .unwrap_or_default()
            .contains("missing")
    );
    assert!(
        v["output"]
            .as_str()
            .unwrap_or_default()
            .contains("graded by hand")
    );
}

#[test]
fn reports_round_trip_through_json() {
    let report = grade_jelly(Partial, &Options::default());
    let back: Report = serde_json::from_str(&report.to_json().expect("json")).expect("parses");
    assert_eq!(back, report);
}

#[test]
fn the_table_lists_every_item_with_points_and_the_feedback() {
    let report = grade_jelly(Partial, &Options::default());
    let table = report.table();
    assert!(table.contains("score 72.5 / 80"), "{table}");
    assert!(table.contains("max 80 of the course's 100: the report (20) is graded by hand"));
    assert!(
        table.contains("1. springs: struct, shear and bend springs      10 / 15  partial"),
        "{table}"
    );
    assert!(
        table.contains("4. integrators: midpoint                        0 / 2.5  panicked"),
        "{table}"
    );
    assert!(table.contains("missing 2400: (0,0,0)–(2,0,0)"), "{table}");
    assert!(table.contains("hint"));
}

#[test]
fn a_report_of_nothing_run_scores_zero_with_the_reason() {
    for assignment in Assignment::ALL {
        let report = assignment.not_run("the crate did not build", &Options::default());
        assert_eq!(report.score, 0.0);
        assert_eq!(
            report.max_score,
            assignment.grade_reference(&Options::default()).max_score
        );
        let text = serde_json::to_string(&report.gradescope()).expect("serialises");
        validate_gradescope(&text, report.max_score);
        assert!(report.table().contains("the crate did not build"));
    }
}

#[test]
fn reference_cloth_trait_is_usable_directly() {
    // A student can call the reference to compare (for example in their own tests).
    let s = ClothHomework::springs(&Reference, 3);
    assert_eq!(s.len(), 2 * 3 * 2 + 2 * 2 * 2 + 2 * 3);
}
