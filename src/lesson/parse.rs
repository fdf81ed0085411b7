//! Reading a lesson file: its blocks of front matter, each parsed, checked and resolved into
//! a [`Lesson`] (format in the parent module's docs), every error at its file and line.

use std::path::Path;

use serde::Deserialize;

use super::{
    Goal, GoalKind, Hidden, Keys, Lesson, LessonError, Plot, PredictOption, Prediction, Step,
    TryItem, check_budget_at, check_omega_cost, default_settle_speed, numbers,
};
use crate::physics::Method;
use crate::scene;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HeaderToml {
    number: toml::Spanned<u32>,
    slug: toml::Spanned<String>,
    title: String,
    summary: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StepToml {
    title: String,
    scene: toml::Spanned<String>,
    params: Option<toml::Spanned<toml::Table>>,
    method: Option<toml::Spanned<String>>,
    dt: Option<toml::Spanned<f64>>,
    #[serde(default)]
    plots: Vec<Plot>,
    #[serde(default, rename = "try")]
    try_list: Vec<toml::Spanned<TryToml>>,
    goal: Option<toml::Spanned<Goal>>,
    predict: Option<toml::Spanned<PredictToml>>,
    hide: Option<toml::Spanned<HideToml>>,
    camera: Option<toml::Spanned<CameraToml>>,
    speed: Option<toml::Spanned<SpeedToml>>,
}

/// `speed = 0.5` (simulated seconds per wall second), or `speed = "machine"`: real time, or as
/// fast as the machine steps it when it cannot keep up (a step that knowingly runs below real
/// time, so not held to the real-time budget).
#[derive(Deserialize)]
#[serde(untagged)]
enum SpeedToml {
    Factor(f64),
    Word(String),
}

/// `camera = { body = 2 }`: the body the step's first view frames and the camera follows.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraToml {
    body: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HideToml {
    title: Option<String>,
    #[serde(default, rename = "try")]
    try_items: Vec<usize>,
    from: Option<String>,
    #[serde(default)]
    goal: bool,
    #[serde(default)]
    plots: Vec<Plot>,
    #[serde(default)]
    limit: bool,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum TryToml {
    Text(String),
    Keyed { text: String, keys: String },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PredictToml {
    question: String,
    options: Vec<OptionToml>,
    answer: usize,
    keys: Option<String>,
    expect: Option<GoalKind>,
    time: Option<f64>,
    speed: Option<f64>,
    body: Option<usize>,
    #[serde(default)]
    explain: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OptionToml {
    text: String,
    keys: Option<String>,
    expect: Option<GoalKind>,
    time: Option<f64>,
    speed: Option<f64>,
    body: Option<usize>,
}

/// Parses lesson text; `file` names it in errors and `base_dir` resolves scene file paths.
///
/// # Errors
/// A [`LessonError`] naming the file and line: missing or unterminated front matter, TOML errors
/// (with column), unknown keys, a scene or parameter that does not build, an unknown method, a
/// non-positive dt or goal time, a lesson without steps.
pub fn parse(text: &str, file: &str, base_dir: Option<&Path>) -> Result<Lesson, LessonError> {
    let err = |line: usize, column: Option<usize>, message: String| LessonError {
        file: file.to_string(),
        line,
        column,
        // What the file wrote is cut where it is quoted (a scene's name, a key, a value); this
        // bounds the rest, which lists what is known (the scenes, the parameters).
        message: scene::file::excerpt(&message, 4 * scene::file::MAX_MESSAGE),
    };
    // A byte order mark is no content (scene files accept it too).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines: Vec<&str> = text.lines().collect();
    // Blocks: (kind "lesson" | "step", first front-matter line index, toml text, body text).
    let mut blocks: Vec<(bool, usize, String, String)> = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let trimmed = lines[i].trim_end();
        let is_step = trimmed == "+++ step";
        if trimmed == "+++" || is_step {
            if !is_step && !blocks.is_empty() {
                return Err(err(
                    i + 1,
                    None,
                    "expected `+++ step` to start a step (the lesson header comes once, first)"
                        .into(),
                ));
            }
            let start = i + 1;
            let end = (start..lines.len())
                .find(|&j| lines[j].trim_end() == "+++")
                .ok_or_else(|| {
                    err(
                        i + 1,
                        None,
                        "front matter opened here is never closed with `+++`".into(),
                    )
                })?;
            let toml_text = lines[start..end].join("\n");
            let body_end = (end + 1..lines.len())
                .find(|&j| matches!(lines[j].trim_end(), "+++ step" | "+++"))
                .unwrap_or(lines.len());
            let body = lines[end + 1..body_end].join("\n").trim().to_string();
            blocks.push((is_step, start, toml_text, body));
            i = body_end;
        } else if blocks.is_empty() && !trimmed.is_empty() {
            return Err(err(
                i + 1,
                None,
                "expected the lesson header: a `+++` line, TOML, and `+++`".into(),
            ));
        } else {
            i += 1;
        }
    }
    // Line and column of a byte offset inside a front-matter block that starts at line index `start`.
    let position = |start: usize, toml_text: &str, offset: usize| {
        let before = &toml_text[..offset.min(toml_text.len())];
        let line = start + 1 + before.matches('\n').count();
        let column = before
            .rfind('\n')
            .map_or(before.len(), |p| before.len() - p - 1)
            + 1;
        (line, column)
    };
    let toml_err = |start: usize, toml_text: &str, e: toml::de::Error| {
        let (line, column) = e
            .span()
            .map_or((start + 1, 1), |s| position(start, toml_text, s.start));
        err(line, Some(column), e.message().trim().to_string())
    };
    // Bounded before the TOML reader builds its tree.
    for (_, start, toml_text, _) in &blocks {
        if let Err(e) = scene::file::bounds::check(toml_text) {
            let (line, column) = position(*start, toml_text, e.offset);
            return Err(err(line, Some(column), e.message));
        }
    }

    let Some((false, hstart, htext, _)) = blocks.first() else {
        return Err(err(
            1,
            None,
            "expected the lesson header: a `+++` line, TOML, and `+++`".into(),
        ));
    };
    let header: HeaderToml = toml::from_str(htext).map_err(|e| toml_err(*hstart, htext, e))?;
    let mut steps = Vec::new();
    for (_, start, toml_text, body) in blocks.iter().skip(1) {
        let st: StepToml = toml::from_str(toml_text).map_err(|e| toml_err(*start, toml_text, e))?;
        let at = |offset: usize| position(*start, toml_text, offset);
        let method = match &st.method {
            Some(m) => Some(m.get_ref().parse::<Method>().map_err(|e| {
                let (l, c) = at(m.span().start);
                err(l, Some(c), e.to_string())
            })?),
            None => None,
        };
        if let Some(dt) = &st.dt
            && !(*dt.get_ref() > 0.0 && dt.get_ref().is_finite())
        {
            let (l, c) = at(dt.span().start);
            return Err(err(
                l,
                Some(c),
                format!("dt = {}: expected a time step in seconds > 0", dt.get_ref()),
            ));
        }
        if let Some(goal) = &st.goal {
            let g = goal.get_ref();
            let valid = g.time > 0.0 && g.time.is_finite() && g.speed > 0.0;
            if !valid {
                let (l, c) = at(goal.span().start);
                return Err(err(
                    l,
                    Some(c),
                    "goal: expected time > 0 (s) and speed > 0 (m/s)".into(),
                ));
            }
        }
        let params: Vec<String> = st
            .params
            .as_ref()
            .map(|p| {
                p.get_ref()
                    .iter()
                    .map(|(k, v)| format!("{k}={}", value_text(v)))
                    .collect()
            })
            .unwrap_or_default();
        // Where a scene's error points: the `scene` line for its name, the parameter's own
        // key for a parameter, else the step's first line.
        let scene_at = at(st.scene.span().start);
        let param_at = |key: &str| -> (usize, Option<usize>) {
            let Some(p) = &st.params else {
                return (*start, None);
            };
            let span = p.span();
            let inside = &toml_text[span.start..span.end.min(toml_text.len())];
            let found = inside.match_indices(key).find(|(i, _)| {
                let after = inside[i + key.len()..].trim_start();
                let before = inside[..*i].chars().next_back();
                after.starts_with('=') && before.is_none_or(|c| !(c.is_alphanumeric() || c == '_'))
            });
            let (l, c) = at(span.start + found.map_or(0, |(i, _)| i));
            (l, Some(c))
        };
        let mut try_list = Vec::new();
        for item in st.try_list {
            let (l, c) = at(item.span().start);
            try_list.push(match item.into_inner() {
                TryToml::Text(text) => TryItem { text, keys: None },
                TryToml::Keyed { text, keys } => {
                    let parsed = Keys::parse(&keys).map_err(|m| err(l, Some(c), m))?;
                    TryItem {
                        text,
                        keys: Some(parsed),
                    }
                }
            });
        }
        let hide = match st.hide {
            None => Hidden::default(),
            Some(h) => {
                let (l, c) = at(h.span().start);
                let h = h.into_inner();
                let hidden = Hidden {
                    title: h.title,
                    try_items: h.try_items.iter().map(|n| n.wrapping_sub(1)).collect(),
                    from: h.from,
                    goal: h.goal,
                    plots: h.plots,
                    limit: h.limit,
                };
                check_hidden(&hidden, st.predict.is_some(), try_list.len(), body)
                    .map_err(|m| err(l, Some(c), m))?;
                hidden
            }
        };
        let goal_span = st.goal.as_ref().map(|g| at(g.span().start));
        let goal = st.goal.map(toml::Spanned::into_inner);
        if let (Some(g), Some((l, c))) = (&goal, goal_span) {
            let keyed = |i: usize| try_list.get(i).is_some_and(|t| t.keys.is_some());
            match g.try_item {
                Some(n) if n == 0 || !keyed(n - 1) => {
                    return Err(err(
                        l,
                        Some(c),
                        format!(
                            "goal: try = {n}: expected the number (from 1) of a try item with keys"
                        ),
                    ));
                }
                None if !(0..try_list.len()).any(keyed) => {
                    return Err(err(
                        l,
                        Some(c),
                        "goal: expected a try item with `keys` that reaches it (the tests play it)"
                            .into(),
                    ));
                }
                _ => {}
            }
            if g.body.is_some() && g.kind != GoalKind::Settle {
                return Err(err(
                    l,
                    Some(c),
                    "goal: `body` applies to `settle` only".into(),
                ));
            }
        }
        let predict = match st.predict {
            None => None,
            Some(p) => {
                let (l, c) = at(p.span().start);
                Some(prediction(p.into_inner()).map_err(|m| err(l, Some(c), m))?)
            }
        };
        // Placeholders: known names, methods and scenes (computed when the step opens).
        if let Some((offset, message)) = numbers::check(body).into_iter().next() {
            let line = body_line(&lines, *start, offset);
            return Err(err(line, None, message));
        }
        let camera = st.camera.map(|c| (at(c.span().start), c.into_inner().body));
        // The speed, and the rate the real-time budget holds it to (0: none, for "machine").
        let (speed, budget_speed) = match st.speed {
            None => (None, 1.0),
            Some(v) => match v.get_ref() {
                SpeedToml::Factor(f) if (1.0 / 64.0..=64.0).contains(f) => (Some(*f), *f),
                SpeedToml::Word(w) if w == "machine" => (Some(1.0), 0.0),
                _ => {
                    let (l, c) = at(v.span().start);
                    return Err(err(
                        l,
                        Some(c),
                        "speed: expected simulated seconds per wall second from 1/64 to 64, or \"machine\""
                            .into(),
                    ));
                }
            },
        };
        let step = Step {
            speed,
            camera_body: camera.map(|c| c.1),
            title: st.title,
            scene: st.scene.get_ref().clone(),
            params,
            method,
            dt: st.dt.map(|d| *d.get_ref()),
            plots: st.plots,
            try_list,
            goal,
            predict,
            hide,
            text: body.clone(),
            base_dir: base_dir.map(Path::to_path_buf),
        };
        // Validate now, so a broken lesson shows its error in the menu, not mid-lesson.
        let scene = step.build_scene().map_err(|e| {
            let (line, column) = match &e {
                scene::SceneError::UnknownScene { .. } => (scene_at.0, Some(scene_at.1)),
                scene::SceneError::Param(
                    scene::params::ParamError::UnknownKey { key, .. }
                    | scene::params::ParamError::BadValue { key, .. }
                    | scene::params::ParamError::OutOfRange { key, .. },
                ) => param_at(key),
                _ => (*start, None),
            };
            err(line, column, format!("step \"{}\": {e}", step.title))
        })?;
        if let Some(((l, c), body)) = camera
            && !(1..=scene.bodies.len()).contains(&body)
        {
            return Err(err(
                l,
                Some(c),
                format!(
                    "camera: body = {body}: expected the number (from 1) of one of the scene's {} bodies",
                    scene.bodies.len()
                ),
            ));
        }
        check_budget_at(
            &scene,
            scene.dt,
            step.horizon(),
            budget_speed,
            &format!("step \"{}\"", step.title),
        )
        .map_err(|m| err(*start, None, m))?;
        if numbers::needs_omega(body) {
            check_omega_cost(&scene, &format!("step \"{}\"", step.title))
                .map_err(|m| err(*start, None, m))?;
        }
        // `{{param:KEY}}`: a parameter of its scene.
        if let Some((offset, message)) = numbers::check_params(body, &step.scene).into_iter().next()
        {
            let line = body_line(&lines, *start, offset);
            return Err(err(line, None, message));
        }
        steps.push(step);
    }
    if steps.is_empty() {
        return Err(err(
            lines.len().max(1),
            None,
            "a lesson needs at least one `+++ step`".into(),
        ));
    }
    let header_lines = (
        position(*hstart, htext, header.number.span().start).0,
        position(*hstart, htext, header.slug.span().start).0,
    );
    Ok(Lesson {
        number: header.number.into_inner(),
        slug: header.slug.into_inner(),
        header_lines,
        title: header.title,
        summary: header.summary,
        steps,
        source: file.to_string(),
    })
}

/// Turns every lesson whose number or slug an earlier one (in number order, then file order)
/// already has into an error at the line of its `number` or `slug`, naming the other file: two
/// lessons with one number would make `springlab lesson 3` ambiguous.
pub(super) fn reject_duplicates(lessons: &mut [Result<Lesson, LessonError>]) {
    // (number, slug, file:line of its number, file:line of its slug)
    let mut seen: Vec<(u32, String, String, String)> = Vec::new();
    for entry in lessons.iter_mut() {
        let Ok(lesson) = entry else { continue };
        let by_number = seen.iter().find(|(n, ..)| *n == lesson.number);
        let by_slug = seen.iter().find(|(_, s, ..)| *s == lesson.slug);
        let error = match (by_number, by_slug) {
            (Some((n, _, at, _)), _) => Some((
                lesson.header_lines.0,
                format!(
                    "lesson number {n} is already used by {at}; give each lesson its own number"
                ),
            )),
            (None, Some((_, slug, _, at))) => Some((
                lesson.header_lines.1,
                format!(
                    "lesson slug \"{slug}\" is already used by {at}; give each lesson its own slug"
                ),
            )),
            (None, None) => None,
        };
        match error {
            Some((line, message)) => {
                *entry = Err(LessonError {
                    file: lesson.source.clone(),
                    line,
                    column: None,
                    message,
                });
            }
            None => seen.push((
                lesson.number,
                lesson.slug.clone(),
                format!("{}:{}", lesson.source, lesson.header_lines.0),
                format!("{}:{}", lesson.source, lesson.header_lines.1),
            )),
        }
    }
}

/// The 1-based file line of byte `offset` of the body of the block whose front matter starts at
/// line index `start`.
fn body_line(lines: &[&str], start: usize, offset: usize) -> usize {
    // The body starts after the closing `+++`; leading blank lines were trimmed.
    let close = (start..lines.len())
        .find(|&j| lines[j].trim_end() == "+++")
        .unwrap_or(start);
    let first = (close + 1..lines.len())
        .find(|&j| !lines[j].trim().is_empty())
        .unwrap_or(close + 1);
    let mut rest = offset;
    for (j, line) in lines.iter().enumerate().skip(first) {
        if rest <= line.len() {
            return j + 1;
        }
        rest -= line.len() + 1;
    }
    lines.len()
}

/// Checks a step's `hide`: only with a prediction, try items that exist, `from` the start of a
/// line of the text (no placeholder in it).
fn check_hidden(h: &Hidden, predicts: bool, items: usize, body: &str) -> Result<(), String> {
    if !predicts {
        return Err(
            "hide: expected a `predict` in the same step (it hides until the answer)".into(),
        );
    }
    if let Some(&n) = h.try_items.iter().find(|&&i| i >= items) {
        return Err(format!(
            "hide: try = {}: expected the number (from 1) of a try item, at most {items}",
            n.wrapping_add(1)
        ));
    }
    if let Some(from) = &h.from {
        let found = body
            .lines()
            .any(|l| l.trim_start().starts_with(from.as_str()));
        if from.trim().is_empty() || from.contains("{{") || !found {
            return Err(format!(
                "hide: from = \"{from}\": expected the first words of a line of the step's text \
                 (without placeholders)"
            ));
        }
    }
    Ok(())
}

/// A prediction from its front matter, each option's claim resolved.
fn prediction(p: PredictToml) -> Result<Prediction, String> {
    if p.options.len() < 2 || p.options.len() > 6 {
        return Err("predict: expected 2 to 6 options".into());
    }
    if p.answer == 0 || p.answer > p.options.len() {
        return Err(format!(
            "predict: answer = {}: expected the number (from 1) of an option, at most {}",
            p.answer,
            p.options.len()
        ));
    }
    let mut options = Vec::new();
    for (i, o) in p.options.into_iter().enumerate() {
        let n = i + 1;
        let keys = o.keys.or_else(|| p.keys.clone()).ok_or_else(|| {
            format!("predict: option {n}: expected `keys` (on the option or the prediction)")
        })?;
        let keys = Keys::parse(&keys).map_err(|m| format!("predict: option {n}: {m}"))?;
        let kind = o.expect.or(p.expect).ok_or_else(|| {
            format!("predict: option {n}: expected `expect` = survive, diverge or settle")
        })?;
        let time = o.time.or(p.time).ok_or_else(|| {
            format!("predict: option {n}: expected `time` (s) of the run that decides it")
        })?;
        let speed = o.speed.or(p.speed).unwrap_or_else(default_settle_speed);
        if !(time > 0.0 && time.is_finite() && speed > 0.0) {
            return Err(format!(
                "predict: option {n}: expected time > 0 (s) and speed > 0 (m/s)"
            ));
        }
        let body = o.body.or(p.body);
        if body.is_some() && kind != GoalKind::Settle {
            return Err(format!(
                "predict: option {n}: `body` applies to `settle` only"
            ));
        }
        options.push(PredictOption {
            claim: Goal {
                kind,
                time,
                speed,
                body,
                try_item: None,
                text: o.text.clone(),
            },
            text: o.text,
            keys,
        });
    }
    Ok(Prediction {
        question: p.question,
        options,
        answer: p.answer - 1,
        explain: p.explain,
    })
}

/// TOML value → the text `--set` accepts (`3`, `0.5`, `[0, 1]`, `[0.0, 2.0, 0.0]`).
fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::Array(items) => {
            let inner: Vec<String> = items.iter().map(value_text).collect();
            format!("[{}]", inner.join(", "))
        }
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}
