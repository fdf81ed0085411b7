//! `springlab render` through the real binary: the files it writes, decoded, and its messages
//! for bad input.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("render-cli-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn springlab_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_springlab"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run springlab")
}

fn success(dir: &Path, args: &[&str]) -> String {
    let out = springlab_in(dir, args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn failure(args: &[&str]) -> String {
    let dir = scratch(&format!("fail-{}", args.join("_").replace(['/', '.'], "-")));
    let out = springlab_in(&dir, args);
    assert!(!out.status.success(), "expected failure for {args:?}");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn gif_frames(path: &Path) -> (usize, u16, u16) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(File::open(path).expect("gif file"))
        .expect("a GIF");
    let (w, h) = (decoder.width(), decoder.height());
    let mut frames = 0;
    while decoder.read_next_frame().expect("a frame").is_some() {
        frames += 1;
    }
    (frames, w, h)
}

/// (frames declared in acTL, frames actually decoded, width, height).
fn apng_frames(path: &Path) -> (u32, u32, u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(File::open(path).expect("apng")));
    let mut reader = decoder.read_info().expect("a PNG");
    let info = reader.info();
    let declared = info.animation_control.expect("animated").num_frames;
    let (w, h) = (info.width, info.height);
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let mut decoded = 0;
    while reader.next_frame(&mut buf).is_ok() {
        decoded += 1;
        if decoded > declared + 1 {
            break;
        }
    }
    (declared, decoded, w, h)
}

#[test]
fn frames_gif_and_apng_have_the_asked_frame_count() {
    let dir = scratch("counts");
    let stdout = success(
        &dir,
        &[
            "render", "rope", "--frames", "7", "--every", "3", "--size", "160x120", "--out", "f",
            "--gif", "r.gif", "--apng", "r.apng",
        ],
    );
    assert!(
        stdout.contains("wrote 7 frames of 160x120 to f/frame_00000.png … frame_00006.png"),
        "{stdout}"
    );
    let mut files: Vec<String> = std::fs::read_dir(dir.join("f"))
        .expect("frames dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let expected: Vec<String> = (0..7).map(|k| format!("frame_{k:05}.png")).collect();
    assert_eq!(files, expected);
    let frame = png::Decoder::new(std::io::BufReader::new(
        File::open(dir.join("f/frame_00006.png")).expect("frame"),
    ))
    .read_info()
    .expect("a PNG");
    assert_eq!((frame.info().width, frame.info().height), (160, 120));
    assert_eq!(gif_frames(&dir.join("r.gif")), (7, 160, 120));
    assert_eq!(apng_frames(&dir.join("r.apng")), (7, 7, 160, 120));
}

#[test]
fn default_output_is_the_frames_directory() {
    let dir = scratch("default-out");
    success(
        &dir,
        &["render", "oscillator", "--frames", "2", "--size", "64x48"],
    );
    assert!(dir.join("frames/frame_00000.png").is_file());
    assert!(dir.join("frames/frame_00001.png").is_file());
    assert!(!dir.join("frames/frame_00002.png").exists());
}

#[test]
fn frame_k_is_the_state_after_k_times_every_steps() {
    // Frames 0..=2 every 5 steps equal frames 0, 5, 10 of a run drawn every step.
    let dir = scratch("every");
    let args = |every: &str, frames: &str, out: &str| {
        vec![
            "render".to_string(),
            "rope".into(),
            "--frames".into(),
            frames.into(),
            "--every".into(),
            every.into(),
            "--size".into(),
            "96x72".into(),
            "--out".into(),
            out.into(),
        ]
    };
    let run = |a: Vec<String>| {
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        success(&dir, &a);
    };
    run(args("5", "3", "sparse"));
    run(args("1", "11", "dense"));
    for (sparse, dense) in [(0, 0), (1, 5), (2, 10)] {
        let a = std::fs::read(dir.join(format!("sparse/frame_{sparse:05}.png"))).expect("frame");
        let b = std::fs::read(dir.join(format!("dense/frame_{dense:05}.png"))).expect("frame");
        assert!(a == b, "sparse frame {sparse} = dense frame {dense}");
    }
    let a = std::fs::read(dir.join("sparse/frame_00001.png")).expect("frame");
    let b = std::fs::read(dir.join("dense/frame_00004.png")).expect("frame");
    assert!(a != b, "frames of different steps differ");
}

#[test]
fn two_runs_write_the_same_bytes() {
    let dir = scratch("determinism");
    for name in ["a.gif", "b.gif"] {
        success(
            &dir,
            &[
                "render", "ropes", "--frames", "4", "--every", "8", "--size", "120x90", "--gif",
                name,
            ],
        );
    }
    let a = std::fs::read(dir.join("a.gif")).expect("gif");
    let b = std::fs::read(dir.join("b.gif")).expect("gif");
    assert!(a == b);
}

#[test]
fn energy_chart_is_written() {
    let dir = scratch("chart");
    let stdout = success(
        &dir,
        &["render", "rope", "--energy-chart", "e.png", "--time", "2"],
    );
    assert!(stdout.contains("wrote energy chart e.png"), "{stdout}");
    let decoder = png::Decoder::new(std::io::BufReader::new(
        File::open(dir.join("e.png")).expect("chart"),
    ));
    let mut reader = decoder.read_info().expect("a PNG");
    assert_eq!((reader.info().width, reader.info().height), (640, 480));
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    reader.next_frame(&mut buf).expect("pixels");
    let dark = buf.chunks(3).filter(|p| p.iter().all(|&c| c < 100)).count();
    assert!(
        dark > 500,
        "text, axes and lines are drawn ({dark} dark pixels)"
    );
    // No frames were asked for, so no frames directory.
    assert!(!dir.join("frames").exists());
}

#[test]
fn a_diverged_run_stops_with_a_message() {
    let dir = scratch("diverged");
    let out = springlab_in(
        &dir,
        &[
            "render",
            "rope",
            "--method",
            "explicit-euler",
            "--dt",
            "0.1",
            "--frames",
            "60",
            "--every",
            "2",
            "--size",
            "80x60",
            "--gif",
            "d.gif",
            "--apng",
            "d.apng",
        ],
    );
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("diverged at step") && stderr.contains("Rendering stopped after"),
        "{stderr}"
    );
    let (frames, _, _) = gif_frames(&dir.join("d.gif"));
    assert!((1..60).contains(&frames), "{frames} frames");
    // The APNG's header is corrected to the frames written.
    let (declared, decoded, _, _) = apng_frames(&dir.join("d.apng"));
    assert_eq!((declared as usize, decoded as usize), (frames, frames));
}

#[test]
fn bad_sizes_are_explained() {
    for (size, message) in [
        ("0x480", "width and height must be at least 1 pixel"),
        ("640x0", "width and height must be at least 1 pixel"),
        ("9000x100", "width and height must be at most 8192 pixels"),
        ("100x8193", "width and height must be at most 8192 pixels"),
        (
            "640",
            "expected WIDTHxHEIGHT in pixels, for example 640x480",
        ),
        (
            "axb",
            "expected WIDTHxHEIGHT in pixels, for example 640x480",
        ),
        (
            "-5x10",
            "expected WIDTHxHEIGHT in pixels, for example 640x480",
        ),
    ] {
        let stderr = failure(&["render", "rope", "--frames", "2", "--size", size]);
        assert!(
            stderr.contains(&format!("--size {size}: {message}")),
            "{size}: {stderr}"
        );
    }
}

#[test]
fn unwritable_outputs_are_explained() {
    let dir = scratch("unwritable");
    std::fs::write(dir.join("taken"), b"a file").expect("file");
    let out = springlab_in(&dir, &["render", "rope", "--frames", "2", "--out", "taken"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("cannot write taken"), "{stderr}");

    let out = springlab_in(
        &dir,
        &[
            "render",
            "rope",
            "--frames",
            "2",
            "--gif",
            "missing/dir/r.gif",
        ],
    );
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("cannot write missing/dir/r.gif: directory missing/dir does not exist"),
        "{stderr}"
    );

    let out = springlab_in(
        &dir,
        &[
            "render",
            "rope",
            "--energy-chart",
            "nowhere/e.png",
            "--time",
            "1",
        ],
    );
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("cannot write nowhere/e.png: directory nowhere does not exist"),
        "{stderr}"
    );

    let out = springlab_in(
        &dir,
        &["render", "rope", "--frames", "2", "--out", "taken/sub"],
    );
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("cannot write taken/sub"), "{stderr}");
}

