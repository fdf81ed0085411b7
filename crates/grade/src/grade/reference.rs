//! The reference solution: every homework trait implemented with springlab's own physics.
//!
//! Nothing here repeats a formula: the rope comes from [`crate::scene::builder::rope`], lattices
//! from [`crate::scene::lattice`], forces from [`crate::physics::Spring::force_on_a`] and
//! [`crate::physics::forces`], collisions from [`crate::physics::collide`], and every integrator
//! step from [`Method::step`] on the model inside the [`Physics`] it is given. The grader compares
//! a student's answers with these.
//!
//! Two settings make springlab's general code the course's textbook case:
//! - collisions use a resting speed of 0 (every approach bounces) and no gravity in the
//!   one-particle model, so the response is exactly `v' = -k_r v_N + v_T` plus the projection onto
//!   the surface; the impact friction of the response is switched off (friction acts through the
//!   contact force only, as in the course);
//! - the sphere–particle impulse is springlab's sphere step over a time step of zero length, which
//!   leaves only the impulse and the separation.

use glam::DVec3;

use super::assignments::{
    Body, Bowl, ClothHomework, ContactCoefficients, JellyHomework, Particle, Plane, Rope,
    RopeHomework, Spring, SpringSetup, State,
};
use super::system::Physics;
use crate::physics::collide::{
    Collider, ContactParams, DynamicSphere, contact_forces, resolve, step_spheres,
};
use crate::physics::{self, Method, MethodParams, Model, SpringKind, Workspace};
use crate::scene::builder::{Builder, RopeSpec, rope};
use crate::scene::lattice::{ClothSpec, CubeSpec, KindCoefficients, cloth, cube};

/// springlab's answers to every homework (see the module documentation).
#[derive(Clone, Copy, Debug, Default)]
pub struct Reference;

/// A springlab state at `x` moving at `v`.
fn sim_state(x: Vec<DVec3>, v: Vec<DVec3>) -> physics::State {
    physics::State::new(x, v)
}

/// One step of `method` on `physics`' model, for a state given as slices; `None` when the state
/// does not fit the model (the grader never does that).
fn step_xv(
    method: Method,
    physics: &Physics,
    x: &[DVec3],
    v: &[DVec3],
    x_prev: Option<&[DVec3]>,
    dt: f64,
    params: &MethodParams,
) -> Option<physics::State> {
    let n = physics.particle_count();
    if x.len() != n || v.len() != n || x_prev.is_some_and(|p| p.len() != n) {
        return None;
    }
    let mut state = sim_state(x.to_vec(), v.to_vec());
    if let Some(prev) = x_prev {
        state.x_prev = prev.to_vec();
        state.history_valid = true;
    }
    // The explicit methods' workspace is scratch only, written before it is read: one per
    // thread serves every step (the live comparison takes thousands a second). The others keep
    // something between steps (Verlet's rods, implicit Euler's contact set): a fresh one each.
    let scratch_only = matches!(
        method,
        Method::ExplicitEuler | Method::SemiImplicitEuler | Method::Midpoint | Method::Rk4
    );
    if scratch_only {
        SCRATCH.with(|w| method.step(physics.model(), &mut state, dt, params, &mut w.borrow_mut()));
    } else {
        method.step(
            physics.model(),
            &mut state,
            dt,
            params,
            &mut Workspace::new(),
        );
    }
    Some(state)
}

thread_local! {
    /// The explicit methods' workspace (see [`step_xv`]).
    static SCRATCH: std::cell::RefCell<Workspace> = std::cell::RefCell::new(Workspace::new());
}

fn step_state(method: Method, state: &mut State, dt: f64, physics: &Physics) {
    if let Some(next) = step_xv(
        method,
        physics,
        &state.x,
        &state.v,
        None,
        dt,
        &MethodParams::default(),
    ) {
        state.x = next.x;
        state.v = next.v;
    }
}

fn step_rope(method: Method, rope: &mut Rope, dt: f64, params: &MethodParams, physics: &Physics) {
    let x: Vec<DVec3> = rope.masses.iter().map(|m| m.position).collect();
    let v: Vec<DVec3> = rope.masses.iter().map(|m| m.velocity).collect();
    let prev: Vec<DVec3> = rope.masses.iter().map(|m| m.last_position).collect();
    let x_prev = (method == Method::Verlet).then_some(prev.as_slice());
    if let Some(next) = step_xv(method, physics, &x, &v, x_prev, dt, params) {
        for (i, m) in rope.masses.iter_mut().enumerate() {
            m.position = next.x[i];
            m.velocity = next.v[i];
            if method == Method::Verlet {
                m.last_position = next.x_prev[i];
            }
        }
    }
}

/// A springlab spring between particles 0 and 1.
fn pair_spring(stiffness: f64, rest_length: f64, damping: f64) -> physics::Spring {
    physics::Spring {
        a: 0,
        b: 1,
        rest_length,
        stiffness,
        damping,
        kind: SpringKind::Struct,
    }
}

