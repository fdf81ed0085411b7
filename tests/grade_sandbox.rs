//! Grading against code that reaches outside its own process: one test per attack of issue 24,
//! each a homework crate doing it while `springlab grade` grades it. Each asserts that the
//! attack is contained, that the genuine score is written (the untouched starter scores 5 / 35:
//! "builds and runs"), and that no process of the sandbox user is left afterwards.
//!
//! The attacks use raw system calls (`kill`, `fork`, `setsid`) through inline assembly, as a
//! student could: the homework crate has no dependency but the API. Every test uses its own
//! sandbox user id (`--sandbox-uid`), so tests running at once never see each other's processes.
//! Where the sandbox cannot hold on this machine (not root and no other layer), a test prints
//! why and returns.
#![cfg(all(target_os = "linux", target_arch = "x86_64"))]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

mod results;
mod untrusted;

const ROPE: &str = include_str!("homework/rope.rs");
const INTEGRATORS: &str = include_str!("homework/integrators.rs");

/// System calls for the attacks (x86-64 numbers).
const SYSCALLS: &str = r##"
#[allow(dead_code)]
unsafe fn sys(n: usize, a: usize, b: usize, c: usize) -> isize {
    let r: isize;
    unsafe {
        core::arch::asm!("syscall", inlateout("rax") n as isize => r, in("rdi") a, in("rsi") b,
            in("rdx") c, lateout("rcx") _, lateout("r11") _, options(nostack));
    }
    r
}
#[allow(dead_code)] const KILL: usize = 62;
#[allow(dead_code)] const FORK: usize = 57;
#[allow(dead_code)] const SETSID: usize = 112;
#[allow(dead_code)] const PAUSE: usize = 34;
#[allow(dead_code)] const GETPPID: usize = 110;
const FORGED: &str = r#"{"score": 35.0, "max_score": 35.0, "output": "forged", "tests": []}"#;
"##;

/// The target directory shared by the tests here (the student API compiles once).
fn target() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("grade-sandbox-builds")
}

/// A fresh, empty scratch directory for test `name`.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("grade-sandbox-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

