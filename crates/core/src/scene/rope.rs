//! The GAMES101 rope scenes (`rope`, `ropes`) and the one-spring `oscillator`.
//!
//! GAMES101 assignment 8 works in pixels with gravity (0, -1) and a frame as the time unit; here
//! the rope is in SI units at 1 px = 1 cm: two ends 4 m apart at height 2 m, 1 kg nodes,
//! k = 100 N/m, g = 9.8 m/s², node 0 pinned, dt = 1/64 s (the course's 64 steps per frame).

use glam::DVec3;

use super::builder::{Builder, RopeSpec, rope};
use super::params::{
    ACCELERATION, DAMPING, DISPLACEMENT, LENGTH, MASS, MAX_LENGTH, ParamSpec, Params, Range,
    STIFFNESS,
};
use super::{Body, Scene, SceneError, method_param_specs, method_params};
use crate::physics::{Method, SpringKind};

/// Parameters of `oscillator`.
pub fn oscillator_params() -> Vec<ParamSpec> {
    let mut p = vec![
        ParamSpec::number("mass", "kg", 1.0, MASS, "mass of the moving particle"),
        ParamSpec::number("stiffness", "N/m", 100.0, STIFFNESS, "spring stiffness k"),
        ParamSpec::number("damping", "N·s/m", 0.0, DAMPING, "damper along the spring"),
        ParamSpec::number("rest_length", "m", 1.0, LENGTH, "spring rest length L0"),
        ParamSpec::number(
            "amplitude",
            "m",
            0.1,
            DISPLACEMENT,
            "initial stretch x(0) - L0",
        ),
    ];
    p.extend(method_param_specs(0.0, 0));
    p
}

/// `oscillator`: particle 0 pinned at the origin, particle 1 at `(L0 + amplitude, 0, 0)`, one
/// spring, no gravity. Exact solution `x(t) = L0 + amplitude · cos(ω t)`, `ω = √(k/m)`.
///
/// # Errors
/// None beyond parameter validation; kept fallible like every scene builder.
pub fn oscillator(params: &Params) -> Result<Scene, SceneError> {
    let mut b = Builder::new();
    let rest = params.number("rest_length");
    let p0 = b.particle(DVec3::ZERO, params.number("mass"));
    b.pinned[0] = true;
    let p1 = b.particle(DVec3::new(rest, 0.0, 0.0), params.number("mass"));
    b.spring(
        p0,
        p1,
        params.number("stiffness"),
        params.number("damping"),
        SpringKind::Struct,
    );
    // Stretch after the spring took its rest length from the initial distance.
    b.x[1].x = rest + params.number("amplitude");
    let (model, state) = b.build(DVec3::ZERO, 0.0);
    Ok(Scene {
        name: "oscillator".into(),
        bodies: vec![Body {
            label: "oscillator".into(),
            model,
            state,
            method: Method::Rk4,
            params: method_params(params),
        }],
        dt: 0.01,
        duration: 10.0,
    })
}

fn rope_specs(separation: bool) -> Vec<ParamSpec> {
    let mut p = vec![
        ParamSpec::integer(
            "nodes",
            3,
            Range::Between(2.0, 1_000_000.0),
            "number of nodes",
        ),
        ParamSpec::number("mass", "kg", 1.0, MASS, "mass of each node"),
        ParamSpec::number("stiffness", "N/m", 100.0, STIFFNESS, "spring stiffness k"),
        ParamSpec::number("damping", "N·s/m", 0.0, DAMPING, "damper along each spring"),
        ParamSpec::number("drag", "N·s/m", 0.0, DAMPING, "viscous drag on each node"),
        ParamSpec::number(
            "gravity",
            "m/s²",
            9.8,
            ACCELERATION,
            "downward gravitational acceleration",
        ),
        ParamSpec::vector("start", "m", DVec3::new(0.0, 2.0, 0.0), "first node"),
        ParamSpec::vector("end", "m", DVec3::new(-4.0, 2.0, 0.0), "last node"),
        ParamSpec::indices("pinned", vec![0], "pinned nodes"),
    ];
    if separation {
        p.push(ParamSpec::number(
            "separation",
            "m",
            9.0,
            Range::Between(0.0, MAX_LENGTH),
            "distance between the two ropes along x",
        ));
    }
    p.extend(method_param_specs(0.00005, 1));
    p
}

/// Particles and springs of the oscillator: two particles, one spring.
pub fn oscillator_size(_: &Params) -> (f64, f64) {
    (2.0, 1.0)
}

/// Particles and springs of `rope`, before it is built: `nodes` particles, `nodes - 1` springs.
pub fn rope_size(params: &Params) -> (f64, f64) {
    let n = params.integer("nodes") as f64;
    (n, n - 1.0)
}

/// Particles and springs of `ropes`: twice [`rope_size`].
pub fn ropes_size(params: &Params) -> (f64, f64) {
    let (n, s) = rope_size(params);
    (2.0 * n, 2.0 * s)
}

/// Parameters of `rope`.
pub fn rope_params() -> Vec<ParamSpec> {
    rope_specs(false)
}

/// Parameters of `ropes`.
pub fn ropes_params() -> Vec<ParamSpec> {
    rope_specs(true)
}

fn rope_body(
    params: &Params,
    offset: DVec3,
    method: Method,
    label: &str,
) -> Result<Body, SceneError> {
    let nodes = params.integer("nodes") as usize;
    let spec = RopeSpec {
        start: params.vector("start") + offset,
        end: params.vector("end") + offset,
        nodes,
        node_mass: params.number("mass"),
        stiffness: params.number("stiffness"),
        damping: params.number("damping"),
        pinned: params.indices("pinned", nodes)?,
    };
    if spec.start == spec.end {
        return Err(SceneError::Invalid(
            "`start` and `end` must differ: the rope has no length".into(),
        ));
    }
    let mut b = Builder::new();
    rope(&mut b, &spec);
    let gravity = DVec3::new(0.0, -params.number("gravity"), 0.0);
    let (model, state) = b.build(gravity, params.number("drag"));
    Ok(Body {
        label: label.into(),
        model,
        state,
        method,
        params: method_params(params),
    })
}

/// `rope`: the GAMES101 rope, pinned at node 0, in SI units.
///
/// # Errors
/// A pinned index out of range, or `start == end`.
pub fn rope_scene(params: &Params) -> Result<Scene, SceneError> {
    let body = rope_body(params, DVec3::ZERO, Method::SemiImplicitEuler, "rope")?;
    Ok(Scene {
        name: "rope".into(),
        bodies: vec![body],
        dt: 1.0 / 64.0,
        duration: 10.0,
    })
}

/// `ropes`: GAMES101's two ropes side by side, one under semi-implicit Euler (blue in the course),
/// one under Verlet (green), `separation` metres apart so they never overlap.
///
/// # Errors
/// As [`rope_scene`].
pub fn ropes_scene(params: &Params) -> Result<Scene, SceneError> {
    let offset = DVec3::new(params.number("separation"), 0.0, 0.0);
    let euler = rope_body(params, DVec3::ZERO, Method::SemiImplicitEuler, "euler rope")?;
    let verlet = rope_body(params, offset, Method::Verlet, "verlet rope")?;
    Ok(Scene {
        name: "ropes".into(),
        bodies: vec![euler, verlet],
        dt: 1.0 / 64.0,
        duration: 10.0,
    })
}
