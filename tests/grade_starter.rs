//! The untouched starter code that `springlab homework new` writes compiles against the library
//! and scores 0 on every implementable item, with feedback for every check.

use springlab::grade::{
    CheckOutcome, ItemStatus, Options, Report, grade_cloth, grade_jelly, grade_rope,
};

mod rope_starter {
    include!("../src/grade/templates/rope_lib.rs.txt");
}
mod jelly_starter {
    include!("../src/grade/templates/jelly_lib.rs.txt");
}
mod cloth_starter {
    include!("../src/grade/templates/cloth_lib.rs.txt");
}

/// Every item but `free` scores 0, and every failed check explains itself.
fn assert_zero(report: &Report, free: &[&str]) {
    print!("{}", report.table());
    for item in &report.items {
        if free.contains(&item.id.as_str()) {
            assert_eq!(item.score, item.max_score, "{}", item.label());
            continue;
        }
        assert_eq!(item.score, 0.0, "{} should score 0", item.label());
        assert_eq!(item.status, ItemStatus::Zero, "{}", item.label());
        for check in &item.checks {
            assert_eq!(check.outcome, CheckOutcome::Failed, "{}", check.name);
            let f = check
                .feedback
                .as_ref()
                .expect("a failed check has feedback");
            assert!(
                !f.input.is_empty()
                    && !f.expected.is_empty()
                    && !f.got.is_empty()
                    && !f.hint.is_empty(),
                "{}: {f:?}",
                check.name
            );
        }
        assert!(item.feedback_text().contains("expected"));
    }
}

#[test]
fn rope_starter_scores_zero_except_builds_and_runs() {
    let report = grade_rope(rope_starter::Student, &Options::default());
    assert_zero(&report, &["builds"]);
    assert_eq!(report.score, 5.0);
}

#[test]
fn jelly_starter_scores_zero() {
    let report = grade_jelly(jelly_starter::Student, &Options::default());
    assert_zero(&report, &[]);
    assert_eq!(report.score, 0.0);
}

#[test]
fn cloth_starter_scores_zero() {
    let report = grade_cloth(cloth_starter::Student, &Options::default());
    assert_zero(&report, &[]);
    assert_eq!(report.score, 0.0);
}
