//! A homework method that never returns costs its item, and only its item, once the per-check
//! time limit passes; grading goes on and finishes. The grader abandons the looping thread; the
//! loop here ends only when the test releases it after the grade is complete (the grader cannot
//! tell it from an endless one), so that the abandoned thread does not spin through every other
//! test of the binary.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use springlab::grade::{
    Body, ClothHomework, DVec3, ItemStatus, Options, Physics, Reference, Spring, SpringSetup,
    State, grade_cloth,
};

/// The reference with an RK4 that loops until [`RELEASED`] (a `while` whose condition the
/// homework never changes).
struct Looping;

/// Set by the test once `grade_cloth` has returned: the abandoned loop ends.
static RELEASED: AtomicBool = AtomicBool::new(false);

/// Releases the loop when dropped, so that a failing assertion releases it too.
struct Release;

impl Drop for Release {
    fn drop(&mut self) {
        RELEASED.store(true, Ordering::Relaxed);
    }
}

impl ClothHomework for Looping {
    fn springs(&self, n: usize) -> Vec<SpringSetup> {
        ClothHomework::springs(&Reference, n)
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, k: f64, l: f64) -> DVec3 {
        ClothHomework::spring_force(&Reference, xa, xb, k, l)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
        ClothHomework::damper_force(&Reference, xa, xb, va, vb, kd)
    }

    fn spring_accelerations(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        w: &[f64],
        s: &[Spring],
    ) -> Vec<DVec3> {
        Reference.spring_accelerations(x, v, w, s)
    }

    fn sphere_collision(&self, sphere: &mut Body, radius: f64, p: &mut Body, e: f64) {
        Reference.sphere_collision(sphere, radius, p, e);
    }

    fn explicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        ClothHomework::explicit_euler(&Reference, s, dt, physics);
    }

    fn implicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        ClothHomework::implicit_euler(&Reference, s, dt, physics);
    }

    fn midpoint(&self, s: &mut State, dt: f64, physics: &Physics) {
        ClothHomework::midpoint(&Reference, s, dt, physics);
    }

    fn rk4(&self, s: &mut State, _dt: f64, _physics: &Physics) {
        let mut t = 0.0;
        let end = 1.0;
        while t < end && !RELEASED.load(Ordering::Relaxed) {
            // The step is never added to t.
            std::hint::black_box(&mut s.x);
            t += 0.0;
        }
    }
}

#[test]
fn an_endless_loop_times_out_and_scores_zero_for_its_item_only() {
    let options = Options {
        time_limit: Duration::from_millis(200),
        ..Options::default()
    };
    let start = Instant::now();
    let release = Release;
    let report = grade_cloth(Looping, &options);
    drop(release);
    print!("{}", report.table());
    for item in &report.items {
        if item.id == "rk4" {
            assert_eq!(item.status, ItemStatus::TimedOut);
            assert_eq!(item.score, 0.0);
            let reason = item.reason.as_deref().unwrap_or_default();
            assert!(reason.contains("did not finish within 200 ms"), "{reason}");
            let case = &item.checks[0].feedback.as_ref().expect("feedback").input;
            assert!(
                case.starts_with("one step of dt = 0.01 s"),
                "the case is reported: {case}"
            );
        } else {
            assert_eq!(item.status, ItemStatus::Full, "{}", item.label());
        }
    }
    assert_eq!(report.score, 65.0);
    // One check timed out and the item's other checks were skipped, not run into the same loop.
    assert!(
        start.elapsed() < Duration::from_secs(30),
        "{:?}",
        start.elapsed()
    );
}
