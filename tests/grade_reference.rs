//! The reference implementation, graded through the same library calls a student crate's
//! `tests/grade.rs` makes, gets full marks on every assignment; its Gradescope `results.json`
//! has the fields the autograder specification asks for.

use springlab::grade::{
    Assignment, CheckOutcome, ItemStatus, Options, Reference, Report, grade_cloth, grade_jelly,
    grade_rope,
};

fn assert_full(report: &Report) {
    print!("{}", report.table());
    for item in &report.items {
        assert_eq!(
            item.status,
            ItemStatus::Full,
            "{}: {}\n{}",
            report.assignment,
            item.label(),
            item.feedback_text()
        );
        assert!(
            item.checks
                .iter()
                .all(|c| c.outcome == CheckOutcome::Passed)
        );
    }
    assert_eq!(report.score, report.max_score);
}

#[test]
fn reference_gets_full_marks_on_the_rope() {
    let report = grade_rope(Reference, &Options::default());
    assert_full(&report);
    assert_eq!(report.max_score, 35.0);
    assert_eq!(report.course_max_score, 35.0);
    assert_eq!(report.items.len(), 6);
}

#[test]
fn reference_gets_full_marks_on_the_jelly() {
    let report = grade_jelly(Reference, &Options::default());
    assert_full(&report);
    assert_eq!(report.max_score, 80.0);
    assert_eq!(report.course_max_score, 100.0);
    assert!(
        report.scope().contains("the report (20) is graded by hand"),
        "{}",
        report.scope()
    );
}

#[test]
fn reference_gets_full_marks_on_the_cloth() {
    let report = grade_cloth(Reference, &Options::default());
    assert_full(&report);
    assert_eq!(report.max_score, 80.0);
    assert_eq!(report.course_max_score, 100.0);
}

#[test]
fn grading_is_deterministic_and_other_seeds_also_pass() {
    for assignment in Assignment::ALL {
        let a = assignment.grade_reference(&Options::default());
        let b = assignment.grade_reference(&Options::default());
        assert_eq!(a.items, b.items);
        let other = assignment.grade_reference(&Options {
            seed: 12345,
            ..Options::default()
        });
        assert_full(&other);
    }
}
