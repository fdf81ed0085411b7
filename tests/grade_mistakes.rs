//! Typical student mistakes, planted in otherwise correct homework (the reference with one
//! method changed): each loses points in exactly the item it belongs to, and the report says why.

// Index loops read like the formulas of the planted mistakes (x_i, v_i, a_i).
#![allow(clippy::needless_range_loop)]

use springlab::grade::{
    Body, Bowl, ClothHomework, ContactCoefficients, DVec3, ItemStatus, JellyHomework, Options,
    Particle, Physics, Plane, Reference, Report, Rope, RopeHomework, Spring, SpringSetup, State,
    grade_cloth, grade_jelly, grade_rope,
};

/// Asserts that exactly the items in `lost` lose points (each to at most `max_left` of its
/// maximum, as a fraction) and that every other item gets full marks.
fn assert_loses(report: &Report, lost: &[&str], max_left: f64) {
    print!("{}", report.table());
    for item in &report.items {
        if lost.contains(&item.id.as_str()) {
            assert!(
                item.score <= max_left * item.max_score && item.score < item.max_score,
                "{} should lose points, got {} / {}",
                item.label(),
                item.score,
                item.max_score
            );
            assert!(
                item.feedback_text().contains("expected") || item.reason.is_some(),
                "{} explains itself",
                item.label()
            );
        } else {
            assert_eq!(
                item.status,
                ItemStatus::Full,
                "{} should be untouched\n{}",
                item.label(),
                item.feedback_text()
            );
        }
    }
}

fn item<'a>(report: &'a Report, id: &str) -> &'a springlab::grade::ItemReport {
    report
        .items
        .iter()
        .find(|i| i.id == id)
        .unwrap_or_else(|| panic!("no item {id}"))
}

// ---------------------------------------------------------------------------------------------
// Jelly

#[derive(Clone, Copy, PartialEq)]
enum JellyMistake {
    FlippedSpring,
    FullRelativeVelocityDamper,
    Rk4WithoutK1,
    ExplicitWithNewVelocity,
    ImplicitIsPredictorCorrector,
    MidpointPanics,
    Rk4ReturnsNaN,
    /// The collision handlers without the bounce: projection and contact force are right.
    NoBounce,
    /// A midpoint step that returns NaN below dt = 0.01 s (only the order check goes there).
    MidpointNaNAtSmallSteps,
}

struct Jelly(JellyMistake);

impl JellyHomework for Jelly {
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup> {
        JellyHomework::springs(&Reference, counts)
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, k: f64, l: f64) -> DVec3 {
        let f = JellyHomework::spring_force(&Reference, xa, xb, k, l);
        if self.0 == JellyMistake::FlippedSpring {
            // Direction from a to b instead of b to a.
            -f
        } else {
            f
        }
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
        if self.0 == JellyMistake::FullRelativeVelocityDamper {
            // The whole relative velocity, not its component along the spring.
            -kd * (va - vb)
        } else {
            JellyHomework::damper_force(&Reference, xa, xb, va, vb, kd)
        }
    }

    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3> {
        // Correct accumulation of this homework's own pair forces.
        let mut f = vec![DVec3::ZERO; x.len()];
        for s in springs {
            let fa = self.spring_force(x[s.a], x[s.b], s.stiffness, s.rest_length)
                + self.damper_force(x[s.a], x[s.b], v[s.a], v[s.b], s.damping);
            f[s.a] += fa;
            f[s.b] -= fa;
        }
        f
    }

    fn plane_collision(&self, plane: &Plane, p: &mut Particle, c: &ContactCoefficients) {
        let v = p.v;
        Reference.plane_collision(plane, p, c);
        if self.0 == JellyMistake::NoBounce {
            // Position and force as the reference; the velocity as it came in.
            p.v = v;
        }
    }

    fn bowl_collision(&self, bowl: &Bowl, p: &mut Particle, c: &ContactCoefficients) {
        let v = p.v;
        Reference.bowl_collision(bowl, p, c);
        if self.0 == JellyMistake::NoBounce {
            p.v = v;
        }
    }

