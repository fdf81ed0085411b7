//! Colliders and collision response, each checked against an independent truth: geometry by
//! hand, bounce heights from restitution (h' = e² h), sliding from Newton's law with Coulomb
//! friction, momentum and the law of restitution for impulses, and energy that never rises.

use glam::DVec3;
use springlab::physics::collide::{
    self, Collider, ContactParams, DynamicSphere, after_step, step_spheres,
};
use springlab::physics::particles::pin_particle;
use springlab::physics::{Method, MethodParams, Model, State, Workspace, energy};
use springlab::scene::{Body, Scene};
use springlab::simulation::Simulation;

const G: DVec3 = DVec3::new(0.0, -9.8, 0.0);

/// Free particles of 1 kg (no springs, no drag) under gravity with `colliders`.
fn particles(
    x: Vec<DVec3>,
    v: Vec<DVec3>,
    colliders: Vec<Collider>,
    params: ContactParams,
) -> (Model, State) {
    let n = x.len();
    let model = Model::new(vec![1.0; n], &vec![false; n], Vec::new(), G, 0.0)
        .with_colliders(colliders, params);
    (model, State::new(x, v))
}

/// One step of `method` followed by the collision hook, as `Simulation::step` does it.
fn step(method: Method, model: &Model, state: &mut State, dt: f64, work: &mut Workspace) {
    method.step(model, state, dt, &MethodParams::default(), work);
    after_step(model, state, dt);
}

/// `steps` steps of semi-implicit Euler at dt = 1 ms with the collision hook, calling `each`
/// after every step.
fn run(model: &Model, state: &mut State, steps: usize, mut each: impl FnMut(&State)) {
    let mut work = Workspace::new();
    for _ in 0..steps {
        step(Method::SemiImplicitEuler, model, state, 1e-3, &mut work);
        each(state);
    }
}

/// Frictionless contact with restitution `e`.
fn frictionless(e: f64) -> ContactParams {
    ContactParams {
        restitution: e,
        friction: 0.0,
        ..ContactParams::default()
    }
}

/// A small deterministic generator (SplitMix64) for reproducible "random" starts.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }

    /// A vector with components in `[-r, r]`.
    fn cube(&mut self, r: f64) -> DVec3 {
        DVec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }
}

// ---------------------------------------------------------------- geometry

#[test]
fn signed_distances_and_normals_match_hand_computation() {
    let c = Collider::course_2021_plane().contact(DVec3::new(3.0, 0.5, -2.0));
    assert_eq!(c.map(|c| (c.phi, c.normal)), Some((1.5, DVec3::Y)));

    // Tilted plane through the origin, normal (1,1,0)/√2: the point (1,1,0) is √2 above it.
    let c = Collider::course_2021_tilted_plane()
        .contact(DVec3::new(1.0, 1.0, 0.0))
        .unwrap();
    assert!((c.phi - 2f64.sqrt()).abs() < 1e-15);
    assert!((c.normal - DVec3::new(1.0, 1.0, 0.0) / 2f64.sqrt()).length() < 1e-15);

    // Sphere r 3 at (0,-1,0): (0,4,0) is 2 m outside, normal up.
    let c = Collider::course_2021_sphere()
        .contact(DVec3::new(0.0, 4.0, 0.0))
        .unwrap();
    assert_eq!((c.phi, c.normal), (2.0, DVec3::Y));

    // Bowl r 7 at (2,7,1): its bottom (2,0,1) is on the surface with the normal up; 1 m above
    // the bottom is 1 m inside; above the rim (y > 7) the bowl is not there.
    let bowl = Collider::course_2021_bowl();
    let c = bowl.contact(DVec3::new(2.0, 0.0, 1.0)).unwrap();
    assert_eq!((c.phi, c.normal), (0.0, DVec3::Y));
    assert_eq!(bowl.contact(DVec3::new(2.0, 1.0, 1.0)).unwrap().phi, 1.0);
    assert_eq!(bowl.contact(DVec3::new(2.0, 7.5, 1.0)), None);
    // Below the rim but outside the rim circle (13 m from the axis): not there either.
    assert_eq!(bowl.contact(DVec3::new(15.0, 3.0, 1.0)), None);
}

