//! The homework traits answered by the program: every method of [`RopeHomework`],
//! [`JellyHomework`] and [`ClothHomework`] is one call through the [`Session`].

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glam::DVec3;
use springlab_homework as api;
use springlab_homework::wire::{Reader, Wire, WireError, decode, encode, method};

use super::super::assignments::{
    Body, Bowl, ClothHomework, ContactCoefficients, JellyHomework, Particle, Plane, Rope,
    RopeHomework, Spring, SpringSetup, State,
};
use super::super::runner;
use super::super::system::Physics;
use super::convert::*;
use super::{CallFailure, STEP_ANSWER, Session};

/// A student's program behind the homework traits: every method is a call to the program.
///
/// A call that gets no answer (module docs) unwinds with its [`CallFailure`] as the payload
/// (`std::panic::resume_unwind`, so no panic hook runs); the runner scores the check in progress
/// accordingly, and the next call starts a new program.
#[derive(Clone)]
pub struct Remote {
    session: Arc<Mutex<Session>>,
    /// Deadline of a call made outside a graded check.
    default_limit: Duration,
}

impl std::fmt::Debug for Remote {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Remote").finish_non_exhaustive()
    }
}

impl Remote {
    /// The homework served by `session`; calls outside a check get `default_limit`.
    #[must_use]
    pub fn new(session: Session, default_limit: Duration) -> Remote {
        Remote {
            session: Arc::new(Mutex::new(session)),
            default_limit,
        }
    }

    /// Programs started so far and bytes they printed.
    #[must_use]
    pub fn stats(&self) -> (u32, usize) {
        let s = self
            .session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        (s.starts, s.stray_bytes())
    }

    /// Stops the running program (the report is written after this).
    pub fn shut_down(&self) {
        self.session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .stop();
    }

    fn ask<A: Wire, R: Wire>(&self, m: u8, arguments: &A, physics: Option<&Physics>) -> R {
        let deadline =
            runner::check_deadline().unwrap_or_else(|| Instant::now() + self.default_limit);
        let answer = {
            let mut session = self
                .session
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            session.call(m, &encode(arguments), physics, deadline)
        };
        let value = answer.and_then(|bytes| {
            decode::<R>(&bytes).map_err(|e| CallFailure::Malformed(format!("unreadable: {e}")))
        });
        match value {
            Ok(v) => v,
            Err(failure) => std::panic::resume_unwind(Box::new(failure)),
        }
    }

    /// The assignment its program serves.
    #[must_use]
    pub fn assignment(&self) -> super::super::Assignment {
        self.session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .assignment
    }

    /// `count` steps of a rope integrator in one request (`wire`'s STEPS), each from the last
    /// one's answer, as `count` calls of the trait method would give them: the rope after each
    /// step that came, and why the rest did not (the step after the last one failed).
    /// `damping` is Verlet's γ (`None` for the Euler methods).
    pub fn rope_steps(
        &self,
        m: u8,
        rope: &Rope,
        dt: f64,
        damping: Option<f64>,
        p: &Physics,
        count: u32,
    ) -> (Vec<Rope>, Option<CallFailure>) {
        let w = Self::inverse_mass(p);
        let arguments = match damping {
            None => encode(&(api_rope(rope), dt, w)),
            Some(g) => encode(&(api_rope(rope), dt, g, w)),
        };
        self.ask_steps(m, count, &arguments, p, |bytes| {
            decode::<api::Rope>(bytes).map(|r| local_rope(&r))
        })
    }

    /// `count` steps of a state integrator in one request, as [`Remote::rope_steps`].
    pub fn state_steps(
        &self,
        m: u8,
        state: &State,
        dt: f64,
        p: &Physics,
        count: u32,
    ) -> (Vec<State>, Option<CallFailure>) {
        let arguments = encode(&(api_state(state), dt, Self::inverse_mass(p)));
        // The lists read straight into the grader's vectors.
        self.ask_steps(m, count, &arguments, p, |bytes| {
            let mut r = Reader::new(bytes);
            let state = State {
                x: take_vecs(&mut r)?,
                v: take_vecs(&mut r)?,
            };
            r.finish()?;
            Ok(state)
        })
    }