/// A springlab model of `springs` between particles of the given masses (kg; a non-positive or
/// non-finite mass pins the particle), no gravity, no drag. `None` for an index out of range.
pub(crate) fn model_of(masses: &[f64], pinned: &[bool], springs: &[Spring]) -> Option<Model> {
    let n = masses.len();
    let mut list = Vec::with_capacity(springs.len());
    for s in springs {
        if s.a >= n || s.b >= n || n > u32::MAX as usize {
            return None;
        }
        list.push(physics::Spring {
            a: s.a as u32,
            b: s.b as u32,
            rest_length: s.rest_length,
            stiffness: s.stiffness,
            damping: s.damping,
            kind: SpringKind::Struct,
        });
    }
    let (mass, pin): (Vec<f64>, Vec<bool>) = masses
        .iter()
        .zip(pinned)
        .map(|(&m, &p)| {
            if m.is_finite() && m > 0.0 {
                (m, p)
            } else {
                (1.0, true)
            }
        })
        .unzip();
    Some(Model::new(mass, &pin, list, DVec3::ZERO, 0.0))
}

/// Net spring and damper force (N) on every particle of `model` at `(x, v)`.
fn spring_forces_of(model: &Model, x: &[DVec3], v: &[DVec3]) -> Vec<DVec3> {
    let mut f = vec![DVec3::ZERO; model.particle_count()];
    physics::forces(model, x, v, &mut f);
    f
}

/// A one-particle model against `collider` with the course's contact rules (module docs);
/// `friction` is the Coulomb coefficient of the contact force.
fn contact_model(collider: Collider, c: &ContactCoefficients, friction: f64) -> Model {
    let params = ContactParams {
        restitution: c.restitution,
        friction,
        epsilon: c.epsilon,
        rest_speed: 0.0,
        ..ContactParams::default()
    };
    Model::new(vec![1.0], &[false], Vec::new(), DVec3::ZERO, 0.0)
        .with_colliders(vec![collider], params)
}

/// Contact force, then velocity response and projection, of one particle against `collider`.
fn collide_particle(collider: Collider, p: &mut Particle, c: &ContactCoefficients) {
    // Contact force and friction from the state before the response.
    let mut f = [p.force];
    contact_forces(
        &contact_model(collider, c, c.friction),
        &[p.x],
        &[p.v],
        &mut f,
    );
    // Bounce and projection, with the impact friction off.
    let mut state = sim_state(vec![p.x], vec![p.v]);
    resolve(&contact_model(collider, c, 0.0), &mut state, 0.0);
    p.x = state.x[0];
    p.v = state.v[0];
    p.force = f[0];
}

fn lattice_setup(springs: &[physics::Spring], first: u32) -> Vec<SpringSetup> {
    springs
        .iter()
        .map(|s| SpringSetup {
            a: (s.a - first) as usize,
            b: (s.b - first) as usize,
            kind: s.kind,
        })
        .collect()
}

fn damper(xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3 {
    // Zero stiffness leaves only the damper term of springlab's spring force.
    pair_spring(0.0, 0.0, damping).force_on_a(&[xa, xb], &[va, vb])
}

fn hooke(xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
    pair_spring(stiffness, rest_length, 0.0).force_on_a(&[xa, xb], &[DVec3::ZERO, DVec3::ZERO])
}

impl RopeHomework for Reference {
    /// [`crate::scene::builder::rope`]; an empty rope for `nodes < 2` or a pinned index out of
    /// range.
    fn rope(
        &self,
        start: DVec3,
        end: DVec3,
        nodes: usize,
        node_mass: f64,
        stiffness: f64,
        pinned: &[usize],
    ) -> Rope {
        if nodes < 2 || pinned.iter().any(|&p| p >= nodes) {
            return Rope::default();
        }
        let mut builder = Builder::new();
        rope(
            &mut builder,
            &RopeSpec {
                start,
                end,
                nodes,
                node_mass,
                stiffness,
                damping: 0.0,
                pinned: pinned.to_vec(),
            },
        );
        Rope::from_physics(
            &builder.x,
            &builder.v,
            |i| builder.mass[i],
            |i| builder.pinned[i],
            &builder.springs,
        )
    }

    fn spring_force(&self, a: DVec3, b: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        hooke(a, b, stiffness, rest_length)
    }

    fn spring_forces(&self, rope: &Rope) -> Vec<DVec3> {
        let masses: Vec<f64> = rope.masses.iter().map(|m| m.mass).collect();
        let pinned: Vec<bool> = rope.masses.iter().map(|m| m.pinned).collect();
        let x: Vec<DVec3> = rope.masses.iter().map(|m| m.position).collect();
        let v: Vec<DVec3> = rope.masses.iter().map(|m| m.velocity).collect();
        model_of(&masses, &pinned, &rope.springs)
            .map(|model| spring_forces_of(&model, &x, &v))
            .unwrap_or_default()
    }

    fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        step_rope(
            Method::ExplicitEuler,
            rope,
            dt,
            &MethodParams::default(),
            physics,
        );
    }

    fn semi_implicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        step_rope(
            Method::SemiImplicitEuler,
            rope,
            dt,
            &MethodParams::default(),
            physics,
        );
    }

    fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics) {
        let params = MethodParams {
            verlet_damping: damping,
            iterations: 1,
            ..MethodParams::default()
        };
        step_rope(Method::Verlet, rope, dt, &params, physics);
    }
}