#[test]
fn course_2023_bowl_meets_the_floor_at_the_edge_of_the_hole() {
    let terrain = Collider::course_2023_terrain();
    let (floor, bowl) = (terrain[0], terrain[1]);
    let a = 9.0 / 2f64.sqrt();
    // A point on the hole's edge is on both surfaces: the sphere of radius 9 at height a
    // crosses y = 0 at horizontal radius √(81 - a²) = a.
    let edge = DVec3::new(2.0 + a, 0.0, 1.0);
    assert!(bowl.contact(edge).unwrap().phi.abs() < 1e-12);
    // Over the hole the floor is not there; over the floor it is a plane.
    assert_eq!(floor.contact(DVec3::new(2.0, 1.0, 1.0)), None);
    let c = floor.contact(DVec3::new(2.0 + a + 1.0, 0.25, 1.0)).unwrap();
    assert_eq!((c.phi, c.normal), (0.25, DVec3::Y));
    // Under the floor, 0.1 m beside the shaft and 1 m deep: nearer to the shaft wall.
    let c = floor.contact(DVec3::new(2.0 + a + 0.1, -1.0, 1.0)).unwrap();
    assert!((c.phi + 0.1).abs() < 1e-12);
    assert!((c.normal - DVec3::NEG_X).length() < 1e-12);
}

// ---------------------------------------------------------------- plane, every method

/// Drops a particle from 1 m onto the plane y = 0 and checks, for every method, that it never
/// ends a step below the plane and that the first rebound reaches e² of the drop height.
#[test]
fn dropped_particle_stays_above_the_plane_and_rebounds_to_e_squared() {
    let e: f64 = 0.8;
    let h = 1.0;
    for method in Method::ALL {
        let (model, mut state) = particles(
            vec![DVec3::new(0.0, h, 0.0)],
            vec![DVec3::ZERO],
            vec![Collider::plane(DVec3::ZERO, DVec3::Y)],
            frictionless(e),
        );
        let mut work = Workspace::new();
        let mut bounces = 0;
        let mut rebound = 0.0f64;
        let mut was_rising = false;
        for _ in 0..2500 {
            step(method, &model, &mut state, 1e-3, &mut work);
            let (y, vy) = (state.x[0].y, state.v[0].y);
            assert!(y >= 0.0, "{method}: below the plane at y = {y}");
            let rising = vy > 0.0;
            if rising && !was_rising {
                bounces += 1;
            }
            if bounces == 1 {
                rebound = rebound.max(y);
            }
            was_rising = rising;
        }
        assert!(bounces >= 2, "{method}: only {bounces} bounces");
        // The response happens within ε = 0.01 m of the plane and the integrators err by
        // O(dt): 0.02 m on 0.64 m.
        assert!(
            (rebound - e * e * h).abs() < 0.02,
            "{method}: rebound {rebound}, expected {}",
            e * e * h
        );
    }
}

/// The same drop through `Simulation`, which must call the collision hook itself.
#[test]
fn simulation_step_resolves_collisions() {
    let (model, state) = particles(
        vec![DVec3::new(0.0, 1.0, 0.0)],
        vec![DVec3::ZERO],
        vec![Collider::plane(DVec3::ZERO, DVec3::Y)],
        ContactParams::default(),
    );
    let scene = Scene {
        name: "drop".to_string(),
        bodies: vec![Body {
            label: "particle".to_string(),
            model,
            state,
            method: Method::SemiImplicitEuler,
            params: MethodParams::default(),
        }],
        dt: 1e-3,
        duration: 5.0,
    };
    let mut sim = Simulation::new(scene);
    // Bounces from 1 m with e = 0.8 last √(2h/g) (1 + 2e/(1 - e)) = 4.07 s in all.
    sim.run(5000, |s| {
        let y = s.positions().next().unwrap().y;
        assert!(y >= 0.0, "below the plane at t = {}", s.time());
    });
    assert!(sim.diverged.is_none());
    // After 5 s it rests within the contact band.
    let p = sim.positions().next().unwrap();
    let v = sim.velocities().next().unwrap();
    assert!(p.y < 0.01 && v.length() < 1e-3, "not at rest: {p}, {v}");
}