    fn ask_steps<R>(
        &self,
        m: u8,
        count: u32,
        arguments: &[u8],
        p: &Physics,
        read: impl Fn(&[u8]) -> Result<R, WireError>,
    ) -> (Vec<R>, Option<CallFailure>) {
        let (answers, done) = self
            .session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .steps(m, count, arguments, Some(p), self.default_limit);
        let mut values = Vec::with_capacity(answers.len());
        for bytes in &answers {
            match read(&bytes[STEP_ANSWER..]) {
                Ok(v) => values.push(v),
                Err(e) => {
                    self.shut_down();
                    return (
                        values,
                        Some(CallFailure::Malformed(format!("unreadable: {e}"))),
                    );
                }
            }
        }
        let failure = match done {
            Err(f) => Some(f),
            Ok(()) if values.len() != count as usize => {
                self.shut_down();
                Some(CallFailure::Malformed(format!(
                    "{} answers to {count} steps",
                    values.len()
                )))
            }
            Ok(()) => None,
        };
        (values, failure)
    }

    fn inverse_mass(physics: &Physics) -> Vec<f64> {
        physics.inverse_mass().to_vec()
    }

    fn rope_step(&self, m: u8, rope: &mut Rope, dt: f64, damping: Option<f64>, p: &Physics) {
        let w = Self::inverse_mass(p);
        let out: api::Rope = match damping {
            None => self.ask(m, &(api_rope(rope), dt, w), Some(p)),
            Some(g) => self.ask(m, &(api_rope(rope), dt, g, w), Some(p)),
        };
        *rope = local_rope(&out);
    }

    fn state_step(&self, m: u8, state: &mut State, dt: f64, p: &Physics) {
        let out: api::State = self.ask(m, &(api_state(state), dt, Self::inverse_mass(p)), Some(p));
        *state = local_state(out);
    }

    fn pair(&self, m: u8, a: DVec3, b: DVec3, k: f64, l: f64) -> DVec3 {
        local_vec(self.ask(m, &(api_vec(a), api_vec(b), k, l), None))
    }

    fn damper(&self, m: u8, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, kd: f64) -> DVec3 {
        let args = (api_vec(xa), api_vec(xb), api_vec(va), api_vec(vb), kd);
        local_vec(self.ask(m, &args, None))
    }
}

impl RopeHomework for Remote {
    fn rope(
        &self,
        start: DVec3,
        end: DVec3,
        nodes: usize,
        node_mass: f64,
        stiffness: f64,
        pinned: &[usize],
    ) -> Rope {
        let args = (
            api_vec(start),
            api_vec(end),
            nodes,
            node_mass,
            stiffness,
            pinned.to_vec(),
        );
        local_rope(&self.ask::<_, api::Rope>(method::ROPE_ROPE, &args, None))
    }

    fn spring_force(&self, a: DVec3, b: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        self.pair(method::ROPE_SPRING_FORCE, a, b, stiffness, rest_length)
    }

    fn spring_forces(&self, rope: &Rope) -> Vec<DVec3> {
        local_vecs(self.ask(method::ROPE_SPRING_FORCES, &api_rope(rope), None))
    }

    fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        self.rope_step(method::ROPE_EXPLICIT_EULER, rope, dt, None, physics);
    }

    fn semi_implicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {
        self.rope_step(method::ROPE_SEMI_IMPLICIT_EULER, rope, dt, None, physics);
    }

    fn verlet(&self, rope: &mut Rope, dt: f64, damping: f64, physics: &Physics) {
        self.rope_step(method::ROPE_VERLET, rope, dt, Some(damping), physics);
    }
}

