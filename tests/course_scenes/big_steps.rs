//! The course scenes at large time steps (implicit Euler, XPBD, the cloth at fifty times its
//! step) and the 2023 terrain's rim.

use super::*;

// ------------------------------------------------------------------ implicit methods, big steps

#[test]
fn implicit_euler_and_xpbd_keep_the_jelly_in_the_terrain() {
    for method in [Method::ImplicitEuler, Method::Xpbd] {
        // Ten times the course's step; a looser CG tolerance keeps the solve quick.
        let mut sim = simulation(
            "jelly-bowl",
            &["cg_tolerance=1e-6"],
            Some(method),
            Some(0.01),
        );
        let steps = steps_for(&sim, 2.5);
        run_outside(&mut sim, steps, |s| {
            assert_in_2023_terrain(method.name(), s.positions());
        });
        // It went through the hole.
        assert!(min_y(&sim) < -1.0, "{method}: {}", min_y(&sim));
        assert!(centroid(&sim).y < 2.0, "{method}: {}", centroid(&sim));
    }
}

/// The smallest distance of a cloth particle to a sphere's surface (m), negative inside.
fn cloth_clearance(sim: &Simulation) -> f64 {
    let state = &sim.scene.bodies[0].state;
    let mut clearance = f64::INFINITY;
    for s in &state.spheres {
        for x in &state.x {
            clearance = clearance.min((*x - s.center).length() - s.radius);
        }
    }
    clearance
}

#[test]
fn cloth_spheres_at_fifty_times_the_course_step() {
    // Explicit Euler blows up within a few steps at dt = 5 ms (the course needs 0.1 ms) ...
    let mut sim = simulation(
        "cloth-spheres",
        &[],
        Some(Method::ExplicitEuler),
        Some(0.005),
    );
    sim.run(200, |_| {});
    let d = sim.diverged.as_ref().expect("explicit Euler diverges");
    assert!(d.step < 50, "{d:?}");
    // ... while implicit Euler and XPBD carry the spheres into the cloth and hold them there.
    for method in [Method::ImplicitEuler, Method::Xpbd] {
        let mut sim = simulation("cloth-spheres", &[], Some(method), Some(0.005));
        let mut touched = false;
        for _ in 0..400 {
            sim.step();
            assert!(sim.diverged.is_none(), "{method}: {:?}", sim.diverged);
            let clearance = cloth_clearance(&sim);
            assert!(
                clearance >= -1e-9,
                "{method}: a particle {clearance} m inside a sphere"
            );
            touched |= clearance < 1e-3;
        }
        assert!(touched, "{method}: the spheres never reached the cloth");
        // The spheres sank with the cloth, which holds them: after 2 s they are below where the
        // cloth started (y = 0), and the cloth right under each of them is below its centre.
        let state = &sim.scene.bodies[0].state;
        for s in &state.spheres {
            assert!(s.center.y < 0.0, "{method}: {:?}", s.center);
            let under: Vec<&DVec3> = state
                .x
                .iter()
                .filter(|x| from_axis(**x, s.center.x, s.center.z) < 0.5 * s.radius)
                .collect();
            assert!(!under.is_empty());
            assert!(
                under.iter().all(|x| x.y < s.center.y),
                "{method}: a sphere went through the cloth"
            );
        }
        // Pinned corners did not move.
        for i in [0, 24, 600, 624] {
            assert_eq!(state.x[i].y, 0.0);
        }
    }
}

#[test]
fn cloth_sphere_moves_at_its_velocity_and_pushes_the_cloth() {
    let mut sim = simulation("cloth-sphere", &["sphere_velocity=[0,2,0]"], None, None);
    let steps = steps_for(&sim, 0.25);
    sim.run(steps, |s| {
        assert!(cloth_clearance(s) >= -1e-9, "a particle inside the sphere");
    });
    assert!(sim.diverged.is_none());
    let sphere = sim.scene.bodies[0].state.spheres[0];
    // Kinematic: exactly c = v t.
    assert!((sphere.center - DVec3::new(0.0, 0.5, 0.0)).length() < 1e-9);
    assert_eq!(sphere.velocity, DVec3::new(0.0, 2.0, 0.0));
    // The centre particle rides on top of the sphere (1.5 m), above where it started (1 m).
    let top = sim.scene.bodies[0].state.x[12 * 25 + 12];
    assert!(top.y >= 1.5 - 1e-9, "{top}");
    let report = serde_json::to_value(sim.report(0.0)).expect("json");
    assert_eq!(report["spheres"][0]["radius"], 1.0);
    assert_eq!(report["spheres"][0]["velocity"][1], 2.0);
}

#[test]
fn the_2023_terrain_has_no_gap_at_the_rim() {
    // A particle that crossed the floor just beside the hole, deeper under the floor (0.07 m)
    // than beside the shaft (0.02 m), leaves the solid through the shaft's wall, at ρ = a just
    // below the rim, where the bowl has already turned inwards: the bowl must take it back in.
    use springlab::physics::collide::resolve;
    use springlab::physics::{Model, State};
    let a = 9.0 / SQRT_2;
    let bowl = DVec3::new(2.0, a, 1.0);
    for k in 0..360 {
        let angle = f64::from(k).to_radians();
        let dir = DVec3::new(angle.cos(), 0.0, angle.sin());
        let x = DVec3::new(2.0, -0.07, 1.0) + (a + 0.02) * dir;
        let model = Model::new(
            vec![1.0],
            &[false],
            Vec::new(),
            DVec3::new(0.0, -G, 0.0),
            0.0,
        )
        .with_colliders(
            Collider::course_2023_terrain(),
            springlab::physics::collide::ContactParams::course_2023(),
        );
        let mut state = State::new(vec![x], vec![DVec3::new(0.0, -3.0, 0.0)]);
        resolve(&model, &mut state, 0.01);
        let y = state.x[0];
        assert!(
            (y - bowl).length() <= 9.0 + 1e-9,
            "{k}°: {x} → {y}, {} m outside the bowl",
            (y - bowl).length() - 9.0
        );
        assert!(from_axis(y, 2.0, 1.0) <= a + 1e-9);
    }
}
