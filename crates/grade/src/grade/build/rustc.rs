//! One rustc run in the sandbox: its arguments, its deadline, and its stderr read into a
//! [`BuildFailure`].

use std::ffi::OsString;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::thread;
use std::time::{Duration, Instant};

use super::{BuildFailure, Builder, Toolchain, tail};
use crate::grade::sandbox::{Launch, Rlimits};

/// The compiler's error messages in rustc's stderr: everything from the first line starting
/// with `error`, at most 80 lines of at most 300 characters; or the tail when there is none.
fn compiler_errors(stderr: &str) -> String {
    let cut = |l: &str| -> String {
        if l.chars().count() > 300 {
            let mut s: String = l.chars().take(300).collect();
            s.push('…');
            s
        } else {
            l.to_string()
        }
    };
    let Some(start) = stderr.lines().position(|l| l.starts_with("error")) else {
        return tail(stderr, 30)
            .lines()
            .map(cut)
            .collect::<Vec<_>>()
            .join("\n");
    };
    stderr
        .lines()
        .skip(start)
        .take(80)
        .map(cut)
        .collect::<Vec<_>>()
        .join("\n")
}

impl Builder {
    /// Runs rustc in the sandbox with `args`; its stderr (bounded) on failure.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn rustc(
        &self,
        toolchain: &Toolchain,
        args: Vec<OsString>,
        cwd: &Path,
        read: Vec<PathBuf>,
        out: &Path,
        slot: u32,
        deadline: Instant,
    ) -> Result<(), BuildFailure> {
        let mut env: Vec<(OsString, OsString)> = vec![
            ("PATH".into(), "/usr/bin:/bin".into()),
            ("TMPDIR".into(), out.as_os_str().to_owned()),
            ("HOME".into(), out.as_os_str().to_owned()),
        ];
        env.push(("LC_ALL".into(), "C".into()));
        let mut read = read;
        read.push(toolchain.sysroot.clone());
        let launch = Launch {
            program: toolchain.rustc(),
            args,
            env,
            cwd: cwd.to_path_buf(),
            read,
            write: vec![out.to_path_buf()],
            limits: Rlimits {
                address_space: self.limits.memory_bytes,
                cpu_seconds: self.limits.cpu_seconds,
                file_bytes: 256 << 20,
                open_files: 1024,
                processes: 256,
            },
            slot,
        };
        let mut child = self
            .sandbox
            .spawn(&launch, Stdio::null(), Stdio::null(), Stdio::piped())
            .map_err(|e| BuildFailure::Grader(format!("cannot start rustc in the sandbox: {e}")))?;
        let cap = self.limits.output_bytes;
        let err = child.stderr.take();
        let reader = thread::spawn(move || {
            let mut kept = Vec::new();
            if let Some(mut p) = err {
                let mut chunk = [0u8; 8192];
                while let Ok(n) = p.read(&mut chunk) {
                    if n == 0 {
                        break;
                    }
                    let room = cap.saturating_sub(kept.len());
                    kept.extend_from_slice(&chunk[..n.min(room)]);
                }
            }
            String::from_utf8_lossy(&kept).into_owned()
        });
        let status = loop {
            match child.try_wait() {
                Ok(Some(status)) => break status,
                Ok(None) if Instant::now() > deadline => {
                    kill_group(&mut child);
                    let _ = reader.join();
                    self.sandbox.sweep(slot);
                    return Err(BuildFailure::TimedOut(self.limits.wall));
                }
                Ok(None) => thread::sleep(Duration::from_millis(10)),
                Err(e) => return Err(BuildFailure::Grader(e.to_string())),
            }
        };
        kill_group(&mut child);
        let stderr = reader.join().unwrap_or_default();
        self.sandbox.sweep(slot);
        if status.success() {
            return Ok(());
        }
        use std::os::unix::process::ExitStatusExt;
        // A compiler out of memory aborts (a signal, or 101 for an internal error); an ordinary
        // failed build exits with 1, and its messages may say anything (`compile_error!`).
        if status.code() != Some(1)
            && let Some(memory) = stderr
                .lines()
                .find(|l| l.contains("memory allocation of") || l.contains("out of memory"))
        {
            return Err(BuildFailure::Limit(format!(
                "the compiler ran out of memory (\"{}\"; a build may use {} MiB)",
                memory.trim(),
                self.limits.memory_bytes >> 20
            )));
        }
        match status.signal() {
            Some(24 | 9) if !stderr.lines().any(|l| l.starts_with("error")) => {
                Err(BuildFailure::Limit(format!(
                    "the compiler used up its CPU time ({} s)",
                    self.limits.cpu_seconds
                )))
            }
            _ if stderr.trim().is_empty() => Err(BuildFailure::Compile(format!(
                "rustc ended ({status}) without a message"
            ))),
            _ => Err(BuildFailure::Compile(compiler_errors(&stderr))),
        }
    }
}

/// Arguments of every rustc run: the release profile of the old cargo build.
pub(super) fn common_args() -> Vec<OsString> {
    [
        "--edition",
        "2024",
        "-C",
        "opt-level=3",
        "-C",
        "debuginfo=0",
        "-C",
        "panic=unwind",
        "--error-format",
        "human",
        "--color",
        "never",
    ]
    .map(OsString::from)
    .to_vec()
}

/// Kills the sandbox's process group (A and whatever kept its group) and reaps A.
fn kill_group(child: &mut std::process::Child) {
    if let Ok(pid) = i32::try_from(child.id()) {
        let _ = nix::sys::signal::killpg(
            nix::unistd::Pid::from_raw(pid),
            nix::sys::signal::Signal::SIGKILL,
        );
    }
    let _ = child.kill();
    let _ = child.wait();
}