#[test]
fn bad_counts_and_options_are_explained() {
    for (args, message) in [
        (
            vec!["render", "rope", "--frames", "0"],
            "--frames 0: expected at least 1 frame",
        ),
        (
            vec!["render", "rope", "--frames", "3", "--every", "0"],
            "--every 0: expected a number of steps >= 1",
        ),
        (
            vec!["render", "rope"],
            "render needs --frames N (or --time T)",
        ),
        (
            vec!["render", "rope", "--frames", "2", "--fps", "0"],
            "--fps 0: expected a frame rate from 0.1 to 100",
        ),
        (
            vec![
                "render",
                "rope",
                "--frames",
                "2",
                "--springs",
                "struct,twist",
            ],
            "unknown spring kind `twist`",
        ),
        (
            vec!["render", "rope", "--frames", "2", "--dt", "-1"],
            "--dt -1: expected a time step in seconds > 0",
        ),
        (
            vec!["render", "rope", "--time", "-2", "--energy-chart", "e.png"],
            "--time -2: expected a duration in seconds >= 0",
        ),
        (
            vec!["render", "no-such-scene", "--frames", "2"],
            "unknown scene `no-such-scene`",
        ),
        (
            vec![
                "render",
                "rope",
                "--frames",
                "2",
                "--colour",
                "strain",
                "--max-strain",
                "0",
            ],
            "--max-strain 0: expected a strain > 0",
        ),
    ] {
        let stderr = failure(&args);
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    }
}

