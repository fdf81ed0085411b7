//! `springlab homework autograder --assignment A --out autograder.zip`: the files a Gradescope
//! course uploads for a programming assignment.
//!
//! ```text
//! autograder.zip
//!   setup.sh         run once when Gradescope builds the image (as root, in
//!                    /autograder/source; base image Ubuntu 22.04): checks that springlab
//!                    starts (glibc 2.35), installs a Rust toolchain if there is none (rustup,
//!                    minimal profile, under /usr/local so the sandbox user can read it) and
//!                    grades the untouched starter crate once: the student API is compiled
//!                    before the first submission, and a toolchain that cannot build it stops
//!                    the set-up with a message
//!   run_autograder   run for every submission: `springlab grade /autograder/submission
//!                    --assignment A --seed S --seed-per-submission
//!                    --gradescope /autograder/results/results.json` (S: the zip's secret
//!                    seed, [`secret_seed`] or `--seed`); when the
//!                    grader fails (non-zero exit) it writes a failure result instead
//!                    (SPRINGLAB_AUTOGRADER_ROOT replaces /autograder, for a local test run)
//!   springlab        this binary (Linux, x86-64, glibc 2.35: Ubuntu 22.04)
//!   README.txt       what the files are
//! ```
//! A submission may be the crate folder, its `src/` contents, or the crate folder one level
//! down (see [`super::build::locate`]). The zip is written with deflate (`miniz_oxide`) and
//! Unix permissions, so the scripts stay executable.
//!
//! Reference: Gradescope, "Autograder Specifications" (setup.sh, run_autograder,
//! /autograder/submission, /autograder/results/results.json).

use std::path::Path;

use super::Assignment;

/// The environment variable that replaces `/autograder` in `run_autograder`.
pub const ROOT_ENV: &str = "SPRINGLAB_AUTOGRADER_ROOT";

const SETUP: &str = r#"#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder image.
# Base image: Ubuntu 22.04 (glibc 2.35, which this springlab binary needs).
# It installs a Rust toolchain where the sandbox user can read it (submissions are compiled by
# rustc running as an unprivileged user), checks that this toolchain builds the student API,
# and compiles the API once. Any failure stops the set-up with a message.
set -euo pipefail
cd "$(dirname "$0")"
fail() { echo "setup.sh: $*" >&2; exit 1; }
chmod +x ./springlab ./run_autograder
./springlab --version >/dev/null 2>&1 || fail "the springlab binary does not start on this image \
($(ldd --version 2>&1 | head -n 1)); it needs glibc 2.35 or newer: choose the Ubuntu 22.04 base image"
export PATH="$HOME/.cargo/bin:/usr/local/cargo/bin:$PATH"
if ! command -v rustc >/dev/null 2>&1; then
  export RUSTUP_HOME=/usr/local/rustup CARGO_HOME=/usr/local/cargo
  apt-get update
  apt-get install -y --no-install-recommends ca-certificates curl build-essential
  curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal --no-modify-path
  chmod -R a+rX "$RUSTUP_HOME" "$CARGO_HOME"
fi
command -v cc >/dev/null 2>&1 || fail "no C compiler (cc) to link with: apt-get install build-essential"
# run_autograder uses this very compiler (no rustup proxy, no environment needed).
SYSROOT="$(rustc --print sysroot)" || fail "rustc does not run"
echo "export RUSTC='$SYSROOT/bin/rustc'" >springlab.env
./springlab grade --sandbox-report
# A folder of its own (never a fixed name in a shared /tmp), removed on the way out.
WARM="$(mktemp -d)" || fail "cannot make a temporary folder"
trap 'rm -rf "$WARM"' EXIT
./springlab homework new "$WARM/hw" --assignment {{ASSIGNMENT}} >/dev/null
# A grader error (a rustc too old for edition 2024, an unreadable toolchain) exits non-zero;
# the untouched starter must build.
./springlab grade "$WARM/hw" --target-dir "$PWD/target" --json "$WARM/report.json" \
  >"$WARM/grade.txt" 2>&1 || { cat "$WARM/grade.txt" >&2; fail "the grader cannot run"; }
