//! Landlock through its three system calls (no crate: the rules are built before `fork` and the
//! child only calls `landlock_restrict_self`, which allocates nothing).
//!
//! ```text
//! fd = landlock_create_ruleset({handled_access_fs, handled_access_net, scoped})
//! landlock_add_rule(fd, PATH_BENEATH, {allowed_access, parent_fd})   per path
//! prctl(PR_SET_NO_NEW_PRIVS); landlock_restrict_self(fd)              in the child
//! ```
//! Every right the kernel's ABI knows is *handled*, so whatever no rule allows is denied: file
//! access outside the listed paths, TCP bind and connect (ABI 4), signals and abstract Unix
//! sockets reaching outside the sandbox (ABI 6). A process under Landlock also cannot ptrace,
//! or open `/proc/<pid>/mem|environ|fd` of, a process outside its domain.
//!
//! Reference: the kernel's `Documentation/userspace-api/landlock.rst` and
//! `include/uapi/linux/landlock.h` (the constants below).

#![allow(unsafe_code)]

use std::ffi::CString;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::os::unix::ffi::OsStrExt;
use std::path::Path;

use nix::libc;

const CREATE_RULESET_VERSION: u32 = 1;
const RULE_PATH_BENEATH: libc::c_int = 1;

pub(crate) const EXECUTE: u64 = 1 << 0;
pub(crate) const WRITE_FILE: u64 = 1 << 1;
pub(crate) const READ_FILE: u64 = 1 << 2;
pub(crate) const READ_DIR: u64 = 1 << 3;
const REFER: u64 = 1 << 13;
const TRUNCATE: u64 = 1 << 14;
const IOCTL_DEV: u64 = 1 << 15;
/// Rights that apply to a file (the others only to directories).
const FILE_RIGHTS: u64 = EXECUTE | WRITE_FILE | READ_FILE | TRUNCATE | IOCTL_DEV;
const NET_BIND_TCP: u64 = 1 << 0;
const NET_CONNECT_TCP: u64 = 1 << 1;
const SCOPE_ABSTRACT_UNIX_SOCKET: u64 = 1 << 0;
const SCOPE_SIGNAL: u64 = 1 << 1;

/// Read and execute beneath a path.
pub(crate) const READ: u64 = EXECUTE | READ_FILE | READ_DIR;

#[repr(C)]
struct RulesetAttr {
    handled_access_fs: u64,
    handled_access_net: u64,
    scoped: u64,
}

#[repr(C, packed)]
struct PathBeneathAttr {
    allowed_access: u64,
    parent_fd: i32,
}

/// The Landlock ABI version of the running kernel, or the reason there is none.
pub(crate) fn abi() -> Result<i32, String> {
    // SAFETY: the documented version query: null attributes, size 0, the VERSION flag.
    let v = unsafe {
        libc::syscall(
            libc::SYS_landlock_create_ruleset,
            std::ptr::null::<RulesetAttr>(),
            0usize,
            CREATE_RULESET_VERSION,
        )
    };
    if v >= 1 {
        return Ok(v as i32);
    }
    let e = io::Error::last_os_error();
    Err(match e.raw_os_error() {
        Some(libc::ENOSYS) => "the kernel has no Landlock (before 5.13, or not built in)".into(),
        Some(libc::EOPNOTSUPP) => {
            "Landlock is built in but not enabled (boot with lsm=…,landlock)".into()
        }
        Some(libc::EPERM) => {
            "the container's seccomp profile forbids Landlock's system calls".into()
        }
        _ => format!("Landlock is unavailable: {e}"),
    })
}

/// Every file-system right of ABI `abi`.
fn fs_rights(abi: i32) -> u64 {
    let mut all = (1 << 13) - 1;
    if abi >= 2 {
        all |= REFER;
    }
    if abi >= 3 {
        all |= TRUNCATE;
    }
    if abi >= 5 {
        all |= IOCTL_DEV;
    }
    all
}

/// A ruleset of ABI `abi`: `read` paths readable and executable, `write` paths fully usable
/// beneath, `devices` (such as `/dev/null`) readable and writable; nothing else. Paths that do
/// not exist are left out.
pub(crate) fn ruleset(
    abi: i32,
    read: &[&Path],
    write: &[&Path],
    devices: &[&Path],
) -> io::Result<OwnedFd> {
    let all = fs_rights(abi);
    let attr = RulesetAttr {
        handled_access_fs: all,
        handled_access_net: if abi >= 4 {
            NET_BIND_TCP | NET_CONNECT_TCP
        } else {
            0
        },
        scoped: if abi >= 6 {
            SCOPE_ABSTRACT_UNIX_SOCKET | SCOPE_SIGNAL
        } else {
            0
        },
    };
    let size = if abi >= 6 {
        std::mem::size_of::<RulesetAttr>()
    } else if abi >= 4 {
        16
    } else {
        8
    };
    // SAFETY: a valid attribute struct of at least `size` bytes.
    let fd = unsafe { libc::syscall(libc::SYS_landlock_create_ruleset, &raw const attr, size, 0) };
    if fd < 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: the kernel returned a new file descriptor that nothing else owns.
    let ruleset = unsafe { OwnedFd::from_raw_fd(fd as i32) };
    let add = |path: &Path, rights: u64| -> io::Result<()> {
        let Ok(c) = CString::new(path.as_os_str().as_bytes()) else {
            return Ok(());
        };
        // SAFETY: a NUL-terminated path; O_PATH opens without reading.
        let pfd = unsafe { libc::open(c.as_ptr(), libc::O_PATH | libc::O_CLOEXEC) };
        if pfd < 0 {
            return Ok(()); // not on this system
        }
        // SAFETY: pfd was just opened and is owned here.
        let pfd = unsafe { OwnedFd::from_raw_fd(pfd) };
        let is_dir = std::fs::metadata(path).is_ok_and(|m| m.is_dir());
        let allowed = if is_dir {
            rights & all
        } else {
            rights & all & FILE_RIGHTS
        };
        if !add_rule(ruleset.as_raw_fd(), pfd.as_raw_fd(), allowed) {
            return Err(io::Error::other(format!(
                "Landlock refused a rule for {}: {}",
                path.display(),
                io::Error::last_os_error()
            )));
        }
        Ok(())
    };
    for p in read {
        add(p, READ)?;
    }
    for p in write {
        add(p, all)?;
    }
    for p in devices {
        add(p, READ_FILE | WRITE_FILE)?;
    }
    Ok(ruleset)
}

/// Adds a path-beneath rule for the open `path_fd` (system calls only: safe after `fork`).
pub(crate) fn add_rule(ruleset: libc::c_int, path_fd: libc::c_int, allowed: u64) -> bool {
    let rule = PathBeneathAttr {
        allowed_access: allowed,
        parent_fd: path_fd,
    };
    // SAFETY: a valid rule struct; both descriptors are open.
    unsafe {
        libc::syscall(
            libc::SYS_landlock_add_rule,
            ruleset,
            RULE_PATH_BENEATH,
            &raw const rule,
            0,
        ) == 0
    }
}

/// Enforces `ruleset` on the calling thread (no_new_privs must be set). Safe after `fork`.
pub(crate) fn restrict_self(ruleset: libc::c_int) -> bool {
    // SAFETY: the documented call with an open ruleset descriptor and no flags.
    unsafe { libc::syscall(libc::SYS_landlock_restrict_self, ruleset, 0) == 0 }
}