#[test]
fn start_skips_simulated_time_before_the_first_frame() {
    // `--start 10 dt` then one frame equals frame 10 of a run drawn every step (dt = 1/64 s).
    let dir = scratch("start");
    success(
        &dir,
        &[
            "render",
            "rope",
            "--frames",
            "11",
            "--every",
            "1",
            "--size",
            "96x72",
            "--out",
            "dense",
            "--no-overlay",
        ],
    );
    success(
        &dir,
        &[
            "render",
            "rope",
            "--frames",
            "1",
            "--start",
            "0.15625",
            "--size",
            "96x72",
            "--out",
            "late",
            "--no-overlay",
        ],
    );
    let a = std::fs::read(dir.join("late/frame_00000.png")).expect("frame");
    let b = std::fs::read(dir.join("dense/frame_00010.png")).expect("frame");
    assert!(a == b, "--start 10·dt shows step 10");
    assert!(
        failure(&["render", "rope", "--frames", "1", "--start", "-1"])
            .contains("--start -1: expected a time in seconds >= 0")
    );
}

/// `--every 0` and `--frames 0` are named as what is wrong, with or without the other option
/// (not priced as an endless render first).
#[test]
fn zero_every_or_frames_is_named() {
    for args in [
        &["render", "rope", "--every", "0"][..],
        &["render", "rope", "--every", "0", "--frames", "2"][..],
    ] {
        let err = failure(args);
        assert!(
            err.contains("--every 0: expected a number of steps >= 1"),
            "{err}"
        );
    }
    let err = failure(&["render", "rope", "--frames", "0", "--every", "0"]);
    assert!(
        err.contains("--frames 0: expected at least 1 frame"),
        "{err}"
    );
}

/// One frame is "1 frame", named alone; several name the first and the last file.
#[test]
fn the_summary_names_the_frames_written() {
    let dir = scratch("one-frame");
    let stdout = success(
        &dir,
        &[
            "render", "rope", "--frames", "1", "--size", "64x48", "--out", "f",
        ],
    );
    assert_eq!(
        stdout.trim_end(),
        "wrote 1 frame of 64x48 to f/frame_00000.png"
    );
}
