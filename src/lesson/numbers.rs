//! Numbers in lesson text that the code computes when a step opens, so that they cannot drift
//! from what springlab does.
//!
//! A placeholder is `{{NAME}}` or `{{NAME:ARGUMENT}}`, computed on the step's scene (its
//! parameters applied), or on another scene with `@SCENE key=value …` at the end:
//!
//! | placeholder | value |
//! |---|---|
//! | `{{param:stiffness}}` | a scene parameter's value |
//! | `{{particles}}`, `{{springs}}`, `{{springs:shear}}` | counts (all, or one kind) |
//! | `{{springs*30}}` | a count times a factor (two significant digits) |
//! | `{{omega_max}}` | the stiffest mode ω_max (rad/s, power iteration, stiffest body) |
//! | `{{limit_dt:METHOD}}`, `{{limit_dt_omega:METHOD}}` | the damped theory's largest stable dt (s), and times ω_max |
//! | `{{lambda:METHOD}}` | the real part of the root λ (1/s) of the mode that sets that limit |
//! | `{{order:METHOD}}` | the fitted convergence order (`study convergence`, 4 levels) |
//! | `{{error_ratio:A,B}}` | A's error over B's at the smallest dt of that study |
//! | `{{stable_dt_omega:METHOD}}` | the measured linear limit dt·ω_max (`study stability`) |
//! | `{{crossover:A,B}}` | the error (m) below which A needs fewer force evaluations than B (`study work-precision`, 6 levels; where the fitted power laws cross) |
//! | `{{wp_error:METHOD}}` | the error (m) at the largest dt of that study |
//!
//! The theory values are cheap (no simulation); the studies are run only on small scenes
//! (at most [`MAX_STUDY_SPRINGS`] springs). A value that does not exist ("none", "any dt")
//! is written in words.

use std::cell::OnceCell;

use crate::physics::{Method, SpringKind};
use crate::scene::{self, Scene};
use crate::study::convergence::{self, ConvergenceOptions, ConvergenceReport};
use crate::study::stability::{self, StabilityOptions, StabilityReport};
use crate::study::{self as studies, theory};

/// What a placeholder shows when its value cannot be computed (a scene too large to study, a
/// method the study did not fit).
pub const UNKNOWN: &str = "⟨?⟩";

/// Scenes with more springs than this are not studied for a placeholder.
pub const MAX_STUDY_SPRINGS: usize = 200;

/// The placeholder kinds and whether their argument is a method (`Some(1)`), two methods
/// (`Some(2)`), something else (`None` with `arg = true`) or nothing.
const KINDS: &[(&str, Arg)] = &[
    ("param", Arg::Text),
    ("particles", Arg::None),
    ("springs", Arg::OptionalText),
    ("omega_max", Arg::None),
    ("limit_dt", Arg::Methods(1)),
    ("limit_dt_omega", Arg::Methods(1)),
    ("lambda", Arg::Methods(1)),
    ("order", Arg::Methods(1)),
    ("error_ratio", Arg::Methods(2)),
    ("stable_dt_omega", Arg::Methods(1)),
    ("crossover", Arg::Methods(2)),
    ("wp_error", Arg::Methods(1)),
];

#[derive(Clone, Copy, PartialEq)]
enum Arg {
    None,
    Text,
    OptionalText,
    Methods(usize),
}

/// One placeholder, parsed.
#[derive(Clone, Debug, PartialEq)]
struct Placeholder {
    kind: String,
    arg: Option<String>,
    factor: Option<f64>,
    scene: Option<(String, Vec<String>)>,
}

