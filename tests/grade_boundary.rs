//! Grading through the real boundary: homework crates written as students would, built by
//! `springlab grade` and run as separate programs. Each asserts the score a fair grader gives.
//!
//! Builds are the slow part, so every test here shares one cargo target directory (the student
//! API compiles once; each crate then builds in about a second) and a crate serves several
//! assertions: the class folder holds the planted mistakes, the hostile crate does one hostile
//! thing per method.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const ROPE: &str = include_str!("homework/rope.rs");
const JELLY: &str = include_str!("homework/jelly.rs");
const CLOTH: &str = include_str!("homework/cloth.rs");
const INTEGRATORS: &str = include_str!("homework/integrators.rs");

/// The target directory shared by every build of this file.
fn target() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("grade-builds")
}

/// A fresh, empty scratch directory for test `name`.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("grade-boundary-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

fn springlab(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_springlab"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run springlab")
}

fn ok(out: &Output) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// `springlab homework new parent/name --assignment a`, then `lib` as src/lib.rs (and the
/// shared integrators beside it).
fn homework(parent: &Path, name: &str, assignment: &str, lib: Option<&str>) -> PathBuf {
    ok(&springlab(
        parent,
        &["homework", "new", name, "--assignment", assignment],
    ));
    let dir = parent.join(name);
    if let Some(lib) = lib {
        std::fs::write(dir.join("src/lib.rs"), lib).expect("write lib.rs");
        std::fs::write(dir.join("src/integrators.rs"), INTEGRATORS).expect("write");
    }
    dir
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).expect("JSON")
}

/// `text` with `from` replaced by `to`, which must occur exactly once.
fn patch(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "{from}");
    text.replace(from, to)
}

#[test]
fn correct_homework_gets_full_marks_graded_by_a_relative_path() {
    let parent = scratch("full");
    let t = target();
    let t = t.to_str().expect("utf-8");
    for (name, lib, max) in [
        ("rope", ROPE, 35.0),
        ("jelly", JELLY, 80.0),
        ("cloth", CLOTH, 80.0),
    ] {
        homework(&parent, name, name, Some(lib));
        // From the parent directory, as the README writes it.
        let stdout = ok(&springlab(
            &parent,
            &["grade", name, "--gradescope", "r.json", "--target-dir", t],
        ));
        assert!(
            stdout.contains(&format!("score {max} / {max}")),
            "{name}: {stdout}"
        );
        let results = json(&parent.join("r.json"));
        assert_eq!(results["score"].as_f64(), Some(max), "{name}");
        for test in results["tests"].as_array().expect("tests") {
            assert_eq!(test["score"], test["max_score"], "{name}: {test}");
        }
    }
}

/// The class: a correct rope, planted mistakes, the untouched starter, and a crate that reaches
/// for springlab's reference solution. `(folder, lib.rs, expected score)`.
fn class() -> Vec<(&'static str, String, f64)> {
    let explicit = "fn explicit_euler(&self, rope: &mut Rope, dt: f64, physics: &Physics) {";
    vec![
        ("c01-correct", ROPE.to_string(), 35.0),
        // exit(0) inside one method: only explicit Euler's 5 points.
        (
            "c02-exit-in-explicit-euler",
            patch(
                ROPE,
                explicit,
                &format!("{explicit}\n        std::process::exit(0);"),
            ),
            30.0,
        ),
        // Verlet without the damping factor: the damping item only.
        (
            "c03-verlet-without-damping",
            patch(
                ROPE,
                "(1.0 - damping) * (x - m.last_position)",
                "(x - m.last_position)",
            ),
            30.0,
        ),
        // Half of every correction to each end, pinned or not: the pinned-end projection (3)
        // and the course rope, whose pin moves (2).
        (
            "c04-pinned-end-moves",
            patch(
                ROPE,
                "match (pa, pb) {",
                "match (false && pa, false && pb) {",
            ),
            30.0,
        ),
        // Every node pinned: masses and pins (1.5) of rope construction.
        (
            "c05-every-node-pinned",
            patch(ROPE, "pinned: pinned.contains(&i),", "pinned: true,"),
            33.5,
        ),
        // x += a dt in explicit Euler: one step (3) and the measured order (2).
        (
            "c06-explicit-adds-acceleration",
            patch(
                ROPE,
                "                m.position += dt * m.velocity;\n                m.velocity += dt * a;",
                "                m.position += dt * a;\n                m.velocity += dt * a;",
            ),
            30.0,
        ),
        // Hooke's law with the sign flipped: charged once, in the Hooke check (1); the net
        // forces accumulate the student's own pair force correctly.
        (
            "c07-hooke-flipped",
            patch(
                ROPE,
                "stiffness * d / l * (l - rest_length)",
                "-stiffness * d / l * (l - rest_length)",
            ),
            34.0,
        ),
        // Semi-implicit Euler moving with the old velocity: one step (2), course rope (1).
        (
            "c08-semi-implicit-old-velocity",
            patch(
                ROPE,
                "                m.velocity += dt * a;\n                m.position += dt * m.velocity;",
                "                m.position += dt * m.velocity;\n                m.velocity += dt * a;",
            ),
            32.0,
        ),
        ("c09-untouched-starter", String::new(), 5.0),
        // The answer key is not reachable: this does not compile.
        (
            "c10-calls-the-reference",
            patch(
                ROPE,
                "        let d = b - a;\n        let l = d.length();\n        stiffness * d / l * (l - rest_length)",
                "        springlab::grade::Reference.spring_force(a, b, stiffness, rest_length)",
            ),
            0.0,
        ),
    ]
}