fn springlab(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_springlab"));
    command.current_dir(dir).args(args);
    for (k, v) in env {
        command.env(k, v);
    }
    // A guard against a grader that blocks (the FIFO case): never a timing assertion.
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run springlab");
    let start = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > Duration::from_secs(300) {
            let _ = child.kill();
            panic!("springlab {args:?} did not end within 300 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

/// The sandbox report of this machine; `None` (with the reason printed) when no layer that
/// could hold these attacks is active.
fn layers() -> Option<String> {
    let out = springlab(Path::new("/"), &["grade", "--sandbox-report"], &[]);
    let report = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{report}");
    let active = |name: &str| {
        report
            .lines()
            .any(|l| l.starts_with(name) && l.contains(" active "))
    };
    if !active("user") && !active("landlock") {
        eprintln!(
            "SKIPPED: neither another user (springlab is not root) nor Landlock is available \
             here, so nothing keeps a student's program from the grader's files:\n{report}"
        );
        return None;
    }
    Some(report)
}

fn is_active(report: &str, layer: &str) -> bool {
    report
        .lines()
        .any(|l| l.starts_with(layer) && l.contains(" active "))
}

/// Processes whose real user id is `uid`.
fn processes_of(uid: u32) -> Vec<u32> {
    std::fs::read_dir("/proc")
        .expect("/proc")
        .filter_map(Result::ok)
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|pid| {
            std::fs::read_to_string(format!("/proc/{pid}/status"))
                .ok()
                .and_then(|s| {
                    s.lines()
                        .find(|l| l.starts_with("Uid:"))
                        .and_then(|l| l.split_whitespace().nth(1)?.parse::<u32>().ok())
                })
                == Some(uid)
        })
        .collect()
}

/// `springlab homework new parent/name --assignment rope`; `lib` as src/lib.rs when given.
fn homework(parent: &Path, name: &str, lib: Option<&str>) -> PathBuf {
    let out = springlab(
        parent,
        &["homework", "new", name, "--assignment", "rope"],
        &[],
    );
    assert!(out.status.success(), "{out:?}");
    let dir = parent.join(name);
    if let Some(lib) = lib {
        std::fs::write(dir.join("src/lib.rs"), lib).expect("write lib.rs");
        std::fs::write(dir.join("src/integrators.rs"), INTEGRATORS).expect("write");
    }
    dir
}

/// The untouched starter with `attack()` called at the start of `rope` (the first method the
/// grader calls) and `code` (which defines `attack`) appended.
fn starter_with(parent: &Path, name: &str, code: &str) -> PathBuf {
    let dir = homework(parent, name, None);
    let lib = std::fs::read_to_string(dir.join("src/lib.rs")).expect("lib.rs");
    assert_eq!(lib.matches("        Rope::default()\n").count(), 1);
    let lib = lib.replace(
        "        Rope::default()\n",
        "        attack();\n        Rope::default()\n",
    );
    std::fs::write(
        dir.join("src/lib.rs"),
        format!("{lib}\n{SYSCALLS}\n{code}\n"),
    )
    .expect("write lib.rs");
    dir
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}: {text}", path.display()))
}

/// Grades `dir` as sandbox user `uid` with `--gradescope results.json --json report.json` in
/// its parent and `extra` arguments; asserts exit 0; returns (stdout, results, report).
fn grade(
    dir: &Path,
    uid: u32,
    extra: &[&str],
    env: &[(&str, &str)],
) -> (String, serde_json::Value, serde_json::Value) {
    let parent = dir.parent().expect("parent");
    let results = parent.join("results.json");
    let report = parent.join("report.json");
    let t = target();
    let uid = uid.to_string();
    let mut args = vec![
        "grade",
        dir.to_str().expect("utf-8"),
        "--gradescope",
        results.to_str().expect("utf-8"),
        "--json",
        report.to_str().expect("utf-8"),
        "--target-dir",
        t.to_str().expect("utf-8"),
        "--sandbox-uid",
        &uid,
        "--time-limit-ms",
        "3000",
    ];
    args.extend_from_slice(extra);
    let out = springlab(parent, &args, env);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{:?}\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    (stdout, json(&results), json(&report))
}

/// The genuine score of the starter, everywhere it is written, and no process left of `uid`.
fn assert_genuine(stdout: &str, results: &serde_json::Value, report: &serde_json::Value, uid: u32) {
    assert!(stdout.contains("score 5 / 35"), "{stdout}");
    assert_eq!(results["score"].as_f64(), Some(5.0), "{results}");
    assert_eq!(
        results["tests"].as_array().map(Vec::len),
        Some(6),
        "{results}"
    );
    assert_eq!(report["score"].as_f64(), Some(5.0), "{report}");
    assert!(
        report["sandbox"]
            .as_str()
            .is_some_and(|s| s.starts_with("sandbox: "))
    );
    assert_eq!(
        processes_of(uid),
        Vec::<u32>::new(),
        "processes of the sandbox user"
    );
}

/// Reads the grader's command line from `/proc/<parent>/cmdline` (and every other process's),
/// writes a perfect results.json and report.json at the paths it names and at the known ones,
/// and kills the grader.
fn kill_and_forge(name: &str, uid: u32, env: &[(&str, &str)]) {
    let Some(_) = layers() else { return };
    let root = scratch(name);
    let results = root.join("results.json");
    let report = root.join("report.json");
    let code = format!(
        r#"
const KNOWN: [&str; 2] = [{results:?}, {report:?}];
fn attack() {{
    let mut targets: Vec<String> = KNOWN.iter().map(|s| s.to_string()).collect();
    let mut pids: Vec<usize> = vec![std::os::unix::process::parent_id() as usize];
    if let Ok(d) = std::fs::read_dir("/proc") {{
        for e in d.flatten() {{
            if let Ok(pid) = e.file_name().to_string_lossy().parse::<usize>() {{ pids.push(pid); }}
        }}
    }}
    for pid in &pids {{
        if let Ok(cmd) = std::fs::read(format!("/proc/{{pid}}/cmdline")) {{
            let args: Vec<String> = cmd.split(|b| *b == 0)
                .map(|a| String::from_utf8_lossy(a).into_owned()).collect();
            if args.iter().any(|a| a == "grade") {{
                for w in args.windows(2) {{
                    if w[0] == "--gradescope" || w[0] == "--json" {{ targets.push(w[1].clone()); }}
                }}
                unsafe {{ sys(KILL, *pid, 9, 0); }}
            }}
        }}
    }}
    for t in &targets {{ let _ = std::fs::write(t, FORGED); }}
    unsafe {{ sys(KILL, std::os::unix::process::parent_id() as usize, 9, 0); }}
}}
"#
    );
    let dir = starter_with(&root, "hw", &code);
    let (stdout, results, report) = grade(&dir, uid, &[], env);
    assert_genuine(&stdout, &results, &report, uid);
}

#[test]
fn kill_and_forge_through_proc_cmdline_is_contained() {
    kill_and_forge("forge", 64001, &[]);
}

#[test]
fn kill_and_forge_is_contained_without_namespaces() {
    // As in a container whose seccomp profile forbids unshare: the other layers hold.
    kill_and_forge(
        "forge-nons",
        64002,
        &[("SPRINGLAB_SANDBOX_DISABLE", "namespaces")],
    );
}

/// fork + setsid + fork: a daemon that waits for the grader's final write and rewrites it.
fn daemon(name: &str, uid: u32, env: &[(&str, &str)]) {
    let Some(_) = layers() else { return };
    let root = scratch(name);
    let results = root.join("results.json");
    let code = format!(
        r#"
fn attack() {{
    unsafe {{
        if sys(FORK, 0, 0, 0) == 0 {{
            sys(SETSID, 0, 0, 0);
            if sys(FORK, 0, 0, 0) == 0 {{
                std::thread::sleep(std::time::Duration::from_millis(1500));
                let _ = std::fs::write({results:?}, FORGED);
                loop {{ sys(PAUSE, 0, 0, 0); }}
            }}
        }}
    }}
}}
"#
    );
    let dir = starter_with(&root, "hw", &code);
    let (stdout, first, report) = grade(&dir, uid, &[], env);
    assert_genuine(&stdout, &first, &report, uid);
    // Past the daemon's wait: the results are still the grader's.
    std::thread::sleep(Duration::from_millis(2500));
    assert_eq!(json(&results), first);
    assert_eq!(processes_of(uid), Vec::<u32>::new());
}

#[test]
fn a_setsid_daemon_does_not_outlive_the_grade() {
    daemon("daemon", 64003, &[]);
}

#[test]
fn a_setsid_daemon_does_not_outlive_the_grade_without_namespaces() {
    daemon(
        "daemon-nons",
        64004,
        &[("SPRINGLAB_SANDBOX_DISABLE", "namespaces")],
    );
}

#[test]
fn two_hundred_forks_leave_nothing_behind() {
    let Some(_) = layers() else { return };
    let uid = 64005;
    let root = scratch("forks");
    let code = r#"
fn attack() {
    for _ in 0..200 {
        unsafe {
            if sys(FORK, 0, 0, 0) == 0 {
                loop { sys(PAUSE, 0, 0, 0); }
            }
        }
    }
}
"#;
    let dir = starter_with(&root, "hw", code);
    let (stdout, results, report) = grade(&dir, uid, &[], &[]);
    assert_genuine(&stdout, &results, &report, uid);
    // And with namespaces left out: the sandbox user's processes are swept.
    let (stdout, results, report) = grade(
        &dir,
        uid,
        &[],
        &[("SPRINGLAB_SANDBOX_DISABLE", "namespaces")],
    );
    assert_genuine(&stdout, &results, &report, uid);
}

/// A class: `c1` plants a `.cargo/config.toml` with a `rustc-wrapper` in every folder above its
/// working directory and in the target directory, and overwrites its classmates' `src/lib.rs`
/// (in the class folder and in any build folder it can find); `c2` and `c3` are correct, `c4`
/// the untouched starter. Each scores its own: 5, 35, 35, 5; the wrapper never runs.
#[test]
fn a_class_batch_is_safe_from_planted_build_config_and_overwritten_classmates() {
    let Some(_) = layers() else { return };
    let uid = 64006;
    let root = scratch("class");
    let class = root.join("class");
    std::fs::create_dir_all(&class).expect("class");
    let marker = root.join("wrapper-ran");
    let wrapper = root.join("wrapper.sh");
    let t = target();
    let code = format!(
        r##"
fn plant(dir: &std::path::Path) {{
    let cargo = dir.join(".cargo");
    let _ = std::fs::create_dir_all(&cargo);
    let _ = std::fs::write(cargo.join("config.toml"),
        format!("[build]\nrustc-wrapper = {{:?}}\n", {wrapper:?}));
}}
fn attack() {{
    let _ = std::fs::write({wrapper:?}, "#!/bin/sh\ntouch {marker}\nexec \"$@\"\n");
    let mut dir = std::env::current_dir().unwrap_or_default();
    loop {{
        plant(&dir);
        if !dir.pop() {{ break; }}
    }}
    plant(std::path::Path::new({t:?}));
    plant(std::path::Path::new({class:?}));
    let starter = "use springlab_homework::*;\npub struct Student;\n";
    for c in ["c2-correct", "c3-correct"] {{
        let _ = std::fs::write(std::path::Path::new({class:?}).join(c).join("src/lib.rs"), starter);
    }}
    // Build folders of this run, wherever they are.
    let tmp = std::env::temp_dir();
    if let Ok(d) = std::fs::read_dir(&tmp) {{
        for e in d.flatten() {{
            if let Ok(subs) = std::fs::read_dir(e.path()) {{
                for s in subs.flatten() {{
                    let _ = std::fs::write(s.path().join("crate/src/lib.rs"), starter);
                }}
            }}
        }}
    }}
}}
"##,
        marker = marker.display()
    );
    starter_with(&class, "c1-attacker", &code);
    homework(&class, "c2-correct", Some(ROPE));
    homework(
        &class,
        "c3-correct",
        Some(&format!("{ROPE}\n// another student\n")),
    );
    homework(&class, "c4-starter", None);
    let uid_s = uid.to_string();
    let out = springlab(
        &root,
        &[
            "grade",
            "class",
            "--csv",
            "grades.csv",
            "--target-dir",
            t.to_str().expect("utf-8"),
            "--sandbox-uid",
            &uid_s,
            "--time-limit-ms",
            "3000",
        ],
        &[],
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(root.join("grades.csv")).expect("grades.csv");
    let scores: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(2)
                .and_then(|s| s.parse().ok())
                .expect("score")
        })
        .collect();
    assert_eq!(scores, [5.0, 35.0, 35.0, 5.0], "{csv}");
    assert!(!marker.exists(), "the planted rustc-wrapper ran");
    assert_eq!(processes_of(uid), Vec::<u32>::new());
    // A later run with a new starter: built without the wrapper, genuine score.
    let later = homework(&root, "later", None);
    let lib = std::fs::read_to_string(later.join("src/lib.rs")).expect("lib");
    std::fs::write(later.join("src/lib.rs"), format!("{lib}\n// later\n")).expect("write");
    let (stdout, results, report) = grade(&later, uid, &[], &[]);
    assert_genuine(&stdout, &results, &report, uid);
    assert!(
        !marker.exists(),
        "the planted rustc-wrapper ran in a later run"
    );
}

