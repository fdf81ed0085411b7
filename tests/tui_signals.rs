//! Every terminating signal restores the terminal (issue 28, item 3): the lesson app runs in a
//! pseudo-terminal made here, is sent SIGTERM, SIGHUP, SIGINT (with `kill`, as raw mode turns the
//! key off) or SIGQUIT, and must leave the terminal as it found it: the terminal settings back
//! in canonical mode with echo, and, after the last switch to the alternate screen, the escape
//! sequences that leave it, turn the mouse off and show the cursor.
#![cfg(unix)]

use std::fs::File;
use std::io::Read;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};

use crate::common::{find, wait_for};
use nix::pty::{Winsize, openpty};
use nix::sys::signal::{Signal, kill};
use nix::sys::termios::{LocalFlags, tcgetattr};
use nix::unistd::Pid;

const ENTER_ALTERNATE: &[u8] = b"\x1b[?1049h";
const LEAVE_ALTERNATE: &[u8] = b"\x1b[?1049l";
const MOUSE_ON: &[u8] = b"\x1b[?1000h";
const MOUSE_OFF: &[u8] = b"\x1b[?1000l";
const SHOW_CURSOR: &[u8] = b"\x1b[?25h";

fn rfind(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).rposition(|w| w == needle)
}

fn canonical_with_echo(flags: LocalFlags) -> bool {
    flags.contains(LocalFlags::ICANON) && flags.contains(LocalFlags::ECHO)
}

fn restored_after(signal: Signal) {
    let size = Winsize {
        ws_row: 30,
        ws_col: 100,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    let pty = openpty(Some(&size), None).expect("openpty");
    let before = tcgetattr(&pty.slave).expect("tcgetattr");
    assert!(
        canonical_with_echo(before.local_flags),
        "a fresh pty is canonical"
    );
    let data = tempfile::tempdir().expect("temp dir");
    let slave = || Stdio::from(pty.slave.try_clone().expect("dup"));
    let mut command = Command::new(env!("CARGO_BIN_EXE_springlab"));
    command
        .args(["lesson", "1", "--no-save"])
        .current_dir(data.path())
        .env("TERM", "xterm-256color")
        .env("SPRINGLAB_DATA_DIR", data.path())
        .stdin(slave())
        .stdout(slave())
        .stderr(slave());
    // SAFETY: setsid and setrlimit are plain system calls, safe between fork and exec.
    unsafe {
        command.pre_exec(|| {
            nix::unistd::setsid().map_err(std::io::Error::from)?;
            // SIGQUIT dumps core by default: not here.
            nix::sys::resource::setrlimit(nix::sys::resource::Resource::RLIMIT_CORE, 0, 0)
                .map_err(std::io::Error::from)
        });
    }
    let mut child = command.spawn().expect("spawn springlab");

    let output = Arc::new(Mutex::new(Vec::<u8>::new()));
    {
        let output = Arc::clone(&output);
        let mut master = File::from(pty.master.try_clone().expect("dup"));
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = master.read(&mut buf) {
                if n == 0 {
                    break;
                }
                output.lock().expect("lock").extend_from_slice(&buf[..n]);
            }
        });
    }
    let seen = |needle: &[u8]| find(&output.lock().expect("lock"), needle).is_some();
    wait_for("the app turning the mouse on", || seen(MOUSE_ON));
    let raw = tcgetattr(&pty.slave).expect("tcgetattr");
    assert!(
        !raw.local_flags.contains(LocalFlags::ICANON),
        "the app runs in raw mode"
    );

    kill(Pid::from_raw(child.id() as i32), signal).expect("kill");
    let status = child.wait().expect("wait");
    assert_eq!(
        status.signal(),
        Some(signal as i32),
        "{signal}: ended by the signal itself ({status})"
    );
    let after = tcgetattr(&pty.slave).expect("tcgetattr");
    assert!(
        canonical_with_echo(after.local_flags),
        "{signal}: terminal settings restored"
    );
    wait_for("the alternate screen left", || {
        let out = output.lock().expect("lock");
        let enter = rfind(&out, ENTER_ALTERNATE).expect("entered");
        find(&out[enter..], LEAVE_ALTERNATE).is_some()
    });
    let out = output.lock().expect("lock");
    let tail = &out[rfind(&out, ENTER_ALTERNATE).expect("entered")..];
    assert!(find(tail, MOUSE_OFF).is_some(), "{signal}: mouse off");
    let leave = rfind(tail, LEAVE_ALTERNATE).expect("left");
    assert!(
        find(&tail[leave..], SHOW_CURSOR).is_some(),
        "{signal}: cursor shown"
    );
}

#[test]
fn sigterm_restores_the_terminal() {
    restored_after(Signal::SIGTERM);
}

#[test]
fn sighup_restores_the_terminal() {
    restored_after(Signal::SIGHUP);
}

#[test]
fn sigint_sent_with_kill_restores_the_terminal() {
    restored_after(Signal::SIGINT);
}

#[test]
fn sigquit_restores_the_terminal() {
    restored_after(Signal::SIGQUIT);
}
