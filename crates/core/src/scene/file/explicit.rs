//! Form 2 of a scene file: explicit `[world]`, `[[particles]]`, `[[ropes]]`, `[[springs]]` and
//! `[run]`, checked in that order into one body. Every check names the line and column of the
//! value it rejects (through [`Source`]); the counts and the memory estimate are checked before
//! anything large is built.

use glam::DVec3;
use toml::Spanned;

use super::{
    DEFAULT_DT, DEFAULT_GRAVITY, DEFAULT_METHOD, DEFAULT_TIME, FileSpec, MAX_PARTICLES,
    MAX_ROPE_NODES, ParticleSpec, RopeBlock, RunSpec, Source, SpringSpec, Vec3, run_settings,
};
use crate::budget::{BASE_BYTES, Estimate, Limits, PARSE_BYTES, body_bytes};
use crate::physics::{Method, MethodParams, Spring, SpringKind};
use crate::scene::builder::{Builder, RopeSpec, rope};
use crate::scene::params::{DAMPING, MASS, MAX_LENGTH, ParamSpec, Params, Range, STIFFNESS, Value};
use crate::scene::{Body, Scene, SceneError, method_param_specs, method_params};

/// The scene of a Form 2 file: one body labelled `label`.
pub(super) fn load_explicit(
    source: &Source<'_>,
    file: &FileSpec,
    file_name: &str,
    label: &str,
    limits: &Limits,
) -> Result<Scene, SceneError> {
    reject_params(source, file)?;
    let (gravity, drag) = world(source, file)?;
    let mut b = Builder::new();
    add_particles(source, file, &mut b)?;
    let ropes = checked_ropes(source, file, b.len())?;
    let (particles, springs) = check_memory(source, file, &ropes, b.len(), limits)?;
    b.reserve(particles, springs);
    for spec in &ropes {
        rope(&mut b, spec);
    }
    if b.is_empty() {
        return Err(source.error(
            0..0,
            "the file has no particles: add [[particles]] or [[ropes]], or name a built-in scene \
             with `scene = \"...\"` (see `springlab scenes`)",
        ));
    }
    add_springs(source, file, &mut b)?;
    let run = run(source, file, file_name)?;
    let (model, state) = b.build(gravity, drag);
    Ok(Scene {
        name: file_name.to_string(),
        bodies: vec![Body {
            label: label.to_string(),
            model,
            state,
            method: run.method,
            params: method_params(&run.settings),
        }],
        dt: run.dt,
        duration: run.duration,
    })
}

/// `[params]` belongs to Form 1 only.
fn reject_params(source: &Source<'_>, file: &FileSpec) -> Result<(), SceneError> {
    match &file.params {
        Some(params) => Err(source.error(
            params.span(),
            "[params] needs a built-in scene: add `scene = \"...\"` (see `springlab scenes`), \
             or give the values in [world], [[particles]], [[springs]] and [[ropes]]",
        )),
        None => Ok(()),
    }
}

/// Gravity (m/s²) and drag (N·s/m) of `[world]`, defaults where not given.
fn world(source: &Source<'_>, file: &FileSpec) -> Result<(DVec3, f64), SceneError> {
    let mut gravity = DEFAULT_GRAVITY;
    let mut drag = 0.0;
    if let Some(world) = &file.world {
        let world = world.get_ref();
        if let Some(g) = &world.gravity {
            gravity = source.vector("gravity", "m/s²", g)?;
        }
        if let Some(d) = &world.drag {
            let spec = ParamSpec::number("drag", "N·s/m", 0.0, DAMPING, "drag");
            drag = source.number(&spec, d)?;
        }
    }
    Ok((gravity, drag))
}

/// Every `[[particles]]` entry, checked and added to `b`.
fn add_particles(source: &Source<'_>, file: &FileSpec, b: &mut Builder) -> Result<(), SceneError> {
    let mass_spec = ParamSpec::number("mass", "kg", 1.0, MASS, "mass");
    for p in file.particles.iter().flat_map(|ps| ps.get_ref()) {
        add_particle(source, &mass_spec, p.get_ref(), b)?;
    }
    Ok(())
}

fn add_particle(
    source: &Source<'_>,
    mass_spec: &ParamSpec,
    p: &ParticleSpec,
    b: &mut Builder,
) -> Result<(), SceneError> {
    let x = source.vector("position", "m", &p.position)?;
    let mass = source.number(mass_spec, &p.mass)?;
    let v = match &p.velocity {
        Some(v) => source.vector("velocity", "m/s", v)?,
        None => DVec3::ZERO,
    };
    let i = b.len();
    b.particle(x, mass);
    if let Some(slot) = b.v.get_mut(i) {
        *slot = v;
    }
    if let Some(slot) = b.pinned.get_mut(i) {
        *slot = p.pinned.unwrap_or(false);
    }
    Ok(())
}