/// `include_str!` of files outside the crate (the system's password file, the grader's own
/// source) and a build-time environment variable: the build fails, and the feedback holds none of
/// their contents.
#[test]
fn include_str_of_outside_files_is_refused_and_never_echoed() {
    let Some(report) = layers() else { return };
    if !is_active(&report, "landlock") && !is_active(&report, "user") {
        return;
    }
    let uid = 64007;
    let root = scratch("include");
    let secret = root.join("secret.txt");
    std::fs::write(&secret, "the grader's secret 4f1c").expect("secret");
    let own = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/grade/src/grade/reference.rs");
    let code = format!(
        r#"
const PASSWD: &str = include_str!("/etc/passwd");
const SECRET: &str = include_str!({secret:?});
const OWN: &str = include_str!({own:?});
fn attack() {{ panic!("{{PASSWD}}{{SECRET}}{{OWN}}{{}}", option_env!("HOME").unwrap_or("")); }}
"#
    );
    let dir = starter_with(&root, "hw", &code);
    let (stdout, results, report) = grade(&dir, uid, &[], &[]);
    assert!(stdout.contains("score 0 / 35"), "{stdout}");
    assert!(stdout.contains("the crate did not build"), "{stdout}");
    let everything = format!("{stdout}{results}{report}");
    assert!(everything.contains("couldn't read"), "{everything}");
    assert!(!everything.contains("root:x:0:0"), "{everything}");
    assert!(!everything.contains("4f1c"), "{everything}");
    assert!(
        !everything.contains("impl RopeHomework for Reference"),
        "{everything}"
    );
    assert_eq!(results["score"].as_f64(), Some(0.0));
    assert_eq!(processes_of(uid), Vec::<u32>::new());
}

