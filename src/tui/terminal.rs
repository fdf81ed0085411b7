//! The terminal around the app: opening it on the menu or a lesson, raw mode and the
//! alternate screen, restored on return, on error and on panic.

use std::io::{IsTerminal, stdout};

use anyhow::{Context as _, bail};
use ratatui::DefaultTerminal;
use ratatui::crossterm::event::{DisableMouseCapture, EnableMouseCapture};
use ratatui::crossterm::execute;

use crate::lesson::{Lesson, LessonError};

use super::{App, ColourDepth, Graphics, Progress, Protocol, Theme, ViewMode, raster};

/// Where the app keeps progress and where its lessons came from.
#[derive(Debug, Default)]
pub struct RunOptions {
    /// The student's progress (a file, or memory only with `--no-save`).
    pub progress: Progress,
    /// The `--lessons` directory, if any.
    pub lessons_dir: Option<std::path::PathBuf>,
}

/// Opens the app on the menu, or on lesson `open` (an index into `lessons`), and runs it until
/// the user quits. The terminal is restored on return, on error and on panic.
///
/// # Errors
/// Standard output is not a terminal, the lesson does not open, or the terminal fails.
pub fn run(
    lessons: Vec<Result<Lesson, LessonError>>,
    open: Option<usize>,
    view: Option<ViewMode>,
    options: RunOptions,
) -> anyhow::Result<()> {
    if !stdout().is_terminal() || !std::io::stdin().is_terminal() {
        bail!(
            "the lesson app needs a terminal; `springlab lessons` lists the lessons, \
             `springlab run <scene>` runs a scene headless"
        );
    }
    let theme = Theme::from_env();
    let mut terminal = init_terminal().context("cannot set up the terminal")?;
    // Ask the terminal before anything else reads its input (raw mode is on).
    let graphics = Graphics::detect();
    let default = if graphics.protocol.is_some() {
        ViewMode::Raster
    } else {
        ViewMode::HalfBlocks
    };
    let mut app = App::new(lessons, theme)
        .with_display(view.unwrap_or(default), graphics, ColourDepth::from_env())
        .with_progress(options.progress)
        .with_lessons_dir(options.lessons_dir);
    if let Ok(size) = terminal.size() {
        app.resize(size.width, size.height);
    }
    if let Some(i) = open
        && let Err(e) = app.open_lesson(i)
    {
        restore_terminal();
        bail!(e);
    }
    if view == Some(ViewMode::Raster)
        && graphics.protocol.is_none()
        && let Some(run) = app.lesson_mut()
    {
        run.set_message("no raster view: the terminal answered no graphics protocol (halfblocks)");
    }
    let result = execute!(stdout(), EnableMouseCapture)
        .map_err(anyhow::Error::from)
        .and_then(|()| app.run(&mut terminal));
    if graphics.protocol == Some(Protocol::Kitty) {
        use std::io::Write as _;
        let _ = write!(stdout(), "{}", raster::kitty_delete(graphics.tmux_wrap));
    }
    restore_terminal();
    result
}

/// Sets the terminal up for the app: raw mode, the alternate screen, and a panic hook that
/// restores it (see [`restore_terminal`]) before the panic message is printed.
///
/// # Errors
/// The terminal cannot be set up.
pub fn init_terminal() -> std::io::Result<DefaultTerminal> {
    let terminal = ratatui::try_init()?;
    // ratatui's hook (installed by `try_init`) leaves raw mode and the alternate screen; ours
    // runs first and empties the screen and turns the mouse off.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        leave_clean();
        hook(info);
    }));
    Ok(terminal)
}

/// Restores the terminal: the alternate screen emptied and left, raw mode and the mouse off.
///
/// The alternate screen is emptied first because tmux, when the window changed size while the
/// app ran, reflows what the alternate screen holds into the shell's screen on leaving it
/// (lines wider than the shell's old width wrap into its history and come back above the prompt);
/// an empty screen leaves nothing.
pub fn restore_terminal() {
    leave_clean();
    ratatui::restore();
}

fn leave_clean() {
    use ratatui::crossterm::cursor::MoveTo;
    use ratatui::crossterm::terminal::{Clear, ClearType};
    let _ = execute!(
        stdout(),
        DisableMouseCapture,
        Clear(ClearType::All),
        MoveTo(0, 0)
    );
}
