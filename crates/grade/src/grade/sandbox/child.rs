//! What a sandboxed child does between `fork` and `exec` (module docs of [`super`]): entering
//! the namespaces as A, B and C, then confining C. System calls only, on data prepared before
//! the fork: no allocation, no lock.

#![allow(unsafe_code)]

use std::io;

use nix::libc;

use super::{Rlimits, errno, landlock, seccomp};

/// Writes `data` to the file `path` (both NUL-terminated where needed); system calls only.
unsafe fn write_file(path: &[u8], data: &[u8]) -> bool {
    // SAFETY: path is NUL-terminated by the caller.
    let fd = unsafe { libc::open(path.as_ptr().cast(), libc::O_WRONLY | libc::O_CLOEXEC) };
    if fd < 0 {
        return false;
    }
    // SAFETY: a valid buffer and descriptor.
    let n = unsafe { libc::write(fd, data.as_ptr().cast(), data.len()) };
    // SAFETY: closes the descriptor just opened.
    unsafe { libc::close(fd) };
    n == data.len() as isize
}

/// Closes every descriptor but those in `keep` (negative entries are ignored).
unsafe fn close_all_but(keep: &[libc::c_int]) {
    // The kept descriptors in ascending order, on the stack (no allocation).
    let mut sorted = [-1; 4];
    let mut n = 0;
    for &fd in keep {
        if fd >= 0 && n < sorted.len() {
            sorted[n] = fd;
            n += 1;
        }
    }
    sorted[..n].sort_unstable();
    let mut low = 0u32;
    // SAFETY: close_range on ranges of this process's descriptors.
    unsafe {
        for &fd in &sorted[..n] {
            let fd = fd as u32;
            if fd > low {
                libc::syscall(libc::SYS_close_range, low, fd - 1, 0u32);
            }
            low = low.max(fd + 1);
        }
        libc::syscall(libc::SYS_close_range, low, u32::MAX, 0u32);
    }
}

/// A pidfd of process `pid` (close-on-exec), or -1 where the kernel has none (before 5.3:
/// ENOSYS).
unsafe fn pidfd_open(pid: libc::pid_t) -> libc::c_int {
    // SAFETY: pidfd_open takes a pid and flags; no memory.
    let fd = unsafe { libc::syscall(libc::SYS_pidfd_open, pid, 0) };
    libc::c_int::try_from(fd).unwrap_or(-1)
}

/// In A: waits until B ends; or, as soon as the grader process
/// has ended (whichever thread forked A), kills B (and with it the whole namespace) and exits.
/// With pidfds of both, `poll` sleeps until one of them ends; without (an old kernel), the
/// checks run every 50 ms.
unsafe fn watch(grader: libc::pid_t, grader_fd: libc::c_int, b: libc::pid_t) {
    // SAFETY: (the whole function) system calls only, on locals.
    unsafe {
        let b_fd = if grader_fd >= 0 { pidfd_open(b) } else { -1 };
        // `revents` is set by the last poll (a descriptor of -1 is ignored by poll).
        let mut fds = [
            libc::pollfd {
                fd: grader_fd,
                events: libc::POLLIN,
                revents: 0,
            },
            libc::pollfd {
                fd: b_fd,
                events: libc::POLLIN,
                revents: 0,
            },
        ];
        loop {
            let mut status = 0;
            let got = libc::waitpid(b, &raw mut status, libc::WNOHANG);
            if got == b {
                return;
            }
            if got < 0 && errno() != libc::EINTR {
                libc::_exit(126);
            }
            // The grader ended: A was handed to another process (getppid() changed) or the
            // grader's pidfd became readable in the last poll.
            if libc::getppid() != grader || fds[0].revents & (libc::POLLIN | libc::POLLHUP) != 0 {
                libc::kill(b, libc::SIGKILL);
                libc::_exit(137);
            }
            if b_fd >= 0 {
                libc::poll(fds.as_mut_ptr(), 2, -1);
            } else {
                let pause = libc::timespec {
                    tv_sec: 0,
                    tv_nsec: 50_000_000,
                };
                libc::nanosleep(&raw const pause, std::ptr::null_mut());
            }
        }
    }
}