/// An endless loop in constant evaluation: the build is stopped at its limit and scores 0 with
/// the reason.
#[test]
fn a_const_eval_hang_is_stopped_at_the_build_limit() {
    let Some(_) = layers() else { return };
    let uid = 64008;
    let root = scratch("consthang");
    let code = r#"
#[allow(long_running_const_eval)]
const FOREVER: u64 = {
    let mut i: u64 = 1;
    while i != 0 { i = i.wrapping_mul(3) | 1; }
    i
};
fn attack() { std::hint::black_box(FOREVER); }
"#;
    let lib_attr = "#![allow(long_running_const_eval)]\n";
    let dir = starter_with(&root, "hw", code);
    let lib = std::fs::read_to_string(dir.join("src/lib.rs")).expect("lib");
    std::fs::write(dir.join("src/lib.rs"), format!("{lib_attr}{lib}")).expect("write");
    let (stdout, results, _) = grade(&dir, uid, &["--build-limit-s", "3"], &[]);
    assert!(stdout.contains("score 0 / 35"), "{stdout}");
    // Whichever of the build's two limits of 3 s comes first: wall clock or CPU time (rustc
    // may use more than one thread).
    assert!(
        stdout.contains("did not finish within 3 s")
            || stdout.contains("the compiler used up its CPU time (3 s)"),
        "{stdout}"
    );
    assert_eq!(results["score"].as_f64(), Some(0.0));
    assert_eq!(processes_of(uid), Vec::<u32>::new());
}

