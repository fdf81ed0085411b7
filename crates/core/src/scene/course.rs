//! The 3D scenes of the NYCU Computer Animation course, HW1 "Mass-spring system" (2021–2024):
//! a spring cube dropped on four terrains (2021), a jelly that falls through a hole into a bowl
//! (2023), a cloth under four falling spheres (2022) and a cloth over a sphere the user moves
//! (2024). Every course value is a parameter default (`docs/course.md` §2–3); `springlab scenes` lists
//! them with units and ranges.
//!
//! # Cube and jelly (2021, 2023)
//!
//! ```text
//! scene        terrain (collide.rs)                                   start offset   friction
//! cube-plane   plane y = -1, normal +y                                (0, 5, 0)      0.3
//! cube-tilted  plane through 0, normal (1,1,0)/√2: x + y = 0          (0, 5, 0)      0.3
//! cube-sphere  ball, centre (0,-1,0), radius 3                        (0, 5, 0)      0.3
//! cube-bowl    bowl, centre (2,7,1), radius 7, rim at y = 7           (0, 5, 0)      0.3
//! jelly-bowl   floor y = 0 with a hole r = 9/√2 at (2,0,1),           (-4.8, 7, 0)   0.2
//!              bowl r = 9 at (2, 9/√2, 1) cut at y = 0
//! ```
//! Body `i` (`bodies` of them) is an `n × n × n` lattice of edge `L` whose smallest corner is
//! [`course_body_offset`]`(i) = offset + (0, L, -2 L i)` (the course's placement rule), rotated by
//! `rotation` degrees about the axis (1, 0, 1)/√2 through its centre ([`course_rotation_axis`]).
//! Contact: restitution 0.8, friction 0.3 (2021) or 0.2 (2023), contact band ε = 0.01 m
//! ([`ContactParams::course_2021`], [`ContactParams::course_2023`]).
//!
//! With the defaults (L = 4 m, no rotation) the first body fills `[0,4] × [9,13] × [0,4]`, centre
//! (2, 11, 2), and each terrain catches it:
//!
//! - **plane**: the bottom face falls 10 m and lands after `√(2·10/9.8) ≈ 1.43` s.
//! - **tilted plane**: `φ = (x + y)/√2`; the nearest part of the cube is its bottom edge at x = 0,
//!   `φ = 9/√2 ≈ 6.4` m above the slope. The slope falls towards +x, so that edge is the uphill
//!   one: the cube lands on it and tips forward about z. A 45° slope is exactly a cube's tipping
//!   angle, so it keeps tumbling end over end while it slides down along (1, -1, 0)/√2, for
//!   ever: friction 0.3 is below tan 45° = 1.
//! - **sphere**: the ball's top is (0, 2, 0), under the cube's corner column; the centroid is
//!   `√(2² + 2²) ≈ 2.83` m off the ball's axis, so the cube lands off-centre and slides off towards
//!   +x, +z. There is no ground under the ball (none in the course scene): it then falls for ever.
//! - **bowl**: the rim circle (y = 7, radius 7 about x = 2, z = 1) contains the footprint
//!   `x, z ∈ [0, 4]` (its farthest corner (4, ·, 4) is `√(2² + 3²) ≈ 3.6` m from the axis), so the
//!   cube falls in. Resting flat at the bottom, its lower corners are `2√2` m from the axis where
//!   the bowl is at `y = 7 - √(49 - 8) ≈ 0.60`; a rigid cube would span y ∈ [0.6, 4.6], wholly
//!   below the rim: it fits (the soft cube sags and rocks about that). The bowl's bottom is
//!   (2, 0, 1).
//! - **jelly-bowl**: the corner is at (-4.8, 11, 0), the footprint `x ∈ [-4.8, -0.8]`,
//!   `z ∈ [0, 4]`. Its centroid column is `√(4.8² + 1²) ≈ 4.90` m from the hole's axis, inside the
//!   hole (radius 6.36), but its far strip (x = -4.8, 6.8–7.4 m from the axis) is over the floor:
//!   the jelly lands on the hole's edge with that strip, tips over it and falls into the bowl,
//!   whose bottom is at `y = 9/√2 - 9 ≈ -2.64`. The bowl is shallower than the jelly is tall: the
//!   jelly slides and rocks in it with its top above the floor's level, inside the hole.
//!
//! Further bodies are 2L apart along -z; over the ball and the bowl they partly or wholly miss
//! the terrain, as in the course.
//!
//! **Spring coefficients.** The course panel has one spring and one damper coefficient for all
//! three kinds, K = 2000 N/m and D = 60 N·s/m: the parameters `stiffness` and `damping`. Each kind
//! can be given its own value with `struct_stiffness`, `shear_damping`, … whose default -1 (any
//! negative value) means "the common value". A kind whose stiffness and damping are both 0 is not
//! built at all (`--set bend_stiffness=0 --set bend_damping=0` gives a cube without bend
//! springs): the model holds only the springs that act.
//!
//! # Cloth (2022, 2024)
//!
//! A 25 × 25 cloth over x, z ∈ [-2, 2] m, particles of 1 kg, the four corners pinned, damper
//! 750 N·s/m, viscous drag 3.4e-4 N·s/m, dt = 1e-4 s ([`ClothSpec::course_2022`],
//! [`ClothSpec::course_2024`]). No static collider: only spheres.
//!
//! - **cloth-spheres** (2022): cloth at y = 0, spring 25 000 N/m; four dynamic spheres of radius
//!   0.5 m and mass `1000 r³ = 125` kg start at (±0.75, 1, ±0.75), 0.5 m above it, and fall
//!   with it (the cloth sags under its own weight) until they catch up and it holds them. Sphere–cloth
//!   restitution 0, sphere–sphere 0.8 (two-way impulses, [`crate::physics::collide`]).
//! - **cloth-sphere** (2024): cloth at y = 1, spring 20 000 N/m, one kinematic sphere of radius 1
//!   at the origin (its top touches the cloth's centre), moving at `sphere_velocity` (the course
//!   moves it with the arrow keys at ±5 m/s; the terminal app will). Corner pins are the
//!   parameter `pinned`; pinning and unpinning them live (keys 1–4) is the terminal app's job.
//!
//! `pinned` lists corners by the course's key numbers: 1 = particle 0 at (-2, -2), 2 = particle
//! `n - 1` at (+2, -2), 3 = particle `n(n - 1)` at (-2, +2), 4 = particle `n² - 1` at (+2, +2)
//! (coordinates x, z), so it stays valid whatever `n` is.
//!
//! # Default methods
//!
//! Semi-implicit Euler everywhere. It costs one force evaluation per step, like explicit Euler,
//! but it is symplectic: the undamped part of the motion does not gain energy. At the course's
//! time steps (cube: `dt = 0.001` s; cloth: `dt = 1e-4` s) it is stable with a margin of about
//! two: measured, the cube diverges at its impact from `dt = 0.002` s and the cloth under the
//! spheres from `dt = 5e-4` s, under explicit and semi-implicit Euler alike (the dampers, not the
//! springs, set these limits). The course's predictor–corrector (its "implicit Euler") already
//! diverges at the cube's impact at `dt = 0.001` s, and RK4 costs four evaluations a step. For
//! large steps choose `--method implicit-euler` or `xpbd` (the cloth runs at `dt = 0.005` s, see
//! `scenes/cloth_spheres_implicit.toml`).
//!
//! References: NYCU Computer Animation HW1, "Mass-spring system", 2021 (cube), 2022 (cloth),
//! 2023 (jelly), 2024 (cloth); `docs/course.md` §2–3.

