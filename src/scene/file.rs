//! Scene files in TOML: a built-in scene with parameters, or explicit particles and springs.
//!
//! `springlab run my.toml` (and everything else that takes a scene) loads a file with [`load`].
//! A file has one of two forms.
//!
//! **Form 1** names a built-in scene (`springlab scenes` lists them) and sets its parameters in
//! `[params]`, with the same keys, kinds and ranges as `--set`. `--set key=value` on the command
//! line applies on top of `[params]`.
//!
//! ```toml
//! scene = "rope"
//!
//! [params]
//! nodes = 16                  # whole number >= 2
//! pinned = [0]                # particle indices
//! start = [0.0, 2.0, 0.0]     # m
//! stiffness = 500.0           # N/m
//! verlet_damping = 0.0        # method settings are parameters of the built-in scene
//!
//! [run]
//! method = "verlet"
//! dt = 0.005                  # s
//! time = 5.0                  # s
//! ```
//!
//! **Form 2** has no `scene` key: it lists particles, springs and optional rope blocks, and builds
//! one body whose label is the file stem.
//!
//! ```toml
//! [world]
//! gravity = [0.0, -9.8, 0.0]  # m/s², optional, default [0, -9.8, 0]
//! drag = 0.0                  # N·s/m, 0 ..= 1e9, optional, default 0
//!
//! [[particles]]               # particle 0
//! position = [0.0, 0.0, 0.0]  # m
//! mass = 1.0                  # kg, 1e-6 ..= 1e6
//! pinned = true               # optional, default false
//!
//! [[particles]]               # particle 1
//! position = [1.0, 0.0, 0.0]  # m
//! velocity = [0.0, 0.5, 0.0]  # m/s, optional, default at rest
//! mass = 1.0                  # kg, 1e-6 ..= 1e6
//!
//! [[springs]]
//! a = 0                       # particle index
//! b = 1                       # particle index, not a
//! stiffness = 100.0           # N/m, 0 ..= 1e9
//! damping = 0.0               # N·s/m, 0 ..= 1e9, optional, default 0
//! rest_length = 1.0           # m, 0 ..= 1e6, optional, default: the initial distance of a and b
//! kind = "struct"             # struct | shear | bend, optional, default struct
//!
//! [[ropes]]                   # optional: a rope, as in the built-in `rope` scene
//! start = [0.0, 2.0, 0.0]     # m, first node
//! end = [-4.0, 2.0, 0.0]      # m, last node (not start)
//! nodes = 8                   # 2 ..= 1000000
//! mass = 1.0                  # kg per node, 1e-6 ..= 1e6
//! stiffness = 100.0           # N/m, 0 ..= 1e9
//! damping = 0.0               # N·s/m, 0 ..= 1e9
//! pinned = [0]                # node indices within this rope
//!
//! [run]
//! method = "rk4"              # optional, default semi-implicit-euler
//! dt = 0.01                   # s, > 0, optional, default 0.01
//! time = 10.0                 # s, >= 0, optional, default 10
//! verlet_damping = 0.00005    # optional method settings, defaults as MethodParams::default()
//! iterations = 1
//! substeps = 10
//! cg_tolerance = 1e-10
//! ```
//!
//! Particle indices: the `[[particles]]` come first in file order, then the nodes of each
//! `[[ropes]]` block in file order, so springs can join a rope to a particle. A file builds at
//! most [`MAX_PARTICLES`] particles, and a file is refused before it is read when it is larger
//! than the budget's 16 MiB, or before it is built when its particles and springs would need more
//! memory than the budget allows ([`crate::budget`]; `--force` lifts both). Vectors (positions,
//! velocities, gravity) must be finite, each component within ±1e6. Every key of a rope
//! block is optional and defaults to the built-in `rope` scene's value (3 nodes of 1 kg from
//! [0, 2, 0] to [-4, 2, 0], k = 100 N/m, node 0 pinned). `[run]` works in both forms; in Form 1 the method settings (`verlet_damping`,
//! `iterations`, `substeps`, `cg_tolerance`) are parameters of the built-in scene and belong in
//! `[params]`. In both forms the scene's name is the file name.
//!
//! `--set` applies only to Form 1: a Form 2 file lists its values itself, so a `--set` there is an
//! error ([`SceneError::Invalid`]) that says so.
//!
//! # Errors
//!
//! Every problem in the file is a [`SceneError::File`] with the 1-based line and column of the
//! offending key or value, and a message that names what was expected and the allowed range:
//!
//! ```text
//! rope.toml:7:8: `mass` = -1 is out of range: allowed > 0 (kg)
//! two.toml:12:5: spring end `b` = 5 is out of range: allowed 0 ..= 1 (the file has 2 particles)
//! two.toml:3:1: unknown field `gravty`, expected `gravity` or `drag`
//! ```
//!
//! A file that cannot be read is a [`SceneError::Io`]. No input makes the loader panic.

