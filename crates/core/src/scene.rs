//! Scenes: what one simulation needs, the built-in catalogue, and scene files.
//!
//! A [`Scene`] is one or more [`Body`]s, each a model, its state and the method that advances it,
//! plus the scene's default time step and duration. Most scenes have one body; `ropes` has two
//! so that two methods run side by side. Built-in scenes are functions of a typed, range-checked
//! [`Params`] list; the same parameters can be set with `--set key=value` or in a scene file.

pub mod builder;
pub mod course;
pub mod file;
pub mod lattice;
pub mod params;
pub mod rope;

use std::path::Path;

use crate::budget::{BodySize, BudgetError, Estimate, Limits, Stepped, scene_bytes};

use crate::physics::{Method, MethodParams, Model, State};
pub use params::{ParamError, ParamSpec, Params, Range, Value};

/// One simulated body: a model, its state and the method that advances it.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Name shown in output (for example "verlet rope").
    pub label: String,
    /// Masses, springs, gravity, drag.
    pub model: Model,
    /// Positions and velocities.
    pub state: State,
    /// The integration method.
    pub method: Method,
    /// Settings of the method.
    pub params: MethodParams,
}

/// Everything one simulation needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Scene name (the built-in name or the file name).
    pub name: String,
    /// The bodies, simulated independently.
    pub bodies: Vec<Body>,
    /// Default time step (s).
    pub dt: f64,
    /// Default simulated duration (s).
    pub duration: f64,
}

impl Scene {
    /// Total number of particles over all bodies.
    #[must_use]
    pub fn particle_count(&self) -> usize {
        self.bodies.iter().map(|b| b.model.particle_count()).sum()
    }

    /// Total number of springs over all bodies.
    #[must_use]
    pub fn spring_count(&self) -> usize {
        self.bodies.iter().map(|b| b.model.springs().len()).sum()
    }

    /// Sets every body's method.
    pub fn set_method(&mut self, method: Method) {
        for b in &mut self.bodies {
            b.method = method;
        }
    }

    /// The method of the bodies, or their methods joined by `,` when they differ (for example
    /// `semi-implicit-euler,verlet`).
    #[must_use]
    pub fn method_label(&self) -> String {
        let names: Vec<&str> = self.bodies.iter().map(|b| b.method.name()).collect();
        if names.windows(2).all(|w| w[0] == w[1]) {
            return names.first().copied().unwrap_or_default().to_string();
        }
        names.join(",")
    }
}

/// The budget's view of a scene: every body's particles, springs and method.
impl Stepped for Scene {
    fn bodies(&self) -> Vec<BodySize> {
        self.bodies
            .iter()
            .map(|b| BodySize {
                particles: b.model.particle_count() as f64,
                springs: b.model.springs().len() as f64,
                method: b.method,
                params: b.params,
            })
            .collect()
    }

    fn dt(&self) -> f64 {
        self.dt
    }
}

/// Anything a user can get wrong when choosing or describing a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Not a built-in scene and not a file.
    #[error(
        "unknown scene `{name}`; built-in scenes: {known} (or give a path to a .toml scene file)"
    )]
    UnknownScene {
        /// The name given.
        name: String,
        /// Comma-separated built-in names.
        known: String,
    },
    /// A bad parameter.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A problem at a place in a scene file.
    #[error("{path}:{line}:{column}: {message}")]
    File {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The file cannot be read.
    #[error("cannot read scene file {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A combination of values that cannot make a scene.
    #[error("{0}")]
    Invalid(String),
    /// A scene over the memory budget (see [`crate::budget`]).
    #[error(transparent)]
    Budget(#[from] BudgetError),
    /// A scene or lesson file larger than the budget allows, refused before parsing.
    #[error(
        "{path} is {}; scene and lesson files may be at most {} (use --force to read it anyway)",
        crate::budget::bytes(*size as f64), crate::budget::bytes(*limit as f64)
    )]
    FileTooLarge {
        /// The file.
        path: String,
        /// Its size (bytes).
        size: u64,
        /// The limit (bytes).
        limit: u64,
    },
}

/// A built-in scene: its name, a one-line description, its parameters and its builder.
pub struct SceneDef {
    /// The name used on the command line.
    pub name: &'static str,
    /// One line for `springlab scenes`.
    pub summary: &'static str,
    /// The parameter declarations with the course defaults.
    pub params: fn() -> Vec<ParamSpec>,
    /// Builds the scene from parameter values.
    pub build: fn(&Params) -> Result<Scene, SceneError>,
    /// Particles and springs the scene builds from parameter values, computed without building
    /// it (so that a scene over the memory budget is refused before it is allocated): exact
    /// when every spring kind is active, an upper bound otherwise.
    pub size: fn(&Params) -> (f64, f64),
    /// When the studies take the scene's observable by default (s): after what the scene is
    /// about has happened.
    ///
    /// ```text
    /// cube-plane, cube-tilted, cube-sphere, cube-bowl, jelly-bowl   2.5   after the landing (≈ 1.4 s)
    /// cloth-sphere                                                  3     draped and nearly at rest
    /// cloth-spheres                                                 1     the cloth caught the spheres (≈ 0.5 s)
    /// rope, ropes, oscillator                                       1
    /// ```
    pub observe_at: f64,
}

