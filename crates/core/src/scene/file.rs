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
//! cg_tolerance = 1e-3
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

use super::params::{MAX_COMPONENT, ParamError, ParamSpec, Range, Value};
use super::{BUILTIN, Scene, SceneError, builtin};
use crate::budget::{Limits, short};
use crate::physics::Method;
use crate::physics::integrators::method_names;

pub mod bounds;
mod explicit;
use explicit::load_explicit;

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
    // A FIFO, a device or a directory is refused before it is opened (opening a FIFO would
    // wait for a writer, reading a device might never end).
    let kind = std::fs::metadata(path).map_err(io)?;
    if !kind.is_file() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("not a regular file ({})", file_kind(&kind.file_type())),
        )));
    }
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

/// What a path that is not a regular file is, in words.
fn file_kind(kind: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
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
    // Bounded before the TOML reader builds its tree (see `bounds`); `--force` lifts the
    // value count with the file size, never the nesting.
    let max_bytes = if limits.file_bytes <= Limits::DEFAULT.file_bytes {
        bounds::MAX_TREE_BYTES
    } else {
        usize::MAX
    };
    bounds::check_with(text, max_bytes, bounds::MAX_DEPTH)
        .map_err(|e| source.error(e.offset..e.offset, e.message))?;
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
    gravity: Option<Spanned<Vec3>>,
    drag: Option<Spanned<f64>>,
}

/// A vector `[x, y, z]` of exactly three numbers: a longer or shorter array is refused (serde's
/// `[f64; 3]` reads the first three elements of a longer one and ignores the rest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Vec3(pub [f64; 3]);

impl<'de> Deserialize<'de> for Vec3 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Vec3, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Vec3;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a vector [x, y, z] of 3 numbers")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Vec3, A::Error> {
                let mut v = [0.0; 3];
                for (i, x) in v.iter_mut().enumerate() {
                    *x = seq
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                let mut n = 3;
                while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    n += 1;
                }
                if n > 3 {
                    return Err(serde::de::Error::invalid_length(n, &self));
                }
                Ok(Vec3(v))
            }
        }
        d.deserialize_seq(Visitor)
    }
}

/// One `[[particles]]` entry.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParticleSpec {
    position: Spanned<Vec3>,
    velocity: Option<Spanned<Vec3>>,
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
    start: Option<Spanned<Vec3>>,
    end: Option<Spanned<Vec3>>,
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
    verlet_damping_rate: Option<Spanned<f64>>,
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
        if let Some(x) = &self.verlet_damping_rate {
            out.push(("verlet_damping_rate", Value::Number(*x.get_ref()), x.span()));
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
    /// A [`SceneError::File`] at the start of `span`; a message that quotes a long value is
    /// cut to an excerpt ([`excerpt`]).
    fn error(&self, span: Span<usize>, message: impl Into<String>) -> SceneError {
        let (line, column) = line_column(self.text, span.start);
        SceneError::File {
            path: self.path.clone(),
            line,
            column,
            message: excerpt(&message.into(), MAX_MESSAGE),
        }
    }

    /// A parameter error at `span`.
    /// A parameter error at `span`: what the file wrote (the key, the value) is cut to an
    /// excerpt; what springlab says (the known parameters, the range) is kept whole.
    fn param_error(&self, span: Span<usize>, e: &ParamError) -> SceneError {
        let cut = |t: &String| excerpt(t, MAX_QUOTE);
        let e = match e.clone() {
            ParamError::UnknownKey { key, scene, known } => ParamError::UnknownKey {
                key: cut(&key),
                scene,
                known,
            },
            ParamError::BadValue { key, got, expected } => ParamError::BadValue {
                key: cut(&key),
                got: cut(&got),
                expected,
            },
            ParamError::OutOfRange {
                key,
                got,
                range,
                unit,
            } => ParamError::OutOfRange {
                key: cut(&key),
                got: cut(&got),
                range,
                unit,
            },
            other => other,
        };
        let (line, column) = line_column(self.text, span.start);
        SceneError::File {
            path: self.path.clone(),
            line,
            column,
            message: e.to_string(),
        }
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
    fn vector(&self, key: &str, unit: &str, v: &Spanned<Vec3>) -> Result<DVec3, SceneError> {
        let d = DVec3::from_array(v.get_ref().0);
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

/// The most characters of a message about a file (a value it quotes is cut short).
pub const MAX_MESSAGE: usize = 200;
/// The most characters of a key or value a parameter error quotes from the file.
pub const MAX_QUOTE: usize = 60;

/// `text`, or its first `max` characters and `…` when it is longer.
#[must_use]
pub fn excerpt(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((at, _)) => format!("{}…", &text[..at]),
        None => text.to_string(),
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
