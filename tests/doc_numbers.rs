//! No recorded number without a test (issue 26): every number a reader finds in the README and
//! in `docs/*.md` is an input of a command or scene shown beside it, a unit-free count or index,
//! or it is listed below with what keeps it true. The lessons' numbers are checked the same way
//! by `tests/lesson_numbers.rs` (every step of every built-in lesson, with the steps' own inputs
//! and the numbers the loader computes when a step opens).
//!
//! A number is read as written, outside fenced and indented code, inline code, link targets and
//! HTML comments (`12 876` is one number, `10⁹` is `10^9`). It needs no entry when
//! - it also appears in code (a command, a scene parameter, an example) in the same paragraph,
//!   table or the code block next to it: an input shown beside the text;
//! - it is a whole number from 0 to 10 not followed by a unit: a count, an index, a step or a
//!   list number;
//! - it is an ordered list's number or an issue's number.
//!
//! Every other number has an entry `(page, numbers, why)`. `why` starts with its kind:
//! - `test tests/FILE.rs FN: …`: the named test recomputes the number (the test checks that
//!   the function exists);
//! - `code src/FILE `NEEDLE`: …`: a constant or default of the code, which holds `NEEDLE` (checked
//!   here);
//! - `here FN: …`: a test of this file recomputes it;
//! - `source: …`: a fact of a cited source outside springlab (the courses' handouts and
//!   skeletons, their reports, papers, other programs' versions), which no run of springlab can
//!   recompute;
//! - `label: …`: a date, a version, a size or count of something listed, the terminal size a
//!   picture was taken at;
//! - `history: …`: a measurement of code that the page says was replaced; it documents why, and
//!   no test can re-run code that no longer exists;
//! - `timing: …`: a wall-clock measurement; tests are never timed, so the bench or script named
//!   measures it.
//!
//! Pages that are speed measurements as a whole (`docs/performance.md`, `docs/workloads.md`, and
//! the README's "Speed" section between them) are written by `scripts/speed-table.sh` and the
//! benches; they are listed in [`MEASURED`] and not scanned.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::common::{fitted_order, json, oscillator, oscillator_x, springlab};
use springlab::physics::Method;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(page: &str) -> String {
    std::fs::read_to_string(root().join(page)).unwrap_or_else(|e| panic!("{page}: {e}"))
}

/// Pages (or a page's section, after `#`) that are measurements of a machine's speed, with
/// what writes them.
const MEASURED: &[(&str, &str)] = &[
    (
        "docs/performance.md",
        "timing: speed of the fast engine and the renderer, by `scripts/speed-table.sh`, the benches and `springlab bench`",
    ),
    (
        "docs/workloads.md",
        "timing: the peer workloads' timings and checksums (checksums: tests/bench_workloads.rs)",
    ),
    (
        "README.md#Speed",
        "timing: the table `scripts/speed-table.sh` writes between its markers",
    ),
];

/// Superscript digits, read as an exponent: `10⁹` is `10^9`.
const SUPERSCRIPT: &str = "⁰¹²³⁴⁵⁶⁷⁸⁹⁻";

/// Units that make a small whole number a quantity to explain.
const UNITS: &[&str] = &[
    "s", "ms", "m", "cm", "mm", "J", "kJ", "N", "N/m", "N·s/m", "kg", "%", "rad/s", "1/s", "Hz",
    "MB", "MiB", "GiB", "KiB", "GB", "bytes", "°", "min",
];

/// One number as written and the text after it.
struct Token {
    text: String,
    after: String,
}

fn superscript_digit(c: char) -> Option<char> {
    SUPERSCRIPT
        .chars()
        .position(|s| s == c)
        .map(|i| "0123456789-".as_bytes()[i] as char)
}