/// Every `[[ropes]]` block checked (and the particles counted, from `particles` already made)
/// before any rope is built.
fn checked_ropes(
    source: &Source<'_>,
    file: &FileSpec,
    particles: usize,
) -> Result<Vec<RopeSpec>, SceneError> {
    let mut ropes = Vec::new();
    let mut total = particles;
    for block in file.ropes.iter().flat_map(|rs| rs.get_ref()) {
        let spec = rope_spec(source, block)?;
        total += spec.nodes;
        if total > MAX_PARTICLES {
            let span = block
                .get_ref()
                .nodes
                .as_ref()
                .map_or(block.span(), Spanned::span);
            return Err(source.error(
                span,
                format!(
                    "too many particles: this rope brings the file to {total}; allowed at most \
                     {MAX_PARTICLES}"
                ),
            ));
        }
        ropes.push(spec);
    }
    Ok(ropes)
}

/// The particles and springs the file will have, their memory checked against `limits`.
fn check_memory(
    source: &Source<'_>,
    file: &FileSpec,
    ropes: &[RopeSpec],
    particles: usize,
    limits: &Limits,
) -> Result<(usize, usize), SceneError> {
    let total = particles + ropes.iter().map(|r| r.nodes).sum::<usize>();
    let springs = file.springs.as_ref().map_or(0, |s| s.get_ref().len())
        + ropes.iter().map(|r| r.nodes - 1).sum::<usize>();
    let estimate = Estimate {
        what: format!("scene file {}", source.path),
        particles: total as f64,
        springs: springs as f64,
        memory: BASE_BYTES
            + PARSE_BYTES * source.text.len() as f64
            + body_bytes(total as f64, springs as f64, &Method::ALL, 1.0),
        ..Estimate::default()
    };
    estimate.check(limits)?;
    Ok((total, springs))
}

/// The checks of a spring's values.
struct SpringSpecs {
    stiffness: ParamSpec,
    damping: ParamSpec,
    rest_length: ParamSpec,
}

impl SpringSpecs {
    fn new() -> SpringSpecs {
        SpringSpecs {
            stiffness: ParamSpec::number("stiffness", "N/m", 0.0, STIFFNESS, "stiffness"),
            damping: ParamSpec::number("damping", "N·s/m", 0.0, DAMPING, "damping"),
            rest_length: ParamSpec::number(
                "rest_length",
                "m",
                0.0,
                Range::Between(0.0, MAX_LENGTH),
                "rest length",
            ),
        }
    }
}

/// Every `[[springs]]` entry, checked against the particles of `b` and added to it.
fn add_springs(source: &Source<'_>, file: &FileSpec, b: &mut Builder) -> Result<(), SceneError> {
    let specs = SpringSpecs::new();
    for s in file.springs.iter().flat_map(|ss| ss.get_ref()) {
        let spring = spring(source, &specs, s, &b.x)?;
        b.springs.push(spring);
    }
    Ok(())
}

/// One spring between two of the particles at positions `x`.
fn spring(
    source: &Source<'_>,
    specs: &SpringSpecs,
    s: &SpringSpec,
    x: &[DVec3],
) -> Result<Spring, SceneError> {
    let a = spring_end(source, "a", &s.a, x.len())?;
    let bi = spring_end(source, "b", &s.b, x.len())?;
    if a == bi {
        return Err(source.error(
            s.b.span(),
            format!("the spring joins particle {a} to itself: `a` and `b` must differ"),
        ));
    }
    let stiffness = source.number(&specs.stiffness, &s.stiffness)?;
    let damping = match &s.damping {
        Some(d) => source.number(&specs.damping, d)?,
        None => 0.0,
    };
    let xa = x.get(a as usize).copied().unwrap_or(DVec3::ZERO);
    let xb = x.get(bi as usize).copied().unwrap_or(DVec3::ZERO);
    let rest_length = match &s.rest_length {
        Some(r) => source.number(&specs.rest_length, r)?,
        None => (xb - xa).length(),
    };
    let kind = match &s.kind {
        Some(k) => spring_kind(source, k)?,
        None => SpringKind::Struct,
    };
    Ok(Spring {
        a,
        b: bi,
        rest_length,
        stiffness,
        damping,
        kind,
    })
}

