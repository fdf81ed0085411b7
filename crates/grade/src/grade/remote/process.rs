//! Starting and ending a student's program: the session token, reaping the process group, and
//! what its end means in words for the report. (The working directory, the limits, the other layers
//! and the reaping itself come from [`crate::grade::sandbox`].)

use std::io::Read;
use std::process::{ChildStderr, ExitStatus};
use std::sync::Mutex;

use super::Limits;
pub(super) use crate::grade::sandbox::reap;
use crate::grade::untrusted::student_text;

/// Keeps the last 16 KiB of the program's stderr.
pub(super) fn keep_stderr(mut err: ChildStderr, tail: &Mutex<Vec<u8>>) {
    let mut chunk = [0u8; 4096];
    while let Ok(n) = err.read(&mut chunk) {
        if n == 0 {
            break;
        }
        if let Ok(mut t) = tail.lock() {
            t.extend_from_slice(&chunk[..n]);
            let excess = t.len().saturating_sub(16 << 10);
            t.drain(..excess);
        }
    }
}

/// Mebibytes, for messages.
pub(super) fn mib(bytes: u64) -> u64 {
    bytes >> 20
}

/// What an exit status and the end of stderr say about how a program ended.
pub(super) fn describe_end(status: Option<ExitStatus>, stderr: &str, limits: Limits) -> String {
    let last_line = stderr
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .map(|l| format!(" (stderr: \"{}\")", student_text(l.trim())))
        .unwrap_or_default();
    if let Some(line) = stderr.lines().find(|l| l.contains("memory allocation of")) {
        return format!(
            "it ran out of memory: \"{}\"; a homework program may use {} MiB of address space",
            student_text(line.trim()),
            mib(limits.memory_bytes)
        );
    }
    if stderr.contains("has overflowed its stack") {
        return "its stack overflowed (a recursion without end?)".to_string();
    }
    let Some(status) = status else {
        return format!("it stopped answering{last_line}");
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            let name = nix::sys::signal::Signal::try_from(signal)
                .map_or_else(|_| format!("signal {signal}"), |s| s.as_str().to_string());
            let why = match signal {
                6 => "it aborted (std::process::abort, or a panic inside a panic)".to_string(),
                9 => "it was killed".to_string(),
                11 => "it crashed with a segmentation fault".to_string(),
                24 => format!(
                    "it used up its CPU time ({} s for one program)",
                    limits.cpu_seconds
                ),
                25 => format!(
                    "it wrote a file larger than the limit of {} MiB",
                    mib(limits.file_bytes)
                ),
                _ => "it was stopped by a signal".to_string(),
            };
            return format!("{why} ({name}){last_line}");
        }
    }
    match status.code() {
        Some(code) => format!(
            "it exited with status {code} in the middle of a call (std::process::exit?){last_line}"
        ),
        None => format!("it ended ({status}){last_line}"),
    }
}