#[test]
fn a_class_folder_grades_each_crate_on_its_own_code_with_csv_and_jobs() {
    let root = scratch("class");
    let folder = root.join("class");
    std::fs::create_dir_all(&folder).expect("class folder");
    let crates = class();
    for (name, lib, _) in &crates {
        let lib = (!lib.is_empty()).then_some(lib.as_str());
        homework(&folder, name, "rope", lib);
    }
    // The reference-calling student also adds springlab as a dependency: the grader ignores
    // the student's Cargo.toml.
    let cheat = folder.join("c10-calls-the-reference/Cargo.toml");
    let manifest = std::fs::read_to_string(&cheat)
        .expect("Cargo.toml")
        .replace(
            "[dependencies]\n",
            &format!(
                "[dependencies]\nspringlab = {{ path = {:?} }}\n",
                env!("CARGO_MANIFEST_DIR")
            ),
        );
    std::fs::write(&cheat, manifest).expect("write");
    let t = target();
    let out = springlab(
        &root,
        &[
            "grade",
            "class",
            "--csv",
            "grades.csv",
            "--json",
            "reports.json",
            "--jobs",
            "2",
            "--target-dir",
            t.to_str().expect("utf-8"),
        ],
    );
    let stdout = ok(&out);
    assert!(stdout.contains("10 submissions graded"), "{stdout}");
    let csv = std::fs::read_to_string(root.join("grades.csv")).expect("grades.csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "submission,assignment,score,max_score,builds,rope,semi_implicit,explicit,verlet,damping"
    );
    assert_eq!(lines.len(), 11, "{csv}");
    for ((name, _, score), line) in crates.iter().zip(&lines[1..]) {
        let fields: Vec<&str> = line.split(',').collect();
        assert!(fields[0].ends_with(name), "{line}");
        assert_eq!(
            fields[2].parse::<f64>().ok(),
            Some(*score),
            "{line}\n{stdout}"
        );
        assert_eq!(fields[3], "35", "{line}");
    }
    // exit(0) in explicit Euler: every other item full.
    assert!(lines[2].ends_with(",35,5,5,5,0,10,5"), "{}", lines[2]);
    let reports = json(&root.join("reports.json"));
    let reports = reports.as_array().expect("a list of reports");
    let explicit = &reports[1]["items"][3];
    assert_eq!(explicit["status"], "crashed", "{explicit}");
    let reason = explicit["reason"].as_str().unwrap_or_default();
    assert!(reason.contains("exited with status 0"), "{reason}");
    // x += a·dt is told what it did, not that nothing moved.
    let added = serde_json::to_string(&reports[5]["items"][3]).expect("JSON");
    assert!(added.contains("moved by dt·a(t)"), "{added}");
    assert!(!added.contains("not advanced"), "{added}");
    // The reference is out of reach: the build fails on the path `springlab`.
    let cheat = serde_json::to_string(&reports[9]).expect("JSON");
    assert!(cheat.contains("the crate did not build"), "{cheat}");
    assert!(cheat.contains("springlab"), "{cheat}");
    assert!(
        cheat.contains("unresolved") || cheat.contains("unlinked"),
        "{cheat}"
    );

    // The same CARGO_TARGET_DIR for two different crates graded one after the other: each gets
    // its own score.
    for (i, expected) in [(6, 34.0), (7, 32.0), (0, 35.0)] {
        let out = Command::new(env!("CARGO_BIN_EXE_springlab"))
            .current_dir(&folder)
            .env("CARGO_TARGET_DIR", &t)
            .args(["grade", crates[i].0])
            .output()
            .expect("run springlab");
        let stdout = ok(&out);
        assert!(
            stdout.contains(&format!("score {expected} / 35")),
            "{}: {stdout}",
            crates[i].0
        );
    }
}

