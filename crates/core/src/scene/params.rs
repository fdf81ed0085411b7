//! Scene parameters: one typed, range-checked list per scene, set from `--set key=value` or from
//! the `[params]` table of a scene file.

use std::fmt;

use glam::DVec3;

use crate::budget::short;

/// Masses (kg): from a milligram to a thousand tonnes. Excludes subnormal and vanishing masses,
/// whose `1/m` overflows or makes `k/m` meaningless.
pub const MASS: Range = Range::Between(1e-6, 1e6);

/// Spring stiffness (N/m): up to 10⁹, so that `k·Δx`, `½ k Δx²` and `k/m` stay finite for any
/// length and mass allowed here.
pub const STIFFNESS: Range = Range::Between(0.0, 1e9);

/// Damping and drag coefficients (N·s/m), bounded like [`STIFFNESS`].
pub const DAMPING: Range = Range::Between(0.0, 1e9);

/// The largest length, coordinate or displacement (m).
pub const MAX_LENGTH: f64 = 1e6;

/// Lengths that must be positive (m): rest lengths, edges, radii.
pub const LENGTH: Range = Range::Between(1e-6, MAX_LENGTH);

/// Signed lengths (m), for example the oscillator's amplitude.
pub const DISPLACEMENT: Range = Range::Between(-MAX_LENGTH, MAX_LENGTH);

/// Gravitational acceleration (m/s²).
pub const ACCELERATION: Range = Range::Between(-1e6, 1e6);

/// The largest component of a vector parameter (positions in m, velocities in m/s).
pub const MAX_COMPONENT: f64 = 1e6;

/// The value of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// A real number.
    Number(f64),
    /// A whole number.
    Integer(i64),
    /// A 3-vector `[x, y, z]`.
    Vector(DVec3),
    /// A list of particle indices `[i, j, ...]`.
    Indices(Vec<i64>),
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Number(x) => write!(f, "{}", short(*x)),
            Value::Integer(i) => write!(f, "{i}"),
            Value::Vector(v) => write!(f, "[{}, {}, {}]", short(v.x), short(v.y), short(v.z)),
            Value::Indices(list) => {
                let items: Vec<String> = list.iter().map(i64::to_string).collect();
                write!(f, "[{}]", items.join(", "))
            }
        }
    }
}

/// The allowed values of a numeric parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Any value.
    Any,
    /// `value > min`.
    Above(f64),
    /// `value >= min`.
    AtLeast(f64),
    /// `min <= value <= max`.
    Between(f64, f64),
    /// `min <= value < max`.
    From(f64, f64),
}

impl Range {
    fn contains(self, x: f64) -> bool {
        match self {
            Range::Any => x.is_finite(),
            Range::Above(min) => x > min && x.is_finite(),
            Range::AtLeast(min) => x >= min && x.is_finite(),
            Range::Between(min, max) => (min..=max).contains(&x),
            Range::From(min, max) => x >= min && x < max,
        }
    }
}

impl Range {
    /// The range of a whole-number parameter: its bounds as integers (`2 ..= 1000000`).
    #[must_use]
    pub fn integer_text(self) -> String {
        let i = |x: f64| format!("{}", x as i64);
        match self {
            Range::Any => "any whole number".to_string(),
            Range::Above(min) => format!("> {}", i(min)),
            Range::AtLeast(min) => format!(">= {}", i(min)),
            Range::Between(min, max) => format!("{} ..= {}", i(min), i(max)),
            Range::From(min, max) => format!("{} ..< {}", i(min), i(max)),
        }
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Range::Any => write!(f, "any finite value"),
            Range::Above(min) => write!(f, "> {}", short(*min)),
            Range::AtLeast(min) => write!(f, ">= {}", short(*min)),
            Range::Between(min, max) => write!(f, "{} ..= {}", short(*min), short(*max)),
            Range::From(min, max) => write!(f, "{} ..< {}", short(*min), short(*max)),
        }
    }
}

