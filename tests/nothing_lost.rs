//! Nothing lost, nothing clobbered (issue 28), through the binary: outputs on devices, FIFOs,
//! standard output and symbolic links; two outputs on one file; stale frames; `run` and `render`
//! stopped by each terminating signal; scene files bounded in memory; inputs refused.
#![cfg(unix)]

use std::fs;
use std::os::unix::fs::FileTypeExt;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use crate::common::wait_for;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;

fn springlab() -> Command {
    Command::new(env!("CARGO_BIN_EXE_springlab"))
}

fn run_in(dir: &Path, args: &[&str]) -> Output {
    springlab()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run springlab")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Makes a character device `name` in `dir` with `mknod` (major, minor), or `None` with the
/// reason printed when this user may not (not root).
fn device(dir: &Path, name: &str, major: u32, minor: u32) -> Option<PathBuf> {
    let path = dir.join(name);
    let made = Command::new("mknod")
        .arg(&path)
        .arg("c")
        .arg(major.to_string())
        .arg(minor.to_string())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if made {
        Some(path)
    } else {
        println!("skipped: cannot make a device node with mknod (not root)");
        None
    }
}

fn is_char_device(path: &Path) -> bool {
    fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_char_device())
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .map(|r| {
            r.filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

// ---------------------------------------------------------------------------------------------
// Item 1: outputs.

#[test]
fn a_csv_to_a_null_device_leaves_the_device_a_device() {
    let dir = tempfile::tempdir().expect("temp dir");
    let Some(null) = device(dir.path(), "null", 1, 3) else {
        return;
    };
    let out = run_in(dir.path(), &["run", "rope", "--csv", "null"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(is_char_device(&null), "the device was replaced");
    assert_eq!(names(dir.path()), ["null"], "no temporary file left");
    // A render's GIF and chart too.
    let out = run_in(
        dir.path(),
        &[
            "render", "rope", "--frames", "2", "--size", "32x24", "--gif", "null",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(is_char_device(&null));
    assert_eq!(names(dir.path()), ["null"]);
}

#[test]
fn a_full_device_is_an_error_and_stays_a_device() {
    let dir = tempfile::tempdir().expect("temp dir");
    let Some(full) = device(dir.path(), "full", 1, 7) else {
        return;
    };
    let out = run_in(dir.path(), &["run", "rope", "--csv", "full"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("No space left on device"),
        "{}",
        stderr(&out)
    );
    assert!(is_char_device(&full));
    assert_eq!(names(dir.path()), ["full"]);
}

#[test]
fn a_csv_on_standard_output_through_a_pipe() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = run_in(dir.path(), &["run", "rope", "--csv", "-"]);
    assert!(out.status.success(), "{}", stderr(&out));
    // The same CSV as in a file, and the summary on standard error.
    let file = run_in(dir.path(), &["run", "rope", "--csv", "c.csv"]);
    assert!(file.status.success());
    let csv = fs::read(dir.path().join("c.csv")).expect("c.csv");
    assert!(csv.starts_with(b"step,time,kinetic"));
    assert_eq!(out.stdout, csv);
    assert!(stderr(&out).starts_with("scene rope"), "{}", stderr(&out));
    // `--json` also wants standard output.
    let both = run_in(dir.path(), &["run", "rope", "--csv", "-", "--json"]);
    assert!(!both.status.success());
    assert_eq!(
        stderr(&both),
        "springlab: --csv - and --json both write to standard output; write the CSV to a file\n"
    );
}

#[test]
fn a_csv_to_a_fifo_is_written_into_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fifo = dir.path().join("pipe");
    if !mkfifo(&fifo) {
        println!("skipped: mkfifo is not available");
        return;
    }
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || fs::read(&fifo).expect("read the FIFO"))
    };
    let out = run_in(dir.path(), &["run", "rope", "--csv", "pipe"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let got = reader.join().expect("reader");
    let file = run_in(dir.path(), &["run", "rope", "--csv", "c.csv"]);
    assert!(file.status.success());
    assert_eq!(got, fs::read(dir.path().join("c.csv")).expect("c.csv"));
    assert!(
        fs::symlink_metadata(&fifo)
            .expect("fifo")
            .file_type()
            .is_fifo()
    );
}

#[test]
fn a_link_to_a_file_is_followed_and_a_dangling_link_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let real = dir.path().join("real.csv");
    fs::write(&real, "old").expect("write");
    std::os::unix::fs::symlink("real.csv", dir.path().join("link.csv")).expect("link");
    let out = run_in(dir.path(), &["run", "rope", "--csv", "link.csv"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        fs::symlink_metadata(dir.path().join("link.csv"))
            .expect("link")
            .file_type()
            .is_symlink()
    );
    assert!(
        fs::read_to_string(&real)
            .expect("real")
            .starts_with("step,time")
    );

    std::os::unix::fs::symlink("nowhere.csv", dir.path().join("dangling.csv")).expect("link");
    let out = run_in(dir.path(), &["run", "rope", "--csv", "dangling.csv"]);
    assert!(!out.status.success());
    assert_eq!(
        stderr(&out),
        "springlab: cannot write dangling.csv: it is a symbolic link to a file that does not \
         exist; springlab follows links to existing files only and never replaces a link (give \
         the real path)\n"
    );
    assert_eq!(names(dir.path()), ["dangling.csv", "link.csv", "real.csv"]);
}

#[test]
fn two_outputs_on_one_file_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let base = ["render", "rope", "--frames", "2", "--size", "32x24"];
    let cases: [(&[&str], &str); 3] = [
        (
            &["--gif", "x.gif", "--apng", "x.gif"],
            "springlab: --gif and --apng both write x.gif; give each output its own file\n",
        ),
        (
            &["--apng", "x.png", "--energy-chart", "./x.png"],
            "springlab: --apng and --energy-chart both write ./x.png; give each output its own \
             file\n",
        ),
        (
            &["--gif", "-", "--apng", "-"],
            "springlab: --gif and --apng both write -; give each output its own file\n",
        ),
    ];
    for (outputs, message) in cases {
        let mut args = base.to_vec();
        args.extend_from_slice(outputs);
        let out = springlab()
            .args(&args)
            .current_dir(dir.path())
            .stdout(Stdio::piped())
            .output()
            .expect("run");
        assert!(!out.status.success(), "{args:?}");
        assert_eq!(stderr(&out), message);
    }
    assert!(names(dir.path()).is_empty());
}

#[test]
fn stale_frames_are_named_or_removed_never_mixed_silently() {
    let dir = tempfile::tempdir().expect("temp dir");
    let render = |frames: &str, extra: &[&str]| {
        let mut args = vec![
            "render", "rope", "--frames", frames, "--size", "32x24", "--out", "fr",
        ];
        args.extend_from_slice(extra);
        let out = run_in(dir.path(), &args);
        assert!(out.status.success(), "{}", stderr(&out));
        out
    };
    render("12", &[]);
    let out = render("3", &[]);
    assert_eq!(
        stderr(&out),
        "springlab: fr also holds 9 frames of an earlier render (frame_00003.png … \
         frame_00011.png), left in place; --clean-frames removes them\n"
    );
    assert_eq!(names(&dir.path().join("fr")).len(), 12);
    let out = render("3", &["--clean-frames"]);
    assert_eq!(
        stderr(&out),
        "springlab: removed 9 frames of an earlier render from fr (frame_00003.png … \
         frame_00011.png)\n"
    );
    assert_eq!(
        names(&dir.path().join("fr")),
        ["frame_00000.png", "frame_00001.png", "frame_00002.png"]
    );
}

// ---------------------------------------------------------------------------------------------
// Items 3 and 4: `render` and `run` stopped by a signal.

/// Starts a long render into `dir` (frames in `dir/fr`, a GIF and an APNG), waits until frames
/// are being written, sends `signal` and returns its output.
fn killed_render(dir: &Path, signal: Signal) -> Output {
    let child = springlab()
        .args([
            "render", "rope", "--frames", "200000", "--every", "1", "--size", "32x24", "--out",
            "fr", "--gif", "a.gif", "--apng", "a.png",
        ])
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let frames = dir.join("fr");
    wait_for("a staged frame", || {
        names(&frames)
            .iter()
            .filter(|n| n.starts_with(".springlab-frames."))
            .any(|n| frames.join(n).join("frame_00002.png").exists())
    });
    kill(Pid::from_raw(child.id() as i32), signal).expect("kill");
    child.wait_with_output().expect("wait")
}

#[test]
fn a_render_stopped_by_each_signal_leaves_nothing() {
    for (signal, status, cause) in [
        (Signal::SIGTERM, 143, "stopped by SIGTERM"),
        (Signal::SIGHUP, 129, "stopped by SIGHUP"),
        (Signal::SIGQUIT, 131, "stopped by SIGQUIT"),
        (Signal::SIGINT, 130, "interrupted (Ctrl-C)"),
    ] {
        let dir = tempfile::tempdir().expect("temp dir");
        let out = killed_render(dir.path(), signal);
        assert_eq!(
            out.status.code(),
            Some(status),
            "{signal}: {}",
            stderr(&out)
        );
        assert!(
            stderr(&out).ends_with(&format!("{cause}; unfinished outputs were removed\n")),
            "{signal}: {}",
            stderr(&out)
        );
        // The frames' folder was made by the render: it goes too.
        assert!(
            names(dir.path()).is_empty(),
            "{signal}: {:?}",
            names(dir.path())
        );
    }
}

#[test]
fn a_killed_render_leaves_no_frame_at_its_targets() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = killed_render(dir.path(), Signal::SIGKILL);
    assert!(out.status.code().is_none(), "killed");
    // Only hidden files: the staging folder and the animations' temporary files.
    let left: Vec<String> = names(dir.path())
        .into_iter()
        .chain(names(&dir.path().join("fr")))
        .filter(|n| !n.starts_with('.') && n != "fr")
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn a_run_stopped_by_sigterm_removes_its_csv() {
    let dir = tempfile::tempdir().expect("temp dir");
    let child = springlab()
        .args([
            "run",
            "rope",
            "--steps",
            "500000000",
            "--csv",
            "c.csv",
            "--csv-every",
            "1000",
            "--force",
        ])
        .current_dir(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    wait_for("the CSV's temporary file", || {
        names(dir.path()).iter().any(|n| n.starts_with(".c.csv."))
    });
    kill(Pid::from_raw(child.id() as i32), Signal::SIGTERM).expect("kill");
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(143), "{}", stderr(&out));
    assert!(names(dir.path()).is_empty(), "{:?}", names(dir.path()));
}

// ---------------------------------------------------------------------------------------------
// Items 5 and 6: inputs.

/// Runs `springlab args…` in `dir` with at most `bytes` of data segment (heap included).
fn run_limited(dir: &Path, args: &[&str], bytes: u64) -> Output {
    let mut command = springlab();
    command.args(args).current_dir(dir);
    // SAFETY: setrlimit is a plain system call, safe between fork and exec.
    unsafe {
        command.pre_exec(move || {
            nix::sys::resource::setrlimit(nix::sys::resource::Resource::RLIMIT_DATA, bytes, bytes)
                .map_err(std::io::Error::from)
        });
    }
    command.output().expect("run springlab")
}

#[test]
fn sixteen_megabyte_adversarial_scene_files_stay_under_100_mb() {
    let dir = tempfile::tempdir().expect("temp dir");
    let size = 16 * 1024 * 1024 - 64;
    let files = [
        ("arrays.toml", format!("x = [{}]\n", "[],".repeat(size / 3))),
        (
            "tables.toml",
            format!(
                "scene = \"rope\"\n[params]\npinned = [{}]\n",
                "{},".repeat(size / 3)
            ),
        ),
        ("keys.toml", "[[x]]\na = 1\n".repeat(size / 12)),
    ];
    for (name, text) in &files {
        assert!(text.len() < 16 * 1024 * 1024, "{name}");
        fs::write(dir.path().join(name), text).expect("write");
        let out = run_limited(dir.path(), &["run", name, "--steps", "1"], 100 << 20);
        assert_eq!(out.status.code(), Some(1), "{name}: {}", stderr(&out));
        let e = stderr(&out);
        assert!(e.len() < 300, "{name}: {} bytes of error", e.len());
        assert!(
            e.starts_with(&format!("springlab: {name}:")) && e.contains("too many values"),
            "{e}"
        );
        assert_eq!(e.lines().count(), 1);
    }
    // The limit is real: the same file read anyway (--force) does not fit in it.
    let out = run_limited(
        dir.path(),
        &["run", "arrays.toml", "--steps", "1", "--force"],
        100 << 20,
    );
    assert!(
        !stderr(&out).contains("too many values") && !out.status.success(),
        "{}",
        stderr(&out)
    );
}

#[test]
fn vectors_of_other_lengths_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (text, message) in [
        (
            "[[particles]]\nposition = [1, 2, 3, 4, 5]\nmass = 1\n",
            "springlab: v.toml:2:12: `position`: invalid length 5, expected a vector [x, y, z] \
             of 3 numbers\n",
        ),
        (
            "[world]\ngravity = [0, -9.8]\n[[particles]]\nposition = [0, 0, 0]\nmass = 1\n",
            "springlab: v.toml:2:11: `gravity`: invalid length 2, expected a vector [x, y, z] \
             of 3 numbers\n",
        ),
    ] {
        fs::write(dir.path().join("v.toml"), text).expect("write");
        let out = run_in(dir.path(), &["run", "v.toml"]);
        assert_eq!(stderr(&out), message);
    }
    let long = format!(
        "[[particles]]\nposition = [{}0]\nmass = 1\n",
        "0, ".repeat(1_000_000)
    );
    fs::write(dir.path().join("v.toml"), long).expect("write");
    let out = run_in(dir.path(), &["run", "v.toml"]);
    assert!(!out.status.success());
    assert!(stderr(&out).len() < 300, "{}", stderr(&out));
}

#[test]
fn a_fifo_as_scene_or_lesson_file_is_refused_without_waiting() {
    let dir = tempfile::tempdir().expect("temp dir");
    let made = ["s.toml", "01-l.md"]
        .iter()
        .all(|n| mkfifo(&dir.path().join(n)));
    if !made {
        println!("skipped: mkfifo is not available");
        return;
    }
    // Nothing ever writes to these FIFOs: opening one to read would wait for ever.
    let out = run_in(dir.path(), &["run", "s.toml"]);
    assert_eq!(
        stderr(&out),
        "springlab: cannot read scene file s.toml: not a regular file (a FIFO)\n"
    );
    let out = run_in(dir.path(), &["--lessons", ".", "lessons"]);
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains("./01-l.md:1: cannot read: not a regular file (a FIFO)"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!out.status.success());
}

#[test]
fn refused_values_and_options() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (args, message) in [
        (
            &["run", "cube-plane", "--set", "friction=1e308"][..],
            "springlab: `friction` = 1e308 is out of range: allowed 0 ..= 10\n",
        ),
        (
            &["render", "rope", "--frames", "2", "--max-strain", "0"][..],
            "springlab: --max-strain 0: expected a strain > 0 (0.1 = 10 %)\n",
        ),
        (
            &["render", "rope", "--frames", "2", "--max-strain", "nan"][..],
            "springlab: --max-strain NaN: expected a strain > 0 (0.1 = 10 %)\n",
        ),
        (
            &["study", "convergence", "oscillator", "--repeats", "0"][..],
            "springlab: --repeats 0: expected at least 1 timed repeat per point\n",
        ),
        (
            &["--lessons", ".", "lessons"][..],
            "springlab: --lessons .: no lesson files (*.md) in the directory\n",
        ),
    ] {
        let out = run_in(dir.path(), args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        assert_eq!(stderr(&out), message, "{args:?}");
    }
    assert!(names(dir.path()).is_empty());
}

#[test]
fn lessons_over_the_budget_or_with_unknown_parameters_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let header = |n: u32, slug: &str| {
        format!("+++\nnumber = {n}\nslug = \"{slug}\"\ntitle = \"T\"\nsummary = \"S\"\n+++\n\n")
    };
    fs::write(
        dir.path().join("01-big.md"),
        header(1, "big")
            + "+++ step\ntitle = \"Huge\"\nscene = \"rope\"\nparams = { nodes = 1000000 }\n+++\n\
               {{omega_max}} {{limit_dt:rk4}}\n",
    )
    .expect("write");
    fs::write(
        dir.path().join("02-param.md"),
        header(2, "param")
            + "+++ step\ntitle = \"P\"\nscene = \"rope\"\n+++\n{{param:nonexistent}}\n",
    )
    .expect("write");
    fs::write(
        dir.path().join("04-omega.md"),
        header(4, "omega")
            + "+++ step\ntitle = \"Long\"\nscene = \"rope\"\nparams = { nodes = 300000 }\n+++\n\
               {{omega_max}}\n",
    )
    .expect("write");
    let bom = format!(
        "\u{feff}{}",
        (header(3, "bom")
            + "+++ step\ntitle = \"B\"\nscene = \"rope\"\n+++\n{{param:stiffness}}\n")
            .replace('\n', "\r\n")
    );
    fs::write(dir.path().join("03-bom.md"), bom).expect("write");
    let out = run_in(dir.path(), &["--lessons", ".", "lessons"]);
    let listing = String::from_utf8_lossy(&out.stdout);
    assert!(
        listing.contains(" 3. T (bom, 1 steps)") || listing.contains(" 3. T (bom, 1 step)"),
        "{listing}"
    );
    assert!(
        listing.contains(
            "./01-big.md:8: step \"Huge\" needs about 1.28e8 particle and spring updates per \
             simulated second"
        ),
        "{listing}"
    );
    assert!(
        listing.contains(
            "./02-param.md:12: {{param:nonexistent}}: scene `rope` has no parameter `nonexistent`"
        ),
        "{listing}"
    );
    assert!(
        listing.contains(
            "./04-omega.md:8: step \"Long\": its ω_max placeholders may need about 1.2e10 \
             particle and spring updates when the step opens"
        ),
        "{listing}"
    );
    assert_eq!(
        stderr(&out),
        "springlab: 3 lesson file(s) failed to load (marked with ! above)\n"
    );
}

/// An output to a FIFO that nobody reads: the first SIGTERM stops the waiting process, with the
/// stop's status and message (opening a FIFO for writing waits for a reader; that wait checks
/// the stop flag).
#[test]
fn a_signal_ends_the_wait_for_a_fifos_reader() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fifo = dir.path().join("energy.png");
    if !mkfifo(&fifo) {
        println!("skipped: mkfifo is not available");
        return;
    }
    let mut child = springlab()
        .args([
            "render",
            "rope",
            "--time",
            "1",
            "--energy-chart",
            "energy.png",
        ])
        .current_dir(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let pid = child.id();
    // Waiting: asleep at two looks 100 ms apart (the rope's second of simulation takes
    // milliseconds; then only the wait for a reader is left).
    let asleep = || {
        fs::read_to_string(format!("/proc/{pid}/stat"))
            .ok()
            .and_then(|s| {
                s.rsplit(')')
                    .next()
                    .map(|r| r.trim_start().starts_with('S'))
            })
            .unwrap_or(false)
    };
    wait_for("the render waiting for a reader", || {
        asleep() && {
            std::thread::sleep(std::time::Duration::from_millis(100));
            asleep()
        }
    });
    kill(Pid::from_raw(pid as i32), Signal::SIGTERM).expect("kill");
    // A guard against a process that ignores the signal, never a timing assertion.
    let start = std::time::Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > std::time::Duration::from_secs(60) {
            let _ = child.kill();
            panic!("the first SIGTERM did not end the wait for the FIFO's reader");
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let out = child.wait_with_output().expect("output");
    assert_eq!(out.status.code(), Some(143), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("stopped by SIGTERM"),
        "{}",
        stderr(&out)
    );
    assert!(is_fifo(&fifo), "the FIFO stays a FIFO");
}

/// Makes a FIFO at `path` (false where `mkfifo` is not available).
fn mkfifo(path: &Path) -> bool {
    Command::new("mkfifo")
        .arg(path)
        .status()
        .is_ok_and(|s| s.success())
}

fn is_fifo(path: &Path) -> bool {
    fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}