impl SceneDef {
    /// The default parameters.
    #[must_use]
    pub fn default_params(&self) -> Params {
        Params::new(self.name, (self.params)())
    }
}

/// The built-in scenes.
pub const BUILTIN: &[SceneDef] = &[
    SceneDef {
        name: "oscillator",
        summary: "one spring, one free particle, no gravity: x(t) = 1 + 0.1 cos(10 t) exactly",
        params: rope::oscillator_params,
        build: rope::oscillator,
        size: rope::oscillator_size,
        observe_at: 1.0,
    },
    SceneDef {
        name: "rope",
        summary: "GAMES101 rope in SI units: 3 nodes of 1 kg, k = 100 N/m, node 0 pinned, dt = 1/64 s",
        params: rope::rope_params,
        build: rope::rope_scene,
        size: rope::rope_size,
        observe_at: 1.0,
    },
    SceneDef {
        name: "ropes",
        summary: "GAMES101's two ropes side by side: semi-implicit Euler and Verlet at once",
        params: rope::ropes_params,
        build: rope::ropes_scene,
        size: rope::ropes_size,
        observe_at: 1.0,
    },
    SceneDef {
        name: "cube-plane",
        summary: "NYCU 2021: a 10×10×10 spring cube (K = 2000, D = 60) dropped on the plane y = -1",
        params: course::cube_params,
        build: course::cube_plane,
        size: course::cube_size,
        observe_at: 2.5,
    },
    SceneDef {
        name: "cube-tilted",
        summary: "NYCU 2021: the cube lands on a 45° slope (normal (1,1,0)), tips over and slides down",
        params: course::cube_params,
        build: course::cube_tilted,
        size: course::cube_size,
        observe_at: 2.5,
    },
    SceneDef {
        name: "cube-sphere",
        summary: "NYCU 2021: the cube lands off-centre on a ball of radius 3 at (0,-1,0) and slides off",
        params: course::cube_params,
        build: course::cube_sphere,
        size: course::cube_size,
        observe_at: 2.5,
    },
    SceneDef {
        name: "cube-bowl",
        summary: "NYCU 2021: the cube falls into a bowl of radius 7 centred at (2,7,1), rim at y = 7",
        params: course::cube_params,
        build: course::cube_bowl,
        size: course::cube_size,
        observe_at: 2.5,
    },
    SceneDef {
        name: "jelly-bowl",
        summary: "NYCU 2023: the jelly hits the edge of a hole in the floor and falls into the bowl below",
        params: course::jelly_params,
        build: course::jelly_bowl,
        size: course::cube_size,
        observe_at: 2.5,
    },
    SceneDef {
        name: "cloth-spheres",
        summary: "NYCU 2022: four 125 kg spheres fall onto a 25×25 cloth pinned at its corners, dt = 1e-4",
        params: course::cloth_spheres_params,
        build: course::cloth_spheres,
        size: course::cloth_size,
        observe_at: 1.0,
    },
    SceneDef {
        name: "cloth-sphere",
        summary: "NYCU 2024: a 25×25 cloth drapes over a sphere of radius 1 that moves at a set velocity",
        params: course::cloth_sphere_params,
        build: course::cloth_sphere,
        size: course::cloth_size,
        observe_at: 3.0,
    },
];

/// The built-in scene called `name`.
#[must_use]
pub fn builtin(name: &str) -> Option<&'static SceneDef> {
    BUILTIN.iter().find(|d| d.name == name)
}

/// Builds the built-in scene `name` with `--set` assignments applied in order.
///
/// # Errors
/// Unknown scene, unknown key, bad value, or values that make no scene.
pub fn build_builtin(name: &str, sets: &[String]) -> Result<Scene, SceneError> {
    build_builtin_with(name, sets, &Limits::DEFAULT)
}

/// [`build_builtin`] within `limits`: a scene whose particles and springs would need more memory
/// than `limits.memory` is refused before it is built ([`SceneDef::size`]).
///
/// # Errors
/// As [`build_builtin`], and [`SceneError::Budget`].
pub fn build_builtin_with(
    name: &str,
    sets: &[String],
    limits: &Limits,
) -> Result<Scene, SceneError> {
    let def = builtin(name).ok_or_else(|| SceneError::UnknownScene {
        name: file::excerpt(name, file::MAX_QUOTE),
        known: BUILTIN
            .iter()
            .map(|d| d.name)
            .collect::<Vec<_>>()
            .join(", "),
    })?;
    let mut params = def.default_params();
    for s in sets {
        params.set_text(s)?;
    }
    check_size(def, &params, &format!("scene `{name}`"), limits)?;
    (def.build)(&params)
}

