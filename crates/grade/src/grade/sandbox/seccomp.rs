//! A seccomp filter (classic BPF, written out here: the child installs it with one `prctl`
//! after `fork`, which must not allocate).
//!
//! ```text
//! arch ≠ this machine's              → kill the process   (no 32-bit or x32 side door)
//! ptrace, process_vm_readv/writev, pidfd_getfd, kcmp     → EPERM  (no reaching into others)
//! socket(domain ≠ AF_UNIX)           → EAFNOSUPPORT        (no IPv4, IPv6, netlink, packet)
//! io_uring_*                         → EPERM  (its operations would bypass this filter)
//! clone with a CLONE_NEW* flag, unshare, setns, mount and the new mount API, pivot_root,
//! chroot, bpf, perf_event_open, userfaultfd, keyctl, add_key, request_key, module and
//! kexec calls, reboot, swapon/off, acct, quotactl, open_by_handle_at → EPERM
//! clone3                             → ENOSYS (its flags are out of the filter's reach;
//!                                              glibc falls back to clone)
//! everything else                    → allowed
//! ```
//! Reference: the kernel's `Documentation/userspace-api/seccomp_filter.rst`; the filter layout
//! of `struct seccomp_data` (nr at 0, arch at 4, args from 16).

#![allow(unsafe_code)]

use nix::libc::{self, sock_filter};

const LD_W_ABS: u16 = 0x20;
const JEQ_K: u16 = 0x15;
const JGE_K: u16 = 0x35;
const AND_K: u16 = 0x54;
const RET_K: u16 = 0x06;
const ARCH_OFFSET: u32 = 4;
const ARG0_OFFSET: u32 = 16;

#[cfg(target_arch = "x86_64")]
const AUDIT_ARCH: u32 = 0xC000_003E;
#[cfg(target_arch = "aarch64")]
const AUDIT_ARCH: u32 = 0xC000_00B7;

const NAMESPACE_FLAGS: u32 = (libc::CLONE_NEWNS
    | libc::CLONE_NEWUTS
    | libc::CLONE_NEWIPC
    | libc::CLONE_NEWUSER
    | libc::CLONE_NEWPID
    | libc::CLONE_NEWNET
    | libc::CLONE_NEWCGROUP) as u32;

fn stmt(code: u16, k: u32) -> sock_filter {
    sock_filter {
        code,
        jt: 0,
        jf: 0,
        k,
    }
}

fn jump(code: u16, k: u32, jt: u8, jf: u8) -> sock_filter {
    sock_filter { code, jt, jf, k }
}

fn errno(e: i32) -> u32 {
    libc::SECCOMP_RET_ERRNO | (e as u32 & libc::SECCOMP_RET_DATA)
}

/// The system calls refused with EPERM.
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
fn denied() -> Vec<libc::c_long> {
    use libc::*;
    vec![
        SYS_ptrace,
        SYS_process_vm_readv,
        SYS_process_vm_writev,
        SYS_pidfd_getfd,
        SYS_kcmp,
        SYS_io_uring_setup,
        SYS_io_uring_enter,
        SYS_io_uring_register,
        SYS_unshare,
        SYS_setns,
        SYS_mount,
        SYS_umount2,
        SYS_pivot_root,
        SYS_chroot,
        SYS_fsopen,
        SYS_fsconfig,
        SYS_fsmount,
        SYS_fspick,
        SYS_move_mount,
        SYS_open_tree,
        SYS_mount_setattr,
        SYS_bpf,
        SYS_perf_event_open,
        SYS_userfaultfd,
        SYS_keyctl,
        SYS_add_key,
        SYS_request_key,
        SYS_init_module,
        SYS_finit_module,
        SYS_delete_module,
        SYS_kexec_load,
        SYS_reboot,
        SYS_swapon,
        SYS_swapoff,
        SYS_acct,
        SYS_quotactl,
        SYS_open_by_handle_at,
        SYS_name_to_handle_at,
    ]
}