if grep -q "the crate did not build" "$WARM/grade.txt"; then
  cat "$WARM/grade.txt" >&2
  fail "this toolchain ($(rustc --version)) cannot build the untouched starter crate"
fi
echo "setup.sh: ready ($(rustc --version))"
"#;

const RUN: &str = r#"#!/usr/bin/env bash
# Gradescope runs this for every submission; it writes $ROOT/results/results.json.
# springlab grade writes that file for every submission (one that does not build, crashes or
# hangs gets a report saying so) and exits 0 whatever the score. When the grader itself fails
# (non-zero exit), this script writes a result saying so instead: never nothing, never a file
# the submission wrote.
set -uo pipefail
ROOT="${{{ROOT_ENV}}:-/autograder}"
export PATH="$HOME/.cargo/bin:/usr/local/cargo/bin:$PATH"
# The compiler setup.sh checked.
if [ -f "$ROOT/source/springlab.env" ]; then . "$ROOT/source/springlab.env"; fi
mkdir -p "$ROOT/results"
RESULTS="$ROOT/results/results.json"
rm -f "$RESULTS"
"$ROOT/source/springlab" grade "$ROOT/submission" \
  --assignment {{ASSIGNMENT}} \
  --seed {{SEED}} --seed-per-submission \
  --target-dir "$ROOT/source/target" \
  --gradescope "$RESULTS" 2>"$ROOT/results/grader-stderr.txt"
STATUS=$?
if [ "$STATUS" -ne 0 ]; then
  TMP="$(mktemp "$ROOT/results/.failed.XXXXXX")"
  printf '{"score": 0, "output": "The autograder itself failed (exit status %s); this is not a grade of your submission. Please tell your instructor.", "visibility": "visible", "tests": []}\n' "$STATUS" >"$TMP"
  rm -rf "$RESULTS"
  mv -f "$TMP" "$RESULTS"
fi
exit 0
"#;

const README: &str = "springlab autograder for the {{TITLE}} homework ({{ASSIGNMENT}}).

Upload this zip as the autograder of a Gradescope programming assignment. Base image: Ubuntu
22.04 (the springlab binary needs glibc 2.35). setup.sh installs Rust under /usr/local when
there is none, checks that it builds the student API and compiles it once; it fails with a
message otherwise. run_autograder grades /autograder/submission (the student's crate
folder, or just its src/ files) in springlab's sandbox and writes
/autograder/results/results.json (a failure result when the grader itself fails). Students
upload their homework crate made with `springlab homework new DIR --assignment {{ASSIGNMENT}}`.

The graded cases come from the seed in run_autograder, a secret of this zip, and each
submission's code: a student's own `cargo test` grades with the public default seed, so the
cases seen at home are not the graded ones, and a resubmission with changed code gets new ones.
Keep this zip from students.
";

/// A fresh random seed for an autograder (the system's random source).
#[must_use]
pub fn secret_seed() -> u64 {
    let token = super::token::random_token();
    let mut bytes = [0u8; 8];
    bytes.copy_from_slice(&token[..8]);
    u64::from_le_bytes(bytes)
}

/// The files of the autograder for `assignment`: `(name, contents, Unix mode)`; `springlab` is
/// the binary to include, `seed` the secret seed of the graded cases.
#[must_use]
pub fn files(assignment: Assignment, springlab: Vec<u8>, seed: u64) -> Vec<(String, Vec<u8>, u32)> {
    let fill = |t: &str| {
        t.replace("{{ASSIGNMENT}}", assignment.name())
            .replace("{{ROOT_ENV}}", ROOT_ENV)
            .replace("{{TITLE}}", assignment.title())
            .replace("{{SEED}}", &seed.to_string())
    };
    vec![
        ("setup.sh".to_string(), fill(SETUP).into_bytes(), 0o755),
        ("run_autograder".to_string(), fill(RUN).into_bytes(), 0o755),
        ("README.txt".to_string(), fill(README).into_bytes(), 0o644),
        ("springlab".to_string(), springlab, 0o755),
    ]
}