fn parse(inner: &str) -> Result<Placeholder, String> {
    let (head, scene) = match inner.split_once('@') {
        Some((h, rest)) => {
            let mut words = rest.split_whitespace();
            let name = words
                .next()
                .ok_or_else(|| format!("{{{{{inner}}}}}: expected a scene name after @"))?;
            (
                h.trim(),
                Some((name.to_string(), words.map(str::to_string).collect())),
            )
        }
        None => (inner.trim(), None),
    };
    let (head, factor) = match head.split_once('*') {
        Some((h, f)) => (
            h,
            Some(
                f.trim()
                    .parse::<f64>()
                    .map_err(|_| format!("{{{{{inner}}}}}: expected a number after *"))?,
            ),
        ),
        None => (head, None),
    };
    let (kind, arg) = match head.split_once(':') {
        Some((k, a)) => (k.trim(), Some(a.trim().to_string())),
        None => (head.trim(), None),
    };
    let Some((_, spec)) = KINDS.iter().find(|(k, _)| *k == kind) else {
        let names: Vec<&str> = KINDS.iter().map(|(k, _)| *k).collect();
        return Err(format!(
            "unknown placeholder `{{{{{inner}}}}}`; expected one of: {}",
            names.join(", ")
        ));
    };
    match (spec, &arg) {
        (Arg::None, Some(_)) => return Err(format!("{{{{{inner}}}}}: `{kind}` takes no argument")),
        (Arg::Text, None) => return Err(format!("{{{{{inner}}}}}: expected `{kind}:NAME`")),
        (Arg::Methods(n), a) => {
            let list: Vec<&str> = a.as_deref().map_or(vec![], |a| a.split(',').collect());
            if list.len() != *n {
                return Err(format!(
                    "{{{{{inner}}}}}: expected {n} method name(s) after `{kind}:`"
                ));
            }
            for m in list {
                m.trim()
                    .parse::<Method>()
                    .map_err(|e| format!("{{{{{inner}}}}}: {e}"))?;
            }
        }
        _ => {}
    }
    if factor.is_some() && !matches!(kind, "springs" | "particles") {
        return Err(format!("{{{{{inner}}}}}: `*` multiplies counts only"));
    }
    Ok(Placeholder {
        kind: kind.to_string(),
        arg,
        factor,
        scene,
    })
}

/// The placeholders of `text`: `(byte offset, inner text)`.
fn find(text: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(open) = text[from..].find("{{") {
        let start = from + open;
        let Some(close) = text[start + 2..].find("}}") else {
            out.push((start, ""));
            break;
        };
        out.push((start, &text[start + 2..start + 2 + close]));
        from = start + 2 + close + 2;
    }
    out
}

/// Checks every placeholder of `text`: `(byte offset, message)` for each bad one (unknown name,
/// method or scene, or a missing `}}`).
#[must_use]
pub fn check(text: &str) -> Vec<(usize, String)> {
    let mut errors = Vec::new();
    for (offset, inner) in find(text) {
        if inner.is_empty() {
            errors.push((offset, "`{{` without a closing `}}`".to_string()));
            continue;
        }
        match parse(inner) {
            Ok(p) => {
                if let Some((name, sets)) = &p.scene {
                    // Another scene: it must load and obey a lesson step's budget.
                    match scene::load(name, sets) {
                        Err(e) => errors.push((offset, format!("{{{{{inner}}}}}: {e}"))),
                        Ok(s) => {
                            let what = format!("scene `{name}`");
                            let mut checked = super::check_budget(&s, s.dt, 0.0, &what);
                            if checked.is_ok() && NEEDS_OMEGA.contains(&p.kind.as_str()) {
                                checked = super::check_omega_cost(&s, &what);
                            }
                            if let Err(m) = checked {
                                errors.push((offset, format!("{{{{{inner}}}}}: {m}")));
                            }
                        }
                    }
                }
            }
            Err(m) => errors.push((offset, m)),
        }
    }
    errors
}

/// Placeholder kinds computed from ω_max, whose power iteration
/// ([`crate::study::modes`]) may take up to its `MAX_ITERATIONS` passes over the springs.
const NEEDS_OMEGA: &[&str] = &[
    "omega_max",
    "limit_dt",
    "limit_dt_omega",
    "lambda",
    "stable_dt_omega",
];

/// True when a placeholder of `text` on the step's own scene (no `@SCENE`) needs ω_max.
#[must_use]
pub fn needs_omega(text: &str) -> bool {
    find(text).into_iter().any(|(_, inner)| {
        parse(inner).is_ok_and(|p| p.scene.is_none() && NEEDS_OMEGA.contains(&p.kind.as_str()))
    })
}

