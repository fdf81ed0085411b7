//! The lesson app stays responsive under any burst of keys (issue 27, item 8): the cloth of
//! lesson 6 runs in a pseudo-terminal made here, receives 2,000 random keys that change
//! stiffness, damping, drag, dt, speed and the camera (each stiffness or damping key asks for
//! the spectra again: about a third of a second on this cloth, computed off the drawing thread,
//! the newest request winning), then `q` (back to the menu) and `q` (quit); it must exit within
//! a second of the first `q`. A generous bound: the keys are read in one go and none waits for
//! a computation.
#![cfg(unix)]

use std::fs::File;
use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use nix::pty::{Winsize, openpty};

const MOUSE_ON: &[u8] = b"\x1b[?1000h";
const CURSOR_QUERY: &[u8] = b"\x1b[6n";

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Waits until `ready()` holds; a hang guard, not a timing assertion.
fn wait_for(what: &str, mut ready: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ready() {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "never happened: {what}"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn two_thousand_random_keys_then_q_exits_within_a_second() {
    let size = Winsize {
        ws_row: 24,
        ws_col: 80,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    let pty = openpty(Some(&size), None).expect("openpty");
    let data = tempfile::tempdir().expect("temp dir");
    let slave = || Stdio::from(pty.slave.try_clone().expect("dup"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .args(["lesson", "6", "--no-save"])
        .current_dir(data.path())
        .env("TERM", "xterm-256color")
        .env("SPRINGLAB_DATA_DIR", data.path())
        .stdin(slave())
        .stdout(slave())
        .stderr(slave())
        .spawn()
        .expect("spawn springlab");
    let output = Arc::new(Mutex::new(Vec::<u8>::new()));
    {
        let output = Arc::clone(&output);
        let mut master = File::from(pty.master.try_clone().expect("dup"));
        let mut answer = File::from(pty.master.try_clone().expect("dup"));
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = master.read(&mut buf) {
                if n == 0 {
                    break;
                }
                // A terminal answers the cursor position query (the app asks it at start-up).
                if find(&buf[..n], CURSOR_QUERY).is_some() {
                    let _ = answer.write_all(b"\x1b[1;1R");
                }
                output.lock().expect("lock").extend_from_slice(&buf[..n]);
            }
        });
    }
    wait_for("the app turning the mouse on", || {
        find(&output.lock().expect("lock"), MOUSE_ON).is_some()
    });
    // 2,000 keys drawn by a fixed linear congruential generator from the keys that change
    // coefficients, the clock and the view (no step change, no export, no method chooser).
    let pool: &[u8] = b"KkDdAa+-<>[]GgJjtiofc ";
    let mut x: u64 = 27;
    let keys: Vec<u8> = (0..2000)
        .map(|_| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            pool[((x >> 33) % pool.len() as u64) as usize]
        })
        .collect();
    let stiffness_keys = keys
        .iter()
        .filter(|&&k| matches!(k, b'K' | b'k' | b'D' | b'd'))
        .count();
    assert!(
        stiffness_keys > 300,
        "{stiffness_keys} keys recompute the spectra"
    );
    let mut master = File::from(pty.master.try_clone().expect("dup"));
    master.write_all(&keys).expect("write keys");
    let sent = Instant::now();
    master.write_all(b"qq").expect("write q");
    let mut exited = None;
    while sent.elapsed() < Duration::from_secs(30) {
        if let Some(status) = child.try_wait().expect("wait") {
            exited = Some((status, sent.elapsed()));
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let Some((status, after)) = exited else {
        let _ = child.kill();
        panic!("the app did not exit within 30 s of q");
    };
    let out = output.lock().expect("lock");
    let tail = String::from_utf8_lossy(&out[out.len().saturating_sub(600)..]).into_owned();
    assert!(status.success(), "{status}: {tail:?}");
    assert!(
        after < Duration::from_secs(1),
        "the app exited {after:?} after q"
    );
}
