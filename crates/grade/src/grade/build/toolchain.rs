//! The grader's compiler: finding rustc and its sysroot, and hard-linking it where the sandbox
//! user can read it.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use super::tail;
use crate::grade::sandbox::reachable_by;

/// The compiler: its sysroot as the sandbox sees it, and its version.
#[derive(Clone, Debug)]
pub struct Toolchain {
    /// The sysroot the sandbox reads (the real one, or hard links to it in the scratch folder).
    pub sysroot: PathBuf,
    /// `rustc -vV`.
    pub version: String,
}

/// The grader's own environment for running its `rustc` (a rustup proxy needs these).
fn toolchain_env(command: &mut Command) {
    command.env_clear();
    for key in [
        "PATH",
        "HOME",
        "RUSTUP_HOME",
        "RUSTUP_TOOLCHAIN",
        "CARGO_HOME",
        "RUSTC",
    ] {
        if let Some(v) = std::env::var_os(key) {
            command.env(key, v);
        }
    }
}

/// Runs the grader's rustc with `args` (from `/`, so no folder's rust-toolchain file applies).
fn ask_rustc(rustc: &Path, args: &[&str]) -> Result<String, String> {
    let mut command = Command::new(rustc);
    toolchain_env(&mut command);
    let out = command
        .args(args)
        .current_dir("/")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", rustc.display()))?;
    if !out.status.success() {
        return Err(format!(
            "`{} {}` failed: {}",
            rustc.display(),
            args.join(" "),
            tail(&String::from_utf8_lossy(&out.stderr), 5)
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// Hard links (or, for symbolic links, copies of the link) of `from` at `to`, recursively.
fn link_tree(from: &Path, to: &Path) -> std::io::Result<()> {
    let meta = std::fs::symlink_metadata(from)?;
    if meta.file_type().is_symlink() {
        let target = std::fs::read_link(from)?;
        let _ = std::fs::remove_file(to);
        std::os::unix::fs::symlink(target, to)
    } else if meta.is_dir() {
        std::fs::create_dir_all(to)?;
        set_mode(to, 0o755)?;
        for entry in std::fs::read_dir(from)? {
            let entry = entry?;
            link_tree(&entry.path(), &to.join(entry.file_name()))?;
        }
        Ok(())
    } else {
        let _ = std::fs::remove_file(to);
        std::fs::hard_link(from, to)
    }
}

pub(super) fn set_mode(path: &Path, mode: u32) -> std::io::Result<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode))
}

pub(super) fn chown(path: &Path, owner: Option<(u32, u32)>) -> std::io::Result<()> {
    match owner {
        Some((uid, gid)) => std::os::unix::fs::chown(path, Some(uid), Some(gid)),
        None => Ok(()),
    }
}

impl Toolchain {
    /// The grader's rustc (`$RUSTC`, else `rustc` on the PATH) and its sysroot; when the sandbox
    /// user `owner` cannot reach the sysroot (rustup under a closed `/root`), its compiler
    /// parts hard-linked into `scratch/toolchain`.
    ///
    /// # Errors
    /// A sentence for the grader: no rustc, or a sysroot the sandbox can neither reach nor link.
    pub fn find(scratch: &Path, owner: Option<(u32, u32)>) -> Result<Toolchain, String> {
        let rustc = std::env::var_os("RUSTC")
            .filter(|v| !v.is_empty())
            .map_or_else(|| PathBuf::from("rustc"), PathBuf::from);
        let sysroot = PathBuf::from(ask_rustc(&rustc, &["--print", "sysroot"])?);
        let real = sysroot.join("bin").join("rustc");
        let version = ask_rustc(&real, &["-vV"])?;
        let reachable = owner.is_none_or(|(u, g)| reachable_by(&real, u, g));
        if reachable {
            return Ok(Toolchain { sysroot, version });
        }
        let host = version
            .lines()
            .find_map(|l| l.strip_prefix("host: "))
            .ok_or_else(|| format!("`rustc -vV` names no host: {version}"))?
            .to_string();
        let mirror = scratch.join("toolchain");
        let link = || -> std::io::Result<()> {
            std::fs::create_dir_all(mirror.join("bin"))?;
            set_mode(&mirror, 0o755)?;
            set_mode(&mirror.join("bin"), 0o755)?;
            link_tree(&real, &mirror.join("bin").join("rustc"))?;
            let lib = mirror.join("lib");
            std::fs::create_dir_all(lib.join("rustlib"))?;
            set_mode(&lib, 0o755)?;
            set_mode(&lib.join("rustlib"), 0o755)?;
            for entry in std::fs::read_dir(sysroot.join("lib"))? {
                let entry = entry?;
                if entry.file_type()?.is_dir() {
                    continue;
                }
                link_tree(&entry.path(), &lib.join(entry.file_name()))?;
            }
            link_tree(
                &sysroot.join("lib").join("rustlib").join(&host),
                &lib.join("rustlib").join(&host),
            )
        };
        link().map_err(|e| {
            format!(
                "the toolchain at {} cannot be read by the sandbox user (a folder above it is \
                 closed) and cannot be linked into {}: {e}; install Rust where other users can \
                 read it (for example RUSTUP_HOME=/usr/local/rustup CARGO_HOME=/usr/local/cargo), \
                 or run with --sandbox-uid 0",
                sysroot.display(),
                mirror.display()
            )
        })?;
        Ok(Toolchain {
            sysroot: mirror,
            version,
        })
    }

    pub(super) fn rustc(&self) -> PathBuf {
        self.sysroot.join("bin").join("rustc")
    }
}