#[test]
fn fast_particle_does_not_tunnel_through_a_plane() {
    // 10 m/s at dt = 0.01 s moves 0.1 m per step, ten times the contact band.
    for method in Method::ALL {
        let params = ContactParams {
            epsilon: 0.01,
            ..ContactParams::default()
        };
        let (model, mut state) = particles(
            vec![DVec3::new(0.0, 0.05, 0.0)],
            vec![DVec3::new(0.0, -10.0, 0.0)],
            vec![Collider::plane(DVec3::ZERO, DVec3::Y)],
            params,
        );
        let mut work = Workspace::new();
        for _ in 0..50 {
            step(method, &model, &mut state, 0.01, &mut work);
            assert!(state.x[0].y >= 0.0, "{method}: tunnelled to {}", state.x[0]);
        }
        // The same for the floor of the 2023 terrain, over its solid part.
        let (model, mut state) = particles(
            vec![DVec3::new(12.0, 0.05, 1.0)],
            vec![DVec3::new(0.0, -10.0, 0.0)],
            Collider::course_2023_terrain(),
            params,
        );
        for _ in 0..50 {
            step(method, &model, &mut state, 0.01, &mut work);
            assert!(state.x[0].y >= 0.0, "{method}: tunnelled to {}", state.x[0]);
        }
    }
}

// ---------------------------------------------------------------- energy

/// Random starts near each collider: (position, velocity).
fn random_starts(collider: &str, rng: &mut Rng, n: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut x = Vec::new();
    let mut v = Vec::new();
    for _ in 0..n {
        let p = match collider {
            "plane" => DVec3::new(rng.range(-1.0, 1.0), rng.range(0.05, 2.0), 0.0),
            "tilted" => {
                // A point of the plane x + y = 0 lifted along the normal.
                let s = rng.range(-2.0, 2.0);
                DVec3::new(s, -s, rng.range(-1.0, 1.0))
                    + rng.range(0.05, 2.0) * DVec3::new(1.0, 1.0, 0.0) / 2f64.sqrt()
            }
            "sphere" => {
                let d = (rng.cube(1.0) + DVec3::new(0.0, 1.5, 0.0)).normalize();
                DVec3::new(0.0, -1.0, 0.0) + rng.range(3.05, 5.0) * d
            }
            "bowl" => {
                let mut d = rng.cube(1.0).normalize();
                d.y = -d.y.abs();
                DVec3::new(2.0, 7.0, 1.0) + rng.range(0.0, 6.9) * d
            }
            _ => DVec3::new(
                rng.range(-6.0, 10.0),
                rng.range(0.05, 3.0),
                rng.range(-6.0, 8.0),
            ),
        };
        x.push(p);
        v.push(rng.cube(5.0));
    }
    (x, v)
}

fn collider_set(name: &str) -> Vec<Collider> {
    match name {
        "plane" => vec![Collider::plane(DVec3::ZERO, DVec3::Y)],
        "tilted" => vec![Collider::course_2021_tilted_plane()],
        "sphere" => vec![Collider::course_2021_sphere()],
        "bowl" => vec![Collider::course_2021_bowl()],
        _ => Collider::course_2023_terrain(),
    }
}

/// With e ≤ 1 and no friction a collision can only remove energy. For every method and
/// collider, the collision hook never leaves the energy above what it was before the step or
/// after the integrator's part of it (the hook may give back what an integrator lost by letting
/// a particle sink, never more); with semi-implicit Euler, which itself never gains energy under
/// gravity, the energy falls or stays at every whole step.
#[test]
fn collisions_never_add_energy() {
    let mut rng = Rng(2021);
    for name in ["plane", "tilted", "sphere", "bowl", "hole-plane"] {
        for e in [1.0, 0.8] {
            for method in Method::ALL {
                let (x, v) = random_starts(name, &mut rng, 20);
                let (model, mut state) = particles(x, v, collider_set(name), frictionless(e));
                let mut work = Workspace::new();
                let mut contacts = 0;
                for n in 0..2000 {
                    let before = energy(&model, &state).total;
                    method.step(
                        &model,
                        &mut state,
                        1e-3,
                        &MethodParams::default(),
                        &mut work,
                    );
                    let integrated = energy(&model, &state).total;
                    let v_before = state.v.clone();
                    after_step(&model, &mut state, 1e-3);
                    contacts += usize::from(v_before != state.v);
                    let after = energy(&model, &state).total;
                    let tol = 1e-9 * (1.0 + before.abs());
                    assert!(
                        after <= before.max(integrated) + tol,
                        "{name}, e = {e}, {method}, step {n}: {before} -> {integrated} -> {after}"
                    );
                    if method == Method::SemiImplicitEuler {
                        assert!(
                            after <= before + tol,
                            "{name}, e = {e}, step {n}: {before} -> {after}"
                        );
                    }
                }
                assert!(contacts > 0, "{name}, {method}: no collision happened");
            }
        }
    }
}