/// The numbers of `s`: digits with a decimal point and an exponent (`1e-3`), digit groups
/// separated by a space (`12 876`), and a superscript exponent (`10⁹` → `10^9`). A digit right
/// after a letter, `_` or `.` is part of a name (`f64`, `x86`, `v0.2`), not a number.
fn tokens(s: &str) -> Vec<Token> {
    let c: Vec<char> = s.chars().collect();
    let digit = |i: usize| c.get(i).is_some_and(char::is_ascii_digit);
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let starts =
            digit(i) && (i == 0 || !(c[i - 1].is_alphanumeric() || matches!(c[i - 1], '_' | '.')));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < c.len()
            && (digit(j)
                || (c[j] == '.' && digit(j + 1))
                || (c[j] == 'e' && (digit(j + 1) || c.get(j + 1) == Some(&'-')))
                || (c[j] == '-' && j > 0 && c[j - 1] == 'e'))
        {
            j += 1;
        }
        let mut text: String = c[i..j].iter().collect();
        // Thousands written with a (thin) space or a comma: `12 876`, `10 000`, `2,000`.
        while j - i <= 3
            && text.chars().all(|d| d.is_ascii_digit())
            && matches!(c.get(j), Some(' ' | ',' | '\u{2009}' | '\u{202f}'))
            && (1..=3).all(|k| digit(j + k))
            && !digit(j + 4)
        {
            text.extend(&c[j + 1..j + 4]);
            j += 4;
        }
        if c.get(j).and_then(|&x| superscript_digit(x)).is_some() {
            text.push('^');
            while let Some(d) = c.get(j).and_then(|&x| superscript_digit(x)) {
                text.push(d);
                j += 1;
            }
        }
        // A number run into a word is part of it: `12th`, `3D`.
        if c.get(j).is_some_and(char::is_ascii_alphabetic) {
            i = j;
            continue;
        }
        let after: String = c[j..].iter().collect();
        out.push(Token {
            text,
            after: after
                .trim_start_matches([' ', '\u{a0}', '\u{202f}', '\u{2009}'])
                .to_string(),
        });
        i = j;
    }
    out
}

/// A whole number 0 ..= 10 not followed by a unit: a count, an index or a list number.
fn structural(t: &Token) -> bool {
    let small = t.text.parse::<u32>().is_ok_and(|v| v <= 10) && !t.text.contains('^');
    let unit = UNITS.iter().any(|u| {
        t.after.strip_prefix(u).is_some_and(|rest| {
            rest.chars()
                .next()
                .is_none_or(|x| !x.is_alphanumeric() && x != '/')
        })
    });
    small && !unit
}

/// A line split into its prose (inline code and link targets out) and its inline code.
fn split_code(line: &str) -> (String, String) {
    let mut prose = String::new();
    let mut code = String::new();
    for (k, part) in line.split('`').enumerate() {
        if k % 2 == 1 {
            code.push_str(part);
            code.push(' ');
        } else {
            prose.push_str(part);
            prose.push(' ');
        }
    }
    // Link targets: `](…)`.
    let mut clean = String::new();
    let mut rest = prose.as_str();
    while let Some(i) = rest.find("](") {
        clean.push_str(&rest[..=i]);
        rest = rest[i..].find(')').map_or("", |j| &rest[i + j + 1..]);
    }
    clean.push_str(rest);
    (clean, code)
}

/// A page as blocks: `(is code, lines with their numbers)`. Code is a fenced block or an
/// indented block after a blank line; prose blocks are separated by blank lines.
fn blocks(text: &str) -> Vec<(bool, Vec<(usize, String)>)> {
    let mut out = Vec::new();
    let mut prose: Vec<(usize, String)> = Vec::new();
    let mut code: Vec<(usize, String)> = Vec::new();
    let (mut fenced, mut indented, mut previous_blank) = (false, false, true);
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        if line.trim_start().starts_with("```") {
            if fenced {
                out.push((true, std::mem::take(&mut code)));
            } else if !prose.is_empty() {
                out.push((false, std::mem::take(&mut prose)));
            }
            fenced = !fenced;
            continue;
        }
        if fenced {
            code.push((n, line.to_string()));
            continue;
        }
        if line.trim().is_empty() {
            if !prose.is_empty() {
                out.push((false, std::mem::take(&mut prose)));
            }
            previous_blank = true;
            continue;
        }
        if line.starts_with("    ") && (previous_blank || indented) {
            indented = true;
            previous_blank = false;
            code.push((n, line.to_string()));
            continue;
        }
        if indented {
            out.push((true, std::mem::take(&mut code)));
            indented = false;
        }
        previous_blank = false;
        prose.push((n, line.to_string()));
    }
    if !prose.is_empty() {
        out.push((false, prose));
    }
    if !code.is_empty() {
        out.push((true, code));
    }
    out
}

