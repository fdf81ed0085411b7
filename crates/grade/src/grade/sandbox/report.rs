//! What the sandbox of this machine holds: each layer, active or missing and why
//! (`springlab grade --sandbox-report`).

use nix::libc;

use super::{Layer, LayerState, Sandbox};

impl Sandbox {
    /// Each layer: active or missing, and why.
    #[must_use]
    pub fn layers(&self) -> Vec<LayerState> {
        let state = |layer, r: Result<String, &String>| match r {
            Ok(detail) => LayerState {
                layer,
                active: true,
                detail,
            },
            Err(why) => LayerState {
                layer,
                active: false,
                detail: why.clone(),
            },
        };
        vec![
            state(
                Layer::User,
                self.user.as_ref().map(|()| {
                    format!(
                        "uid {} gid {} (job k of --jobs: uid {} + k), no supplementary groups, \
                         no_new_privs",
                        self.config.uid, self.config.gid, self.config.uid
                    )
                }),
            ),
            state(
                Layer::Namespaces,
                self.namespaces.as_ref().map(|f| {
                    format!(
                        "pid, net, mount, ipc, uts{}: nothing outlives the program, no network, \
                         /proc shows the sandbox only",
                        if f & libc::CLONE_NEWUSER != 0 {
                            ", user"
                        } else {
                            ""
                        }
                    )
                }),
            ),
            state(
                Layer::Landlock,
                self.landlock.as_ref().map(|abi| {
                    let mut what = String::from(
                        "files (read: toolchain, submission, API; write: its own directory)",
                    );
                    if *abi >= 4 {
                        what.push_str(", TCP");
                    }
                    if *abi >= 6 {
                        what.push_str(", signals and abstract sockets outside");
                    }
                    format!("ABI {abi}: {what}")
                }),
            ),
            state(
                Layer::Seccomp,
                self.seccomp.as_ref().map(|_| {
                    "no sockets but AF_UNIX, no ptrace, process_vm_*, io_uring, namespaces, \
                     mounts, bpf, keyrings"
                        .to_string()
                }),
            ),
            LayerState {
                layer: Layer::Limits,
                active: true,
                detail: format!(
                    "CPU, address space, file size, open files, processes{}, no core files; \
                     wall clock by the grader",
                    if self.user.is_ok() {
                        ""
                    } else {
                        " (not binding on root)"
                    }
                ),
            },
        ]
    }

    /// One line: `sandbox: user ✓, namespaces ✓, landlock ✓ (ABI 7), seccomp ✓, limits ✓`,
    /// with `✗` for a missing layer.
    #[must_use]
    pub fn summary(&self) -> String {
        let parts: Vec<String> = self
            .layers()
            .iter()
            .map(|l| {
                let mark = if l.active { "on" } else { "off" };
                match (l.layer, &self.landlock) {
                    (Layer::Landlock, Ok(abi)) => format!("landlock on (ABI {abi})"),
                    (Layer::User, _) if l.active => format!("user on (uid {})", self.config.uid),
                    _ => format!("{} {mark}", l.layer.name()),
                }
            })
            .collect();
        format!("sandbox: {}", parts.join(", "))
    }

    /// The full report: one line per layer.
    #[must_use]
    pub fn report(&self) -> String {
        let mut out = String::new();
        for l in self.layers() {
            out.push_str(&format!(
                "{:<11} {:<7} {}\n",
                l.layer.name(),
                if l.active { "active" } else { "missing" },
                l.detail
            ));
        }
        if self.namespaces.is_err() && self.user.is_ok() {
            out.push_str(&format!(
                "cleanup     active  every process of the sandbox user is killed after each build \
                 and program (uid {} must be used by nothing else)\n",
                self.config.uid
            ));
        }
        out
    }
}