// ---------------------------------------------------------------- friction

#[test]
fn sliding_particle_slows_down_and_stops_where_coulomb_says() {
    // On y = 0 at 3 m/s with k_f = 0.3: deceleration k_f g, so it stops after
    // t = v / (k_f g) = 1.02 s, having slid d = v² / (2 k_f g) = 1.53 m.
    let (v0, mu, g) = (3.0, 0.3, 9.8);
    let (model, mut state) = particles(
        vec![DVec3::ZERO],
        vec![DVec3::new(v0, 0.0, 0.0)],
        vec![Collider::plane(DVec3::ZERO, DVec3::Y)],
        ContactParams::course_2021(),
    );
    let mut speed = v0;
    run(&model, &mut state, 2000, |state| {
        let s = state.v[0].length();
        assert!(s <= speed + 1e-12, "friction sped it up: {speed} -> {s}");
        speed = s;
    });
    let expected = v0 * v0 / (2.0 * mu * g);
    assert!(speed < 1e-6, "still moving at {speed} m/s");
    assert!(
        (state.x[0].x - expected).abs() < 0.01,
        "slid {} m, expected {expected}",
        state.x[0].x
    );
    assert!(state.x[0].y.abs() < 0.01);
}

/// On the 45° tilted plane friction 0.3 < tan 45° = 1 cannot hold a particle: it slides with
/// acceleration g (sin 45° - k_f cos 45°); friction 1.2 > 1 holds it.
#[test]
fn tilted_plane_holds_a_particle_only_when_friction_exceeds_the_slope() {
    let g = 9.8;
    let t = 1.0;
    for (mu, expected) in [
        (0.3, 0.5 * g * (0.5f64.sqrt() - 0.3 * 0.5f64.sqrt()) * t * t),
        (1.2, 0.0),
    ] {
        let params = ContactParams {
            friction: mu,
            ..ContactParams::course_2021()
        };
        let (model, mut state) = particles(
            vec![DVec3::ZERO],
            vec![DVec3::ZERO],
            vec![Collider::course_2021_tilted_plane()],
            params,
        );
        run(&model, &mut state, 1000, |_| {});
        let slid = state.x[0].length();
        assert!(
            (slid - expected).abs() < 0.01 * expected.max(0.1),
            "k_f = {mu}: slid {slid} m, expected {expected}"
        );
    }
}

// ---------------------------------------------------------------- 2023 hole and bowl

#[test]
fn particle_over_the_hole_falls_into_the_bowl_and_stays_there() {
    let a = 9.0 / 2f64.sqrt();
    let center = DVec3::new(2.0, a, 1.0);
    let (model, mut state) = particles(
        vec![DVec3::new(4.0, 0.5, 1.0)],
        vec![DVec3::ZERO],
        Collider::course_2023_terrain(),
        ContactParams::course_2023(),
    );
    let mut fell_in = false;
    run(&model, &mut state, 10_000, |state| {
        let x = state.x[0];
        fell_in |= x.y < 0.0;
        if fell_in {
            assert!((x - center).length() <= 9.0 + 1e-9, "left the bowl: {x}");
            assert!(x.y <= 0.0, "above the rim: {x}");
        }
    });
    // It comes to rest where static friction can hold it: the bowl's slope at angle θ from the
    // bottom is tan θ, so within θ ≤ atan k_f of the bottom (1.77 m sideways for k_f = 0.2).
    assert!(fell_in);
    let (x, v) = (state.x[0], state.v[0]);
    let from_axis = (x - center).with_y(0.0).length();
    let theta = (from_axis / 9.0).asin();
    assert!(v.length() < 1e-6, "still moving at {v}");
    assert!(
        theta.tan() <= 0.2 + 1e-3,
        "held on a slope of {theta} rad at {x}"
    );
}

