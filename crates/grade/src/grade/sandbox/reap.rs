//! Reaping a sandboxed program: its exit status and peak memory, after the rest of its process
//! group is killed (the system calls the standard library does not offer).

#![allow(unsafe_code)]

use std::process::{Child, ExitStatus};

/// The exit status of `child` if it has ended, and its peak resident memory (KiB) where the
/// system reports it (Linux: `wait4`). Before reaping, the rest of its process group is killed,
/// while the ended leader still holds the group's id.
#[cfg(unix)]
pub(crate) fn reap(child: &mut Child) -> Option<(ExitStatus, Option<u64>)> {
    use nix::libc;
    use std::os::unix::process::ExitStatusExt;
    let pid = libc::pid_t::try_from(child.id()).ok()?;
    // SAFETY: an all-zero siginfo_t is a valid value of this plain C struct.
    let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
    // SAFETY: waitid on our own child with a valid pointer; WNOHANG | WNOWAIT neither blocks
    // nor reaps.
    let polled = unsafe {
        libc::waitid(
            libc::P_PID,
            pid as libc::id_t,
            &raw mut info,
            libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
        )
    };
    // SAFETY: si_pid is set by waitid (zero while the child runs).
    if polled != 0 || unsafe { info.si_pid() } == 0 {
        return None;
    }
    let _ = nix::sys::signal::killpg(
        nix::unistd::Pid::from_raw(pid),
        nix::sys::signal::Signal::SIGKILL,
    );
    let mut status: libc::c_int = 0;
    // SAFETY: an all-zero rusage is a valid value of this plain C struct.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: wait4 on our own ended child with valid pointers to locals; it returns at once.
    let got = unsafe { libc::wait4(pid, &raw mut status, 0, &raw mut usage) };
    (got == pid).then(|| {
        (
            ExitStatus::from_raw(status),
            u64::try_from(usage.ru_maxrss).ok(),
        )
    })
}

#[cfg(not(unix))]
pub(crate) fn reap(child: &mut Child) -> Option<(ExitStatus, Option<u64>)> {
    child.try_wait().ok().flatten().map(|s| (s, None))
}