    fn explicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        if self.0 == JellyMistake::ExplicitWithNewVelocity {
            let a = physics.accelerations(&s.x, &s.v);
            for i in 0..s.x.len() {
                s.v[i] += dt * a[i];
                // The position with the NEW velocity: this is semi-implicit Euler.
                s.x[i] += dt * s.v[i];
            }
        } else {
            JellyHomework::explicit_euler(&Reference, s, dt, physics);
        }
    }

    fn implicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        if self.0 == JellyMistake::ImplicitIsPredictorCorrector {
            // The course's "implicit Euler": predict with explicit Euler, evaluate there once,
            // step from the old state.
            let a = physics.accelerations(&s.x, &s.v);
            let xp: Vec<DVec3> = (0..s.x.len()).map(|i| s.x[i] + dt * s.v[i]).collect();
            let vp: Vec<DVec3> = (0..s.x.len()).map(|i| s.v[i] + dt * a[i]).collect();
            let ap = physics.accelerations(&xp, &vp);
            for i in 0..s.x.len() {
                s.x[i] += dt * vp[i];
                s.v[i] += dt * ap[i];
            }
        } else {
            JellyHomework::implicit_euler(&Reference, s, dt, physics);
        }
    }

    fn midpoint(&self, s: &mut State, dt: f64, physics: &Physics) {
        if self.0 == JellyMistake::MidpointPanics {
            // Off by one: reads one particle past the end.
            let n = s.x.len();
            let _ = s.x[n];
        }
        JellyHomework::midpoint(&Reference, s, dt, physics);
        if self.0 == JellyMistake::MidpointNaNAtSmallSteps && dt < 0.01 {
            s.x[0] = DVec3::NAN;
        }
    }

    fn rk4(&self, s: &mut State, dt: f64, physics: &Physics) {
        match self.0 {
            JellyMistake::Rk4WithoutK1 => {
                // Seed 003's RK4: k1 is left out of the position update.
                let n = s.x.len();
                let (x, v) = (s.x.clone(), s.v.clone());
                let k1v = physics.accelerations(&x, &v);
                let k1x = v.clone();
                let stage = |kx: &[DVec3], kv: &[DVec3], h: f64| {
                    let xs: Vec<DVec3> = (0..n).map(|i| x[i] + h * kx[i]).collect();
                    let vs: Vec<DVec3> = (0..n).map(|i| v[i] + h * kv[i]).collect();
                    (vs.clone(), physics.accelerations(&xs, &vs))
                };
                let (k2x, k2v) = stage(&k1x, &k1v, 0.5 * dt);
                let (k3x, k3v) = stage(&k2x, &k2v, 0.5 * dt);
                let (k4x, k4v) = stage(&k3x, &k3v, dt);
                for i in 0..n {
                    s.x[i] = x[i] + dt / 6.0 * (2.0 * k2x[i] + 2.0 * k3x[i] + k4x[i]);
                    s.v[i] = v[i] + dt / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
                }
            }
            JellyMistake::Rk4ReturnsNaN => {
                JellyHomework::rk4(&Reference, s, dt, physics);
                // A zero-length normalisation somewhere.
                s.v[0] = DVec3::ZERO.normalize();
            }
            _ => JellyHomework::rk4(&Reference, s, dt, physics),
        }
    }
}

#[test]
fn a_missing_bounce_costs_the_bounce_checks_only() {
    let report = grade_jelly(Jelly(JellyMistake::NoBounce), &Options::default());
    // Bounce is 4 of each obstacle's 10; projection (3) and contact force (3) compare x' and
    // force', which the bounce does not change.
    for id in ["plane", "bowl"] {
        let it = item(&report, id);
        assert_eq!(it.score, 6.0, "{}", it.feedback_text());
        let failed: Vec<&str> = it
            .checks
            .iter()
            .filter(|c| c.score < c.max_score)
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(failed.len(), 1, "{failed:?}");
        assert!(failed[0].starts_with("bounce"), "{failed:?}");
        assert!(
            it.feedback_text().contains("v did not change"),
            "{}",
            it.feedback_text()
        );
    }
    assert_eq!(report.score, 72.0, "{}", report.table());
}

#[test]
fn a_check_that_fails_late_keeps_the_items_passed_checks() {
    let report = grade_jelly(
        Jelly(JellyMistake::MidpointNaNAtSmallSteps),
        &Options::default(),
    );
    let midpoint = item(&report, "midpoint");
    // One step (1) and 100 oscillator steps (0.5) at dt = 0.01 s pass; the order check, at
    // smaller steps, gets NaN.
    assert_eq!(midpoint.score, 1.5, "{}", midpoint.feedback_text());
    assert_eq!(midpoint.status, ItemStatus::NotFinite);
    assert_eq!(report.score, 79.0);
}

