//! Property tests of the lesson parser (issue 28): a byte order mark and CRLF line ends change
//! nothing, and an unknown placeholder (name or scene parameter) is refused at its line, whatever
//! surrounds it.

use proptest::prelude::*;
use springlab::lesson;

/// Placeholders the loader accepts on the `rope` scene.
const KNOWN: &[&str] = &[
    "{{particles}}",
    "{{springs}}",
    "{{param:stiffness}}",
    "{{param:nodes}}",
    "{{omega_max}}",
];

/// Placeholder names the loader knows (an unknown one must not be one of them).
const KINDS: &[&str] = &[
    "param",
    "particles",
    "springs",
    "omega_max",
    "limit_dt",
    "limit_dt_omega",
    "lambda",
    "order",
    "error_ratio",
    "stable_dt_omega",
    "crossover",
    "wp_error",
];

/// A rope parameter name or not.
const ROPE_PARAMS: &[&str] = &[
    "nodes",
    "mass",
    "stiffness",
    "damping",
    "drag",
    "gravity",
    "start",
    "end",
    "pinned",
    "verlet_damping",
    "verlet_damping_rate",
    "iterations",
    "substeps",
    "cg_tolerance",
];

#[derive(Clone, Debug)]
enum Placeholder {
    Known(usize),
    UnknownName(String),
    UnknownParam(String),
}

fn placeholder() -> impl Strategy<Value = Placeholder> {
    prop_oneof![
        (0..KNOWN.len()).prop_map(Placeholder::Known),
        "[a-z_]{1,12}"
            .prop_filter("not a known name", |n| !KINDS.contains(&n.as_str()))
            .prop_map(Placeholder::UnknownName),
        "[a-z_]{1,12}"
            .prop_filter("not a rope parameter", |n| !ROPE_PARAMS
                .contains(&n.as_str()))
            .prop_map(Placeholder::UnknownParam),
    ]
}

impl Placeholder {
    fn text(&self) -> String {
        match self {
            Placeholder::Known(i) => KNOWN[*i].to_string(),
            Placeholder::UnknownName(n) => format!("{{{{{n}}}}}"),
            Placeholder::UnknownParam(n) => format!("{{{{param:{n}}}}}"),
        }
    }

    fn known(&self) -> bool {
        matches!(self, Placeholder::Known(_))
    }
}

/// A lesson with one step on `rope`, whose body is `before` lines, a line holding the
/// placeholder, and `after` lines.
fn lesson_text(title: &str, before: &[String], p: &Placeholder, after: &[String]) -> String {
    let mut text = format!(
        "+++\nnumber = 1\nslug = \"prop\"\ntitle = \"{title}\"\nsummary = \"s\"\n+++\n\n\
         +++ step\ntitle = \"{title}\"\nscene = \"rope\"\nparams = {{ nodes = 4 }}\n+++\n"
    );
    for line in before {
        text.push_str(line);
        text.push('\n');
    }
    text.push_str(&format!("The value {} here.\n", p.text()));
    for line in after {
        text.push_str(line);
        text.push('\n');
    }
    text
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn bom_and_crlf_change_nothing_and_unknown_placeholders_are_refused(
        title in "[A-Za-z][A-Za-z ]{0,20}",
        before in prop::collection::vec("[a-z][a-z .,]{0,30}", 0..4),
        after in prop::collection::vec("[a-z .,]{0,30}", 0..4),
        p in placeholder(),
        bom in any::<bool>(),
        crlf in any::<bool>(),
    ) {
        let plain = lesson_text(&title, &before, &p, &after);
        let mut variant = if crlf { plain.replace('\n', "\r\n") } else { plain.clone() };
        if bom {
            variant.insert(0, '\u{feff}');
        }
        let a = lesson::parse(&plain, "prop.md", None);
        let b = lesson::parse(&variant, "prop.md", None);
        prop_assert_eq!(&a, &b);
        if p.known() {
            prop_assert!(a.is_ok(), "{:?}", a);
        } else {
            let e = a.expect_err("refused");
            // The placeholder's line: 12 lines of front matter, then the lines before it.
            prop_assert_eq!(e.line, 13 + before.len(), "{}", e);
            prop_assert!(
                e.message.contains("unknown placeholder") || e.message.contains("has no parameter"),
                "{}", e
            );
            prop_assert!(e.to_string().len() < 300, "{}", e);
        }
    }
}