/// Checks every `{{param:KEY}}` of `text`: its scene (`@SCENE`, else the step's `scene`) must be
/// a built-in scene with a parameter `KEY` (a scene file's values are not looked up). Returns
/// `(byte offset, message)` for each bad one.
#[must_use]
pub fn check_params(text: &str, scene: &str) -> Vec<(usize, String)> {
    let mut errors = Vec::new();
    for (offset, inner) in find(text) {
        let Ok(p) = parse(inner) else { continue };
        if p.kind != "param" {
            continue;
        }
        let name = p.scene.as_ref().map_or(scene, |(n, _)| n.as_str());
        let key = p.arg.as_deref().unwrap_or("");
        let Some(def) = scene::builtin(name) else {
            errors.push((
                offset,
                format!(
                    "{{{{{inner}}}}}: `param` reads a built-in scene's parameters; `{name}` is \
                     not a built-in scene"
                ),
            ));
            continue;
        };
        let params = def.default_params();
        if !params.iter().any(|(k, _)| k == key) {
            let known: Vec<&str> = params.iter().map(|(k, _)| k).collect();
            errors.push((
                offset,
                format!(
                    "{{{{{inner}}}}}: scene `{name}` has no parameter `{key}`; its parameters: {}",
                    known.join(", ")
                ),
            ));
        }
    }
    errors
}

/// What one scene's placeholders share (each computed once, on first use).
struct Context {
    name: String,
    sets: Vec<String>,
    scene: Option<Scene>,
    omega: OnceCell<f64>,
    convergence: OnceCell<Option<ConvergenceReport>>,
    work: OnceCell<Option<ConvergenceReport>>,
    stability: OnceCell<Option<StabilityReport>>,
    /// Per body with stiffness: its spectrum at the initial state.
    spectra: OnceCell<Vec<(usize, theory::Spectrum)>>,
}

impl Context {
    fn new(name: &str, sets: &[String], scene: Option<Scene>) -> Context {
        let scene = scene.or_else(|| scene::load(name, sets).ok());
        Context {
            name: name.to_string(),
            sets: sets.to_vec(),
            scene,
            omega: OnceCell::new(),
            convergence: OnceCell::new(),
            work: OnceCell::new(),
            stability: OnceCell::new(),
            spectra: OnceCell::new(),
        }
    }

    fn spectra(&self) -> &[(usize, theory::Spectrum)] {
        self.spectra.get_or_init(|| {
            let Some(scene) = &self.scene else {
                return Vec::new();
            };
            scene
                .bodies
                .iter()
                .enumerate()
                .filter_map(|(i, b)| {
                    let omega = studies::omega_max(&b.model, &b.state).omega;
                    (omega > 0.0).then(|| (i, theory::spectrum(&b.model, &b.state, omega)))
                })
                .collect()
        })
    }

    fn omega(&self) -> f64 {
        *self.omega.get_or_init(|| {
            if self.scene.is_none() {
                return f64::NAN;
            }
            self.spectra()
                .iter()
                .map(|(_, s)| s.omega_max)
                .fold(0.0, f64::max)
        })
    }

    fn small(&self) -> bool {
        self.scene
            .as_ref()
            .is_some_and(|s| s.spring_count() <= MAX_STUDY_SPRINGS)
    }

    fn convergence(&self, work: bool) -> Option<&ConvergenceReport> {
        let cell = if work { &self.work } else { &self.convergence };
        cell.get_or_init(|| {
            if !self.small() {
                return None;
            }
            let (scene, used) = convergence::load_scene(&self.name, &self.sets).ok()?;
            let options = ConvergenceOptions {
                levels: if work { 6 } else { 4 },
                ..ConvergenceOptions::default()
            };
            let mut r = convergence::convergence(&scene, &options, &mut |_, _| {}).ok()?;
            r.sets = used;
            Some(r)
        })
        .as_ref()
    }

    fn stability(&self) -> Option<&StabilityReport> {
        self.stability
            .get_or_init(|| {
                if !self.small() {
                    return None;
                }
                let (scene, _) = stability::load_scene(&self.name, &self.sets).ok()?;
                stability::stability(&scene, &StabilityOptions::default(), &mut |_, _| {}).ok()
            })
            .as_ref()
    }

    /// The damped theory's limit of `method` over every body (the smallest).
    fn theory(&self, method: Method) -> Option<theory::TheoryLimit> {
        let scene = self.scene.as_ref()?;
        let mut best: Option<theory::TheoryLimit> = None;
        for (i, spectrum) in self.spectra() {
            let l = theory::limit(method, &scene.bodies[*i].params, spectrum);
            let better = match (&best, l.dt) {
                (None, _) => true,
                (Some(prev), Some(dt)) => prev.dt.is_none_or(|p| dt < p),
                _ => false,
            };
            if better {
                best = Some(l);
            }
        }
        best
    }
}