/// Every spring of the cube lattice `counts`, from [`crate::scene::lattice::cube`].
fn cube_setup(counts: [usize; 3]) -> Vec<SpringSetup> {
    let spec = CubeSpec {
        counts,
        edge_length: DVec3::ONE,
        coefficients: KindCoefficients::uniform(1.0, 0.0),
        offset: DVec3::ZERO,
        ..CubeSpec::default()
    };
    if spec.validate().is_err() {
        return Vec::new();
    }
    let mut builder = Builder::new();
    let first = cube(&mut builder, &spec);
    lattice_setup(&builder.springs, first)
}

/// Every spring of the `n × n` cloth, from [`crate::scene::lattice::cloth`].
fn cloth_setup(n: usize) -> Vec<SpringSetup> {
    let spec = ClothSpec {
        n,
        pinned: Vec::new(),
        ..ClothSpec::course_2022()
    };
    if spec.validate().is_err() {
        return Vec::new();
    }
    let mut builder = Builder::new();
    let first = cloth(&mut builder, &spec);
    lattice_setup(&builder.springs, first)
}

impl JellyHomework for Reference {
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup> {
        cube_setup(counts)
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        hooke(xa, xb, stiffness, rest_length)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3 {
        damper(xa, xb, va, vb, damping)
    }

    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3> {
        if x.len() != v.len() {
            return Vec::new();
        }
        let masses = vec![1.0; x.len()];
        let pinned = vec![false; x.len()];
        model_of(&masses, &pinned, springs)
            .map(|model| spring_forces_of(&model, x, v))
            .unwrap_or_default()
    }

    fn plane_collision(&self, plane: &Plane, particle: &mut Particle, c: &ContactCoefficients) {
        collide_particle(Collider::plane(plane.point, plane.normal), particle, c);
    }

    fn bowl_collision(&self, bowl: &Bowl, particle: &mut Particle, c: &ContactCoefficients) {
        collide_particle(
            Collider::bowl(bowl.center, bowl.radius, bowl.rim_height),
            particle,
            c,
        );
    }

    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::ExplicitEuler, state, dt, physics);
    }

    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::ImplicitEuler, state, dt, physics);
    }

    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::Midpoint, state, dt, physics);
    }

    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::Rk4, state, dt, physics);
    }
}

impl ClothHomework for Reference {
    fn springs(&self, n: usize) -> Vec<SpringSetup> {
        cloth_setup(n)
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        hooke(xa, xb, stiffness, rest_length)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3 {
        damper(xa, xb, va, vb, damping)
    }

    fn spring_accelerations(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        inverse_mass: &[f64],
        springs: &[Spring],
    ) -> Vec<DVec3> {
        if x.len() != v.len() || x.len() != inverse_mass.len() {
            return Vec::new();
        }
        // m = 1/w; w = 0 pins the particle (model_of pins a non-finite mass).
        let masses: Vec<f64> = inverse_mass.iter().map(|&w| 1.0 / w).collect();
        let pinned: Vec<bool> = inverse_mass.iter().map(|&w| w == 0.0).collect();
        let Some(model) = model_of(&masses, &pinned, springs) else {
            return Vec::new();
        };
        let mut a = vec![DVec3::ZERO; x.len()];
        physics::accelerations(&model, x, v, &mut a);
        a
    }

    fn sphere_collision(
        &self,
        sphere: &mut Body,
        radius: f64,
        particle: &mut Body,
        restitution: f64,
    ) {
        let params = ContactParams {
            sphere_particle_restitution: restitution,
            ..ContactParams::default()
        };
        let w = particle.inverse_mass;
        let (mass, pinned) = if w > 0.0 {
            (1.0 / w, false)
        } else {
            (1.0, true)
        };
        let mut model = Model::new(vec![mass], &[pinned], Vec::new(), DVec3::ZERO, 0.0);
        model.contact = params;
        let ball = if sphere.inverse_mass > 0.0 {
            DynamicSphere {
                center: sphere.x,
                velocity: sphere.v,
                radius,
                mass: 1.0 / sphere.inverse_mass,
                kinematic: false,
            }
        } else {
            DynamicSphere::kinematic(sphere.x, radius, sphere.v)
        };
        let mut state = sim_state(vec![particle.x], vec![particle.v]).with_spheres(vec![ball]);
        // A step of zero length: no motion, only the impulse and the separation.
        step_spheres(&model, &mut state, 0.0);
        sphere.x = state.spheres[0].center;
        sphere.v = state.spheres[0].velocity;
        particle.x = state.x[0];
        particle.v = state.v[0];
    }

    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::ExplicitEuler, state, dt, physics);
    }

    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::ImplicitEuler, state, dt, physics);
    }

    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::Midpoint, state, dt, physics);
    }

    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics) {
        step_state(Method::Rk4, state, dt, physics);
    }
}