use std::collections::BTreeMap;
use std::ops::Range as Span;
use std::path::Path;

use glam::DVec3;
use serde::Deserialize;
use toml::Spanned;

use super::builder::{Builder, RopeSpec, rope};
use super::params::{
    DAMPING, MASS, MAX_COMPONENT, MAX_LENGTH, ParamError, ParamSpec, Params, Range, STIFFNESS,
    Value,
};
use super::{BUILTIN, Body, Scene, SceneError, builtin, method_param_specs, method_params};
use crate::budget::{BASE_BYTES, Estimate, Limits, PARSE_BYTES, body_bytes, short};
use crate::physics::integrators::method_names;
use crate::physics::{Method, MethodParams, Spring, SpringKind};

/// The most nodes a `[[ropes]]` block may have (keeps a typo from allocating terabytes).
pub const MAX_ROPE_NODES: i64 = 1_000_000;

/// The most particles a Form 2 file may build (ropes included).
pub const MAX_PARTICLES: usize = 10_000_000;

/// Default time step of a Form 2 file (s).
pub const DEFAULT_DT: f64 = 0.01;

/// Default simulated duration of a Form 2 file (s).
pub const DEFAULT_TIME: f64 = 10.0;

/// Default gravity of a Form 2 file (m/s²).
pub const DEFAULT_GRAVITY: DVec3 = DVec3::new(0.0, -9.8, 0.0);

/// Default method of a Form 2 file.
pub const DEFAULT_METHOD: Method = Method::SemiImplicitEuler;

/// Loads the scene file at `path`, with `--set` assignments `sets` applied on top (Form 1 only).
///
/// See the [module documentation](self) for the format.
///
/// # Errors
/// [`SceneError::Io`] when the file cannot be read; [`SceneError::File`] with line and column for
/// anything wrong in it; [`SceneError::Param`] for a bad `--set`; [`SceneError::Invalid`] for a
/// `--set` on a file without `scene = ...`.
pub fn load(path: &Path, sets: &[String]) -> Result<Scene, SceneError> {
    load_with(path, sets, &Limits::DEFAULT)
}

/// [`load`] within `limits`: a file larger than `limits.file_bytes` is refused before it is
/// read, and one that would build more memory than `limits.memory` before it is built.
///
/// # Errors
/// As [`load`], and [`SceneError::FileTooLarge`] or [`SceneError::Budget`].
pub fn load_with(path: &Path, sets: &[String], limits: &Limits) -> Result<Scene, SceneError> {
    let text = read_bounded(path, limits.file_bytes)?;
    from_str_with(&text, path, sets, limits)
}