/// In A (module docs): new namespaces, then B and C; returns only in C. `grader` is the pid of
/// the grader process (A's parent): when it ends, A kills B ([`watch`]).
pub(super) unsafe fn enter_namespaces(
    grader: libc::pid_t,
    ns: libc::c_int,
    userns: bool,
    uid_map: &str,
    gid_map: &str,
    proc_rule: bool,
    ruleset_fd: libc::c_int,
) -> io::Result<()> {
    // SAFETY: (the whole function) system calls only, on data prepared before the fork.
    unsafe {
        // A pidfd of the grader process, then a check that it is still A's parent (it may have
        // ended before the pidfd was opened).
        let grader_fd = pidfd_open(grader);
        if libc::getppid() != grader {
            return Err(io::Error::from_raw_os_error(libc::ESRCH));
        }
        if libc::unshare(ns) != 0 {
            return Err(io::Error::last_os_error());
        }
        if userns {
            let _ = write_file(b"/proc/self/setgroups\0", b"deny");
            if !write_file(b"/proc/self/uid_map\0", uid_map.as_bytes())
                || !write_file(b"/proc/self/gid_map\0", gid_map.as_bytes())
            {
                return Err(io::Error::last_os_error());
            }
        }
        let mut pipe = [0; 2];
        if libc::pipe2(pipe.as_mut_ptr(), libc::O_CLOEXEC) != 0 {
            return Err(io::Error::last_os_error());
        }
        let b = libc::fork();
        if b < 0 {
            return Err(io::Error::last_os_error());
        }
        if b > 0 {
            // A: wait for B (or kill it when the grader ends), then end as the program ended.
            close_all_but(&[pipe[0], grader_fd]);
            watch(grader, grader_fd, b);
            let mut word = [0u8; 4];
            if libc::read(pipe[0], word.as_mut_ptr().cast(), 4) != 4 {
                libc::_exit(126);
            }
            end_as(i32::from_ne_bytes(word));
        }
        // B: pid 1 of the namespace; dies with A. (Its parent is outside the namespace, so
        // getppid() is 0 here and cannot tell whether A is still alive; A closing its end of
        // the pipe is not needed either: A only ends after B.)
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0);
        libc::close(pipe[0]);
        if grader_fd >= 0 {
            libc::close(grader_fd);
        }
        if proc_rule
            && libc::mount(
                std::ptr::null(),
                c"/".as_ptr(),
                std::ptr::null(),
                libc::MS_REC | libc::MS_PRIVATE,
                std::ptr::null(),
            ) == 0
            && libc::mount(
                c"proc".as_ptr(),
                c"/proc".as_ptr(),
                c"proc".as_ptr(),
                libc::MS_NOSUID | libc::MS_NODEV | libc::MS_NOEXEC,
                c"hidepid=invisible".as_ptr().cast(),
            ) == 0
            && ruleset_fd >= 0
        {
            let pfd = libc::open(c"/proc".as_ptr(), libc::O_PATH | libc::O_CLOEXEC);
            if pfd >= 0 {
                landlock::add_rule(ruleset_fd, pfd, landlock::READ_FILE | landlock::READ_DIR);
                libc::close(pfd);
            }
        }
        let c = libc::fork();
        if c < 0 {
            libc::_exit(126);
        }
        if c > 0 {
            // B: reap everything; when C ends, report its status and exit (the kernel then
            // kills whatever is left in the namespace).
            close_all_but(&[pipe[1]]);
            loop {
                let mut status = 0;
                let pid = libc::waitpid(-1, &raw mut status, 0);
                if pid == c {
                    let word = status.to_ne_bytes();
                    libc::write(pipe[1], word.as_ptr().cast(), 4);
                    libc::_exit(0);
                }
                if pid < 0 && errno() != libc::EINTR {
                    libc::_exit(126);
                }
            }
        }
        // C.
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0);
        libc::close(pipe[1]);
        Ok(())
    }
}