use glam::DVec3;

use super::builder::Builder;
use super::lattice::{
    ClothSpec, CubeSpec, KindCoefficients, cloth, corners, course_body_offset,
    course_rotation_axis, cube,
};
use super::params::{ACCELERATION, DAMPING, LENGTH, MASS, ParamSpec, Params, Range, STIFFNESS};
use super::{Body, Scene, SceneError, method_param_specs, method_params};
use crate::physics::collide::{Collider, ContactParams, DynamicSphere};
use crate::physics::{Method, SpringKind};

/// The course's time step for the cube and the jelly (s).
pub const CUBE_DT: f64 = 0.001;

/// The course's time step for the cloth (s).
pub const CLOTH_DT: f64 = 1e-4;

/// The method every course scene starts with (see the module documentation).
pub const DEFAULT_METHOD: Method = Method::SemiImplicitEuler;

/// The most bodies a cube scene may have.
pub const MAX_BODIES: i64 = 10;

/// The most particles along a cube's edge.
pub const MAX_CUBE_N: i64 = 40;

/// The most particles along a cloth's side.
pub const MAX_CLOTH_N: i64 = 200;

/// Spring coefficients shared by the cube and the cloth: the common `stiffness` and `damping`
/// (course defaults) and the per-kind overrides (-1: same as the common value).
fn coefficient_specs(stiffness: f64, damping: f64) -> Vec<ParamSpec> {
    let override_ =
        |name, unit, doc| ParamSpec::number(name, unit, -1.0, Range::Between(-1.0, 1e9), doc);
    vec![
        ParamSpec::number(
            "stiffness",
            "N/m",
            stiffness,
            STIFFNESS,
            "spring stiffness K of every kind (the course's one coefficient)",
        ),
        ParamSpec::number(
            "damping",
            "N·s/m",
            damping,
            DAMPING,
            "damper D along every spring (the course's one coefficient)",
        ),
        override_(
            "struct_stiffness",
            "N/m",
            "struct springs' stiffness; -1: same as `stiffness`",
        ),
        override_(
            "shear_stiffness",
            "N/m",
            "shear springs' stiffness; -1: same as `stiffness`",
        ),
        override_(
            "bend_stiffness",
            "N/m",
            "bend springs' stiffness; -1: same as `stiffness`",
        ),
        override_(
            "struct_damping",
            "N·s/m",
            "struct springs' damper; -1: same as `damping`",
        ),
        override_(
            "shear_damping",
            "N·s/m",
            "shear springs' damper; -1: same as `damping`",
        ),
        override_(
            "bend_damping",
            "N·s/m",
            "bend springs' damper; -1: same as `damping`",
        ),
    ]
}

