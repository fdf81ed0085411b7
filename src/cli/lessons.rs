//! `springlab` (the lesson menu), `springlab lesson <N|slug>` and `springlab lessons`.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

use crate::lesson::{self, Lesson, LessonError};
use crate::tui;

/// The embedded lessons, or those of `dir`.
///
/// # Errors
/// `dir` cannot be read.
pub fn load(dir: Option<&Path>) -> anyhow::Result<Vec<Result<Lesson, LessonError>>> {
    match dir {
        None => Ok(lesson::builtin()),
        Some(dir) => {
            let lessons = lesson::load_dir(dir).with_context(|| {
                format!("--lessons {}: cannot read the directory", dir.display())
            })?;
            if lessons.is_empty() {
                bail!(
                    "--lessons {}: no lesson files (*.md) in the directory",
                    dir.display()
                );
            }
            Ok(lessons)
        }
    }
}

/// `springlab`: the lesson menu.
///
/// # Errors
/// No terminal, an unreadable `--lessons` directory, or a terminal failure.
pub fn menu(
    dir: Option<&Path>,
    view: Option<tui::ViewMode>,
    (no_save, theme): (bool, Option<tui::Background>),
) -> anyhow::Result<()> {
    tui::run(load(dir)?, None, view, options(dir, (no_save, theme), None))
}

/// Where progress goes (`--no-save`: nowhere), the lessons' directory, the theme and the homework.
fn options(
    dir: Option<&Path>,
    (no_save, theme): (bool, Option<tui::Background>),
    homework: Option<PathBuf>,
) -> tui::RunOptions {
    let progress = match tui::Progress::default_path() {
        Some(path) if !no_save => tui::Progress::load(&path),
        _ => tui::Progress::in_memory(),
    };
    tui::RunOptions {
        progress,
        lessons_dir: dir.map(Path::to_path_buf),
        homework,
        theme,
    }
}

/// `springlab lesson <N|slug>`: the app, opened on that lesson.
///
/// # Errors
/// No such lesson (the message lists them), a lesson that failed to load, `--homework` not a
/// homework crate, no terminal.
pub fn open(
    dir: Option<&Path>,
    which: &str,
    view: Option<tui::ViewMode>,
    (no_save, theme): (bool, Option<tui::Background>),
    homework: Option<&Path>,
) -> anyhow::Result<()> {
    let lessons = load(dir)?;
    let index = find(&lessons, which)?;
    if let Some(h) = homework {
        crate::grade::external::assignment_of(h).map_err(|e| anyhow::anyhow!("--homework: {e}"))?;
    }
    tui::run(
        lessons,
        Some(index),
        view,
        options(dir, (no_save, theme), homework.map(Path::to_path_buf)),
    )
}

/// The index of lesson `which` (a number or a slug) in `lessons`.
///
/// # Errors
/// No lesson has that number or slug; the message lists the lessons.
pub fn find(lessons: &[Result<Lesson, LessonError>], which: &str) -> anyhow::Result<usize> {
    if let Some(i) = tui::find_lesson(lessons, which) {
        return Ok(i);
    }
    let known: Vec<String> = lessons
        .iter()
        .filter_map(|l| l.as_ref().ok())
        .map(|l| format!("{} ({})", l.number, l.slug))
        .collect();
    let broken = lessons.iter().filter(|l| l.is_err()).count();
    let mut message = format!(
        "no lesson `{which}`; lessons: {}",
        if known.is_empty() {
            "none".to_string()
        } else {
            known.join(", ")
        }
    );
    if broken > 0 {
        message.push_str(&format!(
            " ({broken} failed to load: `springlab lessons` shows why)"
        ));
    }
    bail!(message)
}

/// `springlab lessons`: one line per lesson; a lesson that failed to load prints its error.
///
/// # Errors
/// Some lesson failed to load (after listing all of them), or stdout cannot be written.
pub fn list(dir: Option<&Path>) -> anyhow::Result<()> {
    let lessons = load(dir)?;
    let mut out = std::io::stdout().lock();
    let mut broken = 0;
    for l in &lessons {
        match l {
            Ok(l) => writeln!(
                out,
                "{:>2}. {} ({}, {} steps): {}",
                l.number,
                l.title,
                l.slug,
                l.steps.len(),
                l.summary
            )?,
            Err(e) => {
                broken += 1;
                writeln!(out, " !  {e}")?;
            }
        }
    }
    if lessons.is_empty() {
        writeln!(out, "no lessons")?;
    }
    out.flush()?;
    if broken > 0 {
        bail!("{broken} lesson file(s) failed to load (marked with ! above)");
    }
    Ok(())
}
