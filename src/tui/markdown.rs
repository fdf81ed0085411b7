//! The small part of Markdown lessons use, rendered as terminal lines.
//!
//! - `#` headings: bold (level 1 also underlined);
//! - paragraphs: consecutive lines joined and word-wrapped to the width;
//! - `- ` / `* ` / `1. ` list items: wrapped with a hanging indent;
//! - code: lines indented by four spaces (after a blank line) and ```` ``` ```` fences, kept
//!   verbatim (formulas line up as written), indented by two;
//! - inline `**bold**` and `` `code` ``; everything else is shown as written.

use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};

use super::Theme;

/// A piece of text with one style, before wrapping.
type Piece = (String, Style);

/// Renders `text` into lines of at most `width` columns (code lines are not wrapped).
#[must_use]
pub fn render(text: &str, width: u16, theme: Theme) -> Vec<Line<'static>> {
    let width = usize::from(width.max(8));
    let mut out: Vec<Line<'static>> = Vec::new();
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
            out.extend(code_line(line, width, code_style));
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
            out.extend(code_line(code, width, code_style));
            previous_blank = false;
            in_code = true;
            continue;
        }
        in_code = false;
        let trimmed = line.trim_start();
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
    out
}

/// A code line indented by two, verbatim when it fits. A longer one is broken where the author
/// left a gap of two or more spaces (between the parts of a formula), else at single spaces, else
/// anywhere; continuation lines are indented by four more.
fn code_line(line: &str, width: usize, style: Style) -> Vec<Line<'static>> {
    let indent = "  ";
    let fits = |t: &str| Span::raw(t).width() + indent.len() <= width;
    if fits(line) {
        return vec![Line::from(Span::styled(format!("{indent}{line}"), style))];
    }
    // Parts separated by runs of 2+ spaces (the runs are dropped at a break).
    let mut parts: Vec<String> = Vec::new();
    let mut rest = line.trim_end();
    while let Some(i) = rest.find("  ") {
        let (part, tail) = rest.split_at(i);
        if !part.trim().is_empty() {
            parts.push(part.to_string());
        }
        rest = tail.trim_start();
    }
    if !rest.is_empty() {
        parts.push(rest.to_string());
    }
    let leading = line.len() - line.trim_start().len();
    if let Some(first) = parts.first_mut()
        && leading > 0
        && !first.starts_with(' ')
    {
        first.insert_str(0, &line[..leading]);
    }
    let continuation = "      ";
    let mut lines: Vec<String> = Vec::new();
    let mut current = String::new();
    let limit = |first: bool| width.saturating_sub(if first { 2 } else { 6 }).max(4);
    for part in parts {
        let candidate = if current.is_empty() {
            part.clone()
        } else {
            format!("{current}  {part}")
        };
        if Span::raw(candidate.as_str()).width() <= limit(lines.is_empty()) {
            current = candidate;
            continue;
        }
        if !current.is_empty() {
            lines.push(std::mem::take(&mut current));
        }
        // The part alone: break at single spaces, or anywhere.
        for word in part.split(' ') {
            let candidate = if current.is_empty() {
                word.to_string()
            } else {
                format!("{current} {word}")
            };
            if Span::raw(candidate.as_str()).width() <= limit(lines.is_empty()) {
                current = candidate;
            } else {
                if !current.is_empty() {
                    lines.push(std::mem::take(&mut current));
                }
                let mut chunk = String::new();
                for c in word.chars() {
                    if chunk.chars().count() >= limit(lines.is_empty()) {
                        lines.push(std::mem::take(&mut chunk));
                    }
                    chunk.push(c);
                }
                current = chunk;
            }
        }
    }
    if !current.is_empty() {
        lines.push(current);
    }
    lines
        .into_iter()
        .enumerate()
        .map(|(i, l)| {
            let prefix = if i == 0 { indent } else { continuation };
            Line::from(Span::styled(format!("{prefix}{l}"), style))
        })
        .collect()
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
