//! The small part of Markdown lessons use, rendered as terminal lines.
//!
//! - `#` headings: bold (level 1 also underlined);
//! - paragraphs: consecutive lines joined and word-wrapped to the width;
//! - `- ` / `* ` / `1. ` list items: wrapped with a hanging indent;
//! - code: lines indented by four spaces (after a blank line) and ```` ``` ```` fences, kept
//!   verbatim (formulas line up as written), indented by two, never wrapped: the lesson screen
//!   clips a long one with a marker and scrolls code sideways ([`clip`]);
//! - tables: lines starting with `|`, kept verbatim like code;
//! - inline `**bold**` and `` `code` ``; everything else is shown as written.

use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};

use super::Theme;

/// A piece of text with one style, before wrapping.
type Piece = (String, Style);

/// Renders `text` into lines of at most `width` columns; code and table lines are kept whole
/// (see [`render_marked`]).
#[must_use]
pub fn render(text: &str, width: u16, theme: Theme) -> Vec<Line<'static>> {
    render_marked(text, width, theme)
        .into_iter()
        .map(|(l, _)| l)
        .collect()
}

/// A line and whether it is code or a table row (kept whole, to be clipped and scrolled).
pub type Marked = (Line<'static>, bool);

/// As [`render`], each line marked true when it is code or a table row.
#[must_use]
pub fn render_marked(text: &str, width: u16, theme: Theme) -> Vec<Marked> {
    let width = usize::from(width.max(8));
    let mut out: Vec<Line<'static>> = Vec::new();
    // Indices of `out` that are code or table lines.
    let mut code_at: Vec<usize> = Vec::new();
    let mut paragraph: Vec<String> = Vec::new();
    // The open list item: its marker and its text lines.
    let mut item: Option<(String, Vec<String>)> = None;
    let mut fenced = false;
    let mut previous_blank = true;
    let mut in_code = false;
    let code_style = theme.fg(Color::LightCyan);

    let flush = |out: &mut Vec<Line<'static>>,
                 paragraph: &mut Vec<String>,
                 item: &mut Option<(String, Vec<String>)>| {
        if !paragraph.is_empty() {
            let joined = paragraph.join(" ");
            out.extend(wrap(&inline(&joined, Style::new(), theme), width, "", ""));
            paragraph.clear();
        }
        if let Some((marker, lines)) = item.take() {
            let joined = lines.join(" ");
            let indent = " ".repeat(marker.chars().count());
            out.extend(wrap(
                &inline(&joined, Style::new(), theme),
                width,
                &marker,
                &indent,
            ));
        }
    };

    for raw in text.lines() {
        let line = raw.trim_end();
        if line.trim_start().starts_with("```") {
            flush(&mut out, &mut paragraph, &mut item);
            fenced = !fenced;
            previous_blank = false;
            continue;
        }
        if fenced {
            code_at.push(out.len());
            out.push(code_line(line, code_style));
            continue;
        }
        if line.trim().is_empty() {
            flush(&mut out, &mut paragraph, &mut item);
            in_code = false;
            if !previous_blank && !out.is_empty() {
                out.push(Line::from(""));
            }
            previous_blank = true;
            continue;
        }
        let indented = line.starts_with("    ") || line.starts_with('\t');
        if indented && paragraph.is_empty() && item.is_none() && (previous_blank || in_code) {
            let code = line
                .strip_prefix("    ")
                .unwrap_or_else(|| line.trim_start_matches('\t'));
            code_at.push(out.len());
            out.push(code_line(code, code_style));
            previous_blank = false;
            in_code = true;
            continue;
        }
        in_code = false;
        let trimmed = line.trim_start();
        if trimmed.starts_with('|') && paragraph.is_empty() && item.is_none() {
            code_at.push(out.len());
            out.push(code_line(trimmed, Style::new()));
            previous_blank = false;
            continue;
        }
        if let Some(heading) = heading(trimmed) {
            flush(&mut out, &mut paragraph, &mut item);
            let (level, title) = heading;
            let mut style = Style::new()
                .add_modifier(Modifier::BOLD)
                .patch(theme.fg(Color::LightYellow));
            if level == 1 {
                style = style.add_modifier(Modifier::UNDERLINED);
            }
            out.extend(wrap(&inline(title, style, theme), width, "", ""));
            previous_blank = false;
            continue;
        }
        if let Some((marker, rest)) = list_marker(trimmed) {
            flush(&mut out, &mut paragraph, &mut item);
            item = Some((marker, vec![rest.to_string()]));
        } else if let Some((_, lines)) = &mut item {
            lines.push(trimmed.to_string());
        } else {
            paragraph.push(trimmed.to_string());
        }
        previous_blank = false;
    }
    flush(&mut out, &mut paragraph, &mut item);
    while out.last().is_some_and(|l| l.width() == 0) {
        out.pop();
    }
    out.into_iter()
        .enumerate()
        .map(|(i, l)| (l, code_at.contains(&i)))
        .collect()
}

/// The columns `offset ..` of `line` in at most `width` columns: a line that goes on to the
/// right ends in `›`, one scrolled past its start begins with `‹` (both in `marker` style).
#[must_use]
pub fn clip(line: &Line<'static>, offset: usize, width: usize, marker: Style) -> Line<'static> {
    // Cells: (symbol, style), one per column (wide characters take their width; a combining
    // mark, of no width, joins the cell before it: `d̂` is one cell).
    let mut cells: Vec<(String, Style, usize)> = Vec::new();
    for span in &line.spans {
        for c in span.content.chars() {
            let w = Span::raw(c.to_string()).width();
            match cells.last_mut() {
                Some(last) if w == 0 => last.0.push(c),
                _ => cells.push((c.to_string(), line.style.patch(span.style), w)),
            }
        }
    }
    let total: usize = cells.iter().map(|c| c.2).sum();
    if total <= width && offset == 0 {
        return line.clone();
    }
    let offset = offset.min(total.saturating_sub(1));
    let mut spans: Vec<Span<'static>> = Vec::new();
    let mut col = 0;
    let mut used = 0;
    let left = offset > 0;
    let right = total > offset + width;
    let room = width.saturating_sub(usize::from(left) + usize::from(right));
    if left {
        spans.push(Span::styled("‹", marker));
    }
    for (sym, style, w) in cells {
        if col >= offset && used + w <= room {
            spans.push(Span::styled(sym, style));
            used += w;
        }
        col += w;
    }
    if right {
        spans.push(Span::raw(" ".repeat(room - used)));
        spans.push(Span::styled("›", marker));
    }
    Line::from(spans)
}

/// A code line indented by two, verbatim (never wrapped: see [`clip`]).
fn code_line(line: &str, style: Style) -> Line<'static> {
    Line::from(Span::styled(format!("  {line}"), style))
}

/// One "try" item as a bulleted, wrapped block.
#[must_use]
pub fn bullet(text: &str, width: u16, theme: Theme) -> Vec<Line<'static>> {
    wrap(
        &inline(text, Style::new(), theme),
        usize::from(width.max(8)),
        "• ",
        "  ",
    )
}