/// The coefficients of each kind: the override when it is `>= 0`, else the common value (the
/// one place of that rule; the resolution study asks it too).
#[must_use]
pub fn coefficients(params: &Params) -> KindCoefficients {
    let stiffness = params.number("stiffness");
    let damping = params.number("damping");
    let pick = |key: &str, common: f64| {
        let value = params.number(key);
        if value < 0.0 { common } else { value }
    };
    KindCoefficients {
        struct_: (
            pick("struct_stiffness", stiffness),
            pick("struct_damping", damping),
        ),
        shear: (
            pick("shear_stiffness", stiffness),
            pick("shear_damping", damping),
        ),
        bend: (
            pick("bend_stiffness", stiffness),
            pick("bend_damping", damping),
        ),
    }
}

/// The kinds worth building: those with a non-zero stiffness or damping.
fn active_kinds(coefficients: &KindCoefficients) -> Vec<SpringKind> {
    SpringKind::ALL
        .into_iter()
        .filter(|&kind| {
            let (k, d) = coefficients.get(kind);
            k > 0.0 || d > 0.0
        })
        .collect()
}

fn gravity_spec() -> ParamSpec {
    ParamSpec::number(
        "gravity",
        "m/s²",
        9.8,
        ACCELERATION,
        "downward gravitational acceleration",
    )
}

fn gravity(params: &Params) -> DVec3 {
    DVec3::new(0.0, -params.number("gravity"), 0.0)
}

/// Parameters of the cube scenes, with the start `offset` (m) and `friction` of the course year.
fn lattice_specs(offset: DVec3, friction: f64) -> Vec<ParamSpec> {
    let mut p = vec![
        ParamSpec::integer(
            "bodies",
            1,
            Range::Between(1.0, MAX_BODIES as f64),
            "number of cubes, placed at offset + (0, L, -2 L i) (the course's rule)",
        ),
        ParamSpec::integer(
            "n",
            10,
            Range::Between(2.0, MAX_CUBE_N as f64),
            "particles along each edge (n³ per cube)",
        ),
        ParamSpec::number("edge", "m", 4.0, LENGTH, "edge length L of the cube"),
        ParamSpec::number("mass", "kg", 1.0, MASS, "mass of each particle"),
    ];
    p.extend(coefficient_specs(2000.0, 60.0));
    p.extend([
        gravity_spec(),
        ParamSpec::vector(
            "offset",
            "m",
            offset,
            "start offset: body i's smallest corner is offset + (0, L, -2 L i)",
        ),
        ParamSpec::number(
            "rotation",
            "°",
            0.0,
            Range::Any,
            "rotation of each cube about the axis (1, 0, 1) through its centre",
        ),
        ParamSpec::number(
            "restitution",
            "",
            0.8,
            Range::Between(0.0, 1.0),
            "restitution k_r of particle–terrain collisions",
        ),
        ParamSpec::number(
            "friction",
            "",
            friction,
            // Real coefficients are below about 2; past 10 the friction impulse of a contact
            // only overflows (1e308 ended in NaN).
            Range::Between(0.0, 10.0),
            "Coulomb friction coefficient k_f of the terrain",
        ),
    ]);
    // Verlet without projection: the springs are forces, as in the course; projecting every
    // spring to its rest length would make the jelly a rigid body. No Verlet damping: the
    // dampers damp (GAMES101's γ = 5e-5 per step at dt = 1e-3 would be a 0.05 1/s drag that
    // makes the cube land 0.22 m late).
    p.extend(method_param_specs(0.0, 0));
    p
}