#[test]
fn particle_over_the_floor_rests_on_it() {
    let (model, mut state) = particles(
        vec![DVec3::new(12.0, 1.0, 1.0)],
        vec![DVec3::ZERO],
        Collider::course_2023_terrain(),
        ContactParams::course_2023(),
    );
    run(&model, &mut state, 4000, |state| {
        assert!(state.x[0].y >= 0.0);
    });
    let (x, v) = (state.x[0], state.v[0]);
    assert!(x.y < 0.01 && v.length() < 1e-6, "not resting: {x}, {v}");
    assert!((x.x - 12.0).abs() < 1e-9 && (x.z - 1.0).abs() < 1e-9);
}

// ---------------------------------------------------------------- dynamic spheres

fn weightless(spheres: Vec<DynamicSphere>, x: Vec<DVec3>, v: Vec<DVec3>) -> (Model, State) {
    let n = x.len();
    let model = Model::new(vec![1.0; n], &vec![false; n], Vec::new(), DVec3::ZERO, 0.0);
    (model, State::new(x, v).with_spheres(spheres))
}

fn momentum(model: &Model, state: &State) -> DVec3 {
    let particles: DVec3 = model.mass.iter().zip(&state.v).map(|(&m, &v)| m * v).sum();
    let spheres: DVec3 = state.spheres.iter().map(|s| s.mass * s.velocity).sum();
    particles + spheres
}

#[test]
fn sphere_particle_impulse_conserves_momentum_and_stops_the_approach() {
    // Sphere (125 kg) moving at 1 m/s into a particle at rest that it overlaps, off-axis.
    let mut sphere = DynamicSphere::new(DVec3::ZERO, 0.5);
    sphere.velocity = DVec3::new(1.0, 0.0, 0.0);
    let (model, mut state) = weightless(
        vec![sphere],
        vec![DVec3::new(0.4, 0.2, 0.0)],
        vec![DVec3::new(-0.5, 0.0, 0.3)],
    );
    let p0 = momentum(&model, &state);
    let e0 = energy(&model, &state).total;
    step_spheres(&model, &mut state, 0.0);
    let p1 = momentum(&model, &state);
    assert!((p1 - p0).length() < 1e-12, "momentum {p0} -> {p1}");
    // e = 0: no relative velocity along the line of centres afterwards.
    let s = state.spheres[0];
    let d = (state.x[0] - s.center).normalize();
    assert!((state.v[0] - s.velocity).dot(d).abs() < 1e-12);
    // Separated: the particle is on the surface.
    assert!(((state.x[0] - s.center).length() - 0.5).abs() < 1e-12);
    assert!(energy(&model, &state).total < e0);
}

#[test]
fn sphere_sphere_impulse_follows_restitution_and_loses_energy() {
    let mut a = DynamicSphere::new(DVec3::ZERO, 0.5);
    let mut b = DynamicSphere::new(DVec3::new(0.85, 0.1, 0.0), 0.4);
    a.velocity = DVec3::new(2.0, 0.0, 0.0);
    b.velocity = DVec3::new(-1.0, 0.5, 0.0);
    let (model, mut state) = weightless(vec![a, b], Vec::new(), Vec::new());
    let d = (b.center - a.center).normalize();
    let approach = (b.velocity - a.velocity).dot(d);
    let p0 = momentum(&model, &state);
    let e0 = energy(&model, &state).total;
    step_spheres(&model, &mut state, 0.0);
    let [a1, b1] = [state.spheres[0], state.spheres[1]];
    assert!((momentum(&model, &state) - p0).length() < 1e-12);
    // Newton's law of restitution along the line of centres: v_rel' = -0.8 v_rel.
    let separation = (b1.velocity - a1.velocity).dot(d);
    assert!((separation + 0.8 * approach).abs() < 1e-12);
    // Kinetic energy lost: ½ μ (1 - e²) v_rel², μ = m_a m_b / (m_a + m_b).
    let mu = a.mass * b.mass / (a.mass + b.mass);
    let lost = 0.5 * mu * (1.0 - 0.64) * approach * approach;
    let e1 = energy(&model, &state).total;
    assert!(
        (e0 - e1 - lost).abs() < 1e-9 * e0,
        "lost {}, expected {lost}",
        e0 - e1
    );
    assert!(((b1.center - a1.center).length() - 0.9).abs() < 1e-12);
}

