//! A refinement: the same body at another resolution (the module docs of
//! [`super`]: "Refining the same body", "Spring kinds").

use serde::Serialize;

use crate::scene::lattice::KindCoefficients;
use crate::scene::{self, Params, Scene, SceneDef, Value};
use crate::study::StudyError;

/// How a built-in scene's body is divided (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Dimension {
    /// A cube: `n` particles per edge, springs `k ∝ h`.
    Volume,
    /// A cloth: `n` per side, springs unchanged.
    Membrane,
    /// A rope: `nodes`, springs `k ∝ 1/h`.
    Line,
}

impl Dimension {
    /// The rule in words, for the output.
    #[must_use]
    pub fn rule(self) -> &'static str {
        match self {
            Dimension::Volume => {
                "the same cube at every n: edge, total mass and material kept (particle mass ∝ \
                 1/n³; stiffness and dampers ∝ h = L/(n - 1), a spring standing for material of \
                 cross-section h²)"
            }
            Dimension::Membrane => {
                "the same cloth at every n: size, total mass and material kept (particle mass and \
                 drag ∝ 1/n²; stiffness and dampers unchanged, a spring standing for a strip of \
                 width h)"
            }
            Dimension::Line => {
                "the same rope at every node count N: length, total mass and material kept \
                 (node mass and drag ∝ 1/N; stiffness and dampers ∝ 1/h = (N - 1)/ℓ); pinned \
                 nodes kept at their place along the rope"
            }
        }
    }

    /// The resolution parameter: `n` or `nodes`.
    #[must_use]
    pub fn key(self) -> &'static str {
        match self {
            Dimension::Volume | Dimension::Membrane => "n",
            Dimension::Line => "nodes",
        }
    }

    /// The smallest resolution that makes the body.
    #[must_use]
    pub fn min(self) -> i64 {
        match self {
            Dimension::Volume => 3,
            Dimension::Membrane => 3,
            Dimension::Line => 2,
        }
    }
}

/// Which spring kinds a run has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kinds {
    /// Every kind of the scene.
    All,
    /// Without the bend springs.
    NoBend,
    /// Without the shear springs.
    NoShear,
}

impl Kinds {
    /// `all`, `no bend`, `no shear`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Kinds::All => "all",
            Kinds::NoBend => "no bend",
            Kinds::NoShear => "no shear",
        }
    }

    /// The parameter values that remove the kind.
    fn values(self) -> Vec<(&'static str, Value)> {
        let zero = |stiffness, damping| {
            vec![
                (stiffness, Value::Number(0.0)),
                (damping, Value::Number(0.0)),
            ]
        };
        match self {
            Kinds::All => Vec::new(),
            Kinds::NoBend => zero("bend_stiffness", "bend_damping"),
            Kinds::NoShear => zero("shear_stiffness", "shear_damping"),
        }
    }
}

/// A built-in scene that can be refined, with the values of its parameters that the levels
/// scale (after the user's `--set`).
#[derive(Clone, Debug)]
pub struct Refinement {
    /// The built-in scene.
    pub scene: String,
    /// How its body is divided.
    pub dimension: Dimension,
    /// Its own resolution (`n` or `nodes`).
    pub base: i64,
    /// The user's assignments, applied first at every level.
    pub sets: Vec<String>,
    params: Params,
}

/// The scene is not a refinable built-in.
fn not_refinable(name: &str) -> StudyError {
    StudyError::Scene(scene::SceneError::Invalid(format!(
        "scene `{name}` cannot be refined: the resolution study and advise's resolutions need a \
         built-in scene with a resolution parameter (`n`: cube-plane, cube-tilted, cube-sphere, \
         cube-bowl, jelly-bowl, cloth-spheres, cloth-sphere; `nodes`: rope, ropes)"
    )))
}

impl Refinement {
    /// The refinement of the built-in `name` with the user's `sets`, or `None` when `name` is
    /// not a built-in with a resolution parameter.
    ///
    /// # Errors
    /// A bad assignment in `sets`.
    pub fn of(name: &str, sets: &[String]) -> Result<Option<Refinement>, StudyError> {
        let Some(def) = scene::builtin(name) else {
            return Ok(None);
        };
        let specs = (def.params)();
        let has = |key: &str| specs.iter().any(|p| p.name == key);
        let dimension = if has("nodes") {
            Dimension::Line
        } else if has("n") && has("edge") {
            Dimension::Volume
        } else if has("n") && has("drag") {
            Dimension::Membrane
        } else {
            return Ok(None);
        };
        let params = params_of(def, sets)?;
        Ok(Some(Refinement {
            scene: name.to_string(),
            dimension,
            base: params.integer(dimension.key()),
            sets: sets.to_vec(),
            params,
        }))
    }

    /// [`Refinement::of`] that fails for a scene that cannot be refined.
    ///
    /// # Errors
    /// As [`Refinement::of`], and a scene without a resolution parameter.
    pub fn require(name: &str, sets: &[String]) -> Result<Refinement, StudyError> {
        Refinement::of(name, sets)?.ok_or_else(|| not_refinable(name))
    }

    /// True when the scene has the springs that `kinds` removes (so the variant differs).
    #[must_use]
    pub fn has_kind(&self, kinds: Kinds) -> bool {
        // The coefficients as the lattice scenes build them (an override of -1: the common
        // value); a rope has one kind.
        let active = |kind: fn(&KindCoefficients) -> (f64, f64)| {
            let (stiffness, damping) = kind(&scene::course::coefficients(&self.params));
            stiffness > 0.0 || damping > 0.0
        };
        match (self.dimension, kinds) {
            (_, Kinds::All) => true,
            (Dimension::Line, _) => false,
            (_, Kinds::NoBend) => active(|c| c.bend),
            (_, Kinds::NoShear) => active(|c| c.shear),
        }
    }

