//! Asking the terminal: write escape-sequence queries, then read its answers from standard input
//! (in raw mode) until they are complete or a timeout passes. Shared by the graphics-protocol
//! detection (`graphics`) and the background colour (`theme`).

use std::time::Duration;

/// Writes `queries` to standard output and reads standard input until `complete` says the bytes
/// read so far hold every answer, or `timeout` passes; returns the bytes read.
///
/// # Errors
/// Writing the queries, polling or reading standard input failed.
#[cfg(unix)]
pub fn ask(
    queries: &[u8],
    timeout: Duration,
    complete: impl Fn(&[u8]) -> bool,
) -> std::io::Result<Vec<u8>> {
    use rustix::event::{PollFd, PollFlags, Timespec, poll};
    use std::io::Write;
    use std::os::fd::AsFd;
    use std::time::Instant;

    let mut out = std::io::stdout();
    out.write_all(queries)?;
    out.flush()?;
    let stdin = std::io::stdin();
    let fd = stdin.as_fd();
    let deadline = Instant::now() + timeout;
    let mut bytes = Vec::new();
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break;
        }
        let timeout = Timespec {
            tv_sec: left.as_secs() as _,
            tv_nsec: left.subsec_nanos().into(),
        };
        let mut fds = [PollFd::from_borrowed_fd(fd, PollFlags::IN)];
        if poll(&mut fds, Some(&timeout))? == 0 {
            break;
        }
        let mut chunk = [0u8; 256];
        let n = rustix::io::read(fd, &mut chunk)?;
        if n == 0 {
            break;
        }
        bytes.extend_from_slice(&chunk[..n]);
        if complete(&bytes) {
            break;
        }
    }
    Ok(bytes)
}

/// Without Unix terminals nothing is asked: no answer.
///
/// # Errors
/// Never.
#[cfg(not(unix))]
pub fn ask(
    _queries: &[u8],
    _timeout: Duration,
    _complete: impl Fn(&[u8]) -> bool,
) -> std::io::Result<Vec<u8>> {
    Ok(Vec::new())
}
