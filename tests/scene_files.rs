//! Scene files (`springlab::scene::file`): every bad input gives `file:line:col: message` with
//! what was expected; good files build the scenes they describe.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use springlab::physics::integrators::method_names;
use springlab::scene::{self, ParamError, Scene, SceneError};
use springlab::{Method, Simulation, SpringKind};

mod good;

/// A fresh directory under the system temp dir, unique to this process and call.
fn fresh_dir() -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir =
        std::env::temp_dir().join(format!("springlab-scene-files-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Writes `text` to `name` in a fresh directory.
fn write(name: &str, text: &str) -> PathBuf {
    let path = fresh_dir().join(name);
    std::fs::write(&path, text).expect("write scene file");
    path
}

/// Loads `text` as the file `name` with `--set` assignments `sets`, then removes the file.
fn load_with(name: &str, text: &str, sets: &[&str]) -> (PathBuf, Result<Scene, SceneError>) {
    let path = write(name, text);
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let result = scene::load(path.to_str().expect("utf-8 temp path"), &sets);
    let _ = std::fs::remove_dir_all(path.parent().expect("parent"));
    (path, result)
}

fn load(name: &str, text: &str) -> Scene {
    match load_with(name, text, &[]).1 {
        Ok(scene) => scene,
        Err(e) => panic!("expected {name} to load, got: {e}"),
    }
}

/// Loads `text`, expects a [`SceneError::File`] at `line:column`, checks that the printed error
/// starts with `path:line:column: `, and returns the message.
fn file_error(name: &str, text: &str, line: usize, column: usize) -> String {
    file_error_with(name, text, &[], line, column)
}

fn file_error_with(name: &str, text: &str, sets: &[&str], line: usize, column: usize) -> String {
    let (path, result) = load_with(name, text, sets);
    let err = match result {
        Ok(_) => panic!("expected an error for {name}:\n{text}"),
        Err(e) => e,
    };
    let printed = err.to_string();
    let prefix = format!("{}:{line}:{column}: ", path.display());
    assert!(
        printed.starts_with(&prefix),
        "expected prefix `{prefix}`, got `{printed}`"
    );
    match err {
        SceneError::File {
            path: p,
            line: l,
            column: c,
            message,
        } => {
            assert_eq!(p, path.display().to_string());
            assert_eq!((l, c), (line, column), "{message}");
            message
        }
        other => panic!("expected a file error, got {other:?}"),
    }
}

/// Asserts that `message` contains every one of `words`.
fn assert_has(message: &str, words: &[&str]) {
    for w in words {
        assert!(
            message.contains(w),
            "message `{message}` should contain `{w}`"
        );
    }
}

/// Two free particles 1 m apart (6 lines); springs are appended by the tests.
const TWO: &str = "[[particles]]
position = [0, 0, 0]
mass = 1
[[particles]]
position = [1, 0, 0]
mass = 1
";

// --- Bad values --------------------------------------------------------------------------------

#[test]
fn negative_mass_is_out_of_range_with_unit() {
    let m = file_error(
        "mass.toml",
        "[[particles]]\nposition = [0, 0, 0]\nmass = -1\n",
        3,
        8,
    );
    assert_has(
        &m,
        &[
            "`mass` = -1",
            "out of range",
            "allowed 1e-6 ..= 1e6",
            "(kg)",
        ],
    );
}

#[test]
fn zero_dt_is_out_of_range() {
    let m = file_error("dt.toml", "scene = \"oscillator\"\n[run]\ndt = 0\n", 3, 6);
    assert_has(&m, &["`dt` = 0", "out of range", "allowed > 0", "(s)"]);
    let m = file_error("dt2.toml", &format!("{TWO}[run]\ndt = -0.5\n"), 8, 6);
    assert_has(&m, &["`dt` = -0.5", "allowed > 0 (s)"]);
}

#[test]
fn negative_time_is_out_of_range() {
    let m = file_error("time.toml", "scene = \"rope\"\n[run]\ntime = -1.0\n", 3, 8);
    assert_has(&m, &["`time` = -1", "allowed >= 0 (s)"]);
}

#[test]
fn fewer_than_two_nodes_in_params() {
    let m = file_error(
        "nodes.toml",
        "scene = \"rope\"\n[params]\nnodes = 1\n",
        3,
        9,
    );
    assert_has(
        &m,
        &["`nodes` = 1", "out of range", "allowed 2 ..= 1000000"],
    );
}

/// `nodes = 16.0` is a number where a whole number is expected, and says so as written.
#[test]
fn a_number_with_a_point_for_a_whole_number() {
    let m = file_error(
        "point.toml",
        "scene = \"rope\"\n[params]\nnodes = 16.0\n",
        3,
        9,
    );
    assert_eq!(m, "`nodes` = 16.0: expected a whole number 2 ..= 1000000");
}

/// An unknown key lists every known parameter whole; only what the file wrote is cut.
#[test]
fn an_unknown_key_lists_every_known_parameter() {
    let m = file_error(
        "colour.toml",
        "scene = \"rope\"\n[params]\ncolour = 1\n",
        3,
        1,
    );
    assert!(m.ends_with("substeps, cg_tolerance"), "{m}");
    let long = "k".repeat(500);
    let m = file_error(
        "long.toml",
        &format!("scene = \"rope\"\n[params]\n{long} = 1\n"),
        3,
        1,
    );
    assert!(
        m.starts_with(&format!("unknown parameter `{}…`", "k".repeat(60))),
        "{m}"
    );
    assert!(m.ends_with("cg_tolerance"), "{m}");
}

#[test]
fn fewer_than_two_nodes_in_rope_block() {
    let m = file_error("nodes.toml", "[[ropes]]\nnodes = 1\n", 2, 9);
    assert_has(
        &m,
        &["`nodes` = 1", "out of range", "allowed 2 ..= 1000000"],
    );
    // A typo that would allocate terabytes is caught by the same range.
    let m = file_error("huge.toml", "[[ropes]]\nnodes = 1000000000000\n", 2, 9);
    assert_has(&m, &["`nodes` = 1000000000000", "out of range"]);
}

#[test]
fn too_many_rope_nodes_in_total() {
    // Eleven ropes of a million nodes each would need gigabytes: refused at the eleventh.
    let text = "[[ropes]]\nnodes = 1000000\n".repeat(11);
    let m = file_error("many.toml", &text, 22, 9);
    assert_has(&m, &["too many particles", "11000000", "at most 10000000"]);
}

#[test]
fn pinned_index_out_of_range_in_params() {
    let m = file_error(
        "pinned.toml",
        "scene = \"rope\"\n[params]\nnodes = 4\npinned = [0, 7]\n",
        4,
        10,
    );
    assert_has(
        &m,
        &["`pinned` = 7", "out of range", "0 ..= 3", "4 particles"],
    );
}

#[test]
fn pinned_index_out_of_range_in_rope_block() {
    let m = file_error(
        "pinned.toml",
        "[[ropes]]\nnodes = 4\npinned = [0, 7]\n",
        3,
        14,
    );
    assert_has(&m, &["pinned node 7", "out of range", "0 ..= 3", "4 nodes"]);
    let m = file_error("neg.toml", "[[ropes]]\npinned = [-1]\n", 2, 11);
    assert_has(&m, &["pinned node -1", "0 ..= 2", "3 nodes"]);
}

#[test]
fn pinned_index_from_set_is_a_parameter_error() {
    // The bad value came from the command line, not the file: no file position.
    let (_, result) = load_with(
        "pinned.toml",
        "scene = \"rope\"\n[params]\nnodes = 4\npinned = [0]\n",
        &["pinned=[9]"],
    );
    match result {
        Err(SceneError::Param(ParamError::OutOfRange { key, got, .. })) => {
            assert_eq!((key.as_str(), got.as_str()), ("pinned", "9"));
        }
        other => panic!("expected a parameter error, got {other:?}"),
    }
}

#[test]
fn spring_end_out_of_range_names_the_particle_count() {
    let text = format!("{TWO}[[springs]]\na = 0\nb = 5\nstiffness = 10\n");
    let m = file_error("spring.toml", &text, 9, 5);
    assert_has(
        &m,
        &[
            "`b` = 5",
            "out of range",
            "0 ..= 1",
            "the file has 2 particles",
        ],
    );
    let text = format!("{TWO}[[springs]]\na = -1\nb = 1\nstiffness = 10\n");
    let m = file_error("spring.toml", &text, 8, 5);
    assert_has(&m, &["`a` = -1", "0 ..= 1"]);
}

#[test]
fn spring_joining_a_particle_to_itself() {
    let text = format!("{TWO}[[springs]]\na = 1\nb = 1\nstiffness = 10\n");
    let m = file_error("self.toml", &text, 9, 5);
    assert_has(&m, &["particle 1 to itself", "`a` and `b` must differ"]);
}

#[test]
fn negative_spring_values_are_out_of_range() {
    let text = format!("{TWO}[[springs]]\na = 0\nb = 1\nstiffness = -10\n");
    let m = file_error("k.toml", &text, 10, 13);
    assert_has(&m, &["`stiffness` = -10", "allowed 0 ..= 1e9", "(N/m)"]);
    let text = format!("{TWO}[[springs]]\na = 0\nb = 1\nstiffness = 10\ndamping = -1\n");
    let m = file_error("kd.toml", &text, 11, 11);
    assert_has(&m, &["`damping` = -1", "allowed 0 ..= 1e9", "(N·s/m)"]);
    let text = format!("{TWO}[[springs]]\na = 0\nb = 1\nstiffness = 10\nrest_length = -2\n");
    let m = file_error("l0.toml", &text, 11, 15);
    assert_has(&m, &["`rest_length` = -2", "allowed 0 ..= 1e6", "(m)"]);
}

#[test]
fn unknown_top_level_key_lists_the_expected_ones() {
    let m = file_error("key.toml", "partcles = 3\n", 1, 1);
    assert_has(
        &m,
        &[
            "unknown field `partcles`",
            "`particles`",
            "`springs`",
            "`scene`",
        ],
    );
}

#[test]
fn unknown_key_in_a_particle_lists_the_expected_ones() {
    let text = format!("{TWO}colour = \"red\"\n");
    let m = file_error("key.toml", &text, 7, 1);
    assert_has(
        &m,
        &["unknown field `colour`", "`position`", "`mass`", "`pinned`"],
    );
}

#[test]
fn unknown_key_in_world_and_run() {
    let m = file_error("key.toml", "[world]\ngravty = [0, -1, 0]\n", 2, 1);
    assert_has(&m, &["unknown field `gravty`", "`gravity`", "`drag`"]);
    let m = file_error("key.toml", "scene = \"rope\"\n[run]\nsteps = 10\n", 3, 1);
    assert_has(&m, &["unknown field `steps`", "`method`", "`dt`", "`time`"]);
}

#[test]
fn unknown_parameter_lists_the_known_ones() {
    let m = file_error("key.toml", "scene = \"rope\"\n[params]\nnode = 3\n", 3, 1);
    assert_has(
        &m,
        &[
            "unknown parameter `node`",
            "scene `rope`",
            "nodes",
            "stiffness",
            "pinned",
        ],
    );
}

#[test]
fn unknown_method_lists_the_methods() {
    let m = file_error(
        "method.toml",
        "scene = \"rope\"\n[run]\nmethod = \"rk5\"\n",
        3,
        10,
    );
    assert_has(&m, &["unknown method `rk5`", &method_names()]);
}

#[test]
fn unknown_spring_kind_lists_the_kinds() {
    let text = format!("{TWO}[[springs]]\na = 0\nb = 1\nstiffness = 10\nkind = \"torsion\"\n");
    let m = file_error("kind.toml", &text, 11, 8);
    assert_has(
        &m,
        &["unknown spring kind `torsion`", "struct, shear, bend"],
    );
}

#[test]
fn string_where_a_number_is_expected() {
    let m = file_error(
        "type.toml",
        "[[particles]]\nposition = [0, 0, 0]\nmass = \"heavy\"\n",
        3,
        8,
    );
    assert_has(&m, &["`mass`", "string \"heavy\"", "expected a number"]);
    let m = file_error("type.toml", "[world]\ngravity = [0, \"down\", 0]\n", 2, 15);
    assert_has(&m, &["`gravity`", "string \"down\"", "expected a number"]);
}

#[test]
fn string_where_a_parameter_number_is_expected() {
    let m = file_error(
        "type.toml",
        "scene = \"rope\"\n[params]\nnodes = \"16\"\n",
        3,
        9,
    );
    assert_has(
        &m,
        &["`nodes` = \"16\"", "expected a whole number 2 ..= 1000000"],
    );
    let m = file_error(
        "type.toml",
        "scene = \"rope\"\n[params]\nstart = [0, 2]\n",
        3,
        9,
    );
    assert_has(&m, &["`start` = [0, 2]", "expected a vector [x, y, z]"]);
    let m = file_error(
        "type.toml",
        "scene = \"rope\"\n[params]\nnodes = 16.5\n",
        3,
        9,
    );
    assert_has(&m, &["`nodes` = 16.5", "expected a whole number"]);
}

#[test]
fn wrong_types_in_run_and_vectors() {
    let m = file_error(
        "type.toml",
        &format!("{TWO}[run]\niterations = 1.5\n"),
        8,
        14,
    );
    assert_has(&m, &["`iterations`", "1.5", "expected a whole number"]);
    let m = file_error(
        "type.toml",
        "[[particles]]\nposition = [0, 0]\nmass = 1\n",
        2,
        12,
    );
    assert_has(
        &m,
        &[
            "invalid length 2",
            "expected a vector [x, y, z] of 3 numbers",
        ],
    );
    let m = file_error("type.toml", "world = 3\n", 1, 9);
    assert_has(&m, &["integer `3`", "expected a table"]);
}

#[test]
fn method_settings_out_of_range_in_run() {
    let m = file_error("it.toml", &format!("{TWO}[run]\niterations = -1\n"), 8, 14);
    assert_has(&m, &["`iterations` = -1", "out of range", "0 ..= 1000"]);
    let m = file_error(
        "vd.toml",
        &format!("{TWO}[run]\nverlet_damping = 1.0\n"),
        8,
        18,
    );
    assert_has(&m, &["`verlet_damping` = 1", "out of range", "0 ..< 1"]);
}

#[test]
fn missing_required_key() {
    let m = file_error(
        "missing.toml",
        "[[particles]]\nposition = [0, 0, 0]\n",
        1,
        1,
    );
    assert_has(&m, &["missing field `mass`"]);
    let text = format!("{TWO}[[springs]]\na = 0\nb = 1\n");
    let m = file_error("missing.toml", &text, 7, 1);
    assert_has(&m, &["missing field `stiffness`"]);
}

#[test]
fn unknown_builtin_scene_lists_the_builtins() {
    let m = file_error("scene.toml", "scene = \"pendulum\"\n", 1, 9);
    assert_has(
        &m,
        &[
            "unknown built-in scene `pendulum`",
            "oscillator",
            "rope",
            "ropes",
        ],
    );
}

#[test]
fn no_particles() {
    let m = file_error("empty.toml", "", 1, 1);
    assert_has(&m, &["no particles", "[[particles]]", "scene ="]);
    let m = file_error("world.toml", "[world]\ndrag = 0.5\n", 1, 1);
    assert_has(&m, &["no particles"]);
}

#[test]
fn nan_and_infinity_are_rejected() {
    let m = file_error(
        "nan.toml",
        "[[particles]]\nposition = [0, 0, 0]\nmass = nan\n",
        3,
        8,
    );
    assert_has(
        &m,
        &["`mass` = NaN", "out of range", "allowed 1e-6 ..= 1e6 (kg)"],
    );
    let m = file_error(
        "inf.toml",
        "[[particles]]\nposition = [inf, 0, 0]\nmass = 1\n",
        2,
        12,
    );
    assert_has(&m, &["`position` = [inf, 0, 0]", "finite numbers", "(m)"]);
    let m = file_error(
        "g.toml",
        &format!("{TWO}[world]\ngravity = [0, -nan, 0]\n"),
        8,
        11,
    );
    assert_has(&m, &["`gravity`", "NaN", "finite numbers", "(m/s²)"]);
    let text = format!("{TWO}[[springs]]\na = 0\nb = 1\nstiffness = inf\n");
    let m = file_error("k.toml", &text, 10, 13);
    assert_has(&m, &["`stiffness` = inf", "out of range"]);
    let m = file_error("dt.toml", "scene = \"rope\"\n[run]\ndt = nan\n", 3, 6);
    assert_has(&m, &["`dt` = NaN", "allowed > 0 (s)"]);
    let m = file_error("p.toml", "scene = \"rope\"\n[params]\nmass = inf\n", 3, 8);
    assert_has(
        &m,
        &["`mass` = inf", "out of range", "allowed 1e-6 ..= 1e6 (kg)"],
    );
}

#[test]
fn toml_syntax_errors_have_a_position() {
    let m = file_error("syntax.toml", "scene = \"rope\"\n[params\n", 2, 8);
    assert_has(&m, &["expected `]`"]);
    let m = file_error("dup.toml", "scene = \"rope\"\nscene = \"ropes\"\n", 2, 1);
    assert_has(&m, &["duplicate key `scene`"]);
    let m = file_error(
        "bare.toml",
        "[[particles]]\nposition = [0, 0, 0]\nmass = \n",
        3,
        8,
    );
    assert!(!m.is_empty());
}

#[test]
fn rope_block_with_no_length() {
    let m = file_error(
        "rope.toml",
        "[[ropes]]\nstart = [1, 1, 1]\nend = [1, 1, 1]\n",
        3,
        7,
    );
    assert_has(&m, &["`start` and `end`", "must differ"]);
}

#[test]
fn builtin_scene_with_no_length_points_at_the_scene() {
    let m = file_error(
        "rope.toml",
        "scene = \"rope\"\n[params]\nend = [0.0, 2.0, 0.0]\n",
        1,
        9,
    );
    assert_has(&m, &["`start` and `end` must differ"]);
}

#[test]
fn explicit_sections_next_to_a_builtin_scene() {
    let text = "scene = \"rope\"\n[[particles]]\nposition = [0, 0, 0]\nmass = 1\n";
    let m = file_error("mixed.toml", text, 2, 1);
    assert_has(
        &m,
        &["[[particles]] cannot be used with `scene = \"rope\"`"],
    );
    let m = file_error("mixed.toml", "scene = \"rope\"\n[world]\ndrag = 1\n", 2, 1);
    assert_has(&m, &["[world] cannot be used"]);
}

#[test]
fn params_without_a_builtin_scene() {
    let m = file_error("params.toml", "[params]\nnodes = 3\n", 1, 1);
    assert_has(&m, &["[params] needs a built-in scene", "scene = "]);
}

#[test]
fn method_settings_of_a_builtin_belong_in_params() {
    let m = file_error(
        "run.toml",
        "scene = \"rope\"\n[run]\niterations = 2\n",
        3,
        14,
    );
    assert_has(&m, &["`iterations`", "set it in [params]"]);
}

#[test]
fn set_on_an_explicit_file_is_an_error() {
    let (_, result) = load_with("two.toml", TWO, &["stiffness=10"]);
    match result {
        Err(SceneError::Invalid(m)) => {
            assert_has(
                &m,
                &["--set stiffness=10", "--set applies only", "scene = "],
            );
        }
        other => panic!("expected an invalid-use error, got {other:?}"),
    }
}

#[test]
fn bad_set_on_a_builtin_file_is_a_parameter_error() {
    let (_, result) = load_with("rope.toml", "scene = \"rope\"\n", &["nodez=3"]);
    assert!(
        matches!(
            result,
            Err(SceneError::Param(ParamError::UnknownKey { .. }))
        ),
        "{result:?}"
    );
}

#[test]
fn missing_and_unreadable_files_are_io_errors() {
    let dir = fresh_dir();
    let path = dir.join("does-not-exist.toml");
    match scene::load(path.to_str().expect("utf-8"), &[]) {
        Err(SceneError::Io { path: p, .. }) => assert_eq!(p, path.display().to_string()),
        other => panic!("expected an I/O error, got {other:?}"),
    }
    let path = fresh_dir().join("latin1.toml");
    std::fs::write(&path, b"scene = \"r\xe9pe\"\n").expect("write");
    let result = scene::load(path.to_str().expect("utf-8"), &[]);
    assert!(matches!(result, Err(SceneError::Io { .. })), "{result:?}");
    let _ = std::fs::remove_dir_all(dir);
    let _ = std::fs::remove_dir_all(path.parent().expect("parent"));
}

#[test]
fn nested_garbage_does_not_panic() {
    // Deep nesting, odd types and stray tables: errors, never panics.
    let deep = format!("scene = {}1{}\n", "[".repeat(200), "]".repeat(200));
    let (_, result) = load_with("deep.toml", &deep, &[]);
    assert!(result.is_err());
    for text in [
        "scene = 1\n",
        "particles = [1, 2]\n",
        "[[springs]]\na = 0\nb = 1\nstiffness = 1\n",
        "[run]\nmethod = 3\n",
        "scene = \"rope\"\n[params]\npinned = [0.5]\n",
        "scene = \"rope\"\n[params]\nstart = [1, 2, \"x\"]\n",
        "scene = \"rope\"\n[params]\nnodes = { a = 1 }\n",
        "[[ropes]]\nnodes = 9223372036854775807\n",
        "[[ropes]]\nnodes = -9223372036854775808\n",
        "[[particles]]\nposition = [1e308, 1e308, 0]\nmass = 1e308\n[[springs]]\na = 0\nb = 0\nstiffness = 1\n",
    ] {
        let (_, result) = load_with("garbage.toml", text, &[]);
        assert!(result.is_err(), "{text}");
    }
}