/// A static of 8 GiB: the compiler's memory limit stops it; 0 with the reason.
#[test]
fn compile_time_memory_is_limited() {
    let Some(_) = layers() else { return };
    let uid = 64009;
    let root = scratch("bigstatic");
    let code = r#"
static BIG: [u8; 1 << 33] = [7; 1 << 33];
fn attack() { std::hint::black_box(&BIG[12345]); }
"#;
    let dir = starter_with(&root, "hw", code);
    let (stdout, results, _) = grade(&dir, uid, &["--build-memory-mb", "1024"], &[]);
    assert!(stdout.contains("score 0 / 35"), "{stdout}");
    assert!(
        stdout.contains("memory") || stdout.contains("allocate"),
        "the reason names memory: {stdout}"
    );
    assert_eq!(results["score"].as_f64(), Some(0.0));
    assert_eq!(processes_of(uid), Vec::<u32>::new());
}

/// TCP and UDP to a listener of this test on the loopback: nothing arrives.
#[test]
fn no_tcp_or_udp_leaves_the_sandbox() {
    let Some(report) = layers() else { return };
    if !is_active(&report, "seccomp") && !is_active(&report, "namespaces") {
        eprintln!("SKIPPED: neither seccomp nor a network namespace is available:\n{report}");
        return;
    }
    let uid = 64010;
    let tcp = std::net::TcpListener::bind("127.0.0.1:0").expect("tcp listener");
    let udp = std::net::UdpSocket::bind("127.0.0.1:0").expect("udp socket");
    tcp.set_nonblocking(true).expect("nonblocking");
    udp.set_nonblocking(true).expect("nonblocking");
    let root = scratch("network");
    let code = format!(
        r#"
fn attack() {{
    use std::io::Write;
    if let Ok(mut s) = std::net::TcpStream::connect("127.0.0.1:{tcp}") {{
        let _ = s.write_all(b"tcp escaped");
    }}
    if let Ok(u) = std::net::UdpSocket::bind("127.0.0.1:0") {{
        let _ = u.send_to(b"udp escaped", "127.0.0.1:{udp}");
    }}
    if let Ok(u) = std::net::UdpSocket::bind("[::1]:0") {{
        let _ = u.send_to(b"udp6 escaped", "127.0.0.1:{udp}");
    }}
}}
"#,
        tcp = tcp.local_addr().expect("addr").port(),
        udp = udp.local_addr().expect("addr").port()
    );
    let dir = starter_with(&root, "hw", &code);
    let (stdout, results, report) = grade(&dir, uid, &[], &[]);
    assert_genuine(&stdout, &results, &report, uid);
    assert!(tcp.accept().is_err(), "a TCP connection arrived");
    let mut buf = [0u8; 64];
    assert!(udp.recv_from(&mut buf).is_err(), "a UDP datagram arrived");
}