#[test]
fn a_flipped_spring_loses_the_spring_force_only() {
    let report = grade_jelly(Jelly(JellyMistake::FlippedSpring), &Options::default());
    assert_loses(&report, &["spring_force"], 0.0);
    let feedback = item(&report, "spring_force").feedback_text();
    assert!(feedback.contains("opposite sign"), "{feedback}");
}

#[test]
fn a_damper_on_the_full_relative_velocity_loses_the_damper_force_only() {
    let report = grade_jelly(
        Jelly(JellyMistake::FullRelativeVelocityDamper),
        &Options::default(),
    );
    assert_loses(&report, &["damper_force"], 0.0);
    assert!(
        item(&report, "damper_force")
            .feedback_text()
            .contains("along the spring")
    );
}

#[test]
fn rk4_without_k1_in_the_position_loses_rk4_only() {
    let report = grade_jelly(Jelly(JellyMistake::Rk4WithoutK1), &Options::default());
    assert_loses(&report, &["rk4"], 0.0);
    assert!(item(&report, "rk4").feedback_text().contains("order"));
}

#[test]
fn explicit_euler_with_the_new_velocity_loses_explicit_euler_only() {
    let report = grade_jelly(
        Jelly(JellyMistake::ExplicitWithNewVelocity),
        &Options::default(),
    );
    // Semi-implicit Euler is first order too: the measured order still passes.
    assert_loses(&report, &["explicit"], 0.2);
    assert!(
        item(&report, "explicit")
            .feedback_text()
            .contains("OLD velocity")
    );
}

#[test]
fn the_courses_predictor_corrector_is_not_implicit_euler() {
    let report = grade_jelly(
        Jelly(JellyMistake::ImplicitIsPredictorCorrector),
        &Options::default(),
    );
    assert_loses(&report, &["implicit"], 0.0);
    let feedback = item(&report, "implicit").feedback_text();
    assert!(feedback.contains("predictor"), "{feedback}");
}

#[test]
fn a_panicking_integrator_scores_zero_for_its_item_only() {
    let report = grade_jelly(Jelly(JellyMistake::MidpointPanics), &Options::default());
    assert_loses(&report, &["midpoint"], 0.0);
    let midpoint = item(&report, "midpoint");
    assert_eq!(midpoint.status, ItemStatus::Panicked);
    let reason = midpoint.reason.as_deref().unwrap_or_default();
    assert!(
        reason.contains("panicked") && reason.contains("index out of bounds"),
        "{reason}"
    );
    assert!(
        reason.contains("grade_mistakes.rs"),
        "the location is reported: {reason}"
    );
}

#[test]
fn an_integrator_returning_nan_scores_zero_for_its_item_only() {
    let report = grade_jelly(Jelly(JellyMistake::Rk4ReturnsNaN), &Options::default());
    assert_loses(&report, &["rk4"], 0.0);
    let rk4 = item(&report, "rk4");
    assert_eq!(rk4.status, ItemStatus::NotFinite);
    assert!(
        rk4.feedback_text().contains("NaN"),
        "{}",
        rk4.feedback_text()
    );
}

// ---------------------------------------------------------------------------------------------
// Rope

#[derive(Clone, Copy, PartialEq)]
enum RopeMistake {
    VerletWithoutDamping,
    PinnedNodeMovesInProjection,
    EveryNodePinned,
}

struct RopeStudent(RopeMistake);

impl RopeHomework for RopeStudent {
    fn rope(&self, start: DVec3, end: DVec3, n: usize, m: f64, k: f64, pinned: &[usize]) -> Rope {
        let mut rope = Reference.rope(start, end, n, m, k, pinned);
        if self.0 == RopeMistake::EveryNodePinned {
            for mass in &mut rope.masses {
                mass.pinned = true;
            }
        }
        rope
    }

    fn spring_force(&self, a: DVec3, b: DVec3, k: f64, l: f64) -> DVec3 {
        RopeHomework::spring_force(&Reference, a, b, k, l)
    }

    fn spring_forces(&self, rope: &Rope) -> Vec<DVec3> {
        Reference.spring_forces(rope)
    }

    fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        RopeHomework::explicit_euler(&Reference, rope, dt, physics);
    }

    fn semi_implicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        Reference.semi_implicit_euler(rope, dt, physics);
    }

    fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics) {
        match self.0 {
            RopeMistake::VerletWithoutDamping => Reference.verlet(rope, dt, 0.0, physics),
            RopeMistake::PinnedNodeMovesInProjection => {
                let a = physics.accelerations_of(rope);
                for (m, a) in rope.masses.iter_mut().zip(a) {
                    let x = m.position;
                    m.position = x + (1.0 - damping) * (x - m.last_position) + a * dt * dt;
                    m.last_position = x;
                }
                for s in rope.springs.clone() {
                    let d = rope.masses[s.b].position - rope.masses[s.a].position;
                    let correction = d * ((d.length() - s.rest_length) / d.length());
                    // Half each, pinned or not.
                    rope.masses[s.a].position += 0.5 * correction;
                    rope.masses[s.b].position -= 0.5 * correction;
                }
            }
            RopeMistake::EveryNodePinned => Reference.verlet(rope, dt, damping, physics),
        }
    }
}

#[test]
fn verlet_without_damping_loses_the_damping_item_only() {
    let report = grade_rope(
        RopeStudent(RopeMistake::VerletWithoutDamping),
        &Options::default(),
    );
    assert_loses(&report, &["damping"], 0.0);
}

#[test]
fn a_pinned_node_that_moves_loses_verlet_points() {
    let report = grade_rope(
        RopeStudent(RopeMistake::PinnedNodeMovesInProjection),
        &Options::default(),
    );
    assert_loses(&report, &["verlet"], 0.6);
    assert!(item(&report, "verlet").feedback_text().contains("pinned"));
}

#[test]
fn pinning_every_node_loses_rope_construction_points() {
    let report = grade_rope(
        RopeStudent(RopeMistake::EveryNodePinned),
        &Options::default(),
    );
    assert_loses(&report, &["rope"], 0.8);
    assert!(item(&report, "rope").feedback_text().contains("pinned"));
}

// ---------------------------------------------------------------------------------------------
// Cloth: the two mistakes of seed 003

#[derive(Clone, Copy, PartialEq)]
enum ClothMistake {
    /// `if (radius + 0.01 < distance)`: collides when far apart.
    SphereTestReversed,
    /// `position += deltaTime * acceleration`.
    ExplicitAddsAcceleration,
}

struct Cloth(ClothMistake);

impl ClothHomework for Cloth {
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
        if self.0 == ClothMistake::SphereTestReversed {
            let d = p.x - sphere.x;
            if radius + 0.01 < d.length() {
                let n = d.normalize();
                let v_rel = (p.v - sphere.v).dot(n);
                if v_rel < 0.0 {
                    let j = -(1.0 + e) * v_rel / (sphere.inverse_mass + p.inverse_mass);
                    sphere.v -= sphere.inverse_mass * j * n;
                    p.v += p.inverse_mass * j * n;
                }
            }
        } else {
            Reference.sphere_collision(sphere, radius, p, e);
        }
    }

    fn explicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        if self.0 == ClothMistake::ExplicitAddsAcceleration {
            let a = physics.accelerations(&s.x, &s.v);
            for i in 0..s.x.len() {
                s.x[i] += dt * a[i];
                s.v[i] += dt * a[i];
            }
        } else {
            ClothHomework::explicit_euler(&Reference, s, dt, physics);
        }
    }

    fn implicit_euler(&self, s: &mut State, dt: f64, physics: &Physics) {
        ClothHomework::implicit_euler(&Reference, s, dt, physics);
    }

    fn midpoint(&self, s: &mut State, dt: f64, physics: &Physics) {
        ClothHomework::midpoint(&Reference, s, dt, physics);
    }

    fn rk4(&self, s: &mut State, dt: f64, physics: &Physics) {
        ClothHomework::rk4(&Reference, s, dt, physics);
    }
}

#[test]
fn a_sphere_test_that_collides_when_far_apart_loses_the_collision_item() {
    let report = grade_cloth(Cloth(ClothMistake::SphereTestReversed), &Options::default());
    assert_loses(&report, &["sphere"], 0.2);
}

#[test]
fn explicit_euler_adding_acceleration_to_position_loses_explicit_euler() {
    let report = grade_cloth(
        Cloth(ClothMistake::ExplicitAddsAcceleration),
        &Options::default(),
    );
    assert_loses(&report, &["explicit"], 0.0);
    // The hint says what the step did: the errors stay the same size as dt shrinks, and the
    // position moved by dt·a.
    let feedback = item(&report, "explicit").feedback_text();
    assert!(!feedback.contains("not advanced"), "{feedback}");
    assert!(
        feedback.contains("moved by dt·a(t), the acceleration"),
        "{feedback}"
    );
    assert!(feedback.contains("error stays the same size"), "{feedback}");
}
