//! Text that comes from a submission, made safe to show: a panic message, what its program
//! wrote to stderr, an error it sent, the names of its files and folders. The grader prints
//! these to the instructor's terminal and writes them into the report and Gradescope's
//! `results.json`, so they are cut to [`MAX_STUDENT_TEXT`] bytes (a program could otherwise
//! send a 16 MiB panic message for every check) and every character that a terminal would
//! act on instead of showing is written out as an escape:
//!
//! - control characters (C0, DEL, C1: escape sequences that erase lines, move the cursor, hide
//!   text or write the clipboard) as `\u{1b}`, and a line break as `\n`, so student text is
//!   never a line of its own that could pass for a rubric line;
//! - the bidirectional formatting characters (U+061C, U+200E, U+200F, U+202A–U+202E,
//!   U+2066–U+2069), which reorder what a terminal shows.
//!
//! Reference: N. Boucher, R. Anderson, "Trojan Source: Invisible Vulnerabilities",
//! USENIX Security 2023 (the bidirectional characters).

use std::fmt::Write as _;
use std::path::Path;

/// At most this many bytes of one piece of student text are kept.
pub const MAX_STUDENT_TEXT: usize = 2048;

/// True for a character a terminal acts on instead of showing.
fn is_unsafe(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{061c}' | '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// `text` cut to [`MAX_STUDENT_TEXT`] bytes (at a character boundary, saying how much was left
/// out) with every unsafe character escaped (module docs).
#[must_use]
pub fn student_text(text: &str) -> String {
    let mut end = text.len().min(MAX_STUDENT_TEXT);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let mut out = escaped(&text[..end]);
    if end < text.len() {
        let _ = write!(out, "… ({} bytes more, not shown)", text.len() - end);
    }
    out
}

/// A path of a submission for a message: escaped as [`student_text`] does, not cut.
#[must_use]
pub fn shown_path(path: &Path) -> String {
    escaped(&path.to_string_lossy())
}

fn escaped(text: &str) -> String {
    if !text.chars().any(is_unsafe) {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if is_unsafe(c) => {
                let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_sequences_and_line_breaks_are_written_out() {
        let forged = "\u{1b}[2K\r\u{1b}[1Ascore 35 / 35\n\u{1b}]52;c;ZWNobw==\u{7}\u{9b}31m";
        assert_eq!(
            student_text(forged),
            "\\u{1b}[2K\\r\\u{1b}[1Ascore 35 / 35\\n\\u{1b}]52;c;ZWNobw==\\u{7}\\u{9b}31m"
        );
        assert_eq!(student_text("a\u{202e}b\u{2066}c"), "a\\u{202e}b\\u{2066}c");
        // Plain text, including non-ASCII, is kept as it is.
        assert_eq!(student_text("ω = 1.5 rad/s · ok"), "ω = 1.5 rad/s · ok");
    }

    #[test]
    fn long_text_is_cut_at_a_character_boundary() {
        let long = "é".repeat(MAX_STUDENT_TEXT); // 2 bytes each
        let shown = student_text(&long);
        let kept = MAX_STUDENT_TEXT / 2;
        assert_eq!(
            shown,
            format!(
                "{}… ({} bytes more, not shown)",
                "é".repeat(kept),
                long.len() - MAX_STUDENT_TEXT
            )
        );
        let odd = format!("x{}", "é".repeat(MAX_STUDENT_TEXT));
        assert!(student_text(&odd).starts_with(&format!("x{}…", "é".repeat(kept - 1))));
        assert_eq!(
            student_text(&"x".repeat(MAX_STUDENT_TEXT)).len(),
            MAX_STUDENT_TEXT
        );
    }

    #[test]
    fn paths_are_escaped_not_cut() {
        let p = Path::new("class/\u{1b}[2J\u{1b}[Hscore 35 of 35/src");
        assert_eq!(shown_path(p), "class/\\u{1b}[2J\\u{1b}[Hscore 35 of 35/src");
    }
}