/// A zip archive of `files` (deflated, Unix permissions, a fixed date so the same input gives
/// the same bytes).
#[must_use]
pub fn zip(files: &[(String, Vec<u8>, u32)]) -> Vec<u8> {
    // 1980-01-01 00:00, the zip epoch.
    const DATE: u16 = (1 << 5) | 1;
    let mut out = Vec::new();
    let mut central = Vec::new();
    let u16le = |v: &mut Vec<u8>, x: u16| v.extend_from_slice(&x.to_le_bytes());
    let u32le = |v: &mut Vec<u8>, x: u32| v.extend_from_slice(&x.to_le_bytes());
    for (name, data, mode) in files {
        let crc = crc32fast::hash(data);
        let packed = miniz_oxide::deflate::compress_to_vec(data, 6);
        let offset = out.len() as u32;
        let name_len = name.len() as u16;
        // Local header.
        u32le(&mut out, 0x0403_4b50);
        u16le(&mut out, 20);
        u16le(&mut out, 0x0800); // UTF-8 names
        u16le(&mut out, 8); // deflate
        u16le(&mut out, 0);
        u16le(&mut out, DATE);
        u32le(&mut out, crc);
        u32le(&mut out, packed.len() as u32);
        u32le(&mut out, data.len() as u32);
        u16le(&mut out, name_len);
        u16le(&mut out, 0);
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(&packed);
        // Central directory entry.
        u32le(&mut central, 0x0201_4b50);
        u16le(&mut central, (3 << 8) | 20); // made by Unix, so the mode below counts
        u16le(&mut central, 20);
        u16le(&mut central, 0x0800);
        u16le(&mut central, 8);
        u16le(&mut central, 0);
        u16le(&mut central, DATE);
        u32le(&mut central, crc);
        u32le(&mut central, packed.len() as u32);
        u32le(&mut central, data.len() as u32);
        u16le(&mut central, name_len);
        u16le(&mut central, 0);
        u16le(&mut central, 0);
        u16le(&mut central, 0);
        u16le(&mut central, 0);
        u32le(&mut central, (0o100_000 | mode) << 16); // regular file with its permissions
        u32le(&mut central, offset);
        central.extend_from_slice(name.as_bytes());
    }
    let central_offset = out.len() as u32;
    out.extend_from_slice(&central);
    u32le(&mut out, 0x0605_4b50);
    u16le(&mut out, 0);
    u16le(&mut out, 0);
    u16le(&mut out, files.len() as u16);
    u16le(&mut out, files.len() as u16);
    u32le(&mut out, central.len() as u32);
    u32le(&mut out, central_offset);
    u16le(&mut out, 0);
    out
}

/// Writes the autograder zip of `assignment` to `out`, with the binary at `springlab`.
///
/// # Errors
/// When the binary cannot be read or the zip cannot be written.
pub fn write(
    assignment: Assignment,
    springlab: &Path,
    out: &Path,
    seed: u64,
) -> std::io::Result<usize> {
    let binary = std::fs::read(springlab)?;
    let files = files(assignment, binary, seed);
    let bytes = zip(&files);
    // A temporary file renamed into place: a half-written zip is never left behind.
    super::write_result(out, &bytes).map_err(std::io::Error::other)?;
    Ok(bytes.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_autograder_grades_with_the_secret_seed_per_submission() {
        let files = files(Assignment::Rope, Vec::new(), 42);
        let run = files
            .iter()
            .find(|(name, _, _)| name == "run_autograder")
            .map(|(_, text, _)| String::from_utf8_lossy(text).into_owned())
            .expect("run_autograder");
        assert!(run.contains("--assignment rope \\\n  --seed 42 --seed-per-submission \\\n"));
        assert!(!run.contains("{{"), "{run}");
        // Two autograders made without --seed get different seeds.
        assert_ne!(secret_seed(), secret_seed());
    }
}