/// The declaration of one parameter: name, meaning, unit, default and allowed range.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// The key used by `--set` and scene files.
    pub name: &'static str,
    /// One line for `springlab scenes`.
    pub doc: &'static str,
    /// The unit, or "" when dimensionless.
    pub unit: &'static str,
    /// The course value.
    pub default: Value,
    /// Allowed range (numbers and integers; for index lists, each index).
    pub range: Range,
}

impl ParamSpec {
    /// A real-valued parameter.
    #[must_use]
    pub const fn number(
        name: &'static str,
        unit: &'static str,
        default: f64,
        range: Range,
        doc: &'static str,
    ) -> ParamSpec {
        ParamSpec {
            name,
            doc,
            unit,
            default: Value::Number(default),
            range,
        }
    }

    /// A whole-number parameter.
    #[must_use]
    pub const fn integer(
        name: &'static str,
        default: i64,
        range: Range,
        doc: &'static str,
    ) -> ParamSpec {
        ParamSpec {
            name,
            doc,
            unit: "",
            default: Value::Integer(default),
            range,
        }
    }

    /// A 3-vector parameter.
    #[must_use]
    pub const fn vector(
        name: &'static str,
        unit: &'static str,
        default: DVec3,
        doc: &'static str,
    ) -> ParamSpec {
        ParamSpec {
            name,
            doc,
            unit,
            default: Value::Vector(default),
            range: Range::Any,
        }
    }

    /// A list of particle indices (checked against the particle count by the scene).
    #[must_use]
    pub fn indices(name: &'static str, default: Vec<i64>, doc: &'static str) -> ParamSpec {
        ParamSpec {
            name,
            doc,
            unit: "",
            default: Value::Indices(default),
            range: Range::AtLeast(0.0),
        }
    }

