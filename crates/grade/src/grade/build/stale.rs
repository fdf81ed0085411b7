//! Scratch folders that a grader left behind when it could not clean up (killed by SIGKILL, or a
//! process that ended without running destructors): each holds a copy of the student's sources
//! and, as root, hard links to the whole toolchain. A new grader removes the ones whose process
//! is gone before it makes its own.
//!
//! ```text
//! <temporary directory>/springlab-grade-<pid>-<random>   removed when all hold:
//!     it is a directory, not a link
//!     its owner is the owner of this grader's own scratch folder
//!     no process <pid> exists (kill(pid, 0) answers ESRCH)
//! ```
//! A folder whose process still runs (another grader, or a reused process id) is left alone.

use std::os::unix::fs::MetadataExt;
use std::path::Path;

use nix::errno::Errno;
use nix::sys::signal::kill;
use nix::unistd::Pid;

/// The prefix every scratch folder's name starts with.
pub const PREFIX: &str = "springlab-grade-";

/// Removes, from `dir`, the scratch folders of graders that no longer run and that belong to the
/// user `owner`. Returns how many were removed.
pub fn sweep(dir: &Path, owner: u32) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(scratch_pid) else {
            continue;
        };
        let path = entry.path();
        let Ok(meta) = std::fs::symlink_metadata(&path) else {
            continue;
        };
        if !meta.is_dir() || meta.uid() != owner || alive(pid) {
            continue;
        }
        if std::fs::remove_dir_all(&path).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// The process id in a scratch folder's name `springlab-grade-<pid>-<random>`.
fn scratch_pid(name: &str) -> Option<i32> {
    let rest = name.strip_prefix(PREFIX)?;
    let (pid, tag) = rest.split_once('-')?;
    if tag.is_empty() || !tag.chars().all(|c| c.is_ascii_alphanumeric()) {
        return None;
    }
    pid.parse::<i32>().ok().filter(|p| *p > 0)
}

/// True unless the system says no process `pid` exists.
fn alive(pid: i32) -> bool {
    !matches!(kill(Pid::from_raw(pid), None), Err(Errno::ESRCH))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A process id that has ended: a child that was started and reaped.
    fn ended_pid() -> i32 {
        let mut child = std::process::Command::new("true")
            .spawn()
            .expect("spawn true");
        let pid = i32::try_from(child.id()).expect("pid");
        child.wait().expect("wait");
        pid
    }

    #[test]
    fn names_are_read_strictly() {
        assert_eq!(scratch_pid("springlab-grade-1234-ab12"), Some(1234));
        assert_eq!(scratch_pid("springlab-grade-1234-"), None);
        assert_eq!(scratch_pid("springlab-grade-x-ab"), None);
        assert_eq!(scratch_pid("springlab-grade-0-ab"), None);
        assert_eq!(scratch_pid("springlab-grade-12-a/b"), None);
        assert_eq!(scratch_pid("springlab-grade"), None);
    }

    #[test]
    fn only_folders_of_ended_graders_go() {
        let tmp = tempfile::tempdir().expect("tempdir");
        let dir = tmp.path();
        let owner = std::fs::metadata(dir).expect("meta").uid();
        let dead = ended_pid();
        let me = std::process::id();
        let stale = dir.join(format!("{PREFIX}{dead}-abc"));
        std::fs::create_dir_all(stale.join("toolchain/lib")).expect("stale");
        std::fs::write(stale.join("toolchain/lib/x"), b"x").expect("file");
        let running = dir.join(format!("{PREFIX}{me}-def"));
        std::fs::create_dir(&running).expect("running");
        let other = dir.join("springlab-grade");
        std::fs::create_dir(&other).expect("cache-like name");
        // A link named like a stale folder is not followed or removed.
        let target = dir.join("kept");
        std::fs::create_dir(&target).expect("kept");
        let link = dir.join(format!("{PREFIX}{dead}-link"));
        std::os::unix::fs::symlink(&target, &link).expect("link");

        assert_eq!(sweep(dir, owner), 1);
        assert!(!stale.exists(), "the ended grader's folder is removed");
        assert!(running.exists(), "a running grader's folder stays");
        assert!(
            other.exists(),
            "a folder that is not a scratch folder stays"
        );
        assert!(
            link.symlink_metadata().is_ok() && target.exists(),
            "links stay"
        );
        // Another owner's folder stays even when its grader has ended.
        std::fs::create_dir(&stale).expect("stale again");
        assert_eq!(sweep(dir, owner.wrapping_add(1)), 0);
        assert!(stale.exists());
    }
}