#[test]
fn kinematic_sphere_pushes_particles_and_is_not_moved() {
    let velocity = DVec3::new(1.0, 0.0, 0.0);
    let sphere = DynamicSphere::kinematic(DVec3::ZERO, 1.0, velocity);
    let mut rng = Rng(2024);
    let x: Vec<DVec3> = (0..50).map(|_| rng.cube(1.2)).collect();
    let v: Vec<DVec3> = (0..50).map(|_| rng.cube(2.0)).collect();
    let (model, mut state) = weightless(vec![sphere], x, v);
    let dt = 0.01;
    step_spheres(&model, &mut state, dt);
    let s = state.spheres[0];
    assert_eq!(s.center, dt * velocity);
    assert_eq!(s.velocity, velocity);
    for (x, v) in state.x.iter().zip(&state.v) {
        let d = *x - s.center;
        assert!(d.length() >= 1.0 - 1e-12, "particle left inside at {x}");
        // e = 0: no particle that was hit still approaches the sphere's centre.
        if (d.length() - 1.0).abs() < 1e-12 {
            assert!((*v - velocity).dot(d) >= -1e-12);
        }
    }
}

#[test]
fn falling_sphere_rests_on_the_ground() {
    let model = Model::new(Vec::new(), &[], Vec::new(), G, 0.0).with_colliders(
        vec![Collider::plane(DVec3::ZERO, DVec3::Y)],
        ContactParams::default(),
    );
    let mut state = State::new(Vec::new(), Vec::new())
        .with_spheres(vec![DynamicSphere::new(DVec3::new(0.0, 2.0, 0.0), 0.5)]);
    run(&model, &mut state, 5000, |state| {
        assert!(state.spheres[0].center.y >= 0.5);
    });
    assert!((state.spheres[0].center.y - 0.5).abs() < 0.01);
}

// ---------------------------------------------------------------- pinning, no colliders

#[test]
fn pinned_particle_stays_put_under_every_method() {
    for method in Method::ALL {
        let (mut model, mut state) = particles(
            vec![DVec3::new(0.0, 1.0, 0.0), DVec3::new(1.0, 1.0, 0.0)],
            vec![DVec3::new(1.0, 2.0, 3.0); 2],
            vec![Collider::plane(DVec3::ZERO, DVec3::Y)],
            ContactParams::default(),
        );
        let mut work = Workspace::new();
        step(method, &model, &mut state, 1e-3, &mut work);
        let here = state.x[0];
        assert!(pin_particle(&mut model, &mut state, 0));
        assert!(!pin_particle(&mut model, &mut state, 2));
        assert_eq!(state.v[0], DVec3::ZERO);
        for _ in 0..100 {
            step(method, &model, &mut state, 1e-3, &mut work);
        }
        assert_eq!(state.x[0], here, "{method}: the pinned particle moved");
    }
}

#[test]
fn without_colliders_or_spheres_the_hook_changes_nothing() {
    let (model, state) = {
        let m = Model::new(vec![1.0], &[false], Vec::new(), G, 0.0);
        (
            m,
            State::new(vec![DVec3::new(0.0, -5.0, 0.0)], vec![DVec3::X]),
        )
    };
    let mut a = state.clone();
    let mut b = state;
    let mut work = Workspace::new();
    for _ in 0..10 {
        Method::Verlet.step(&model, &mut a, 1e-3, &MethodParams::default(), &mut work);
        step(Method::Verlet, &model, &mut b, 1e-3, &mut work);
    }
    assert_eq!(a, b);
    // And the contact force is zero without colliders.
    let mut f = vec![DVec3::ZERO];
    collide::contact_forces(&model, &a.x, &a.v, &mut f);
    assert_eq!(f[0], DVec3::ZERO);
}

