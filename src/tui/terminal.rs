//! The terminal around the app: opening it on the menu or a lesson, raw mode and the
//! alternate screen, restored on return, on error, on panic and on every terminating signal
//! (SIGTERM, SIGHUP, SIGINT sent with `kill`, SIGQUIT): a thread of its own waits for the
//! signal (`signal_hook::iterator`, no code in the signal handler itself), takes standard
//! output's lock so that no frame is drawn after it, writes the escape sequences that leave the
//! app's modes, puts back the terminal settings saved before raw mode, then lets the signal end
//! the process as it would have (so the shell still sees "terminated by SIGTERM"). The
//! student's progress needs no saving there: it is saved whenever it changes.

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
    /// The `--homework` crate, if any.
    pub homework: Option<std::path::PathBuf>,
    /// `--theme`: the background the colours are for (`None`: ask the terminal).
    pub theme: Option<super::Background>,
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
    let notice = options.progress.notice().map(str::to_string);
    let mut terminal = init_terminal().context("cannot set up the terminal")?;
    // Ask the terminal before anything else reads its input (raw mode is on).
    let theme = theme.on(options.theme.unwrap_or_else(super::theme::detect));
    let graphics = Graphics::detect();
    let default = if graphics.protocol.is_some() {
        ViewMode::Raster
    } else {
        ViewMode::HalfBlocks
    };
    let mut app = App::new(lessons, theme)
        .with_display(view.unwrap_or(default), graphics, ColourDepth::from_env())
        .with_progress(options.progress)
        .with_lessons_dir(options.lessons_dir)
        .with_homework(options.homework);
    if let Ok(size) = terminal.size() {
        app.resize(size.width, size.height);
    }
    if let Some(i) = open
        && let Err(e) = app.open_lesson(i)
    {
        restore_terminal();
        bail!(e);
    }
    // Said once: a progress file that was kept aside or is not a file (see `Progress::load`).
    if let Some(n) = notice
        && let Some(run) = app.lesson_mut()
    {
        run.set_message(n);
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
    #[cfg(unix)]
    signals::install();
    let terminal = ratatui::try_init()?;
    #[cfg(unix)]
    signals::arm(true);
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
    #[cfg(unix)]
    signals::arm(false);
    leave_clean();
    ratatui::restore();
}

/// The terminating signals' handlers (module docs).
#[cfg(unix)]
mod signals {
    use std::sync::OnceLock;
    use std::sync::atomic::{AtomicBool, Ordering};

    use std::io::Write;

    use rustix::termios::{OptionalActions, Termios, tcgetattr, tcsetattr};
    use signal_hook::consts::{SIGHUP, SIGINT, SIGQUIT, SIGTERM};
    use signal_hook::iterator::Signals;

    /// The terminal's settings before raw mode.
    static SAVED: OnceLock<Termios> = OnceLock::new();
    /// True while the app has the terminal (between set-up and restore).
    static ARMED: AtomicBool = AtomicBool::new(false);

    /// What [`super::restore_terminal`] sends: the mouse modes off (SGR, urxvt, any-event,
    /// button-event, normal tracking), the screen emptied, the cursor home, the alternate screen
    /// left, the cursor shown.
    const LEAVE: &[u8] = b"\x1b[?1006l\x1b[?1015l\x1b[?1003l\x1b[?1002l\x1b[?1000l\
        \x1b[2J\x1b[1;1H\x1b[?1049l\x1b[?25h";

    /// Saves the terminal's settings (before raw mode) and starts the thread that answers the
    /// terminating signals, once.
    pub(super) fn install() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            if let Ok(t) = tcgetattr(rustix::stdio::stdin()) {
                let _ = SAVED.set(t);
            }
            // Fails only when the signals cannot be caught: then they keep their default.
            let Ok(mut signals) = Signals::new([SIGTERM, SIGHUP, SIGINT, SIGQUIT]) else {
                return;
            };
            let _ = std::thread::Builder::new()
                .name("springlab-signals".into())
                .spawn(move || {
                    if let Some(sig) = signals.forever().next() {
                        // Held until the process ends: the app draws nothing after this.
                        let mut out = std::io::stdout().lock();
                        if ARMED.swap(false, Ordering::SeqCst) {
                            leave(&mut out);
                        }
                        let _ = signal_hook::low_level::emulate_default_handler(sig);
                        // A signal whose default is not to end the process: end it anyway.
                        std::process::exit(128 + sig);
                    }
                });
        });
    }

    /// Whether a signal must restore the terminal.
    pub(super) fn arm(on: bool) {
        ARMED.store(on, Ordering::SeqCst);
    }

    /// Restores the terminal from the signal thread.
    fn leave(out: &mut impl Write) {
        let _ = out.write_all(LEAVE);
        let _ = out.flush();
        if let Some(t) = SAVED.get() {
            let _ = tcsetattr(rustix::stdio::stdin(), OptionalActions::Now, t);
        }
    }
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