/// Ends A as the program ended: the same exit code, or the same signal.
unsafe fn end_as(status: libc::c_int) -> ! {
    // SAFETY: system calls only.
    unsafe {
        if libc::WIFEXITED(status) {
            libc::_exit(libc::WEXITSTATUS(status));
        }
        if libc::WIFSIGNALED(status) {
            let sig = libc::WTERMSIG(status);
            let none = libc::rlimit {
                rlim_cur: 0,
                rlim_max: 0,
            };
            libc::setrlimit(libc::RLIMIT_CORE, &raw const none);
            libc::signal(sig, libc::SIG_DFL);
            let mut set: libc::sigset_t = std::mem::zeroed();
            libc::sigemptyset(&raw mut set);
            libc::sigaddset(&raw mut set, sig);
            libc::sigprocmask(libc::SIG_UNBLOCK, &raw const set, std::ptr::null_mut());
            libc::kill(libc::getpid(), sig);
        }
        libc::_exit(125)
    }
}

/// Marks every descriptor from 3 up close-on-exec, so the program starts with its three
/// standard streams only. The grader's own descriptors are close-on-exec already; this is for
/// those it inherited (a shell's redirection `7>>log`, a harness's pipe, cargo's jobserver),
/// which the student's code could otherwise write whatever the sandbox's user and Landlock say.
/// `close_range(…, CLOSE_RANGE_CLOEXEC)` (Linux 5.11), else `fcntl` on each possible number.
unsafe fn cloexec_from_3() {
    const CLOSE_RANGE_CLOEXEC: libc::c_uint = 1 << 2;
    // SAFETY: close_range and fcntl on this process's descriptors; no memory.
    unsafe {
        if libc::syscall(libc::SYS_close_range, 3u32, u32::MAX, CLOSE_RANGE_CLOEXEC) == 0 {
            return;
        }
        let mut limit = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        let top = if libc::getrlimit(libc::RLIMIT_NOFILE, &raw mut limit) == 0 {
            limit.rlim_cur.min(1 << 20) as libc::c_int
        } else {
            1 << 16
        };
        for fd in 3..top {
            libc::fcntl(fd, libc::F_SETFD, libc::FD_CLOEXEC);
        }
    }
}

/// In C: no inherited descriptors, limits, the other user, no_new_privs, Landlock, seccomp.
pub(super) unsafe fn confine(
    uid: Option<u32>,
    gid: u32,
    limits: Rlimits,
    ruleset_fd: libc::c_int,
    filter: Option<&[libc::sock_filter]>,
) -> io::Result<()> {
    let fail = || Err(io::Error::last_os_error());
    // SAFETY: (the whole function) system calls only, on data prepared before the fork.
    unsafe {
        cloexec_from_3();
        let set = |resource, value: u64| {
            let l = libc::rlimit {
                rlim_cur: value,
                rlim_max: value,
            };
            libc::setrlimit(resource, &raw const l) == 0
        };
        if !(set(libc::RLIMIT_AS, limits.address_space)
            && set(libc::RLIMIT_CPU, limits.cpu_seconds)
            && set(libc::RLIMIT_FSIZE, limits.file_bytes)
            && set(libc::RLIMIT_CORE, 0)
            && set(libc::RLIMIT_NOFILE, limits.open_files))
        {
            return fail();
        }
        if let Some(uid) = uid
            && (libc::setgroups(0, std::ptr::null()) != 0
                || libc::setresgid(gid, gid, gid) != 0
                || libc::setresuid(uid, uid, uid) != 0)
        {
            return fail();
        }
        // After the switch: a limit set before it would make the exec fail (the kernel checks
        // the new user's count at setuid).
        if !set(libc::RLIMIT_NPROC, limits.processes) {
            return fail();
        }
        if libc::prctl(libc::PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 {
            return fail();
        }
        if ruleset_fd >= 0 && !landlock::restrict_self(ruleset_fd) {
            return fail();
        }
        if let Some(filter) = filter
            && !seccomp::install(filter)
        {
            return fail();
        }
        Ok(())
    }
}