/// A 3×3×3 spring cube (course K = 2000, D = 60) dropped on every course terrain: under every
/// method no particle ever ends a step inside a collider, and nothing diverges.
#[test]
fn spring_cube_lands_on_every_terrain_under_every_method() {
    use springlab::SpringKind;
    use springlab::physics::diverge;
    use springlab::scene::builder::Builder;
    let terrains = [
        (
            vec![Collider::course_2021_plane()],
            DVec3::new(0.0, 0.0, 0.0),
        ),
        (
            vec![Collider::course_2021_tilted_plane()],
            DVec3::new(0.0, 2.0, 0.0),
        ),
        (
            vec![Collider::course_2021_sphere()],
            DVec3::new(-0.5, 2.5, -0.5),
        ),
        (
            vec![Collider::course_2021_bowl()],
            DVec3::new(0.0, 9.0, 0.0),
        ),
        (Collider::course_2023_terrain(), DVec3::new(-4.8, 7.0, 0.0)),
    ];
    for (colliders, offset) in terrains {
        for method in Method::ALL {
            let mut b = Builder::new();
            let n = 3i32;
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        let p = DVec3::new(f64::from(i), f64::from(j), f64::from(k));
                        b.particle(offset + 0.5 * p, 1.0);
                    }
                }
            }
            // Every pair within the 3×3×3 block around a particle, each once.
            for p in 0..n * n * n {
                for q in p + 1..n * n * n {
                    let (a, c) = ([p / 9, p / 3 % 3, p % 3], [q / 9, q / 3 % 3, q % 3]);
                    if (0..3).all(|d| (a[d] - c[d]).abs() <= 1) {
                        b.spring(p as u32, q as u32, 2000.0, 60.0, SpringKind::Struct);
                    }
                }
            }
            let (model, mut state) = b.build(G, 0.0);
            let model = model.with_colliders(colliders.clone(), ContactParams::default());
            let mut work = Workspace::new();
            for s in 0..2000 {
                step(method, &model, &mut state, 1e-3, &mut work);
                assert!(
                    diverge::check(&state, s, 0.0).is_none(),
                    "{method} diverged"
                );
                for x in &state.x {
                    for c in &colliders {
                        let phi = c.contact(*x).map_or(0.0, |c| c.phi);
                        assert!(phi >= -1e-12, "{method}: inside {c:?} at {x}");
                    }
                }
            }
        }
    }
}

#[test]
fn the_energy_change_of_a_response_is_the_difference_of_the_energies() {
    use springlab::physics::collide::{
        Changes, advance_spheres, collide_spheres_logged, resolve_logged,
    };
    use springlab::physics::energy::{energy, energy_change};
    use springlab::simulation::Simulation;
    for (name, method, steps) in [
        ("cloth-spheres", springlab::Method::SemiImplicitEuler, 8_000),
        ("jelly-bowl", springlab::Method::SemiImplicitEuler, 4_000),
        ("cube-tilted", springlab::Method::SemiImplicitEuler, 3_000),
    ] {
        let mut scene = springlab::scene::load(name, &[]).expect("built-in");
        scene.set_method(method);
        let mut sim = Simulation::new(scene);
        let mut checked = 0;
        for _ in 0..steps / 20 {
            sim.run(20, |_| {});
            let body = &sim.scene.bodies[0];
            let (model, mut state) = (&body.model, body.state.clone());
            // One more step's integration, then the response measured both ways.
            let mut work = springlab::physics::Workspace::new();
            body.method
                .step(model, &mut state, sim.dt(), &body.params, &mut work);
            advance_spheres(model, &mut state, sim.dt());
            let before = energy(model, &state).total;
            let mut changes = Changes::default();
            collide_spheres_logged(model, &mut state, sim.dt(), Some(&mut changes));
            resolve_logged(model, &mut state, sim.dt(), Some(&mut changes));
            changes.finish(model.particle_count());
            let exact = energy(model, &state).total - before;
            let fast = energy_change(model, &state, &changes);
            let scale = energy(model, &state).kinetic.abs() + before.abs() + 1.0;
            assert!(
                (exact - fast).abs() <= 1e-11 * scale,
                "{name}: {fast} J vs {exact} J"
            );
            if exact != 0.0 {
                checked += 1;
            }
        }
        assert!(
            checked > 5,
            "{name}: only {checked} responses changed the energy"
        );
    }
}