/// A jelly homework doing one hostile thing per method; the paths it forges and escapes to.
fn hostile(report: &Path, gradescope: &Path, escaped: &Path) -> String {
    let correct = JELLY;
    let hostile = r##"
use std::io::Write;

/// What the program sees of its environment: nothing, in an empty directory of its own.
fn clean() -> bool {
    std::env::vars_os().count() == 0
        && std::fs::read_dir(".").map(|d| d.count() == 0).unwrap_or(false)
        && std::env::current_dir().map(|d| d.starts_with(std::env::temp_dir())).unwrap_or(false)
}

fn deep(n: u64) -> u64 {
    let buf = [n; 64];
    std::hint::black_box(&buf);
    deep(n + 1) + buf[3]
}

impl JellyHomework for Student {
    fn springs(&self, counts: [usize; 3]) -> Vec<SpringSetup> {
        // Stray output: a line, text without a newline, and bytes imitating a reply with a
        // guessed token.
        println!("debug: springs({counts:?})");
        print!("no newline ");
        let mut fake = vec![0xFF, b'S', b'P', b'L', b'A', b'B', 0xFE, 0x01];
        fake.extend_from_slice(&[0u8; 16]);
        fake.extend_from_slice(&5u32.to_le_bytes());
        fake.extend_from_slice(&[0x82, 1, 2, 3, 4]);
        std::io::stdout().write_all(&fake).unwrap();
        eprintln!("to stderr");
        Correct.springs(counts)
    }

    fn spring_force(&self, _: DVec3, _: DVec3, _: f64, _: f64) -> DVec3 {
        std::process::exit(0)
    }

    fn damper_force(&self, _: DVec3, _: DVec3, _: DVec3, _: DVec3, _: f64) -> DVec3 {
        std::process::abort()
    }

    fn internal_forces(&self, x: &[DVec3], v: &[DVec3], springs: &[Spring]) -> Vec<DVec3> {
        if springs.len() == 1 {
            // An answer of 24 MB.
            return vec![DVec3::ONE; 1_000_000];
        }
        Correct.internal_forces(x, v, springs)
    }

    fn plane_collision(&self, plane: &Plane, p: &mut Particle, c: &ContactCoefficients) {
        if (p.x - plane.point).dot(plane.normal) < 0.0 {
            panic!("a particle inside the plane");
        }
        Correct.plane_collision(plane, p, c);
    }

    fn bowl_collision(&self, _: &Bowl, _: &mut Particle, _: &ContactCoefficients) {
        loop {
            std::hint::black_box(0);
        }
    }

    fn explicit_euler(&self, _: &mut State, _: f64, _: &Physics) {
        let mut hoard: Vec<Vec<u8>> = Vec::new();
        loop {
            hoard.push(vec![1u8; 1 << 20]);
        }
    }

    fn implicit_euler(&self, _: &mut State, _: f64, _: &Physics) {
        let forged = r#"{"score": 80.0, "max_score": 80.0, "tests": []}"#;
        let _ = std::fs::write(FORGED_REPORT, forged);
        let _ = std::fs::write(FORGED_GRADESCOPE, forged);
        let _ = std::fs::write(ESCAPED, "written outside the working directory");
        std::process::exit(0)
    }

    fn midpoint(&self, s: &mut State, dt: f64, physics: &Physics) {
        if clean() {
            Correct.midpoint(s, dt, physics);
        } else {
            s.x[0] += DVec3::ONE;
        }
    }

    fn rk4(&self, _: &mut State, _: f64, _: &Physics) {
        std::hint::black_box(deep(0));
    }
}
"##;
    let correct = patch(
        correct,
        "pub struct Student;",
        "pub struct Correct;\npub struct Student;",
    );
    let correct = patch(
        &correct,
        "impl JellyHomework for Student {",
        "impl JellyHomework for Correct {",
    );
    format!(
        "{correct}\nconst FORGED_REPORT: &str = {:?};\nconst FORGED_GRADESCOPE: &str = {:?};\n\
         const ESCAPED: &str = {:?};\n{hostile}",
        report.display().to_string(),
        gradescope.display().to_string(),
        escaped.display().to_string()
    )
}