/// Parameters of `cube-plane`, `cube-tilted`, `cube-sphere` and `cube-bowl` (NYCU HW1 2021).
pub fn cube_params() -> Vec<ParamSpec> {
    lattice_specs(DVec3::new(0.0, 5.0, 0.0), 0.3)
}

/// Parameters of `jelly-bowl` (NYCU HW1 2023).
pub fn jelly_params() -> Vec<ParamSpec> {
    lattice_specs(DVec3::new(-4.8, 7.0, 0.0), 0.2)
}

/// Particles and springs of a cube scene, before it is built: `bodies` cubes of `n³` particles,
/// each with its struct (edges), shear (face and body diagonals) and bend (two apart along an
/// axis) springs:
///
/// ```text
/// N = bodies · n³        S = bodies · (3n²(n-1) + 6n(n-1)² + 4(n-1)³ + 3n²(n-2))
/// ```
/// Exact when every spring kind is active, an upper bound otherwise (`tests/budget_memory.rs`).
pub fn cube_size(params: &Params) -> (f64, f64) {
    let (bodies, n) = (params.integer("bodies") as f64, params.integer("n") as f64);
    let m = n - 1.0;
    let springs = 3.0 * n * n * m + 6.0 * n * m * m + 4.0 * m * m * m + 3.0 * n * n * (n - 2.0);
    (bodies * n * n * n, bodies * springs)
}

/// Particles and springs of a cloth scene, before it is built: `n²` particles, the struct,
/// shear and bend springs of the cube's lattice in two dimensions:
///
/// ```text
/// N = n²        S = 2n(n-1) + 2(n-1)² + 2n(n-2)
/// ```
pub fn cloth_size(params: &Params) -> (f64, f64) {
    let n = params.integer("n") as f64;
    let springs = 2.0 * n * (n - 1.0) + 2.0 * (n - 1.0) * (n - 1.0) + 2.0 * n * (n - 2.0);
    (n * n, springs)
}

/// A cube scene: `bodies` lattices on `colliders`, with the contact coefficients `contact`
/// (restitution and friction then taken from the parameters).
fn lattice_scene(
    name: &str,
    label: &str,
    params: &Params,
    colliders: Vec<Collider>,
    contact: ContactParams,
) -> Result<Scene, SceneError> {
    let n = params.integer("n") as usize;
    let edge = params.number("edge");
    let coefficients = coefficients(params);
    let angle = params.number("rotation").to_radians();
    let contact = ContactParams {
        restitution: params.number("restitution"),
        friction: params.number("friction"),
        ..contact
    };
    let count = params.integer("bodies") as usize;
    let mut bodies = Vec::with_capacity(count);
    for index in 0..count {
        let spec = CubeSpec {
            counts: [n; 3],
            edge_length: DVec3::splat(edge),
            mass: params.number("mass"),
            coefficients,
            offset: course_body_offset(index, edge, params.vector("offset")),
            rotation: (angle != 0.0).then(|| (course_rotation_axis(), angle)),
            kinds: active_kinds(&coefficients),
        };
        spec.validate()?;
        let mut b = Builder::new();
        cube(&mut b, &spec);
        let (model, state) = b.build(gravity(params), 0.0);
        bodies.push(Body {
            label: if count == 1 {
                label.to_string()
            } else {
                format!("{label} {}", index + 1)
            },
            model: model.with_colliders(colliders.clone(), contact),
            state,
            method: DEFAULT_METHOD,
            params: method_params(params),
        });
    }
    Ok(Scene {
        name: name.into(),
        bodies,
        dt: CUBE_DT,
        duration: 5.0,
    })
}