/// The grader's /proc: environ (with a secret), fd, and mem opened for writing; whatever is
/// found is put in a panic message, which the feedback would show.
#[test]
fn the_graders_proc_is_out_of_reach() {
    let Some(_) = layers() else { return };
    let uid = 64011;
    let root = scratch("proc");
    let code = r#"
fn attack() {
    let mut found = String::new();
    let mut pids: Vec<String> = vec![std::os::unix::process::parent_id().to_string()];
    if let Ok(d) = std::fs::read_dir("/proc") {
        pids.extend(d.flatten().map(|e| e.file_name().to_string_lossy().into_owned()));
    }
    for pid in pids {
        if let Ok(env) = std::fs::read(format!("/proc/{pid}/environ")) {
            found.push_str(&String::from_utf8_lossy(&env));
        }
        if let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) {
            for fd in fds.flatten() {
                if let Ok(t) = std::fs::read_link(fd.path()) {
                    found.push_str(&format!(" fd {}", t.display()));
                }
            }
        }
        if std::fs::OpenOptions::new().read(true).write(true)
            .open(format!("/proc/{pid}/mem")).is_ok() {
            found.push_str(&format!(" mem of {pid} opened"));
        }
    }
    if found.contains("SPRINGLAB_TEST_SECRET") || found.contains("mem of") {
        panic!("{found}");
    }
}
"#;
    let dir = starter_with(&root, "hw", code);
    let (stdout, results, report) = grade(
        &dir,
        uid,
        &[],
        &[("SPRINGLAB_TEST_SECRET", "the grader's environment 9d2e")],
    );
    assert_genuine(&stdout, &results, &report, uid);
    let everything = format!("{stdout}{results}{report}");
    assert!(!everything.contains("9d2e"), "{everything}");
    assert!(!everything.contains("mem of"), "{everything}");
}

/// The command name (`/proc/PID/comm`) and state letter of process `pid`.
fn comm_and_state(pid: u32) -> Option<(String, char)> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let (open, close) = (stat.find('(')?, stat.rfind(')')?);
    let state = stat[close + 1..].trim_start().chars().next()?;
    Some((stat[open + 1..close].to_string(), state))
}

/// A grader that dies while the student's program loops (SIGKILLed, as by a course harness,
/// without any cleanup of its own) takes the program with it: with namespaces, the process
/// between the grader and the namespace watches the grader process and kills the namespace
/// when it ends. (Without namespaces the program is the grader's direct child and is swept at
/// the next grade of that slot: docs/grading.md.)
#[test]
fn a_looping_program_does_not_outlive_a_killed_grader() {
    let Some(report) = layers() else { return };
    if !is_active(&report, "namespaces") {
        println!("no PID namespace on this machine: nothing watches the grader\n{report}");
        return;
    }
    let uid = 64020;
    let root = scratch("killed-grader");
    let dir = starter_with(
        &root,
        "spinner",
        "fn attack() { loop { std::hint::spin_loop(); } }",
    );
    let t = target();
    let mut grader = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .current_dir(&root)
        .args([
            "grade",
            dir.to_str().expect("utf-8"),
            "--target-dir",
            t.to_str().expect("utf-8"),
            "--sandbox-uid",
            &uid.to_string(),
            "--time-limit-ms",
            "120000",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run springlab");
    // The program (the grader copies it as `program`) running as the sandbox user; a guard of 300 s
    // against a build that never ends, never a timing assertion.
    let spinning = || {
        processes_of(uid)
            .into_iter()
            .any(|pid| comm_and_state(pid).is_some_and(|(c, s)| c == "program" && s == 'R'))
    };
    let start = Instant::now();
    while !spinning() {
        if let Some(status) = grader.try_wait().expect("wait") {
            let out = grader.wait_with_output().expect("output");
            panic!("the grader ended ({status}) before the program looped: {out:?}");
        }
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no looping program within 300 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    grader.kill().expect("SIGKILL the grader");
    grader.wait().expect("reap the grader");
    let start = Instant::now();
    while !processes_of(uid).is_empty() && start.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let left = processes_of(uid);
    for pid in &left {
        // Never leave a spinning program behind, even when the test fails.
        let _ = nix::sys::signal::kill(
            nix::unistd::Pid::from_raw(i32::try_from(*pid).expect("pid")),
            nix::sys::signal::Signal::SIGKILL,
        );
    }
    let named: Vec<_> = left.iter().map(|&p| (p, comm_and_state(p))).collect();
    assert_eq!(
        named,
        Vec::new(),
        "processes of the sandbox user 5 s after the grader was killed"
    );
}