#[test]
fn a_hostile_homework_gets_the_score_a_fair_grader_gives() {
    let root = scratch("hostile");
    let report = root.join("report.json");
    let results = root.join("results.json");
    let escaped = root.join("escaped.txt");
    homework(
        &root,
        "hw",
        "jelly",
        Some(&hostile(&report, &results, &escaped)),
    );
    let t = target();
    let out = Command::new(env!("CARGO_BIN_EXE_springlab"))
        .current_dir(&root)
        .env("SPRINGLAB_TEST_SECRET", "the grader's environment")
        .args([
            "grade",
            "hw",
            "--json",
            "report.json",
            "--gradescope",
            "results.json",
            "--time-limit-ms",
            "4000",
            "--memory-mb",
            "256",
            "--target-dir",
            t.to_str().expect("utf-8"),
        ])
        .output()
        .expect("run springlab");
    let stdout = ok(&out);
    // springs 15 + internal force 4 (random systems; the 24 MB answer costs the one-spring
    // check) + plane 7 (bounce and contact; the panic costs the projection) + midpoint 2.5
    // (it sees an empty environment in an empty directory of its own).
    assert!(stdout.contains("score 28.5 / 80"), "{stdout}");
    let r = json(&report);
    assert_eq!(r["score"].as_f64(), Some(28.5));
    let g = json(&results);
    assert_eq!(
        g["score"].as_f64(),
        Some(28.5),
        "the forged report was replaced"
    );
    assert_eq!(g["tests"].as_array().map(Vec::len), Some(10));
    let expect = [
        ("springs", 15.0, "full", ""),
        ("spring_force", 0.0, "crashed", "exited with status 0"),
        ("damper_force", 0.0, "crashed", "aborted"),
        ("internal_force", 4.0, "malformed", "at most 16 MiB"),
        ("plane", 7.0, "panicked", "a particle inside the plane"),
        ("bowl", 0.0, "timed_out", "did not finish within 4000 ms"),
        ("explicit", 0.0, "crashed", "ran out of memory"),
        ("implicit", 0.0, "crashed", "exited with status 0"),
        ("midpoint", 2.5, "full", ""),
        ("rk4", 0.0, "crashed", "stack overflowed"),
    ];
    for (item, (id, score, status, reason)) in
        r["items"].as_array().expect("items").iter().zip(expect)
    {
        assert_eq!(item["id"], id);
        assert_eq!(item["score"].as_f64(), Some(score), "{item}");
        assert_eq!(item["status"], status, "{item}");
        let text = item["reason"].as_str().unwrap_or_default();
        assert!(text.contains(reason), "{id}: {text}");
    }
    // Out of memory near the limit: the failed allocation is reported with the limit.
    let explicit = r["items"][6]["reason"].as_str().unwrap_or_default();
    assert!(explicit.contains("256 MiB of address space"), "{explicit}");
    let in_use: u64 = explicit
        .split("it had ")
        .nth(1)
        .and_then(|t| t.split(" MiB in use").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("peak memory reported: {explicit}"));
    assert!((200..=256).contains(&in_use), "{explicit}");
    // A file written outside the working directory: contained by the sandbox where another
    // user or Landlock is active (as root, or on a kernel with Landlock), written otherwise.
    let sandbox = r["sandbox"].as_str().unwrap_or_default();
    let contained = sandbox.contains("user on") || sandbox.contains("landlock on");
    assert_eq!(escaped.exists(), !contained, "{sandbox}");
}