    /// What a value must look like, for error messages.
    #[must_use]
    pub fn expected(&self) -> String {
        match &self.default {
            Value::Number(_) => format!("a number {}", self.range),
            Value::Integer(_) => format!("a whole number {}", self.range.integer_text()),
            Value::Vector(_) => format!(
                "a vector [x, y, z] of finite numbers, each within ±{}{}",
                short(MAX_COMPONENT),
                if self.unit.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", self.unit)
                }
            ),
            // Particle indices are checked against the particle count by the scene; any other
            // index list (the cloth's corner keys 1 ..= 4) says its range.
            Value::Indices(_) if self.range == Range::AtLeast(0.0) => {
                "a list of particle indices [i, j, ...]".to_string()
            }
            Value::Indices(_) => format!(
                "a list [i, j, ...] of whole numbers {}",
                self.range.integer_text()
            ),
        }
    }

    /// Checks `value` against the kind and range; converts an integer given for a number.
    ///
    /// # Errors
    /// [`ParamError::BadValue`] for the wrong kind, [`ParamError::OutOfRange`] outside the range.
    pub fn check(&self, value: Value) -> Result<Value, ParamError> {
        let bad = |got: &Value| ParamError::BadValue {
            key: self.name.to_string(),
            // A number as a number, `16.0`, where a whole number `16` was expected.
            got: match (got, got.to_string()) {
                (Value::Number(_), s) if s.chars().all(|c| c.is_ascii_digit() || c == '-') => {
                    format!("{s}.0")
                }
                (_, s) => s,
            },
            expected: self.expected(),
        };
        let out_of_range = |got: String| ParamError::OutOfRange {
            key: self.name.to_string(),
            got,
            range: match self.default {
                Value::Integer(_) | Value::Indices(_) => self.range.integer_text(),
                _ => self.range.to_string(),
            },
            unit: self.unit.to_string(),
        };
        let value = match (&self.default, value) {
            (Value::Number(_), Value::Integer(i)) => Value::Number(i as f64),
            (Value::Number(_), v @ Value::Number(_))
            | (Value::Integer(_), v @ Value::Integer(_))
            | (Value::Vector(_), v @ Value::Vector(_))
            | (Value::Indices(_), v @ Value::Indices(_)) => v,
            (_, v) => return Err(bad(&v)),
        };
        match &value {
            Value::Number(x) if !self.range.contains(*x) => Err(out_of_range(short(*x))),
            Value::Integer(i) if !self.range.contains(*i as f64) => {
                Err(out_of_range(i.to_string()))
            }
            Value::Vector(v) if !(v.is_finite() && v.abs().max_element() <= MAX_COMPONENT) => {
                Err(bad(&value))
            }
            Value::Indices(list) => match list.iter().find(|&&i| !self.range.contains(i as f64)) {
                Some(i) => Err(out_of_range(i.to_string())),
                None => Ok(value),
            },
            _ => Ok(value),
        }
    }

    /// Parses command-line text (`--set key=text`) into a value of this parameter's kind.
    ///
    /// # Errors
    /// As [`ParamSpec::check`], or [`ParamError::BadValue`] for text that does not parse.
    pub fn parse(&self, text: &str) -> Result<Value, ParamError> {
        let bad = || ParamError::BadValue {
            key: self.name.to_string(),
            got: text.to_string(),
            expected: self.expected(),
        };
        let text = text.trim();
        let list = || -> Option<Vec<&str>> {
            let inner = text.strip_prefix('[')?.strip_suffix(']')?;
            Some(
                inner
                    .split(',')
                    .map(str::trim)
                    .filter(|s| !s.is_empty())
                    .collect(),
            )
        };
        let value = match &self.default {
            Value::Number(_) => Value::Number(text.parse().map_err(|_| bad())?),
            Value::Integer(_) => Value::Integer(text.parse().map_err(|_| bad())?),
            Value::Vector(_) => {
                let items = list().ok_or_else(bad)?;
                let nums: Result<Vec<f64>, _> = items.iter().map(|s| s.parse::<f64>()).collect();
                match nums.map_err(|_| bad())?.as_slice() {
                    &[x, y, z] => Value::Vector(DVec3::new(x, y, z)),
                    _ => return Err(bad()),
                }
            }
            Value::Indices(_) => {
                let items = list().ok_or_else(bad)?;
                let nums: Result<Vec<i64>, _> = items.iter().map(|s| s.parse::<i64>()).collect();
                Value::Indices(nums.map_err(|_| bad())?)
            }
        };
        self.check(value)
    }
}

/// A bad parameter name or value.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The key is not a parameter of this scene.
    #[error("unknown parameter `{key}` for scene `{scene}`; known parameters: {known}")]
    UnknownKey {
        /// The key given.
        key: String,
        /// The scene.
        scene: String,
        /// Comma-separated known keys.
        known: String,
    },
    /// The value has the wrong kind or does not parse.
    #[error("`{key}` = {got}: expected {expected}")]
    BadValue {
        /// The key.
        key: String,
        /// The value given, as text.
        got: String,
        /// What was expected.
        expected: String,
    },
    /// The value is outside the allowed range.
    #[error("`{key}` = {got} is out of range: allowed {range}{}", if unit.is_empty() { String::new() } else { format!(" ({unit})") })]
    OutOfRange {
        /// The key.
        key: String,
        /// The value given, as text.
        got: String,
        /// The allowed range.
        range: String,
        /// The unit.
        unit: String,
    },
    /// `--set` text without `=`.
    #[error("`{0}`: expected key=value")]
    NotKeyValue(String),
}

/// The parameter values of one scene, in declaration order.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    scene: String,
    specs: Vec<ParamSpec>,
    values: Vec<Value>,
}

impl Params {
    /// The defaults of `specs` for `scene`.
    #[must_use]
    pub fn new(scene: &str, specs: Vec<ParamSpec>) -> Params {
        let values = specs.iter().map(|s| s.default.clone()).collect();
        Params {
            scene: scene.to_string(),
            specs,
            values,
        }
    }

    /// The declarations.
    #[must_use]
    pub fn specs(&self) -> &[ParamSpec] {
        &self.specs
    }

