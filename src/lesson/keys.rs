//! Key sequences of a lesson: what a "try" item, a goal or a prediction asks the student to press.
//!
//! Written in the front matter as words separated by spaces:
//!
//! ```text
//! keys = "D D D space"          # three presses of D, then space
//! keys = "m v + + space"        # the method chooser, Verlet, dt × 4, run
//! keys = "G*3 space wait:2 A"   # G three times, run, two seconds later press A
//! ```
//! A word is one character (`+`, `D`, `m`), a named key (`space`, `enter`, `esc`, `tab`, `up`,
//! `down`, `left`, `right`, `pgup`, `pgdn`), either followed by `*N` to repeat it N times, or
//! `wait:S`: let S seconds of wall time pass (the run advances by S × speed). The app shows the
//! sequence beside the item's text, so the text and the keys cannot disagree; the tests play
//! every sequence through the app.

use std::fmt;

/// One key of a sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Key {
    /// A printable character.
    Char(char),
    /// The space bar.
    Space,
    /// Enter.
    Enter,
    /// Escape.
    Esc,
    /// Tab.
    Tab,
    /// Arrow up.
    Up,
    /// Arrow down.
    Down,
    /// Arrow left.
    Left,
    /// Arrow right.
    Right,
    /// Page up.
    PageUp,
    /// Page down.
    PageDown,
}

impl Key {
    fn name(self) -> String {
        match self {
            Key::Char(c) => c.to_string(),
            Key::Space => "space".into(),
            Key::Enter => "enter".into(),
            Key::Esc => "esc".into(),
            Key::Tab => "tab".into(),
            Key::Up => "up".into(),
            Key::Down => "down".into(),
            Key::Left => "left".into(),
            Key::Right => "right".into(),
            Key::PageUp => "pgup".into(),
            Key::PageDown => "pgdn".into(),
        }
    }
}

/// A key pressed, or wall time let pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stroke {
    /// Press this key.
    Key(Key),
    /// Let this many seconds of wall time pass.
    Wait(f64),
}

/// A parsed key sequence.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Keys {
    /// The strokes, repeats expanded.
    pub strokes: Vec<Stroke>,
}

impl Keys {
    /// Parses a sequence (module docs).
    ///
    /// # Errors
    /// An unknown key name, a bad repeat count or a bad wait, with the word.
    pub fn parse(text: &str) -> Result<Keys, String> {
        let mut strokes = Vec::new();
        for word in text.split_whitespace() {
            if let Some(secs) = word.strip_prefix("wait:") {
                let s: f64 = secs.parse().map_err(|_| {
                    format!("keys: `{word}`: expected wait:SECONDS, for example wait:2")
                })?;
                if !(s > 0.0 && s <= 600.0) {
                    return Err(format!("keys: `{word}`: a wait is 0 < S ≤ 600 seconds"));
                }
                strokes.push(Stroke::Wait(s));
                continue;
            }
            let (name, count) = match word.rsplit_once('*') {
                Some((n, c)) if !n.is_empty() => {
                    let c: usize = c.parse().map_err(|_| {
                        format!("keys: `{word}`: expected KEY*N with N a count, for example D*3")
                    })?;
                    if !(1..=100).contains(&c) {
                        return Err(format!("keys: `{word}`: a repeat count is 1 to 100"));
                    }
                    (n, c)
                }
                _ => (word, 1),
            };
            let key = match name {
                "space" => Key::Space,
                "enter" => Key::Enter,
                "esc" => Key::Esc,
                "tab" => Key::Tab,
                "up" => Key::Up,
                "down" => Key::Down,
                "left" => Key::Left,
                "right" => Key::Right,
                "pgup" => Key::PageUp,
                "pgdn" => Key::PageDown,
                one if one.chars().count() == 1 => Key::Char(one.chars().next().unwrap_or(' ')),
                other => {
                    return Err(format!(
                        "keys: unknown key `{other}`; expected one character, space, enter, esc, \
                         tab, up, down, left, right, pgup, pgdn, KEY*N or wait:SECONDS"
                    ));
                }
            };
            strokes.extend(std::iter::repeat_n(Stroke::Key(key), count));
        }
        if strokes.is_empty() {
            return Err("keys: expected at least one key".into());
        }
        Ok(Keys { strokes })
    }

    /// True when the sequence does more than restore the step (`R`), start the run and wait:
    /// it asks for an action.
    #[must_use]
    pub fn is_action(&self) -> bool {
        self.strokes
            .iter()
            .any(|s| matches!(s, Stroke::Key(k) if !matches!(k, Key::Space | Key::Char('R'))))
    }

    /// True when the sequence starts with `R`: from the step as it opened, whatever was done
    /// before.
    #[must_use]
    pub fn from_step_start(&self) -> bool {
        matches!(self.strokes.first(), Some(Stroke::Key(Key::Char('R'))))
    }
}

impl fmt::Display for Keys {
    /// Repeats folded: `D×3 space`, waits as `(2 s)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut words: Vec<String> = Vec::new();
        let mut i = 0;
        while i < self.strokes.len() {
            match self.strokes[i] {
                Stroke::Wait(s) => {
                    words.push(format!("(wait {s} s)"));
                    i += 1;
                }
                Stroke::Key(k) => {
                    let mut n = 1;
                    while self.strokes.get(i + n) == Some(&Stroke::Key(k)) {
                        n += 1;
                    }
                    words.push(if n > 1 {
                        format!("{}×{n}", k.name())
                    } else {
                        k.name()
                    });
                    i += n;
                }
            }
        }
        f.write_str(&words.join(" "))
    }
}