/// The text of `path`, refused when it has more than `max` bytes (checked while reading, so a
/// file that grows or a device that never ends is refused too).
///
/// # Errors
/// [`SceneError::Io`] or [`SceneError::FileTooLarge`].
pub fn read_bounded(path: &Path, max: u64) -> Result<String, SceneError> {
    use std::io::Read;
    let io = |source| SceneError::Io {
        path: path.display().to_string(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(max.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > max {
        let size = std::fs::metadata(path).map_or(bytes.len() as u64, |m| m.len());
        return Err(SceneError::FileTooLarge {
            path: path.display().to_string(),
            size: size.max(bytes.len() as u64),
            limit: max,
        });
    }
    String::from_utf8(bytes).map_err(|e| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            e.utf8_error(),
        ))
    })
}

/// Builds a scene from TOML `text` as if it had been read from `path` (which names the scene and
/// the body, and prefixes every error message).
///
/// # Errors
/// As [`load`], except that nothing is read.
pub fn from_str(text: &str, path: &Path, sets: &[String]) -> Result<Scene, SceneError> {
    from_str_with(text, path, sets, &Limits::DEFAULT)
}

/// [`from_str`] within `limits` (see [`load_with`]).
///
/// # Errors
/// As [`from_str`], and [`SceneError::Budget`] for a scene over `limits.memory`.
pub fn from_str_with(
    text: &str,
    path: &Path,
    sets: &[String],
    limits: &Limits,
) -> Result<Scene, SceneError> {
    let source = Source {
        path: path.display().to_string(),
        text,
    };
    let file: FileSpec = toml::from_str(text).map_err(|e| source.toml_error(&e))?;
    let file_name = path
        .file_name()
        .map_or_else(|| source.path.clone(), |n| n.to_string_lossy().into_owned());
    match &file.scene {
        Some(name) => {
            let scene = load_builtin(&source, &file, name, &file_name, sets, limits)?;
            super::check_memory(&scene, &source.path, limits)?;
            Ok(scene)
        }
        None => {
            if let Some(set) = sets.first() {
                return Err(SceneError::Invalid(format!(
                    "--set {set}: --set applies only to scene files that name a built-in scene \
                     (`scene = \"...\"`); {} lists its particles and springs itself, so edit \
                     the values in the file",
                    source.path
                )));
            }
            let label = path
                .file_stem()
                .map_or_else(|| file_name.clone(), |n| n.to_string_lossy().into_owned());
            load_explicit(&source, &file, &file_name, &label, limits)
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The file's shape (serde). `Spanned` keeps the byte range of a value for error messages.

/// The whole file (both forms; which one is decided by `scene`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSpec {
    scene: Option<Spanned<String>>,
    params: Option<Spanned<BTreeMap<Spanned<String>, Spanned<toml::Value>>>>,
    world: Option<Spanned<WorldSpec>>,
    particles: Option<Spanned<Vec<Spanned<ParticleSpec>>>>,
    springs: Option<Spanned<Vec<SpringSpec>>>,
    ropes: Option<Spanned<Vec<Spanned<RopeBlock>>>>,
    run: Option<Spanned<RunSpec>>,
}

/// `[world]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WorldSpec {
    gravity: Option<Spanned<[f64; 3]>>,
    drag: Option<Spanned<f64>>,
}

/// One `[[particles]]` entry.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParticleSpec {
    position: Spanned<[f64; 3]>,
    velocity: Option<Spanned<[f64; 3]>>,
    mass: Spanned<f64>,
    pinned: Option<bool>,
}

/// One `[[springs]]` entry.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpringSpec {
    a: Spanned<i64>,
    b: Spanned<i64>,
    stiffness: Spanned<f64>,
    damping: Option<Spanned<f64>>,
    rest_length: Option<Spanned<f64>>,
    kind: Option<Spanned<String>>,
}

/// One `[[ropes]]` entry.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RopeBlock {
    start: Option<Spanned<[f64; 3]>>,
    end: Option<Spanned<[f64; 3]>>,
    nodes: Option<Spanned<i64>>,
    mass: Option<Spanned<f64>>,
    stiffness: Option<Spanned<f64>>,
    damping: Option<Spanned<f64>>,
    pinned: Option<Spanned<Vec<Spanned<i64>>>>,
}

