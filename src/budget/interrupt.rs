//! Ctrl-C: a flag that the long loops check, so that they stop between steps and remove what
//! they had not finished writing.

use std::sync::atomic::{AtomicBool, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// The run was stopped by Ctrl-C.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("interrupted (Ctrl-C); unfinished outputs were removed")]
pub struct Interrupted;

/// What Ctrl-C does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Set the flag; the command's loop stops at its next check and removes its unfinished
    /// outputs (`run`, `render`). A second Ctrl-C exits at once.
    Flag,
    /// Exit at once with status 130, saying so: for commands that write nothing before
    /// they finish (`study`, `bench`), whose runs cannot be stopped half-way.
    Exit,
}

/// Installs the handler (once; later calls do nothing).
pub fn install(mode: Mode) {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // Fails only when another handler is installed: then Ctrl-C keeps its default.
        let _ = ctrlc::set_handler(move || {
            if mode == Mode::Exit || INTERRUPTED.swap(true, Ordering::SeqCst) {
                use std::io::{IsTerminal, Write};
                let mut err = std::io::stderr();
                // On a terminal, leave the line of the progress bar first.
                let newline = if err.is_terminal() { "\n" } else { "" };
                let _ = writeln!(err, "{newline}springlab: {Interrupted}");
                std::process::exit(130);
            }
        });
    });
}

/// True once Ctrl-C was pressed.
#[must_use]
pub fn requested() -> bool {
    INTERRUPTED.load(Ordering::Relaxed)
}

/// `Err(Interrupted)` once Ctrl-C was pressed.
///
/// # Errors
/// [`Interrupted`] after Ctrl-C.
pub fn check() -> Result<(), Interrupted> {
    if requested() {
        Err(Interrupted)
    } else {
        Ok(())
    }
}