    /// The default levels: a geometric sequence of spacings about the scene's own, from
    /// coarse to fine (`coarser` levels below it and `finer` above, ratio about √2; a cloth
    /// keeps an even number of cells per side, so its centre is a particle).
    #[must_use]
    pub fn default_levels(&self, coarser: i32, finer: i32) -> Vec<i64> {
        let cells = (self.base - 1) as f64;
        let even = self.dimension == Dimension::Membrane && (self.base - 1) % 2 == 0;
        let mut levels: Vec<i64> = (-coarser..=finer)
            .map(|k| {
                let c = cells * 2f64.sqrt().powi(k);
                let c = if even {
                    2.0 * (c / 2.0).round()
                } else {
                    c.round()
                };
                c as i64 + 1
            })
            .filter(|&n| n >= self.dimension.min())
            .collect();
        levels.push(self.base);
        levels.sort_unstable();
        levels.dedup();
        levels
    }

    /// The parameter values of level `n` with `kinds` on top of the user's (module docs): the
    /// scaled values (none at the scene's own resolution), then those that remove a kind.
    fn values_for(&self, n: i64, kinds: Kinds) -> Vec<(&'static str, Value)> {
        let mut values = if n == self.base {
            Vec::new()
        } else {
            self.scaled(n)
        };
        values.extend(kinds.values());
        values
    }

    /// The `--set` assignments of level `n` with `kinds`, to show and repeat a level: the
    /// user's, then [`Refinement::params`]'s values as text (the levels are built from the
    /// values, not from this text).
    #[must_use]
    pub fn sets_for(&self, n: i64, kinds: Kinds) -> Vec<String> {
        let mut sets = self.sets.clone();
        for (key, value) in self.values_for(n, kinds) {
            sets.push(match value {
                Value::Indices(list) => {
                    let items: Vec<String> = list.iter().map(i64::to_string).collect();
                    format!("{key}=[{}]", items.join(","))
                }
                other => format!("{key}={other}"),
            });
        }
        sets
    }

    /// The parameters of level `n` with `kinds`: the scene's with the user's assignments, then
    /// the level's values (module docs).
    ///
    /// # Errors
    /// A level outside a parameter's range.
    pub fn params(&self, n: i64, kinds: Kinds) -> Result<Params, StudyError> {
        let mut params = self.params.clone();
        for (key, value) in self.values_for(n, kinds) {
            params.set(key, value).map_err(scene::SceneError::from)?;
        }
        Ok(params)
    }

    /// The values that make level `n` from the scene's own (module docs).
    fn scaled(&self, n: i64) -> Vec<(&'static str, Value)> {
        let p = &self.params;
        let base = self.base as f64;
        let level = n as f64;
        let mut sets = Vec::new();
        let mut put = |key: &'static str, value: f64| {
            if value != p.number(key) {
                sets.push((key, Value::Number(value)));
            }
        };
        let spring_keys = [
            "stiffness",
            "damping",
            "struct_stiffness",
            "shear_stiffness",
            "bend_stiffness",
            "struct_damping",
            "shear_damping",
            "bend_damping",
        ];
        let springs = |ratio: f64, put: &mut dyn FnMut(&'static str, f64)| {
            for key in spring_keys {
                // The per-kind overrides: -1 (any negative) means "the common value".
                let v = p.number(key);
                if v >= 0.0 {
                    put(key, v * ratio);
                }
            }
        };
        match self.dimension {
            Dimension::Volume => {
                put("mass", p.number("mass") * (base / level).powi(3));
                springs((base - 1.0) / (level - 1.0), &mut put);
            }
            Dimension::Membrane => {
                put("mass", p.number("mass") * (base / level).powi(2));
                put("drag", p.number("drag") * (base / level).powi(2));
            }
            Dimension::Line => {
                put("mass", p.number("mass") * base / level);
                put("drag", p.number("drag") * base / level);
                for key in ["stiffness", "damping"] {
                    put(key, p.number(key) * (level - 1.0) / (base - 1.0));
                }
            }
        }
        if self.dimension == Dimension::Line
            && let Ok(pinned) = p.indices("pinned", self.base as usize)
        {
            let mut moved: Vec<i64> = pinned
                .iter()
                .map(|&i| ((i as f64) * (level - 1.0) / (base - 1.0)).round() as i64)
                .collect();
            moved.dedup();
            if moved.iter().zip(&pinned).any(|(a, &b)| *a != b as i64)
                || moved.len() != pinned.len()
            {
                sets.push(("pinned", Value::Indices(moved)));
            }
        }
        sets.push((self.dimension.key(), Value::Integer(n)));
        sets
    }

    /// The scene of level `n` with `kinds`, within `limits`.
    ///
    /// # Errors
    /// A level the scene refuses (out of its range, over the memory budget).
    pub fn scene(
        &self,
        n: i64,
        kinds: Kinds,
        limits: &crate::budget::Limits,
    ) -> Result<Scene, StudyError> {
        let def = scene::builtin(&self.scene).ok_or_else(|| not_refinable(&self.scene))?;
        Ok(scene::build_from(def, &self.params(n, kinds)?, limits)?)
    }
}

fn params_of(def: &SceneDef, sets: &[String]) -> Result<Params, StudyError> {
    let mut params = def.default_params();
    for s in sets {
        params.set_text(s).map_err(scene::SceneError::from)?;
    }
    // A resolution that is not an integer cannot be refined (never the case for built-ins).
    for (key, value) in params.iter() {
        if (key == "n" || key == "nodes") && !matches!(value, Value::Integer(_)) {
            return Err(not_refinable(def.name));
        }
    }
    Ok(params)
}