/// The page's text as scanned: HTML comments and skipped sections blanked, line numbers kept.
fn scanned_text(page: &str) -> String {
    let mut text = read(page);
    for (measured, _) in MEASURED {
        if let Some((p, section)) = measured.split_once('#')
            && p == page
        {
            let head = format!("\n## {section}\n");
            if let Some(a) = text.find(&head) {
                let b = text[a + head.len()..]
                    .find("\n## ")
                    .map_or(text.len(), |b| a + head.len() + b);
                let blank = "\n".repeat(text[a..b].matches('\n').count());
                text.replace_range(a..b, &blank);
            }
        }
    }
    // A region generated from recordings, compared whole by its test.
    if let Some(a) = text.find(stability::BEGIN)
        && let Some(b) = text[a..].find(stability::END)
    {
        let b = a + b;
        let blank = "\n".repeat(text[a..b].matches('\n').count());
        text.replace_range(a..b, &blank);
    }
    while let Some(a) = text.find("<!--") {
        let b = text[a..].find("-->").map_or(text.len(), |b| a + b + 3);
        let blank = "\n".repeat(text[a..b].matches('\n').count());
        text.replace_range(a..b, &blank);
    }
    text
}

/// `(line, number as written)` of every number of `page` that needs an entry.
fn numbers(page: &str) -> Vec<(usize, String)> {
    numbers_in(&scanned_text(page))
}

/// The pages scanned: the README and every page of `docs/` not in [`MEASURED`].
fn pages() -> Vec<String> {
    let mut pages = vec!["README.md".to_string()];
    for dir in ["docs", "docs/studies"] {
        let mut found: Vec<String> = std::fs::read_dir(root().join(dir))
            .expect("docs")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .map(|p| format!("{dir}/{}", p.file_name().unwrap().to_string_lossy()))
            .filter(|p| !MEASURED.iter().any(|(m, _)| m == p))
            .collect();
        found.sort();
        pages.extend(found);
    }
    pages
}