/// The filter for this architecture, or `None` where none is written (other than x86-64 and
/// aarch64).
#[must_use]
pub(crate) fn filter() -> Option<Vec<sock_filter>> {
    #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
    {
        let eperm = errno(libc::EPERM);
        let mut p = vec![
            stmt(LD_W_ABS, ARCH_OFFSET),
            jump(JEQ_K, AUDIT_ARCH, 1, 0),
            stmt(RET_K, libc::SECCOMP_RET_KILL_PROCESS),
            stmt(LD_W_ABS, 0),
        ];
        #[cfg(target_arch = "x86_64")]
        {
            // x32 system call numbers.
            p.push(jump(JGE_K, 0x4000_0000, 0, 1));
            p.push(stmt(RET_K, eperm));
        }
        for nr in denied() {
            p.push(jump(JEQ_K, nr as u32, 0, 1));
            p.push(stmt(RET_K, eperm));
        }
        p.push(jump(JEQ_K, libc::SYS_clone3 as u32, 0, 1));
        p.push(stmt(RET_K, errno(libc::ENOSYS)));
        // clone(flags, …): no new namespaces. The accumulator is reloaded with nr afterwards.
        p.push(jump(JEQ_K, libc::SYS_clone as u32, 0, 4));
        p.push(stmt(LD_W_ABS, ARG0_OFFSET));
        p.push(stmt(AND_K, NAMESPACE_FLAGS));
        p.push(jump(JEQ_K, 0, 1, 0));
        p.push(stmt(RET_K, eperm));
        // socket(domain, …): AF_UNIX only.
        p.push(stmt(LD_W_ABS, 0));
        p.push(jump(JEQ_K, libc::SYS_socket as u32, 0, 3));
        p.push(stmt(LD_W_ABS, ARG0_OFFSET));
        p.push(jump(JEQ_K, libc::AF_UNIX as u32, 1, 0));
        p.push(stmt(RET_K, errno(libc::EAFNOSUPPORT)));
        p.push(stmt(RET_K, libc::SECCOMP_RET_ALLOW));
        Some(p)
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        None
    }
}

/// Installs `filter` on the calling thread (no_new_privs must be set). Safe after `fork`.
pub(crate) fn install(filter: &[sock_filter]) -> bool {
    let prog = libc::sock_fprog {
        len: filter.len() as u16,
        filter: filter.as_ptr().cast_mut(),
    };
    // SAFETY: a valid program that outlives the call.
    unsafe {
        libc::prctl(
            libc::PR_SET_SECCOMP,
            libc::SECCOMP_MODE_FILTER as libc::c_ulong,
            &raw const prog,
        ) == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every jump lands inside the program, every path ends in a return, and the last
    /// instruction allows (the default of a deny list).
    #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
    #[test]
    fn the_filter_is_well_formed() {
        let p = filter().expect("a filter for this architecture");
        assert!(p.len() < 4096, "BPF_MAXINSNS");
        for (i, ins) in p.iter().enumerate() {
            if ins.code & 0x07 == 0x05 {
                assert!(i + 1 + usize::from(ins.jt) < p.len(), "jt of {i}");
                assert!(i + 1 + usize::from(ins.jf) < p.len(), "jf of {i}");
            }
        }
        let last = p.last().expect("instructions");
        assert_eq!((last.code, last.k), (RET_K, libc::SECCOMP_RET_ALLOW));
        // The architecture check comes first and kills on a mismatch.
        assert_eq!((p[0].code, p[0].k), (LD_W_ABS, ARCH_OFFSET));
        assert_eq!(p[2].k, libc::SECCOMP_RET_KILL_PROCESS);
        // Each denied call is answered with EPERM right after its comparison.
        for nr in denied() {
            let at = p
                .iter()
                .position(|ins| ins.code == JEQ_K && ins.k == nr as u32)
                .unwrap_or_else(|| panic!("system call {nr} is not in the filter"));
            assert_eq!(p[at + 1].k, errno(libc::EPERM));
        }
    }
}