/// `cube-plane` (NYCU HW1 2021): the spring cube dropped on the plane y = -1.
///
/// # Errors
/// Values that make no cube (see [`CubeSpec::validate`]).
pub fn cube_plane(params: &Params) -> Result<Scene, SceneError> {
    lattice_scene(
        "cube-plane",
        "cube",
        params,
        vec![Collider::course_2021_plane()],
        ContactParams::course_2021(),
    )
}

/// `cube-tilted` (NYCU HW1 2021): the cube dropped on the 45° slope through the origin with
/// normal (1, 1, 0); it tips onto a face and slides down towards +x.
///
/// # Errors
/// Values that make no cube (see [`CubeSpec::validate`]).
pub fn cube_tilted(params: &Params) -> Result<Scene, SceneError> {
    lattice_scene(
        "cube-tilted",
        "cube",
        params,
        vec![Collider::course_2021_tilted_plane()],
        ContactParams::course_2021(),
    )
}

/// `cube-sphere` (NYCU HW1 2021): the cube dropped on the ball of radius 3 at (0, -1, 0).
///
/// # Errors
/// Values that make no cube (see [`CubeSpec::validate`]).
pub fn cube_sphere(params: &Params) -> Result<Scene, SceneError> {
    lattice_scene(
        "cube-sphere",
        "cube",
        params,
        vec![Collider::course_2021_sphere()],
        ContactParams::course_2021(),
    )
}

/// `cube-bowl` (NYCU HW1 2021): the cube dropped into the bowl of radius 7 at (2, 7, 1).
///
/// # Errors
/// Values that make no cube (see [`CubeSpec::validate`]).
pub fn cube_bowl(params: &Params) -> Result<Scene, SceneError> {
    lattice_scene(
        "cube-bowl",
        "cube",
        params,
        vec![Collider::course_2021_bowl()],
        ContactParams::course_2021(),
    )
}

/// `jelly-bowl` (NYCU HW1 2023): the jelly lands on the edge of the floor's hole and falls
/// through it into the bowl below ([`Collider::course_2023_terrain`]).
///
/// # Errors
/// Values that make no cube (see [`CubeSpec::validate`]).
pub fn jelly_bowl(params: &Params) -> Result<Scene, SceneError> {
    lattice_scene(
        "jelly-bowl",
        "jelly",
        params,
        Collider::course_2023_terrain(),
        ContactParams::course_2023(),
    )
}

/// Parameters shared by the cloth scenes, with the course's spring stiffness.
fn cloth_specs(stiffness: f64) -> Vec<ParamSpec> {
    let mut p = vec![
        ParamSpec::integer(
            "n",
            25,
            Range::Between(2.0, MAX_CLOTH_N as f64),
            "particles along each side (n² in all) over x, z in [-2, 2] m",
        ),
        ParamSpec::number("mass", "kg", 1.0, MASS, "mass of each particle"),
    ];
    p.extend(coefficient_specs(stiffness, 750.0));
    p.extend([
        ParamSpec::number(
            "drag",
            "N·s/m",
            3.4e-4,
            DAMPING,
            "viscous drag on each particle",
        ),
        gravity_spec(),
        ParamSpec {
            range: Range::Between(1.0, 4.0),
            ..ParamSpec::indices(
                "pinned",
                vec![1, 2, 3, 4],
                "pinned corners by key: 1 (-2,-2), 2 (+2,-2), 3 (-2,+2), 4 (+2,+2) in (x, z)",
            )
        },
        ParamSpec::number(
            "restitution",
            "",
            0.0,
            Range::Between(0.0, 1.0),
            "restitution of sphere–cloth impulses",
        ),
    ]);
    p
}

