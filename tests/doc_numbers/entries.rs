//! The numbers of the README and `docs/` that need an entry, page by page (`tests/doc_numbers.rs`
//! says what each kind of reason means and checks that each names something that exists).

use super::Entry;

const ORDERS: &str = "here testing_md_quotes_the_measured_orders_and_rk4s_end: recomputed on the oscillator at the dts the page names";
const COURSE: &str = "here course_md_values_are_the_scenes_defaults: the built-in scene's default (`springlab scenes`)";
const RUBRIC_JELLY: &str = "code crates/grade/src/grade/jelly.rs `| #4 integrators | 25 | explicit Euler 5, implicit Euler 2.5 + midpoint 2.5, RK4 15 |`: the rubric's weights, each a check's points";
const STUDIES: &str = "test tests/recorded_numbers.rs docs_studies_quotes_the_recorded_resolution_study_and_its_limit: from the recording, pinned to the code by tests/lesson8.rs";

pub const ENTRIES: &[Entry] = &[
    // README.md
    (
        "README.md",
        &["10^6"],
        "code crates/core/src/physics/diverge.rs `MAX_SPEED_SQUARED: f64 = 1.0e6`: the divergence check",
    ),
    (
        "README.md",
        &["11"],
        "test tests/course_scenes.rs every_scene_is_listed_builds_with_course_values_and_counts: the jelly's corner at offset (−4.8, 7, 0) + (0, L, 0) with L = 4 m",
    ),
    (
        "README.md",
        &["2023"],
        "label: the NYCU course year of the scene or assignment",
    ),
    (
        "README.md",
        &["1.25"],
        "label: the picture's time, in its file name (render-jelly-bowl-1.25s.png)",
    ),
    (
        "README.md",
        &["80", "100"],
        "test tests/grade_boundary.rs correct_homework_gets_full_marks_graded_by_a_relative_path: a correct jelly or cloth crate scores 80 (of the course's 100)",
    ),
    ("README.md", &["15", "20", "25"], RUBRIC_JELLY),
    (
        "README.md",
        &["22.04", "2.35"],
        "code crates/grade/src/grade/autograder.rs `Ubuntu 22.04`: the image the autograder targets and its glibc",
    ),
    // docs/running.md
    (
        "docs/running.md",
        &["10^9", "3.6", "10^11", "2", "3840", "2160", "10^10", "16"],
        "code crates/core/src/budget.rs `frame_pixels: 3840.0 * 2160.0`: `Limits::DEFAULT` (steps 1e9, work 3.6e11, memory, pixels, file bytes), each refused over it in tests/budget.rs",
    ),
    (
        "docs/running.md",
        &["10^8"],
        "code crates/core/src/budget.rs `pub const RATE: f64 = 1e8`: the rate the time estimates assume",
    ),
    (
        "docs/running.md",
        &["10"],
        "code crates/core/src/budget.rs `pub const NOTICE_SECONDS: f64 = 10.0`",
    ),
    (
        "docs/running.md",
        &["130", "128"],
        "code src/cli/interrupt.rs `0 => 130,`: exit statuses after Ctrl-C or a signal (tests/nothing_lost.rs a_render_stopped_by_each_signal_leaves_nothing)",
    ),
    (
        "docs/running.md",
        &["1e-6", "1e6", "1e9"],
        "code crates/core/src/scene/params.rs `pub const MASS: Range = Range::Between(1e-6, 1e6);`: the ranges (tests/budget.rs denormal_masses_and_overflowing_stiffness_are_out_of_range)",
    ),
    (
        "docs/running.md",
        &["100"],
        "test tests/nothing_lost.rs sixteen_megabyte_adversarial_scene_files_stay_under_100_mb",
    ),
    (
        "docs/running.md",
        &["24", "256", "3.4"],
        "label: colour depth, xterm's palette size and the tmux version that draws sixel",
    ),
    // docs/studies.md
    (
        "docs/studies.md",
        &["20"],
        "code src/study/observe.rs `20`: the observable is sampled at 20 instants",
    ),
    (
        "docs/studies.md",
        &["2.5", "3"],
        "code crates/core/src/scene.rs `observe_at: 2.5`: each scene's observation time T (`SceneDef::observe_at`)",
    ),
    (
        "docs/studies.md",
        &["1"],
        "label: 1 s, the observation time of the other scenes; 1 cm, the tolerance of the recorded studies",
    ),
    (
        "docs/studies.md",
        &["0.01"],
        "code src/cli/study.rs `(default 0.01)`: the default tolerance of `study resolution`, and advise's recorded run's",
    ),
    (
        "docs/studies.md",
        &["0.8"],
        "code src/study/resolution/limit.rs `0.8`: the settling check compares T with 0.8 T",
    ),
    (
        "docs/studies.md",
        &["49", "25", "35"],
        "label: levels of the recorded study (`--n 9,13,17,25,35,49`, docs/studies/README.md)",
    ),
    (
        "docs/studies.md",
        &[
            "0.4025", "0.4642", "0.70", "0.520", "0.088", "0.7465", "0.8462",
        ],
        STUDIES,
    ),
    (
        "docs/studies.md",
        &["1.5"],
        "code src/study/advise.rs `1.5`: advise's stability margin",
    ),
    (
        "docs/studies.md",
        &["8.49e-5"],
        "test tests/recorded_numbers.rs docs_studies_quotes_the_recorded_advice: from the recording, which the_recorded_advice_matches_the_code pins",
    ),
    (
        "docs/studies.md",
        &["16"],
        "code src/study/convergence.rs `16`: the reference's dt_min/16",
    ),
    (
        "docs/studies.md",
        &["2.000", "1.020"],
        "here studies_md_quotes_verlets_orders: `study convergence oscillator --methods verlet`",
    ),
    (
        "docs/studies.md",
        &["2"],
        "label: 2 N·s/m, the damper the study switches on for Verlet's extra row",
    ),
    (
        "docs/studies.md",
        &["5e-5"],
        "test tests/lesson_numbers.rs the_explained_numbers_hold: the rope scenes' γ",
    ),
    (
        "docs/studies.md",
        &["1e-10"],
        "code src/study/stability.rs `1 + ~1e-10`: the linear test's growth tolerance, as the study's definition prints it",
    ),
    (
        "docs/studies.md",
        &["50", "10000", "95", "0.5"],
        "code src/study/stability.rs `50`: the confirmation's horizons, step cap, 95 % check and bisection tolerance",
    ),
    (
        "docs/studies.md",
        &["80"],
        "code src/study/stability/usable/predict.rs `pub const USABLE_AIM: f64 = 0.8;`: the usable dt's prediction aims at 80 % of the allowed residual",
    ),
    (
        "docs/studies.md",
        &["360"],
        "code src/study/theory.rs `360`: the dense limit",
    ),
    (
        "docs/studies.md",
        &["0.1"],
        "here stability_md_is_the_recorded_study: every linear limit within 0.1 % of the theory",
    ),
    (
        "docs/studies.md",
        &["5"],
        "code src/study/stability.rs `STIFFEST_SAMPLE_INTERVAL`: 5 ms",
    ),
    (
        "docs/studies.md",
        &["1.9980", "2.8284"],
        "here stability_md_is_the_recorded_study: the rope's linear dt·ω, from the recording the test re-runs",
    ),
    (
        "docs/studies.md",
        &["1.9", "59", "10^5", "100"],
        "here the_rope_pumps_semi_implicit_eulers_stiff_mode: the run at dt·ω = 1.9",
    ),
    (
        "docs/studies.md",
        &["7"],
        "here stability_md_is_the_recorded_study: the largest shortfall of a scene limit under the theory, from the recordings",
    ),
    // docs/stability.md (its table and stiffest states: stability_md_is_the_recorded_study)
    (
        "docs/stability.md",
        &["1000", "3^3"],
        "label: the size of the course cube and of the small jelly a test uses",
    ),
    (
        "docs/stability.md",
        &["5"],
        "code src/study/stability.rs `pub const STIFFEST_SAMPLE_INTERVAL: f64 = 0.005;`",
    ),
    (
        "docs/stability.md",
        &["50", "95"],
        "code src/study/stability.rs `pub const CONFIRM_HORIZONS: f64 = 50.0;`: with CONFIRM_MARGIN = 0.95",
    ),
    (
        "docs/stability.md",
        &["1", "95", "80"],
        "code src/study/stability/usable.rs `pub const USABLE_FRACTION: f64 = 0.01;`: with USABLE_MARGIN = 0.95 and predict.rs's USABLE_AIM = 0.8",
    ),
    (
        "docs/stability.md",
        &["0.1"],
        "here stability_md_is_the_recorded_study: every linear limit within 0.1 % of the recomputed theory",
    ),
    // docs/testing.md
    (
        "docs/testing.md",
        &[
            "0.1", "1", "0.005", "0.000625", "1.06", "1.02", "0.94", "0.96", "1.98", "2.00", "3.97",
        ],
        ORDERS,
    ),
    (
        "docs/testing.md",
        &["1.0862270842", "1e-12", "1.0862318872", "4.8e-6", "1000"],
        ORDERS,
    ),
    (
        "docs/testing.md",
        &["2.02", "2.80", "2.86", "100", "1.00"],
        "test tests/integrators.rs semi_implicit_euler_and_verlet_are_stable_below_two_and_grow_above: the amplitudes at dt·ω = 1.98 / 2.02 (and RK4's 2.80 / 2.86, implicit Euler's 100, the predictor–corrector's bisection to 1.00 in the same file)",
    ),
    (
        "docs/testing.md",
        &["11", "1.43"],
        "test tests/course_scenes.rs cube_plane_falls_freely_then_rests_on_the_plane",
    ),
    (
        "docs/testing.md",
        &["45", "30"],
        "test tests/course_scenes.rs cube_tilted_tips_over_and_slides_down_the_slope",
    ),
    (
        "docs/testing.md",
        &["5", "2023"],
        "test tests/course_scenes.rs jelly_bowl_rk4_json_ends_in_the_bowl",
    ),
    (
        "docs/testing.md",
        &["50"],
        "here cloth_at_fifty_times_the_course_dt",
    ),
    (
        "docs/testing.md",
        &["1e-6", "1e-3", "5e-4", "2.5e-4"],
        "test tests/contact_energy.rs cube_plane_contacts_never_add_energy_at_three_steps",
    ),
    (
        "docs/testing.md",
        &["0.04"],
        "test tests/contact_energy.rs implicit_euler_contacts_never_add_energy_at_a_large_step",
    ),
    (
        "docs/testing.md",
        &["1.05"],
        "test tests/run_accuracy.rs rope_just_above_rk4s_linear_limit_is_bounded_but_not_accurate",
    ),
    // docs/course.md: the courses' handouts, skeletons and reports.
    (
        "docs/course.md",
        &["2020", "2021", "2022", "2023", "2024", "1998"],
        "label: the courses' years and the paper's",
    ),
    (
        "docs/course.md",
        &["200", "400", "100", "64", "0.00005", "480", "35"],
        "source: the GAMES101 handout and skeleton (the rope in pixels; springlab's rope is in SI units, crates/core/src/scene/rope.rs)",
    ),
    (
        "docs/course.md",
        &[
            "1000", "2700", "2400", "7776", "4860", "2916", "12876", "26", "20",
        ],
        "here course_md_values_are_the_scenes_defaults: the 10³ cube's particles and springs by kind (and the 20 shear neighbours of 26)",
    ),
    (
        "docs/course.md",
        &[
            "2000", "60", "0.001", "9.8", "6.364", "2.64", "4.8", "0.8", "0.3", "0.2", "625",
            "25000", "20000", "750", "3.4", "10^-4", "0.5", "125",
        ],
        COURSE,
    ),
    (
        "docs/course.md",
        &[
            "0.01", "10^6", "15", "25", "80", "40", "0.75", "0.15", "0.0006", "0.0011", "0.0015",
        ],
        "source: the NYCU HW1 skeletons and reports (ε, the instability check, the rubric, the cloth, a report's measured limits); the values springlab's scenes take are checked by course_md_values_are_the_scenes_defaults",
    ),
    // docs/grading.md
    (
        "docs/grading.md",
        &["8", "2000"],
        "code crates/grade/src/grade/build/source.rs `MAX_SOURCE_BYTES: u64 = 8 << 20`: what a submission's copy may hold",
    ),
    (
        "docs/grading.md",
        &["65534"],
        "code src/cli/grade.rs `else 65534, nobody`: the sandbox user's default",
    ),
    (
        "docs/grading.md",
        &["5.13", "64", "22.04", "2.35", "2024"],
        "label: the Linux version with Landlock, the architectures (x86-64, aarch64), the base image and its glibc, the Rust edition",
    ),
    (
        "docs/grading.md",
        &["3", "10", "16", "32", "60", "256", "80", "300", "3072"],
        "code crates/grade/src/grade/remote.rs `file_bytes: 16 << 20`: the program's and the build's limits (crates/grade/src/grade/build.rs, src/cli/grade.rs defaults)",
    ),
    (
        "docs/grading.md",
        &["35"],
        "test tests/grade_boundary.rs correct_homework_gets_full_marks_graded_by_a_relative_path: the rope's 35",
    ),
    (
        "docs/grading.md",
        &["200"],
        "test tests/grade_sandbox.rs two_hundred_forks_leave_nothing_behind",
    ),
    (
        "docs/grading.md",
        &["1023", "4"],
        "test tests/grade_sandbox/untrusted.rs inherited_descriptors_and_a_huge_escaped_panic_reach_nothing: the attack writes descriptors 3 to 1023 and panics with 4 MiB",
    ),
    (
        "docs/grading.md",
        &["2"],
        "code crates/grade/src/grade/untrusted.rs `MAX_STUDENT_TEXT: usize = 2048`: the student text kept",
    ),
    (
        "docs/grading.md",
        &["52"],
        "label: OSC 52, the terminal escape sequence that writes the clipboard",
    ),
    // docs/homework-live.md
    (
        "docs/homework-live.md",
        &["2023", "2022"],
        "label: the course year of the assignment",
    ),
    (
        "docs/homework-live.md",
        &["64"],
        "code homework-api/src/wire.rs `STEPS`: up to 64 steps a request",
    ),
    (
        "docs/homework-live.md",
        &["1e-9"],
        "test tests/homework_live.rs correct_crates_never_part_from_the_reference",
    ),
    (
        "docs/homework-live.md",
        &["4.3", "3.3", "1.1", "5.2"],
        "label: lesson.step where the mistake shows (tests/homework_live.rs each_planted_mistake_parts_at_its_step_and_quantity)",
    ),
    (
        "docs/homework-live.md",
        &["2"],
        "code crates/grade/src/grade/live/build.rs `call_limit: Duration::from_secs(2)`",
    ),
    (
        "docs/homework-live.md",
        &["150"],
        "code crates/grade/src/grade/live/watch.rs `Duration::from_millis(150)`",
    ),
    (
        "docs/homework-live.md",
        &["12"],
        "code crates/grade/src/grade/live/build.rs `at most 12 lines`",
    ),
    (
        "docs/homework-live.md",
        &["1000", "482", "16", "68"],
        "test tests/homework_live.rs implicit_euler_on_the_thousand_particle_jelly_is_refused_with_its_reason: 1000 particles at dt = 1 ms, the message size",
    ),
    (
        "docs/homework-live.md",
        &["5.5"],
        "label: lesson.step of the bench's jelly (benches/homework_live.rs)",
    ),
    (
        "docs/homework-live.md",
        &["24"],
        "label: the bytes of a vector on the wire, three f64 (homework-api/src/wire.rs)",
    ),
    (
        "docs/homework-live.md",
        &["12876"],
        "here course_md_values_are_the_scenes_defaults: the springs of the course's 10³ cube (cube-plane)",
    ),
    (
        "docs/homework-live.md",
        &[
            "0.003", "0.005", "0.008", "0.004", "0.012", "0.22", "0.37", "0.32", "0.36", "0.58",
            "0.53", "0.66", "1.10", "1.07", "13", "15",
        ],
        "timing: CPU seconds per simulated second printed by `cargo bench -p springlab-benches --bench homework_live`, and the load average while it ran",
    ),
    (
        "docs/homework-live.md",
        &[
            "0.21", "0.07", "0.03", "0.01", "0.19", "0.06", "0.10", "0.14", "0.4",
        ],
        "timing: `perf record` of `cargo bench --bench homework_live` (jelly RK4, batched), samples per thread and kind of work scaled to the bench's CPU seconds per simulated second",
    ),
    (
        "docs/homework-live.md",
        &["128"],
        "code crates/grade/src/grade/live.rs `REFERENCE_AHEAD`: two of `LiveOptions::ahead`'s 64 steps",
    ),
    (
        "docs/homework-live.md",
        &["512"],
        "code crates/grade/src/grade/remote/frames.rs `PIPE_BYTES`: 512 KiB",
    ),
    (
        "docs/homework-live.md",
        &["48", "340"],
        "label: bytes on the wire of the 1000-particle jelly, 24 per vector (two lists of 1000: 48 KB; RK4's four requests and answers and the step's answer: 4 × 72 + 48 ≈ 340 KB)",
    ),
    // docs/implicit-euler.md: why the solve is built as it is.
    (
        "docs/implicit-euler.md",
        &[
            "24", "16.8", "25.9", "1.3", "3.2", "200", "2000", "277", "600", "74", "0.28",
        ],
        "history: runs of the alternatives the page says were replaced (projection after the step, no cap, pulling constraints, no sphere guess, two solves)",
    ),
    (
        "docs/implicit-euler.md",
        &["0.04", "0.005", "5", "0.1", "2.5", "1"],
        "label: the dt and horizon of the runs the page describes",
    ),
    (
        "docs/implicit-euler.md",
        &["5.3"],
        "source: the section of Baraff & Witkin's paper",
    ),
    (
        "docs/implicit-euler.md",
        &["10^-10", "10^-2", "0.14", "35", "250", "2.1"],
        "test tests/integrators.rs the_default_cg_tolerance_costs_under_a_tenth_of_the_methods_own_error: checks the solver's change stays under a tenth of the method's own error (the page's 0.14 mm against 35 mm is one run of it)",
    ),
    (
        "docs/implicit-euler.md",
        &["6.77"],
        "test tests/lesson_numbers.rs implicit_euler_on_the_cloth_costs_about_a_sixth_of_the_passes: about seven CG iterations a step on the cloth at dt = 5 ms",
    ),
    // docs/lesson-app.md
    (
        "docs/lesson-app.md",
        &["1280"],
        "code src/tui/export.rs `pub const EXPORT_WIDTH: u32 = 1280;`",
    ),
    (
        "docs/lesson-app.md",
        &["20"],
        "code src/tui.rs `const STEP_BUDGET: Duration = Duration::from_millis(20);`",
    ),
    (
        "docs/lesson-app.md",
        &["60", "30"],
        "code src/tui.rs `const RASTER_FRAME: Duration = Duration::from_micros(33_333);`: 60 and 30 frames a second",
    ),
    (
        "docs/lesson-app.md",
        &["1.000", "1.00"],
        "label: the real-time factor of a run that keeps up (×1)",
    ),
    (
        "docs/lesson-app.md",
        &["80", "24", "100", "32", "120", "40"],
        "label: terminal sizes in cells (tests/tui_layout.rs checks every step at 80×24)",
    ),
    (
        "docs/lesson-app.md",
        &["1", "2000"],
        "history: crossterm's read size and the burst the page describes",
    ),
    (
        "docs/lesson-app.md",
        &["10^7"],
        "code src/tui/lesson_run/usable.rs `pub const SEARCH_BUDGET: f64 = 2.0e7;`",
    ),
    (
        "docs/lesson-app.md",
        &["50"],
        "code src/tui/app_loop.rs `const KEY_BUDGET: Duration = Duration::from_millis(50);`",
    ),
    (
        "docs/lesson-app.md",
        &["2"],
        "code src/tui/lesson_run/observed.rs `pub const SAMPLE_EVERY: f64 = 0.002;`",
    ),
    (
        "docs/lesson-app.md",
        &["3"],
        "code crates/core/src/scene.rs `observe_at: 3.0`: the cloth's observation time",
    ),
    (
        "docs/lesson-app.md",
        &["11", "300"],
        "code src/tui/theme.rs `pub const QUERY_TIMEOUT: Duration = Duration::from_millis(300);`: OSC 11 and its wait",
    ),
    ("docs/lesson-app.md", &["6"], "label: the picture's time"),
    (
        "docs/lesson-app.md",
        &["16", "5.8", "8.1", "5.0", "7.1", "2.8", "3.3"],
        "timing: criterion medians of `cargo bench -p springlab-benches --bench tui_view`",
    ),
    (
        "docs/lesson-app.md",
        &["560", "320", "7.9", "13.3"],
        "timing: criterion medians of the sixel encoding alone (springlab's writer and icy_sixel 0.5 without diffusion) on the frame of `cargo bench -p springlab-benches --bench tui_view`, one run; 560 × 320 is its 70 × 20 cells of 8 × 16 pixels",
    ),
    (
        "docs/lesson-app.md",
        &["4096"],
        "code src/tui/lesson_run.rs `pub const DEFAULT_MAX_STEPS_PER_FRAME: u64 = 4096;`",
    ),
    (
        "docs/lesson-app.md",
        &["1.5"],
        "code src/tui/lesson_run.rs `COEFFICIENT_FACTOR`",
    ),
    (
        "docs/lesson-app.md",
        &["0.25"],
        "code src/tui/lesson_run.rs `pub const FIRST_DRAG_RATE: f64 = 0.25;`",
    ),
    (
        "docs/lesson-app.md",
        &["15"],
        "code src/tui/lesson_run/controls.rs `pub const ORBIT_STEP_DEGREES: f64 = 15.0;`",
    ),
    (
        "docs/lesson-app.md",
        &["1.25"],
        "code crates/render/src/render/camera.rs `pub const ZOOM_STEP: f64 = 1.25;`",
    ),
    // docs/studies/README.md
    (
        "docs/studies/README.md",
        &["13"],
        "test tests/lesson8.rs the_recorded_resolution_study_matches_the_code: the levels it re-runs",
    ),
];