/// Plain text (with inline Markdown) wrapped to `width`, the first line after `first` and the
/// others after `rest` (a hanging indent).
#[must_use]
pub fn wrap_hanging(
    text: &str,
    width: u16,
    first: &str,
    rest: &str,
    theme: Theme,
) -> Vec<Line<'static>> {
    wrap(
        &inline(text, Style::new(), theme),
        usize::from(width.max(8)),
        first,
        rest,
    )
}

/// Plain text (with inline Markdown) wrapped to `width`.
#[must_use]
pub fn wrap_text(text: &str, width: u16, theme: Theme) -> Vec<Line<'static>> {
    wrap(
        &inline(text, Style::new(), theme),
        usize::from(width.max(8)),
        "",
        "",
    )
}

/// `(level, title)` of an ATX heading (`# Title`).
fn heading(line: &str) -> Option<(usize, &str)> {
    let level = line.chars().take_while(|&c| c == '#').count();
    if (1..=6).contains(&level) && line[level..].starts_with(' ') {
        Some((level, line[level..].trim()))
    } else {
        None
    }
}

/// `("• ", rest)` for `- item` / `* item`, `("1. ", rest)` for a numbered item.
fn list_marker(line: &str) -> Option<(String, &str)> {
    if let Some(rest) = line.strip_prefix("- ").or_else(|| line.strip_prefix("* ")) {
        return Some(("• ".to_string(), rest));
    }
    let digits = line.chars().take_while(char::is_ascii_digit).count();
    if digits > 0 && line[digits..].starts_with(". ") {
        return Some((format!("{} ", &line[..digits + 1]), &line[digits + 2..]));
    }
    None
}

/// Splits `text` into styled pieces: `**bold**` and `` `code` `` (markers removed).
fn inline(text: &str, base: Style, theme: Theme) -> Vec<Piece> {
    let mut pieces: Vec<Piece> = Vec::new();
    let mut bold = false;
    let mut code = false;
    let mut current = String::new();
    let style = |bold: bool, code: bool| {
        let mut s = base;
        if bold {
            s = s.add_modifier(Modifier::BOLD);
        }
        if code {
            s = s.patch(theme.fg(Color::LightCyan));
        }
        s
    };
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '`' {
            pieces.push((std::mem::take(&mut current), style(bold, code)));
            code = !code;
        } else if c == '*' && !code && chars.peek() == Some(&'*') {
            chars.next();
            pieces.push((std::mem::take(&mut current), style(bold, code)));
            bold = !bold;
        } else {
            current.push(c);
        }
    }
    pieces.push((current, style(bold, code)));
    pieces.retain(|(t, _)| !t.is_empty());
    pieces
}