/// A number with four significant digits, short: `0.2`, `2.048e-3`, `1011`, `0.000125` → `1.25e-4`.
#[must_use]
pub fn format(x: f64) -> String {
    if !x.is_finite() {
        return "—".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-2..1e5).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{x:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.')
        } else {
            m
        };
        format!("{m}e{e}")
    }
}

/// Two significant digits with thin thousands: `320 000`, `1.3 million`.
fn format_count(x: f64) -> String {
    if x >= 1e6 {
        let m = x / 1e6;
        return format!("{} million", format(round_sig(m, 2)));
    }
    grouped(&(round_sig(x, 2) as i64).to_string())
}

/// Digits in groups of three from the right when there are five or more: `2400`, `12 876`.
fn grouped(s: &str) -> String {
    if s.len() < 5 {
        return s.to_string();
    }
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

fn round_sig(x: f64, digits: i32) -> f64 {
    if x == 0.0 {
        return 0.0;
    }
    let p = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    (x * p).round() / p
}

fn methods(arg: Option<&str>) -> Vec<Method> {
    arg.unwrap_or("")
        .split(',')
        .filter_map(|m| m.trim().parse().ok())
        .collect()
}

fn value(p: &Placeholder, cx: &Context) -> String {
    let ms = methods(p.arg.as_deref());
    let m = ms.first().copied();
    match p.kind.as_str() {
        "param" => {
            let key = p.arg.as_deref().unwrap_or("");
            let Some(def) = scene::builtin(&cx.name) else {
                return UNKNOWN.into();
            };
            let mut params = def.default_params();
            for s in &cx.sets {
                let _ = params.set_text(s);
            }
            params.iter().find(|(k, _)| *k == key).map_or_else(
                || UNKNOWN.into(),
                // A real number to four significant digits (lesson 8's mass per particle
                // is 625/81 kg), everything else as written.
                |(_, v)| match v {
                    scene::params::Value::Number(x) => format(*x),
                    other => other.to_string(),
                },
            )
        }
        "particles" | "springs" => {
            let Some(scene) = &cx.scene else {
                return UNKNOWN.into();
            };
            let n = if p.kind == "particles" {
                scene.particle_count()
            } else {
                let kind = match p.arg.as_deref() {
                    Some("struct") => Some(SpringKind::Struct),
                    Some("shear") => Some(SpringKind::Shear),
                    Some("bend") => Some(SpringKind::Bend),
                    _ => None,
                };
                scene
                    .bodies
                    .iter()
                    .flat_map(|b| b.model.springs())
                    .filter(|s| kind.is_none_or(|k| s.kind == k))
                    .count()
            };
            match p.factor {
                Some(f) => format_count(n as f64 * f),
                None => format_count_exact(n),
            }
        }
        "omega_max" => format(round_sig(cx.omega(), 3)),
        "limit_dt" | "limit_dt_omega" | "lambda" => {
            let Some(l) = m.and_then(|m| cx.theory(m)) else {
                return UNKNOWN.into();
            };
            match (l.stability, p.kind.as_str()) {
                ("conditional", "limit_dt") => format(l.dt.unwrap_or(f64::NAN)),
                ("conditional", "limit_dt_omega") => format(l.dt_omega.unwrap_or(f64::NAN)),
                ("conditional", _) => {
                    format(round_sig(l.binding.map_or(f64::NAN, |b| b.lambda_re), 4))
                }
                ("unconditional", _) => "any dt".into(),
                ("none", _) => "none".into(),
                _ => "not covered".into(),
            }
        }
        "order" => cx
            .convergence(false)
            .and_then(|r| r.methods.iter().find(|x| Some(x.method) == m))
            .and_then(|x| x.order)
            .map_or_else(|| UNKNOWN.into(), |o| format!("{o:.2}")),
        "error_ratio" => {
            let Some(r) = cx.convergence(false) else {
                return UNKNOWN.into();
            };
            let last = |method: Method| {
                r.methods
                    .iter()
                    .find(|x| x.method == method)
                    .and_then(|x| x.points.last())
                    .and_then(|pt| pt.error)
            };
            match (last(ms[0]), last(ms[1])) {
                (Some(a), Some(b)) if b > 0.0 => format!("{:.0}", a / b),
                _ => UNKNOWN.into(),
            }
        }
        "stable_dt_omega" => {
            let Some(r) = cx.stability() else {
                return UNKNOWN.into();
            };
            let Some(x) = r.methods.iter().find(|x| Some(x.method) == m) else {
                return UNKNOWN.into();
            };
            x.linear_dt_omega.map_or_else(
                || x.linear_stability.name().to_string(),
                |z| format!("{z:.4}"),
            )
        }
        "crossover" => cx
            .convergence(true)
            .and_then(|r| crossover(r, ms[0], ms[1]))
            .map_or_else(|| UNKNOWN.into(), |e| format(round_sig(e, 1))),
        "wp_error" => cx
            .convergence(true)
            .and_then(|r| r.methods.iter().find(|x| Some(x.method) == m))
            .and_then(|x| x.points.first())
            .and_then(|pt| pt.error)
            .map_or_else(|| UNKNOWN.into(), |e| format(round_sig(e, 2))),
        _ => UNKNOWN.into(),
    }
}

fn format_count_exact(n: usize) -> String {
    grouped(&n.to_string())
}

/// The error (m) below which `a` needs fewer force evaluations than `b` for the same error:
/// where the two fitted power laws `evals = C e^(-1/p)` cross (each fitted by least squares to
/// the method's fitted points of the work-precision study). `None` when they do not cross (or
/// `a` is cheaper everywhere: then the largest error measured).
#[must_use]
pub fn crossover(report: &ConvergenceReport, a: Method, b: Method) -> Option<f64> {
    // (slope, intercept) of log10 evals against log10 error.
    let fit = |m: Method| -> Option<(f64, f64)> {
        let pts: Vec<(f64, f64)> = report
            .methods
            .iter()
            .find(|x| x.method == m)?
            .points
            .iter()
            .filter(|p| p.fitted)
            .filter_map(|p| {
                p.error
                    .filter(|e| *e > 0.0)
                    .map(|e| (e.log10(), (p.force_evals as f64).log10()))
            })
            .collect();
        if pts.len() < 2 {
            return None;
        }
        let n = pts.len() as f64;
        let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
        let (mx, my) = (sx / n, sy / n);
        let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let slope = sxy / sxx;
        Some((slope, my - slope * mx))
    };
    let (sa, ia) = fit(a)?;
    let (sb, ib) = fit(b)?;
    // ia + sa L = ib + sb L; a (the higher order) has the shallower slope (sa > sb).
    if (sa - sb).abs() < 1e-9 {
        return None;
    }
    let l = (ib - ia) / (sa - sb);
    l.is_finite().then(|| 10f64.powf(l))
}

/// `text` with every placeholder replaced by its value on the step's scene `name` with `sets`
/// (`scene`: that scene already built, if at hand). An unknown placeholder stays as written
/// (lessons are checked when they load).
#[must_use]
pub fn fill(text: &str, name: &str, sets: &[String], scene: Option<Scene>) -> String {
    let found = find(text);
    if found.is_empty() {
        return text.to_string();
    }
    let own = Context::new(name, sets, scene);
    let mut others: Vec<((String, Vec<String>), Context)> = Vec::new();
    let mut out = String::new();
    let mut from = 0;
    for (offset, inner) in found {
        out.push_str(&text[from..offset]);
        let end = offset + 2 + inner.len() + 2;
        match parse(inner) {
            Ok(p) => {
                let v = match &p.scene {
                    None => value(&p, &own),
                    Some(key) => {
                        let i = match others.iter().position(|(k, _)| k == key) {
                            Some(i) => i,
                            None => {
                                others.push((key.clone(), Context::new(&key.0, &key.1, None)));
                                others.len() - 1
                            }
                        };
                        value(&p, &others[i].1)
                    }
                };
                out.push_str(&v);
            }
            Err(_) => out.push_str(&text[offset..end.min(text.len())]),
        }
        from = end.min(text.len());
    }
    out.push_str(&text[from..]);
    out
}