/// `[run]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RunSpec {
    method: Option<Spanned<String>>,
    dt: Option<Spanned<f64>>,
    time: Option<Spanned<f64>>,
    verlet_damping: Option<Spanned<f64>>,
    iterations: Option<Spanned<i64>>,
    substeps: Option<Spanned<i64>>,
    cg_tolerance: Option<Spanned<f64>>,
}

impl RunSpec {
    /// The method settings given, as `(key, value, span)`.
    fn method_settings(&self) -> Vec<(&'static str, Value, Span<usize>)> {
        let mut out = Vec::new();
        if let Some(x) = &self.verlet_damping {
            out.push(("verlet_damping", Value::Number(*x.get_ref()), x.span()));
        }
        if let Some(i) = &self.iterations {
            out.push(("iterations", Value::Integer(*i.get_ref()), i.span()));
        }
        if let Some(i) = &self.substeps {
            out.push(("substeps", Value::Integer(*i.get_ref()), i.span()));
        }
        if let Some(x) = &self.cg_tolerance {
            out.push(("cg_tolerance", Value::Number(*x.get_ref()), x.span()));
        }
        out
    }
}

// ---------------------------------------------------------------------------------------------
// Locations and messages.

/// The file being read: its path (for messages) and its text (for line and column).
struct Source<'a> {
    path: String,
    text: &'a str,
}

impl Source<'_> {
    /// A [`SceneError::File`] at the start of `span`.
    fn error(&self, span: Span<usize>, message: impl Into<String>) -> SceneError {
        let (line, column) = line_column(self.text, span.start);
        SceneError::File {
            path: self.path.clone(),
            line,
            column,
            message: message.into(),
        }
    }

    /// A parameter error at `span`.
    fn param_error(&self, span: Span<usize>, e: &ParamError) -> SceneError {
        self.error(span, e.to_string())
    }

    /// A syntax, unknown-field, missing-field or type error from the TOML reader.
    fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let span = e.span().unwrap_or(0..0);
        let mut message = friendly(e.message());
        if message == "duplicate key"
            && let Some(key) = self.text.get(span.clone())
        {
            message = format!("duplicate key `{key}`");
        } else if message.starts_with("invalid ")
            && let Some(key) = key_before(self.text, span.start)
        {
            message = format!("`{key}`: {message}");
        }
        self.error(span, message)
    }

    /// Checks a number against `spec` (kind, range, finiteness).
    fn number(&self, spec: &ParamSpec, x: &Spanned<f64>) -> Result<f64, SceneError> {
        spec.check(Value::Number(*x.get_ref()))
            .map(|_| *x.get_ref())
            .map_err(|e| self.param_error(x.span(), &e))
    }

    /// Checks that all three components of a vector are finite.
    fn vector(&self, key: &str, unit: &str, v: &Spanned<[f64; 3]>) -> Result<DVec3, SceneError> {
        let d = DVec3::from_array(*v.get_ref());
        if d.is_finite() && d.abs().max_element() <= MAX_COMPONENT {
            Ok(d)
        } else {
            Err(self.error(
                v.span(),
                format!(
                    "`{key}` = [{}, {}, {}]: expected a vector [x, y, z] of finite numbers, each \
                     within ±{} ({unit})",
                    short(d.x),
                    short(d.y),
                    short(d.z),
                    short(MAX_COMPONENT)
                ),
            ))
        }
    }
}

/// The 1-based line and column (in characters) of byte `offset` in `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = text.get(..offset).unwrap_or("");
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
    (line, column)
}

/// The key of a `key = value` whose value (or an element of it) starts at `offset` on the same line.
fn key_before(text: &str, offset: usize) -> Option<&str> {
    let line = text.get(..offset)?.rsplit('\n').next()?;
    let (left, _) = line.rsplit_once('=')?;
    let key = left
        .trim_end()
        .rsplit([' ', '\t', '{', ','])
        .next()?
        .trim_matches('"');
    let bare = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.';
    (!key.is_empty() && key.chars().all(bare)).then_some(key)
}