/// Builds the built-in `def` from `params` (a [`SceneDef::default_params`] with values set)
/// within `limits`, as [`load_with`] builds it from `--set` text: refused before it is built
/// when its size needs more than `limits.memory`, and after, from its bodies.
///
/// # Errors
/// Values that make no scene, and [`SceneError::Budget`].
pub fn build_from(def: &SceneDef, params: &Params, limits: &Limits) -> Result<Scene, SceneError> {
    let what = format!("scene `{}`", def.name);
    check_size(def, params, &what, limits)?;
    let scene = (def.build)(params)?;
    check_memory(&scene, &what, limits)?;
    Ok(scene)
}

/// Refuses the built-in `def` with `params` before it is built when its particles and springs
/// would need more than `limits.memory` (every method's buffers counted).
///
/// # Errors
/// [`SceneError::Budget`].
pub fn check_size(
    def: &SceneDef,
    params: &Params,
    what: &str,
    limits: &Limits,
) -> Result<(), SceneError> {
    let (particles, springs) = (def.size)(params);
    Estimate {
        what: what.to_string(),
        particles,
        springs,
        memory: crate::budget::BASE_BYTES
            + crate::budget::body_bytes(particles, springs, &Method::ALL, 1.0),
        ..Estimate::default()
    }
    .check(limits)?;
    Ok(())
}

/// Loads a built-in scene by name or a scene file by path (anything ending in `.toml` or that
/// exists as a file), with `--set` assignments applied on top.
///
/// # Errors
/// As [`build_builtin`] and [`file::load`].
pub fn load(name_or_path: &str, sets: &[String]) -> Result<Scene, SceneError> {
    load_with(name_or_path, sets, &Limits::DEFAULT)
}

/// [`load`] within `limits`: files over `limits.file_bytes` are not read, and a scene whose
/// model, state and integrator buffers would exceed `limits.memory` is refused before it is
/// built (from the counts of a scene file, or [`SceneDef::size`] of a built-in).
///
/// # Errors
/// As [`load`], and [`SceneError::Budget`] or [`SceneError::FileTooLarge`].
pub fn load_with(
    name_or_path: &str,
    sets: &[String],
    limits: &Limits,
) -> Result<Scene, SceneError> {
    let path = Path::new(name_or_path);
    if builtin(name_or_path).is_none() && (name_or_path.ends_with(".toml") || path.is_file()) {
        return file::load_with(path, sets, limits);
    }
    let scene = build_builtin_with(name_or_path, sets, limits)?;
    check_memory(&scene, &format!("scene `{name_or_path}`"), limits)?;
    Ok(scene)
}

/// Refuses `scene` when stepping it with its own methods would need more than `limits.memory`.
fn check_memory(scene: &Scene, what: &str, limits: &Limits) -> Result<(), SceneError> {
    Estimate {
        what: what.to_string(),
        particles: scene.particle_count() as f64,
        springs: scene.spring_count() as f64,
        memory: scene_bytes(scene, None, 1.0),
        ..Estimate::default()
    }
    .check(limits)?;
    Ok(())
}

/// The methods a parameter acts on when it is a method parameter (the methods whose
/// declaration lists it, see [`method_param_specs`]); `None` for a scene's own parameter. A
/// scene accepts every method parameter, but each changes only a run with one of its methods.
#[must_use]
pub fn method_param(name: &str) -> Option<Vec<Method>> {
    let methods: Vec<Method> = Method::ALL.into_iter().filter(|m| m.reads(name)).collect();
    (!methods.is_empty()).then_some(methods)
}

/// The parameters every scene has for its methods, with the scene's Verlet damping and
/// projection passes as defaults (which methods each acts on: [`method_param`]).
#[must_use]
pub fn method_param_specs(verlet_damping: f64, iterations: i64) -> Vec<ParamSpec> {
    let d = MethodParams::default();
    vec![
        ParamSpec::number(
            "verlet_damping",
            "",
            verlet_damping,
            Range::From(0.0, 1.0),
            "Verlet damping factor γ per step in x + (1 - γ)(x - x_prev) (GAMES101; its decay \
             rate γ/dt changes with dt)",
        ),
        ParamSpec::number(
            "verlet_damping_rate",
            "1/s",
            0.0,
            Range::AtLeast(0.0),
            "Verlet damping rate r, the same at every dt, centred so Verlet stays second order",
        ),
        ParamSpec::integer(
            "iterations",
            iterations,
            Range::Between(0.0, 1000.0),
            "Verlet projection passes per step (0 = none); XPBD passes per substep",
        ),
        ParamSpec::integer(
            "substeps",
            i64::from(d.substeps),
            Range::Between(1.0, 10_000.0),
            "XPBD substeps per step",
        ),
        ParamSpec::number(
            "cg_tolerance",
            "",
            d.cg_tolerance,
            Range::Above(0.0),
            "implicit Euler: CG relative residual",
        ),
    ]
}

/// The method settings from a scene's parameters (see [`method_param_specs`]).
#[must_use]
pub fn method_params(params: &Params) -> MethodParams {
    MethodParams {
        verlet_damping: params.number("verlet_damping"),
        verlet_damping_rate: params.number("verlet_damping_rate"),
        iterations: params.integer("iterations") as u32,
        substeps: params.integer("substeps") as u32,
        cg_tolerance: params.number("cg_tolerance"),
        ..MethodParams::default()
    }
}