/// `(page, numbers as written, why)`; the module docs say what `why` must start with.
type Entry = (&'static str, &'static [&'static str], &'static str);

mod entries;
mod stability;
use entries::ENTRIES;

fn explained(page: &str, number: &str) -> bool {
    ENTRIES
        .iter()
        .any(|(p, ns, _)| *p == page && ns.contains(&number))
}

#[test]
fn every_number_in_the_readme_and_docs_is_an_input_a_count_or_explained() {
    let mut unexplained = Vec::new();
    for page in pages() {
        for (line, n) in numbers(&page) {
            if !explained(&page, &n) {
                unexplained.push(format!("{page}:{line}: {n}"));
            }
        }
    }
    assert!(
        unexplained.is_empty(),
        "numbers without an entry in tests/doc_numbers/entries.rs ({}):\n{}",
        unexplained.len(),
        unexplained.join("\n")
    );
}

/// Every entry is still needed (its page shows each of its numbers) and names something that
/// exists: the test function, the constant in the code, the function of this file.
#[test]
fn every_entry_names_what_keeps_it_true() {
    let mut here = read("tests/doc_numbers.rs");
    for file in ["entries", "stability"] {
        here.push_str(&read(&format!("tests/doc_numbers/{file}.rs")));
    }
    let mut wrong = Vec::new();
    for (page, ns, why) in ENTRIES {
        let found: BTreeSet<String> = numbers(page).into_iter().map(|(_, n)| n).collect();
        for n in *ns {
            if !found.contains(*n) {
                wrong.push(format!(
                    "{page}: {n} is not (or no longer) a number to explain"
                ));
            }
        }
        let (kind, rest) = why.split_once(' ').unwrap_or((why, ""));
        match kind {
            "test" => {
                let mut words = rest.split_whitespace();
                let (file, function) = (words.next().unwrap_or(""), words.next().unwrap_or(""));
                let function = function.trim_end_matches(':');
                let body = std::fs::read_to_string(root().join(file)).unwrap_or_default();
                if !body.contains(&format!("fn {function}(")) {
                    wrong.push(format!("{page} {ns:?}: no `fn {function}` in {file}"));
                }
            }
            "code" => {
                let file = rest.split_whitespace().next().unwrap_or("");
                let needle = rest.split('`').nth(1).unwrap_or("");
                let body = std::fs::read_to_string(root().join(file)).unwrap_or_default();
                if needle.is_empty() || !body.contains(needle) {
                    wrong.push(format!("{page} {ns:?}: `{needle}` not in {file}"));
                }
            }
            "here" => {
                let function = rest.split_whitespace().next().unwrap_or("");
                let function = function.trim_end_matches(':');
                if !here.contains(&format!("fn {function}(")) {
                    wrong.push(format!("{page} {ns:?}: no `fn {function}` here"));
                }
            }
            "source:" | "label:" | "history:" | "timing:" => {}
            _ => wrong.push(format!("{page} {ns:?}: unknown kind in `{why}`")),
        }
    }
    for (page, _) in MEASURED {
        let file = page.split('#').next().unwrap_or(page);
        assert!(Path::new(&root().join(file)).exists(), "{file}");
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The scanner itself: an added number without an entry is found, an input shown in code
/// beside it is not, and neither is a count.
#[test]
fn the_scanner_finds_a_new_number() {
    let t = |s: &str| -> Vec<String> { tokens(s).into_iter().map(|t| t.text).collect() };
    assert_eq!(
        t("at dt = 8.49e-5 s, 12 876 springs, 10⁹ steps, f64 and x86, v0.2, the 12th, 3D"),
        ["8.49e-5", "12876", "10^9"]
    );
    assert!(structural(&tokens("3 springs").remove(0)));
    assert!(!structural(&tokens("3 s").remove(0)));
    assert!(!structural(&tokens("4 %").remove(0)));
    let dir = std::env::temp_dir().join(format!("springlab-doc-numbers-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let page = dir.join("page.md");
    std::fs::write(
        &page,
        "# A page\n\nRun `springlab run rope --dt 0.004`: at dt = 0.004 s it holds 3 springs.\n\
         It ends at 1.234 m.\n\n```sh\nspringlab run x --time 7.5\n```\nthe 7.5 s run\n\n\
         1. The 12th thing, issue 26.\n",
    )
    .expect("write");
    let found: Vec<String> = numbers_in(&std::fs::read_to_string(&page).expect("page"))
        .into_iter()
        .map(|(_, n)| n)
        .collect();
    std::fs::remove_dir_all(&dir).expect("clean up");
    assert_eq!(found, ["1.234"], "only the unexplained result");
}

/// [`numbers`] of a text.
fn numbers_in(text: &str) -> Vec<(usize, String)> {
    let blocks = blocks(text);
    let mut out = Vec::new();
    for (b, (is_code, lines)) in blocks.iter().enumerate() {
        if *is_code {
            continue;
        }
        // Numbers shown in code beside the text: this block's inline code and the code blocks
        // next to it.
        let mut shown = BTreeSet::new();
        for (k, (code, lines)) in blocks
            .iter()
            .enumerate()
            .take(b + 2)
            .skip(b.saturating_sub(1))
        {
            if k != b && !code {
                continue;
            }
            for (_, l) in lines {
                let source = if *code { l.clone() } else { split_code(l).1 };
                shown.extend(tokens(&source).into_iter().map(|t| t.text));
            }
        }
        for (n, line) in lines {
            let (mut prose, _) = split_code(line);
            // An ordered list's number.
            let trimmed = prose.trim_start();
            if let Some(dot) = trimmed.find(". ")
                && dot > 0
                && trimmed[..dot].chars().all(|d| d.is_ascii_digit())
            {
                prose = trimmed[dot + 2..].to_string();
            }
            for t in tokens(&prose) {
                let issue = prose
                    .split(&t.text)
                    .next()
                    .is_some_and(|before| before.trim_end().to_lowercase().ends_with("issue"));
                if shown.contains(&t.text) || structural(&t) || issue {
                    continue;
                }
                out.push((*n, t.text));
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// The numbers this file recomputes (entries `here …`).

/// |x(1 s) − x_exact(1 s)| on the undamped oscillator x(t) = 1 + 0.1 cos(10 t).
fn oscillator_error(method: Method, dt: f64) -> f64 {
    let mut sim = oscillator(method, &["verlet_damping=0", "iterations=0"]);
    sim.set_dt(dt);
    sim.run((1.0 / dt).round() as u64, |_| {});
    (oscillator_x(&sim) - (1.0 + 0.1 * 10f64.cos())).abs()
}

/// docs/testing.md: the table of fitted orders (dt = 0.005 … 0.000625 on the oscillator) and
/// RK4's end point at dt = 0.01 after 10 s against the exact solution.
#[test]
fn testing_md_quotes_the_measured_orders_and_rk4s_end() {
    let page = read("docs/testing.md");
    let rows = [
        ("explicit Euler", Method::ExplicitEuler),
        ("semi-implicit Euler", Method::SemiImplicitEuler),
        ("implicit Euler (Newton + CG)", Method::ImplicitEuler),
        (
            "predictor–corrector (the course's \"implicit\")",
            Method::PredictorCorrector,
        ),
        ("midpoint", Method::Midpoint),
        ("position Verlet", Method::Verlet),
        ("RK4", Method::Rk4),
    ];
    assert!(page.contains("dt = 0.005 … 0.000625"));
    for (name, method) in rows {
        let points: Vec<(f64, f64)> = (0..4)
            .map(|i| {
                let dt = 0.005 / f64::from(1 << i);
                (dt, oscillator_error(method, dt))
            })
            .collect();
        let row = format!("| {name} | {:.2} |", fitted_order(&points));
        assert!(page.contains(&row), "docs/testing.md should have `{row}`");
    }
    let mut sim = oscillator(Method::Rk4, &[]);
    assert_eq!(sim.dt(), 0.01);
    sim.run(1000, |_| {});
    let x = oscillator_x(&sim);
    let exact = 1.0 + 0.1 * 100f64.cos();
    for quote in [
        format!("ends at x = {x:.10}"),
        format!("exact solution is\n{exact:.10}"),
        format!("is {:.1e} m after 1000 steps", (x - exact).abs()),
    ] {
        assert!(
            page.contains(&quote),
            "docs/testing.md should say `{quote}`"
        );
    }
}

/// docs/course.md: the course values springlab's scenes take are their defaults.
#[test]
fn course_md_values_are_the_scenes_defaults() {
    use springlab::lesson::numbers;
    let page = read("docs/course.md");
    let scenes =
        |name: &str| String::from_utf8_lossy(&springlab(&["scenes", name]).stdout).to_string();
    let jelly = scenes("jelly-bowl");
    let cube = scenes("cube-plane");
    for (text, quoted) in [
        (&jelly, "stiffness            = 2000 N/m"),
        (&jelly, "damping              = 60 N·s/m"),
        (&jelly, "dt = 0.001 s"),
        (&jelly, "gravity              = 9.8 m/s²"),
        (&jelly, "offset               = [-4.8, 7, 0] m"),
        (&jelly, "restitution          = 0.8"),
        (&jelly, "friction             = 0.2"),
        (&jelly, "n                    = 10"),
        (&jelly, "edge                 = 4 m"),
        (&cube, "friction             = 0.3"),
    ] {
        assert!(
            text.contains(quoted),
            "`springlab scenes` should show `{quoted}`:\n{text}"
        );
    }
    for quoted in [
        "one spring coefficient 2000 and one damper coefficient 60",
        "dt = 0.001;",
        "(0, −9.8, 0)",
        "offset by (−4.8, 7, 0)",
        "restitution (\"coefResist\") 0.8; friction 0.3 (2021), 0.2 (2023)",
        "10 × 10 × 10 particles (1000) of mass 1, edge length 4",
    ] {
        assert!(page.contains(quoted), "docs/course.md: `{quoted}`");
    }
    // The lattice: particles and springs by kind, shear split into face and body diagonals.
    let fill = |t: &str| numbers::fill(t, "cube-plane", &[], None);
    assert_eq!(fill("{{particles}}"), "1000");
    let (st, sh, be) = (
        fill("{{springs:struct}}"),
        fill("{{springs:shear}}"),
        fill("{{springs:bend}}"),
    );
    let all = fill("{{springs}}");
    let cube = springlab::scene::load("cube-plane", &[]).expect("cube");
    let h = 4.0 / 9.0;
    let springs = cube.bodies[0].model.springs();
    let face = springs
        .iter()
        .filter(|s| (s.rest_length - h * 2f64.sqrt()).abs() < 1e-9)
        .count();
    let body = springs
        .iter()
        .filter(|s| (s.rest_length - h * 3f64.sqrt()).abs() < 1e-9)
        .count();
    let quoted = format!(
        "{st} struct, {be} bend, {sh} shear ({face} face diagonals, {body} body diagonals), {all} in all"
    );
    assert!(page.contains(&quoted), "docs/course.md: `{quoted}`");
    // 26 neighbours in the 3 × 3 × 3 block: 6 axis ones, 20 shear.
    assert_eq!(3 * 3 * 3 - 1 - 6, 20);
    // The 2023 bowl: hole radius 9/√2, centre that high, depth 9 − 9/√2.
    let (radius, centre) = crate::common::jelly_bowl();
    let hole = (radius * radius - centre * centre).sqrt();
    assert!(
        (hole - centre).abs() < 1e-12,
        "the rim is the hole's edge at 45°"
    );
    for quoted in [
        format!("radius 9/√2 ≈ {hole:.3}"),
        format!("({radius:.0} − {centre:.3} ≈ {:.2} m deep", radius - centre),
    ] {
        assert!(page.contains(&quoted), "docs/course.md: `{quoted}`");
    }
}

/// docs/studies.md: Verlet's orders with and without a damper (`study convergence oscillator`).
#[test]
fn studies_md_quotes_verlets_orders() {
    let r = json(&[
        "study",
        "convergence",
        "oscillator",
        "--methods",
        "verlet",
        "--json",
    ]);
    let plain = r["methods"][0]["order"].as_f64().expect("order");
    let companion = &r["verlet_companion"];
    assert_eq!(companion["sets"][0], "damping=2");
    let damped = companion["verlet"]["order"].as_f64().expect("order");
    let quote = format!("Verlet {plain:.3} undamped, {damped:.3} with a damper of 2 N·s/m");
    assert!(
        read("docs/studies.md").contains(&quote),
        "docs/studies.md: `{quote}`"
    );
}

/// docs/studies.md: the undamped rope pumps semi-implicit Euler's stiff mode at dt·ω = 1.9 (below
/// its linear limit 2): the energy grows from E₀ to that order within 100 s.
#[test]
fn the_rope_pumps_semi_implicit_eulers_stiff_mode() {
    let mut scene = springlab::scene::load("rope", &[]).expect("rope");
    scene.set_method(Method::SemiImplicitEuler);
    let b = &scene.bodies[0];
    let omega = springlab::study::omega_max(&b.model, &b.state).omega;
    let mut sim = springlab::simulation::Simulation::new(scene);
    sim.set_dt(1.9 / omega);
    let e0 = sim.energy().total;
    let mut highest = e0;
    let steps = (100.0 / sim.dt()).ceil() as u64;
    sim.run(steps, |s| highest = highest.max(s.energy().total));
    assert!(sim.diverged.is_none());
    let (mantissa, exponent) = {
        let e = highest.log10().floor();
        ((highest / 10f64.powf(e)).round(), e)
    };
    let quote = format!(
        "at dt·ω = 1.9 its energy grows from\n{e0:.0} J to {mantissa}·10{} J within 100 s",
        superscript(exponent as i32)
    );
    assert!(
        read("docs/studies.md").contains(&quote),
        "docs/studies.md: `{quote}`"
    );
}

fn superscript(n: i32) -> String {
    n.to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            d => SUPERSCRIPT
                .chars()
                .nth(d.to_digit(10).expect("digit") as usize)
                .expect("superscript"),
        })
        .collect()
}

/// A method as the pages name it.
fn label(method: &str) -> &str {
    match method {
        "explicit-euler" => "explicit Euler",
        "semi-implicit-euler" => "semi-implicit Euler",
        "implicit-euler" => "implicit Euler",
        "rk4" => "RK4",
        "predictor-corrector" => "the predictor–corrector",
        "velocity-verlet" => "velocity Verlet",
        "verlet" => "Verlet",
        other => other,
    }
}

/// docs/testing.md: on `cloth-spheres` at dt = 5 ms, 50 times the course's 1e-4 s, explicit
/// Euler diverges within a few steps, and XPBD holds the spheres in the cloth with no particle
/// inside a sphere (implicit Euler: tests/integrators.rs
/// implicit_euler_keeps_the_spheres_contacts_inside_the_solve).
#[test]
fn cloth_at_fifty_times_the_course_dt() {
    let run = |method: Method, steps: u64| {
        let mut scene = springlab::scene::load("cloth-spheres", &[]).expect("cloth");
        assert_eq!(scene.dt * 50.0, 0.005);
        scene.set_method(method);
        let mut sim = springlab::simulation::Simulation::new(scene);
        sim.set_dt(0.005);
        let mut deepest = f64::INFINITY;
        sim.run(steps, |s| {
            for state in s.states() {
                for sphere in &state.spheres {
                    for x in &state.x {
                        deepest = deepest.min((*x - sphere.center).length() - sphere.radius);
                    }
                }
            }
        });
        (sim, deepest)
    };
    let (explicit, _) = run(Method::ExplicitEuler, 20);
    assert!(
        explicit.diverged.is_some(),
        "explicit Euler diverges within 20 steps"
    );
    let (xpbd, deepest) = run(Method::Xpbd, 200);
    assert!(xpbd.diverged.is_none());
    assert!(deepest > -1e-6, "a particle {deepest} m inside a sphere");
}