/// A spring end `key` = `i`, an index among `count` particles.
fn spring_end(
    source: &Source<'_>,
    key: &str,
    i: &Spanned<i64>,
    count: usize,
) -> Result<u32, SceneError> {
    usize::try_from(*i.get_ref())
        .ok()
        .filter(|&i| i < count)
        .and_then(|i| u32::try_from(i).ok())
        .ok_or_else(|| {
            source.error(
                i.span(),
                format!(
                    "spring end `{key}` = {} is out of range: allowed 0 ..= {} \
                     (the file has {count} particles)",
                    i.get_ref(),
                    count - 1
                ),
            )
        })
}

fn spring_kind(source: &Source<'_>, k: &Spanned<String>) -> Result<SpringKind, SceneError> {
    SpringKind::from_name(k.get_ref()).ok_or_else(|| {
        source.error(
            k.span(),
            format!(
                "unknown spring kind `{}`; expected one of: {}",
                k.get_ref(),
                SpringKind::ALL.map(SpringKind::name).join(", ")
            ),
        )
    })
}

/// What `[run]` chose: method and its settings, time step (s), duration (s).
struct Run {
    method: Method,
    settings: Params,
    dt: f64,
    duration: f64,
}

/// `[run]`, defaults where not given.
fn run(source: &Source<'_>, file: &FileSpec, file_name: &str) -> Result<Run, SceneError> {
    let d = MethodParams::default();
    let mut run = Run {
        method: DEFAULT_METHOD,
        settings: Params::new(
            file_name,
            method_param_specs(d.verlet_damping, i64::from(d.iterations)),
        ),
        dt: DEFAULT_DT,
        duration: DEFAULT_TIME,
    };
    if let Some(spec) = &file.run {
        let spec: &RunSpec = spec.get_ref();
        for (key, value, span) in spec.method_settings() {
            run.settings
                .set(key, value)
                .map_err(|e| source.param_error(span, &e))?;
        }
        let given = run_settings(source, spec)?;
        run.method = given.method.unwrap_or(run.method);
        run.dt = given.dt.unwrap_or(run.dt);
        run.duration = given.time.unwrap_or(run.duration);
    }
    Ok(run)
}

/// A `[[ropes]]` block checked into a [`RopeSpec`]; missing keys take the built-in `rope` defaults.
fn rope_spec(source: &Source<'_>, block: &Spanned<RopeBlock>) -> Result<RopeSpec, SceneError> {
    let defaults = Params::new("rope", crate::scene::rope::rope_params());
    let r = block.get_ref();
    let vector = |key: &str, v: &Option<Spanned<Vec3>>| match v {
        Some(v) => source.vector(key, "m", v),
        None => Ok(defaults.vector(key)),
    };
    let start = vector("start", &r.start)?;
    let end = vector("end", &r.end)?;
    let number =
        |key: &'static str, unit: &'static str, range: Range, x: &Option<Spanned<f64>>| match x {
            Some(x) => source.number(&ParamSpec::number(key, unit, 0.0, range, key), x),
            None => Ok(defaults.number(key)),
        };
    let node_mass = number("mass", "kg", MASS, &r.mass)?;
    let stiffness = number("stiffness", "N/m", STIFFNESS, &r.stiffness)?;
    let damping = number("damping", "N·s/m", DAMPING, &r.damping)?;
    let nodes = match &r.nodes {
        Some(n) => {
            let spec = ParamSpec::integer(
                "nodes",
                3,
                Range::Between(2.0, MAX_ROPE_NODES as f64),
                "nodes",
            );
            spec.check(Value::Integer(*n.get_ref()))
                .map_err(|e| source.param_error(n.span(), &e))?;
            usize::try_from(*n.get_ref()).unwrap_or(2)
        }
        None => usize::try_from(defaults.integer("nodes")).unwrap_or(2),
    };
    let pinned = match &r.pinned {
        Some(list) => list
            .get_ref()
            .iter()
            .map(|i| {
                usize::try_from(*i.get_ref())
                    .ok()
                    .filter(|&i| i < nodes)
                    .ok_or_else(|| {
                        source.error(
                            i.span(),
                            format!(
                                "pinned node {} is out of range: allowed 0 ..= {} (the rope has \
                                 {nodes} nodes)",
                                i.get_ref(),
                                nodes - 1
                            ),
                        )
                    })
            })
            .collect::<Result<Vec<usize>, SceneError>>()?,
        None => defaults
            .indices("pinned", nodes)
            .map_err(|e| source.param_error(block.span(), &e))?,
    };
    if start == end {
        let span = r
            .end
            .as_ref()
            .or(r.start.as_ref())
            .map_or(block.span(), Spanned::span);
        return Err(source.error(
            span,
            "`start` and `end` of a rope must differ: the rope has no length",
        ));
    }
    Ok(RopeSpec {
        start,
        end,
        nodes,
        node_mass,
        stiffness,
        damping,
        pinned,
    })
}