/// Rewrites the type names of serde's messages into the words of the file format.
fn friendly(message: &str) -> String {
    let mut m = message
        .replace("expected f64", "expected a number")
        .replace("expected i64", "expected a whole number")
        .replace("expected a string", "expected a name in quotes")
        .replace(
            "expected an array of length 3",
            "expected a vector [x, y, z] of 3 numbers",
        )
        .replace("expected a sequence", "expected an array");
    if let Some(i) = m.find("expected struct ") {
        m.truncate(i);
        m.push_str("expected a table");
    }
    m
}

// ---------------------------------------------------------------------------------------------
// Form 1: a built-in scene with parameters.

fn load_builtin(
    source: &Source<'_>,
    file: &FileSpec,
    name: &Spanned<String>,
    file_name: &str,
    sets: &[String],
    limits: &Limits,
) -> Result<Scene, SceneError> {
    // Form 2 sections make no sense next to `scene = ...`.
    let form2 = [
        ("[world]", file.world.as_ref().map(Spanned::span)),
        ("[[particles]]", file.particles.as_ref().map(Spanned::span)),
        ("[[springs]]", file.springs.as_ref().map(Spanned::span)),
        ("[[ropes]]", file.ropes.as_ref().map(Spanned::span)),
    ];
    if let Some((section, span)) = form2
        .into_iter()
        .filter_map(|(s, span)| Some((s, span?)))
        .min_by_key(|(_, span)| span.start)
    {
        return Err(source.error(
            span,
            format!(
                "{section} cannot be used with `scene = \"{}\"`: a file either names a built-in \
                 scene and sets its [params], or lists its own particles and springs (no `scene` key)",
                name.get_ref()
            ),
        ));
    }
    let def = builtin(name.get_ref()).ok_or_else(|| {
        source.error(
            name.span(),
            format!(
                "unknown built-in scene `{}`; built-in scenes: {}",
                name.get_ref(),
                BUILTIN
                    .iter()
                    .map(|d| d.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
    })?;

    let mut params = def.default_params();
    let mut entries: Vec<(&Spanned<String>, &Spanned<toml::Value>)> = file
        .params
        .as_ref()
        .map(|p| p.get_ref().iter().collect())
        .unwrap_or_default();
    entries.sort_by_key(|(key, _)| key.span().start);
    for (key, value) in &entries {
        let spec = params
            .spec(key.get_ref())
            .map_err(|e| source.param_error(key.span(), &e))?
            .clone();
        to_value(&spec, value.get_ref())
            .ok_or_else(|| ParamError::BadValue {
                key: spec.name.to_string(),
                got: value.get_ref().to_string(),
                expected: spec.expected(),
            })
            .and_then(|v| params.set(spec.name, v))
            .map_err(|e| source.param_error(value.span(), &e))?;
    }
    for set in sets {
        params.set_text(set)?;
    }

    // The builder checks combinations (pinned indices against the node count, start != end):
    // point at the file's value when it came from the file and not from `--set`.
    let set_keys: Vec<&str> = sets
        .iter()
        .filter_map(|s| s.split_once('=').map(|(k, _)| k.trim()))
        .collect();
    let value_span = |key: &str| -> Option<Span<usize>> {
        if set_keys.contains(&key) {
            return None;
        }
        entries
            .iter()
            .find(|(k, _)| k.get_ref() == key)
            .map(|(_, v)| v.span())
    };
    super::check_size(def, &params, &format!("scene file {}", source.path), limits)?;
    let mut scene = (def.build)(&params).map_err(|e| match e {
        SceneError::Param(
            ref p @ (ParamError::OutOfRange { ref key, .. } | ParamError::BadValue { ref key, .. }),
        ) => match value_span(key) {
            Some(span) => source.param_error(span, p),
            None => e,
        },
        SceneError::Invalid(message) => source.error(name.span(), message),
        other => other,
    })?;
    scene.name = file_name.to_string();

    if let Some(run) = &file.run {
        let run = run.get_ref();
        if let Some((key, _, span)) = run.method_settings().into_iter().next() {
            return Err(source.error(
                span,
                format!(
                    "`{key}` is a parameter of the built-in scene `{}`: set it in [params], \
                     not in [run]",
                    def.name
                ),
            ));
        }
        let RunSettings { method, dt, time } = run_settings(source, run)?;
        if let Some(m) = method {
            scene.set_method(m);
        }
        if let Some(dt) = dt {
            scene.dt = dt;
        }
        if let Some(t) = time {
            scene.duration = t;
        }
    }
    Ok(scene)
}

/// A TOML value as a parameter value of `spec`'s kind, or `None` when it has the wrong shape.
fn to_value(spec: &ParamSpec, value: &toml::Value) -> Option<Value> {
    let number = |v: &toml::Value| match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(x) => Some(*x),
        _ => None,
    };
    match value {
        toml::Value::Integer(i) => Some(Value::Integer(*i)),
        toml::Value::Float(x) => Some(Value::Number(*x)),
        toml::Value::Array(items) => match spec.default {
            Value::Vector(_) => match items.as_slice() {
                [x, y, z] => Some(Value::Vector(DVec3::new(
                    number(x)?,
                    number(y)?,
                    number(z)?,
                ))),
                _ => None,
            },
            Value::Indices(_) => items
                .iter()
                .map(toml::Value::as_integer)
                .collect::<Option<Vec<i64>>>()
                .map(Value::Indices),
            _ => None,
        },
        _ => None,
    }
}

/// The method, time step (s) and duration (s) of `[run]`, each `None` when not given.
struct RunSettings {
    method: Option<Method>,
    dt: Option<f64>,
    time: Option<f64>,
}

/// The method, time step and duration of `[run]`, checked.
fn run_settings(source: &Source<'_>, run: &RunSpec) -> Result<RunSettings, SceneError> {
    let method = match &run.method {
        Some(m) => Some(m.get_ref().parse::<Method>().map_err(|_| {
            source.error(
                m.span(),
                format!(
                    "unknown method `{}`; expected one of: {}",
                    m.get_ref(),
                    method_names()
                ),
            )
        })?),
        None => None,
    };
    let dt_spec = ParamSpec::number("dt", "s", DEFAULT_DT, Range::Above(0.0), "time step");
    let time_spec = ParamSpec::number("time", "s", DEFAULT_TIME, Range::AtLeast(0.0), "duration");
    let dt = run
        .dt
        .as_ref()
        .map(|x| source.number(&dt_spec, x))
        .transpose()?;
    let time = run
        .time
        .as_ref()
        .map(|x| source.number(&time_spec, x))
        .transpose()?;
    if let (Some(d), Some(t), Some(span)) = (dt, time, run.dt.as_ref().map(Spanned::span))
        && t > 0.0
        && d > t
    {
        return Err(source.error(
            span,
            format!(
                "`dt` = {} s is longer than the run (`time` = {} s): expected a time step at \
                 most the simulated time",
                short(d),
                short(t)
            ),
        ));
    }
    Ok(RunSettings { method, dt, time })
}

// ---------------------------------------------------------------------------------------------
// Form 2: explicit particles, springs and ropes.

fn load_explicit(
    source: &Source<'_>,
    file: &FileSpec,
    file_name: &str,
    label: &str,
    limits: &Limits,
) -> Result<Scene, SceneError> {
    if let Some(params) = &file.params {
        return Err(source.error(
            params.span(),
            "[params] needs a built-in scene: add `scene = \"...\"` (see `springlab scenes`), \
             or give the values in [world], [[particles]], [[springs]] and [[ropes]]",
        ));
    }

    // World.
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

    let mut b = Builder::new();

    // Particles.
    let mass_spec = ParamSpec::number("mass", "kg", 1.0, MASS, "mass");
    for p in file.particles.iter().flat_map(|ps| ps.get_ref()) {
        let p = p.get_ref();
        let x = source.vector("position", "m", &p.position)?;
        let mass = source.number(&mass_spec, &p.mass)?;
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
    }

    // Ropes: all checked (and counted) before any is built.
    let mut ropes = Vec::new();
    let mut total = b.len();
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
    // Memory, from the counts, before anything large is built.
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
    b.reserve(total, springs);
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

    // Springs.
    let count = b.len();
    let stiffness_spec = ParamSpec::number("stiffness", "N/m", 0.0, STIFFNESS, "stiffness");
    let damping_spec = ParamSpec::number("damping", "N·s/m", 0.0, DAMPING, "damping");
    let rest_spec = ParamSpec::number(
        "rest_length",
        "m",
        0.0,
        Range::Between(0.0, MAX_LENGTH),
        "rest length",
    );
    for s in file.springs.iter().flat_map(|ss| ss.get_ref()) {
        let end = |key: &str, i: &Spanned<i64>| -> Result<u32, SceneError> {
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
        };
        let a = end("a", &s.a)?;
        let bi = end("b", &s.b)?;
        if a == bi {
            return Err(source.error(
                s.b.span(),
                format!("the spring joins particle {a} to itself: `a` and `b` must differ"),
            ));
        }
        let stiffness = source.number(&stiffness_spec, &s.stiffness)?;
        let damping = match &s.damping {
            Some(d) => source.number(&damping_spec, d)?,
            None => 0.0,
        };
        let xa = b.x.get(a as usize).copied().unwrap_or(DVec3::ZERO);
        let xb = b.x.get(bi as usize).copied().unwrap_or(DVec3::ZERO);
        let rest_length = match &s.rest_length {
            Some(r) => source.number(&rest_spec, r)?,
            None => (xb - xa).length(),
        };
        let kind = match &s.kind {
            Some(k) => SpringKind::from_name(k.get_ref()).ok_or_else(|| {
                source.error(
                    k.span(),
                    format!(
                        "unknown spring kind `{}`; expected one of: {}",
                        k.get_ref(),
                        SpringKind::ALL.map(SpringKind::name).join(", ")
                    ),
                )
            })?,
            None => SpringKind::Struct,
        };
        b.springs.push(Spring {
            a,
            b: bi,
            rest_length,
            stiffness,
            damping,
            kind,
        });
    }

    // Run settings.
    let d = MethodParams::default();
    let mut settings = Params::new(
        file_name,
        method_param_specs(d.verlet_damping, i64::from(d.iterations)),
    );
    let mut method = DEFAULT_METHOD;
    let mut dt = DEFAULT_DT;
    let mut duration = DEFAULT_TIME;
    if let Some(run) = &file.run {
        let run = run.get_ref();
        for (key, value, span) in run.method_settings() {
            settings
                .set(key, value)
                .map_err(|e| source.param_error(span, &e))?;
        }
        let given = run_settings(source, run)?;
        method = given.method.unwrap_or(method);
        dt = given.dt.unwrap_or(dt);
        duration = given.time.unwrap_or(duration);
    }

    let (model, state) = b.build(gravity, drag);
    Ok(Scene {
        name: file_name.to_string(),
        bodies: vec![Body {
            label: label.to_string(),
            model,
            state,
            method,
            params: method_params(&settings),
        }],
        dt,
        duration,
    })
}

/// A `[[ropes]]` block checked into a [`RopeSpec`]; missing keys take the built-in `rope` defaults.
fn rope_spec(source: &Source<'_>, block: &Spanned<RopeBlock>) -> Result<RopeSpec, SceneError> {
    let defaults = Params::new("rope", super::rope::rope_params());
    let r = block.get_ref();
    let vector = |key: &str, v: &Option<Spanned<[f64; 3]>>| match v {
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