/// The cloth of `spec`'s geometry with the parameters' size, coefficients and pins.
fn cloth_body(params: &Params, course: ClothSpec) -> Result<Builder, SceneError> {
    let n = params.integer("n") as usize;
    // Key k (1..=4, checked by the parameter's range) pins corners(n)[k - 1]; for n >= 2 the
    // four corners are distinct, so every key names one.
    let all = corners(n);
    let pinned = params
        .indices("pinned", 5)?
        .into_iter()
        .filter_map(|key| all.get(key.wrapping_sub(1)).copied())
        .collect();
    let coefficients = coefficients(params);
    let spec = ClothSpec {
        n,
        mass: params.number("mass"),
        coefficients,
        pinned,
        kinds: active_kinds(&coefficients),
        ..course
    };
    spec.validate()?;
    let mut b = Builder::new();
    cloth(&mut b, &spec);
    Ok(b)
}

/// Parameters of `cloth-spheres` (NYCU HW1 2022).
pub fn cloth_spheres_params() -> Vec<ParamSpec> {
    let mut p = cloth_specs(25_000.0);
    p.extend([
        ParamSpec::number(
            "sphere_radius",
            "m",
            0.5,
            LENGTH,
            "radius r of the four spheres (mass 1000 r³ kg)",
        ),
        ParamSpec::number(
            "sphere_restitution",
            "",
            0.8,
            Range::Between(0.0, 1.0),
            "restitution of sphere–sphere impulses",
        ),
    ]);
    p.extend(method_param_specs(0.0, 0));
    p
}

/// Parameters of `cloth-sphere` (NYCU HW1 2024).
pub fn cloth_sphere_params() -> Vec<ParamSpec> {
    let mut p = cloth_specs(20_000.0);
    p.extend([
        ParamSpec::number(
            "sphere_radius",
            "m",
            1.0,
            LENGTH,
            "radius of the sphere at the origin",
        ),
        ParamSpec::vector(
            "sphere_velocity",
            "m/s",
            DVec3::ZERO,
            "velocity of the kinematic sphere (the course's arrow keys: ±5 m/s)",
        ),
    ]);
    p.extend(method_param_specs(0.0, 0));
    p
}

fn cloth_contact(params: &Params) -> ContactParams {
    ContactParams {
        sphere_particle_restitution: params.number("restitution"),
        ..ContactParams::course_2021()
    }
}

/// `cloth-spheres` (NYCU HW1 2022): four heavy spheres fall onto a cloth pinned at its corners.
///
/// # Errors
/// Values that make no cloth (see [`ClothSpec::validate`]).
pub fn cloth_spheres(params: &Params) -> Result<Scene, SceneError> {
    let b = cloth_body(params, ClothSpec::course_2022())?;
    let (model, state) = b.build(gravity(params), params.number("drag"));
    let r = params.number("sphere_radius");
    // Course: (±0.75, 1, ±0.75), 1 m above the cloth.
    let spheres = [(-0.75, -0.75), (0.75, -0.75), (-0.75, 0.75), (0.75, 0.75)]
        .map(|(x, z)| DynamicSphere::new(DVec3::new(x, 1.0, z), r))
        .to_vec();
    let contact = ContactParams {
        sphere_sphere_restitution: params.number("sphere_restitution"),
        ..cloth_contact(params)
    };
    Ok(Scene {
        name: "cloth-spheres".into(),
        bodies: vec![Body {
            label: "cloth".into(),
            model: model.with_colliders(Vec::new(), contact),
            state: state.with_spheres(spheres),
            method: DEFAULT_METHOD,
            params: method_params(params),
        }],
        dt: CLOTH_DT,
        duration: 3.0,
    })
}

/// `cloth-sphere` (NYCU HW1 2024): a cloth at y = 1 over a kinematic sphere at the origin that
/// moves at `sphere_velocity`.
///
/// # Errors
/// Values that make no cloth (see [`ClothSpec::validate`]).
pub fn cloth_sphere(params: &Params) -> Result<Scene, SceneError> {
    let b = cloth_body(params, ClothSpec::course_2024())?;
    let (model, state) = b.build(gravity(params), params.number("drag"));
    let sphere = DynamicSphere::kinematic(
        DVec3::ZERO,
        params.number("sphere_radius"),
        params.vector("sphere_velocity"),
    );
    Ok(Scene {
        name: "cloth-sphere".into(),
        bodies: vec![Body {
            label: "cloth".into(),
            model: model.with_colliders(Vec::new(), cloth_contact(params)),
            state: state.with_spheres(vec![sphere]),
            method: DEFAULT_METHOD,
            params: method_params(params),
        }],
        dt: CLOTH_DT,
        duration: 3.0,
    })
}
