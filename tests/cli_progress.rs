//! The progress bar of a long command on a terminal (issue 29: progress on a terminal): a
//! study runs with its standard error on a pseudo-terminal made here, 80 columns wide, and what
//! it drew must read as one bar: every line of it within the 80 columns (a wrapped line is
//! redrawn below itself at every tick), no line left behind (the bar shown twice left its first
//! drawing on the screen), and a count of runs ended that never goes back (it once showed the
//! index of the run just started, which the costliest-first order makes jump about).
#![cfg(unix)]

use std::fs::File;
use std::io::Read;
use std::process::{Command, Stdio};

use nix::pty::{Winsize, openpty};

/// The text of `bytes` without its escape sequences (`ESC [ … letter`).
fn without_escapes(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let mut out = String::new();
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\x1b' && chars.peek() == Some(&'[') {
            chars.next();
            for d in chars.by_ref() {
                if d.is_ascii_alphabetic() {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

#[test]
fn a_study_draws_one_bar_within_the_terminal_counting_runs_ended() {
    const COLUMNS: u16 = 80;
    let size = Winsize {
        ws_row: 24,
        ws_col: COLUMNS,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    let pty = openpty(Some(&size), None).expect("openpty");
    // About three seconds of runs on two cores: the bar shows after one.
    let mut child = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(["study", "resolution", "cloth-sphere"])
        .env("TERM", "xterm-256color")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::from(pty.slave.try_clone().expect("dup")))
        .spawn()
        .expect("spawn springlab");
    let mut master = File::from(pty.master.try_clone().expect("dup"));
    let reader = std::thread::spawn(move || {
        let mut drawn = Vec::new();
        let mut buf = [0u8; 4096];
        // Ends with an error (EIO) once no one holds the terminal's other end.
        while let Ok(n) = master.read(&mut buf) {
            if n == 0 {
                break;
            }
            drawn.extend_from_slice(&buf[..n]);
        }
        drawn
    });
    let mut table = String::new();
    child
        .stdout
        .take()
        .expect("stdout")
        .read_to_string(&mut table)
        .expect("read the table");
    assert!(child.wait().expect("wait").success());
    drop(pty);
    let drawn = without_escapes(&reader.join().expect("reader"));
    assert!(table.contains("study resolution"), "{table}");

    // The announcement of the work is the one line ended; the bar is redrawn in place.
    let lines: Vec<&str> = drawn.split('\n').collect();
    assert_eq!(lines.len(), 2, "one line and the bar: {drawn:?}");
    assert!(lines[0].contains("Ctrl-C stops it"), "{drawn:?}");
    let drawings: Vec<&str> = (lines[1].split('\r'))
        .map(str::trim_end)
        .filter(|d| !d.is_empty())
        .collect();
    let counts: Vec<(u32, u32)> = (drawings.iter())
        .filter_map(|d| {
            let word = d.split(' ').find(|w| w.contains('/'))?;
            let (done, all) = word.split_once('/')?;
            Some((done.parse().ok()?, all.parse().ok()?))
        })
        .collect();
    assert!(counts.len() >= 2, "the bar drawn: {drawings:?}");
    for d in &drawings {
        assert!(
            d.chars().count() <= usize::from(COLUMNS),
            "{} columns: {d:?}",
            d.chars().count()
        );
    }
    assert!(
        counts
            .windows(2)
            .all(|w| w[0].0 <= w[1].0 && w[0].1 == w[1].1),
        "runs ended, never fewer: {counts:?}"
    );
    assert!(counts.iter().all(|&(done, all)| done <= all), "{counts:?}");
}