/// Greedy word wrap of styled pieces to `width` columns; the first line starts with `first`,
/// the others with `rest` (a hanging indent). Words longer than a line are split.
fn wrap(pieces: &[Piece], width: usize, first: &str, rest: &str) -> Vec<Line<'static>> {
    // Words: runs of non-spaces, possibly spanning pieces of different styles.
    let mut words: Vec<Vec<Piece>> = Vec::new();
    let mut word: Vec<Piece> = Vec::new();
    for (text, style) in pieces {
        let mut part = String::new();
        for c in text.chars() {
            if c == ' ' {
                if !part.is_empty() {
                    word.push((std::mem::take(&mut part), *style));
                }
                if !word.is_empty() {
                    words.push(std::mem::take(&mut word));
                }
            } else {
                part.push(c);
            }
        }
        if !part.is_empty() {
            word.push((part, *style));
        }
    }
    if !word.is_empty() {
        words.push(word);
    }
    let len = |w: &[Piece]| {
        w.iter()
            .map(|(t, _)| Span::raw(t.as_str()).width())
            .sum::<usize>()
    };
    // A one-column word (`=`, `×`, a digit, a letter) stays with the word before it: no line
    // starts with `= 0` or `× 2`, and `t = 0` is never cut (unless the two would not fit on
    // a line together).
    let room = width.saturating_sub(Span::raw(first).width().max(Span::raw(rest).width()));
    let mut glued: Vec<Vec<Piece>> = Vec::with_capacity(words.len());
    for w in words {
        match glued.last_mut() {
            Some(last) if len(&w) == 1 && len(last) + 2 <= room => {
                let style = last.last().map_or(Style::new(), |p| p.1);
                last.push((" ".to_owned(), style));
                last.extend(w);
            }
            _ => glued.push(w),
        }
    }
    let words = glued;
    let mut lines: Vec<Line<'static>> = Vec::new();
    let mut spans: Vec<Span<'static>> = vec![Span::raw(first.to_string())];
    let mut used = Span::raw(first).width();
    let mut empty = true;
    let indent_width = Span::raw(rest).width();
    for w in words {
        let wl = len(&w);
        if !empty && used + 1 + wl > width {
            lines.push(Line::from(std::mem::take(&mut spans)));
            spans.push(Span::raw(rest.to_string()));
            used = indent_width;
            empty = true;
        }
        if !empty {
            spans.push(Span::raw(" "));
            used += 1;
        }
        if used + wl <= width {
            for (t, s) in w {
                spans.push(Span::styled(t, s));
            }
            used += wl;
        } else {
            // A word longer than the line: split it across lines.
            for (t, s) in w {
                for c in t.chars() {
                    if used >= width {
                        lines.push(Line::from(std::mem::take(&mut spans)));
                        spans.push(Span::raw(rest.to_string()));
                        used = indent_width;
                    }
                    spans.push(Span::styled(c.to_string(), s));
                    used += 1;
                }
            }
        }
        empty = false;
    }
    if !empty || lines.is_empty() {
        lines.push(Line::from(spans));
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clipped_line_keeps_combining_marks_with_their_letter() {
        let line = Line::from("  J = -(1 + e)(v_rel · d\u{302}) / (1/m_s + 1/m_p)");
        let marker = Style::new();
        let clipped = clip(&line, 0, 30, marker);
        let text: String = clipped.spans.iter().map(|s| s.content.as_ref()).collect();
        assert_eq!(text, "  J = -(1 + e)(v_rel · d\u{302}) / (›");
        assert_eq!(clipped.width(), 30);
        let scrolled = clip(&line, 23, 30, marker);
        let text: String = scrolled.spans.iter().map(|s| s.content.as_ref()).collect();
        assert!(text.starts_with("‹d\u{302}) /"), "{text}");
    }

    fn text(lines: &[Line]) -> Vec<String> {
        lines
            .iter()
            .map(|l| l.spans.iter().map(|s| s.content.as_ref()).collect())
            .collect()
    }

    /// At every width the words come out in order, no line is wider than the width, and no
    /// line but the first starts with a one-column word: `t = 0`, `× 2` and `(x - L0)` stay
    /// together.
    #[test]
    fn one_column_words_stay_with_the_word_before() {
        let sentence = "the step as it opened: its method, dt, k, pins and view, at t = 0, \
                        then dt × 2 / ÷ 2 and m x'' = -k (x - L0) on a spring";
        let words: Vec<&str> = sentence.split(' ').collect();
        for width in 12..60u16 {
            let lines = text(&wrap_hanging(sentence, width, "", "", Theme::PLAIN));
            let again: Vec<String> = lines.join(" ").split(' ').map(str::to_owned).collect();
            assert_eq!(again, words, "width {width}");
            for line in &lines {
                assert!(
                    Span::raw(line.as_str()).width() <= usize::from(width),
                    "{line:?}"
                );
            }
            for line in &lines[1..] {
                let first = line.split(' ').next().unwrap_or_default();
                assert!(
                    Span::raw(first).width() > 1,
                    "width {width}: {line:?} in {lines:#?}"
                );
            }
        }
    }

    /// A hanging indent: the first line after `first`, the others after `rest`.
    #[test]
    fn hanging_indent() {
        let lines = text(&wrap_hanging(
            "choose a method: its letter or number (listed), or Enter; Tab: one body",
            40,
            "  m         ",
            "            ",
            Theme::PLAIN,
        ));
        assert_eq!(
            lines,
            [
                "  m         choose a method: its letter",
                "            or number (listed), or",
                "            Enter; Tab: one body",
            ]
        );
    }
}