#[test]
fn cargo_test_in_the_homework_crate_grades_it_through_springlab() {
    let root = scratch("selfgrade");
    let dir = homework(&root, "hw", "rope", Some(ROPE));
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(&dir)
        .args(["test", "--release", "--offline", "--test", "grade"])
        .env_remove("CARGO_TARGET_DIR")
        .env(
            "SPRINGLAB_GRADE_ARGS",
            format!("--target-dir {}", target().display()),
        )
        .output()
        .expect("run cargo test");
    let stdout = ok(&out);
    assert!(stdout.contains("score 35 / 35"), "{stdout}");
}

/// The entries of a zip written by `springlab homework autograder`: (name, bytes, mode).
fn unzip(bytes: &[u8]) -> Vec<(String, Vec<u8>, u32)> {
    let u16at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]) as usize;
    let u32at = |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    let end = bytes.len() - 22;
    assert_eq!(u32at(end), 0x0605_4b50, "end of central directory");
    let count = u16at(end + 10);
    let mut at = u32at(end + 16) as usize;
    let mut out = Vec::new();
    for _ in 0..count {
        assert_eq!(u32at(at), 0x0201_4b50);
        let (method, crc, packed, size) = (
            u16at(at + 10),
            u32at(at + 16),
            u32at(at + 20),
            u32at(at + 24),
        );
        let (name_len, extra, comment) = (u16at(at + 28), u16at(at + 30), u16at(at + 32));
        let mode = u32at(at + 38) >> 16;
        let local = u32at(at + 42) as usize;
        let name = String::from_utf8(bytes[at + 46..at + 46 + name_len].to_vec()).expect("name");
        let data_at = local + 30 + u16at(local + 26) + u16at(local + 28);
        let raw = &bytes[data_at..data_at + packed as usize];
        assert_eq!(method, 8, "deflate");
        let data = miniz_oxide::inflate::decompress_to_vec(raw).expect("inflate");
        assert_eq!(data.len(), size as usize);
        assert_eq!(crc32fast::hash(&data), crc, "{name}");
        out.push((name, data, mode));
        at += 46 + name_len + extra + comment;
    }
    out
}

#[test]
fn the_autograder_zip_grades_a_submission_in_a_local_autograder_tree() {
    let root = scratch("autograder");
    ok(&springlab(
        &root,
        &[
            "homework",
            "autograder",
            "--assignment",
            "rope",
            "--out",
            "autograder.zip",
        ],
    ));
    let zip = std::fs::read(root.join("autograder.zip")).expect("zip");
    let entries = unzip(&zip);
    let names: Vec<&str> = entries.iter().map(|(n, _, _)| n.as_str()).collect();
    assert_eq!(
        names,
        ["setup.sh", "run_autograder", "README.txt", "springlab"]
    );
    // A fake /autograder: source/ (the zip), submission/ (the student's src/ files only).
    let fake = root.join("autograder");
    let source = fake.join("source");
    std::fs::create_dir_all(&source).expect("source");
    for (name, data, mode) in &entries {
        let path = source.join(name);
        std::fs::write(&path, data).expect("extract");
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(*mode)).expect("chmod");
        if name != "README.txt" {
            assert_eq!(mode & 0o111, 0o111, "{name} is executable");
        }
    }
    std::fs::create_dir_all(fake.join("submission")).expect("submission");
    std::fs::write(fake.join("submission/lib.rs"), ROPE).expect("lib.rs");
    // The build cache the image would have after setup.sh: the shared one.
    let out = Command::new("bash")
        .arg(source.join("run_autograder"))
        .env("SPRINGLAB_AUTOGRADER_ROOT", &fake)
        .output()
        .expect("run run_autograder");
    ok(&out);
    let results = json(&fake.join("results/results.json"));
    assert_eq!(results["score"].as_f64(), Some(35.0), "{results}");
    assert_eq!(results["tests"].as_array().map(Vec::len), Some(6));
}