    /// `(name, value)` pairs in declaration order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, &Value)> {
        self.specs.iter().map(|s| s.name).zip(&self.values)
    }

    fn index(&self, key: &str) -> Result<usize, ParamError> {
        self.specs
            .iter()
            .position(|s| s.name == key)
            .ok_or_else(|| ParamError::UnknownKey {
                key: key.to_string(),
                scene: self.scene.clone(),
                known: self
                    .specs
                    .iter()
                    .map(|s| s.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// The declaration of `key`.
    ///
    /// # Errors
    /// [`ParamError::UnknownKey`] listing the known keys.
    pub fn spec(&self, key: &str) -> Result<&ParamSpec, ParamError> {
        Ok(&self.specs[self.index(key)?])
    }

    /// Sets `key` to an already typed value (from a scene file).
    ///
    /// # Errors
    /// Unknown key, wrong kind or out of range.
    pub fn set(&mut self, key: &str, value: Value) -> Result<(), ParamError> {
        let i = self.index(key)?;
        self.values[i] = self.specs[i].check(value)?;
        Ok(())
    }

    /// Sets a parameter from `key=value` text (the `--set` flag).
    ///
    /// # Errors
    /// Missing `=`, unknown key, text that does not parse, or out of range.
    pub fn set_text(&mut self, assignment: &str) -> Result<(), ParamError> {
        let (key, text) = assignment
            .split_once('=')
            .ok_or_else(|| ParamError::NotKeyValue(assignment.to_string()))?;
        let i = self.index(key.trim())?;
        self.values[i] = self.specs[i].parse(text)?;
        Ok(())
    }

    fn value(&self, key: &str) -> &Value {
        match self.index(key) {
            Ok(i) => &self.values[i],
            Err(e) => panic!("scene code asked for an undeclared parameter: {e}"),
        }
    }

    /// A number parameter (integers are converted).
    ///
    /// # Panics
    /// If `key` is not declared or not numeric: a bug in the scene, not user input.
    #[must_use]
    pub fn number(&self, key: &str) -> f64 {
        match self.value(key) {
            Value::Number(x) => *x,
            Value::Integer(i) => *i as f64,
            other => panic!("parameter `{key}` is {other}, not a number"),
        }
    }

    /// A whole-number parameter.
    ///
    /// # Panics
    /// If `key` is not declared or not an integer: a bug in the scene, not user input.
    #[must_use]
    pub fn integer(&self, key: &str) -> i64 {
        match self.value(key) {
            Value::Integer(i) => *i,
            other => panic!("parameter `{key}` is {other}, not an integer"),
        }
    }

    /// A vector parameter.
    ///
    /// # Panics
    /// If `key` is not declared or not a vector: a bug in the scene, not user input.
    #[must_use]
    pub fn vector(&self, key: &str) -> DVec3 {
        match self.value(key) {
            Value::Vector(v) => *v,
            other => panic!("parameter `{key}` is {other}, not a vector"),
        }
    }

    /// An index-list parameter, checked against `count` particles.
    ///
    /// # Errors
    /// [`ParamError::OutOfRange`] for an index `>= count`.
    ///
    /// # Panics
    /// If `key` is not declared or not an index list: a bug in the scene, not user input.
    pub fn indices(&self, key: &str, count: usize) -> Result<Vec<usize>, ParamError> {
        match self.value(key) {
            Value::Indices(list) => list
                .iter()
                .map(|&i| {
                    usize::try_from(i)
                        .ok()
                        .filter(|&i| i < count)
                        .ok_or_else(|| ParamError::OutOfRange {
                            key: key.to_string(),
                            got: i.to_string(),
                            range: format!(
                                "0 ..= {} (the scene has {count} particles)",
                                count.saturating_sub(1)
                            ),
                            unit: String::new(),
                        })
                })
                .collect(),
            other => panic!("parameter `{key}` is {other}, not an index list"),
        }
    }
}