impl JellyHomework for Remote {
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup> {
        let got: Vec<api::SpringSetup> = self.ask(method::JELLY_SPRINGS, &counts, None);
        got.iter().map(local_setup).collect()
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        self.pair(method::JELLY_SPRING_FORCE, xa, xb, stiffness, rest_length)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3 {
        self.damper(method::JELLY_DAMPER_FORCE, xa, xb, va, vb, damping)
    }

    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3> {
        let springs: Vec<api::Spring> = springs.iter().map(api_spring).collect();
        let args = (api_vecs(x), api_vecs(v), springs);
        local_vecs(self.ask(method::JELLY_INTERNAL_FORCES, &args, None))
    }

    fn plane_collision(&self, plane: &Plane, particle: &mut Particle, c: &ContactCoefficients) {
        let plane = api::Plane {
            point: api_vec(plane.point),
            normal: api_vec(plane.normal),
        };
        let args = (plane, api_particle(particle), api_contact(c));
        let out: api::Particle = self.ask(method::JELLY_PLANE_COLLISION, &args, None);
        *particle = local_particle(&out);
    }

    fn bowl_collision(&self, bowl: &Bowl, particle: &mut Particle, c: &ContactCoefficients) {
        let bowl = api::Bowl {
            center: api_vec(bowl.center),
            radius: bowl.radius,
            rim_height: bowl.rim_height,
        };
        let args = (bowl, api_particle(particle), api_contact(c));
        let out: api::Particle = self.ask(method::JELLY_BOWL_COLLISION, &args, None);
        *particle = local_particle(&out);
    }

    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_EXPLICIT_EULER, state, dt, physics);
    }

    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_IMPLICIT_EULER, state, dt, physics);
    }

    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_MIDPOINT, state, dt, physics);
    }

    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::JELLY_RK4, state, dt, physics);
    }
}

impl ClothHomework for Remote {
    fn springs(&self, n: usize) -> Vec<SpringSetup> {
        let got: Vec<api::SpringSetup> = self.ask(method::CLOTH_SPRINGS, &n, None);
        got.iter().map(local_setup).collect()
    }

    fn spring_force(&self, xa: DVec3, xb: DVec3, stiffness: f64, rest_length: f64) -> DVec3 {
        self.pair(method::CLOTH_SPRING_FORCE, xa, xb, stiffness, rest_length)
    }

    fn damper_force(&self, xa: DVec3, xb: DVec3, va: DVec3, vb: DVec3, damping: f64) -> DVec3 {
        self.damper(method::CLOTH_DAMPER_FORCE, xa, xb, va, vb, damping)
    }

    fn spring_accelerations(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        inverse_mass: &[f64],
        springs: &[Spring],
    ) -> Vec<DVec3> {
        let springs: Vec<api::Spring> = springs.iter().map(api_spring).collect();
        let args = (api_vecs(x), api_vecs(v), inverse_mass.to_vec(), springs);
        local_vecs(self.ask(method::CLOTH_SPRING_ACCELERATIONS, &args, None))
    }

    fn sphere_collision(
        &self,
        sphere: &mut Body,
        radius: f64,
        particle: &mut Body,
        restitution: f64,
    ) {
        let args = (api_body(sphere), radius, api_body(particle), restitution);
        let (s, p): (api::Body, api::Body) = self.ask(method::CLOTH_SPHERE_COLLISION, &args, None);
        *sphere = local_body(&s);
        *particle = local_body(&p);
    }

    fn explicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_EXPLICIT_EULER, state, dt, physics);
    }

    fn implicit_euler(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_IMPLICIT_EULER, state, dt, physics);
    }

    fn midpoint(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_MIDPOINT, state, dt, physics);
    }

    fn rk4(&self, state: &mut State, dt: f64, physics: &Physics) {
        self.state_step(method::CLOTH_RK4, state, dt, physics);
    }
}