/// The energy change of a response as its formula reads (`physics::energy::energy_change`'s
/// module docs): every recorded particle's kinetic and gravitational terms, then every spring at
/// it once, each with both ends as they were, summed in the same order, without leaving out
/// the springs that did not move.
fn energy_change_in_full(
    model: &Model,
    state: &State,
    changes: &springlab::physics::collide::Changes,
) -> f64 {
    let record = |j: usize| {
        changes
            .particles
            .binary_search_by_key(&(j as u32), |p| p.0)
            .ok()
            .map(|k| changes.particles[k])
    };
    let (x, v) = (&state.x, &state.v);
    let before = |j: usize| record(j).map_or(x[j], |c| c.1);
    let mut delta = 0.0;
    for &(i, x_old, v_old) in &changes.particles {
        let i = i as usize;
        let m = model.mass[i];
        delta += 0.5 * m * (v[i].length_squared() - v_old.length_squared());
        delta -= m * model.gravity.dot(x[i] - x_old);
        for &k in model.springs_at(i) {
            let s = &model.springs()[k as usize];
            let (a, b) = (s.a as usize, s.b as usize);
            let other = if a == i { b } else { a };
            if other < i && record(other).is_some() {
                continue;
            }
            delta += s.energy(x) - s.energy_between(before(a), before(b));
        }
    }
    let spheres: f64 = (state.spheres.iter().filter(|s| !s.kinematic))
        .map(|s| 0.5 * s.mass * s.velocity.length_squared() - s.mass * model.gravity.dot(s.center))
        .sum();
    delta + spheres - changes.spheres_before()
}

#[test]
fn the_energy_change_leaves_out_only_springs_that_did_not_move() {
    // The shortcut (springs whose two ends stayed are not summed) against the full sum, bit for
    // bit: along runs where responses move a few particles and pay from all (cloth-spheres,
    // jelly-bowl), and with one particle far away, infinite or NaN (no shortcut then).
    use springlab::physics::collide::{
        Changes, advance_spheres, collide_spheres_logged, resolve_logged,
    };
    use springlab::physics::energy::energy_change;
    let mut compared = 0;
    let mut paid = 0;
    for (name, steps) in [("cloth-spheres", 6_000), ("jelly-bowl", 3_000)] {
        let mut scene = springlab::scene::load(name, &[]).expect("built-in");
        scene.set_method(Method::SemiImplicitEuler);
        let mut sim = Simulation::new(scene);
        for round in 0..steps / 20 {
            sim.run(20, |_| {});
            let body = &sim.scene.bodies[0];
            let model = &body.model;
            let far = [None, Some(1e60), Some(f64::INFINITY), Some(f64::NAN)][round % 4];
            let mut state = body.state.clone();
            let mut work = Workspace::new();
            body.method
                .step(model, &mut state, sim.dt(), &body.params, &mut work);
            advance_spheres(model, &mut state, sim.dt());
            let mut changes = Changes::default();
            collide_spheres_logged(model, &mut state, sim.dt(), Some(&mut changes));
            resolve_logged(model, &mut state, sim.dt(), Some(&mut changes));
            changes.finish(model.particle_count());
            if let Some(far) = far {
                // A particle no response recorded, where a spring's energy is not finite.
                let i = (0..state.x.len()).rev().find(|&i| {
                    changes
                        .particles
                        .binary_search_by_key(&(i as u32), |p| p.0)
                        .is_err()
                });
                if let Some(i) = i {
                    state.x[i].y = far;
                }
            }
            let fast = energy_change(model, &state, &changes);
            let full = energy_change_in_full(model, &state, &changes);
            assert!(
                fast.to_bits() == full.to_bits() || (fast.is_nan() && full.is_nan()),
                "{name}, round {round}: {fast} J vs {full} J"
            );
            compared += 1;
            paid += usize::from(changes.particles.len() * 2 > state.x.len() && far.is_none());
        }
    }
    // Responses that paid from the whole body (most records only slowed) were among them.
    assert!(
        paid > 5,
        "{paid} of {compared} responses paid from the body"
    );
}
