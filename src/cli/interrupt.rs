//! Ctrl-C and the terminating signals (SIGTERM, SIGHUP, SIGQUIT): a flag that the long loops
//! check, so that they stop between steps and remove what they had not finished writing.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, LazyLock};

/// Set by Ctrl-C or a terminating signal (shared with `signal_hook::flag`'s handlers): the
/// outputs' own flag, so that one waiting for a FIFO's reader gives up too.
static INTERRUPTED: &LazyLock<Arc<AtomicBool>> = &crate::output::STOP;
/// The terminating signal that set [`INTERRUPTED`], 0 for Ctrl-C.
static SIGNAL: LazyLock<Arc<AtomicUsize>> = LazyLock::new(Arc::default);

/// The number of the signal that stopped the run, 0 for Ctrl-C.
fn signal() -> i32 {
    i32::try_from(SIGNAL.load(Ordering::SeqCst)).unwrap_or(0)
}

/// The run was stopped by Ctrl-C or a terminating signal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}; unfinished outputs were removed", cause())]
pub struct Interrupted;

/// What stopped the run, in words.
fn cause() -> String {
    match signal() {
        0 => "interrupted (Ctrl-C)".to_string(),
        sig => format!("stopped by {}", signal_name(sig)),
    }
}

#[cfg(unix)]
fn signal_name(sig: i32) -> String {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGQUIT, SIGTERM};
    match sig {
        SIGTERM => "SIGTERM".into(),
        SIGHUP => "SIGHUP".into(),
        SIGQUIT => "SIGQUIT".into(),
        SIGINT => "SIGINT".into(),
        other => format!("signal {other}"),
    }
}

#[cfg(not(unix))]
fn signal_name(sig: i32) -> String {
    format!("signal {sig}")
}

/// The exit status after [`Interrupted`]: 130 for Ctrl-C, else 128 + the signal's number (143
/// for SIGTERM), as a shell reports a process the signal ended.
#[must_use]
pub fn exit_status() -> u8 {
    match signal() {
        0 => 130,
        sig => u8::try_from(128 + sig).unwrap_or(1),
    }
}

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

/// Installs the handlers (once; later calls do nothing). In [`Mode::Flag`], SIGTERM, SIGHUP and
/// SIGQUIT set the flag as Ctrl-C does (a second one exits at once); in [`Mode::Exit`] they keep
/// their default action.
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
        #[cfg(unix)]
        if mode == Mode::Flag {
            use signal_hook::consts::{SIGHUP, SIGQUIT, SIGTERM};
            for sig in [SIGTERM, SIGHUP, SIGQUIT] {
                // In this order: a second signal exits at once with 128 + its number; the
                // first records which signal it was and sets the flag. Each registration
                // fails only when the signal cannot be caught: then it keeps its default.
                let _ = signal_hook::flag::register_conditional_shutdown(
                    sig,
                    128 + sig,
                    Arc::clone(INTERRUPTED),
                );
                let _ = signal_hook::flag::register_usize(
                    sig,
                    Arc::clone(&SIGNAL),
                    usize::try_from(sig).unwrap_or(0),
                );
                let _ = signal_hook::flag::register(sig, Arc::clone(INTERRUPTED));
            }
        }
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
