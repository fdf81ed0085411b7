//! Light and dark terminals: the background colour asked of the terminal at start-up (OSC 11,
//! a short time limit), a palette per background, and the contrast of every colour against it.
//!
//! The colours of the lesson screen are the 16 named ANSI colours. On a dark background they
//! are drawn as they are (the terminal's own palette; xterm's defaults are the reference the
//! contrast test uses), except blue, which is too dark on black and becomes light blue. On a
//! light background each is replaced by a darker RGB colour of the same hue, white by black, so
//! that every series and label keeps a WCAG contrast ratio of at least 3:1 against white
//! (tested for both palettes):
//!
//! ```text
//! contrast = (L1 + 0.05) / (L2 + 0.05),   L = 0.2126 R + 0.7152 G + 0.0722 B
//! ```
//! where L1 ≥ L2 are the relative luminances of the two colours and R, G, B the linearised
//! sRGB channels (0–1): `c/12.92` below 0.04045, else `((c + 0.055)/1.055)^2.4`
//! (WCAG 2.1, "contrast ratio" and "relative luminance").
//!
//! The query: `ESC ] 11 ; ? ESC \` followed by a device-attributes request (`ESC [ c`, which
//! every terminal answers), read in raw mode until that answer or [`QUERY_TIMEOUT`]; the reply
//! `ESC ] 11 ; rgb:RRRR/GGGG/BBBB` gives the background, light when its luminance is above
//! one half. `SPRINGLAB_THEME=light|dark` overrides it (and a terminal that does not answer is
//! taken as dark).

use std::time::Duration;

use ratatui::style::Color;

/// The terminal's background.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Background {
    /// Black or dark (the default when the terminal does not say).
    Dark,
    /// White or light.
    Light,
}

impl Background {
    /// Parses `light` or `dark`.
    ///
    /// # Errors
    /// Any other word.
    pub fn parse(s: &str) -> Result<Background, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "light" => Ok(Background::Light),
            "dark" => Ok(Background::Dark),
            other => Err(format!("unknown theme `{other}`: expected light or dark")),
        }
    }

    /// The background colour the palette is made for (sRGB).
    #[must_use]
    pub fn rgb(self) -> (u8, u8, u8) {
        match self {
            Background::Dark => (0, 0, 0),
            Background::Light => (255, 255, 255),
        }
    }
}

/// How long the terminal has to answer the background query.
pub const QUERY_TIMEOUT: Duration = Duration::from_millis(300);

/// xterm's default 16-colour palette: the colours as a dark terminal draws them.
const XTERM: [(Color, (u8, u8, u8)); 16] = [
    (Color::Black, (0, 0, 0)),
    (Color::Red, (205, 0, 0)),
    (Color::Green, (0, 205, 0)),
    (Color::Yellow, (205, 205, 0)),
    (Color::Blue, (0, 0, 238)),
    (Color::Magenta, (205, 0, 205)),
    (Color::Cyan, (0, 205, 205)),
    (Color::Gray, (229, 229, 229)),
    (Color::DarkGray, (127, 127, 127)),
    (Color::LightRed, (255, 0, 0)),
    (Color::LightGreen, (0, 255, 0)),
    (Color::LightYellow, (255, 255, 0)),
    (Color::LightBlue, (92, 92, 255)),
    (Color::LightMagenta, (255, 0, 255)),
    (Color::LightCyan, (0, 255, 255)),
    (Color::White, (255, 255, 255)),
];

/// The light palette: each named colour darkened, keeping its hue.
const LIGHT: [(Color, (u8, u8, u8)); 16] = [
    (Color::Black, (0, 0, 0)),
    (Color::Red, (190, 0, 0)),
    (Color::Green, (0, 130, 0)),
    (Color::Yellow, (140, 110, 0)),
    (Color::Blue, (0, 0, 200)),
    (Color::Magenta, (170, 0, 170)),
    (Color::Cyan, (0, 120, 140)),
    (Color::Gray, (90, 90, 90)),
    (Color::DarkGray, (110, 110, 110)),
    (Color::LightRed, (220, 40, 40)),
    (Color::LightGreen, (0, 150, 60)),
    (Color::LightYellow, (170, 120, 0)),
    (Color::LightBlue, (40, 80, 230)),
    (Color::LightMagenta, (200, 0, 200)),
    (Color::LightCyan, (0, 140, 160)),
    (Color::White, (0, 0, 0)),
];

/// The named colours (the 16 of the palette), in ANSI order.
#[must_use]
pub fn named() -> [Color; 16] {
    XTERM.map(|(c, _)| c)
}

/// `c` as drawn on `background`: a named colour replaced as the module docs say; any other
/// colour unchanged.
#[must_use]
pub fn for_background(c: Color, background: Background) -> Color {
    match background {
        Background::Dark if c == Color::Blue => Color::LightBlue,
        Background::Dark => c,
        Background::Light => LIGHT
            .iter()
            .find(|(n, _)| *n == c)
            .map_or(c, |&(_, (r, g, b))| Color::Rgb(r, g, b)),
    }
}

/// The sRGB value of `c` as drawn (after [`for_background`]): RGB colours as they are, named
/// ones by xterm's default palette; `None` for the terminal's default colour and indexed ones.
#[must_use]
pub fn rgb(c: Color) -> Option<(u8, u8, u8)> {
    match c {
        Color::Rgb(r, g, b) => Some((r, g, b)),
        named => XTERM.iter().find(|(n, _)| *n == named).map(|&(_, v)| v),
    }
}

/// Relative luminance of an sRGB colour (module docs).
#[must_use]
pub fn luminance((r, g, b): (u8, u8, u8)) -> f64 {
    let lin = |c: u8| {
        let c = f64::from(c) / 255.0;
        if c <= 0.040_45 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    0.2126 * lin(r) + 0.7152 * lin(g) + 0.0722 * lin(b)
}

/// WCAG contrast ratio of two sRGB colours (1 to 21).
#[must_use]
pub fn contrast(a: (u8, u8, u8), b: (u8, u8, u8)) -> f64 {
    let (la, lb) = (luminance(a), luminance(b));
    (la.max(lb) + 0.05) / (la.min(lb) + 0.05)
}

/// The background an OSC 11 reply names (`ESC ] 11 ; rgb:RRRR/GGGG/BBBB`, 1 to 4 hex digits a
/// channel, ended by BEL or ST), if `bytes` hold one.
#[must_use]
pub fn parse_reply(bytes: &[u8]) -> Option<Background> {
    let text = String::from_utf8_lossy(bytes);
    let start = text.find("]11;rgb:")? + "]11;rgb:".len();
    let rest = &text[start..];
    let end = rest
        .find(|c: char| !(c.is_ascii_hexdigit() || c == '/'))
        .unwrap_or(rest.len());
    let channels: Vec<u8> = rest[..end]
        .split('/')
        .map(|h| {
            let digits = h.len();
            let v = u32::from_str_radix(h, 16).ok()?;
            let max = (1u32 << (4 * digits.clamp(1, 4))) - 1;
            (1..=4).contains(&digits).then(|| (v * 255 / max) as u8)
        })
        .collect::<Option<Vec<u8>>>()?;
    let [r, g, b] = channels[..] else { return None };
    Some(if luminance((r, g, b)) > 0.5 {
        Background::Light
    } else {
        Background::Dark
    })
}

/// The background: `SPRINGLAB_THEME` when set, else the terminal's answer to the query (raw
/// mode must be on), else dark.
#[must_use]
pub fn detect() -> Background {
    if let Ok(t) = std::env::var("SPRINGLAB_THEME")
        && let Ok(b) = Background::parse(&t)
    {
        return b;
    }
    if std::env::var("TERM").is_ok_and(|t| t == "dumb") {
        return Background::Dark;
    }
    ask().unwrap_or(Background::Dark)
}

fn ask() -> Option<Background> {
    // The device attributes' answer (`ESC [ ? … c`) comes after the background's.
    let bytes = super::query::ask(b"\x1b]11;?\x1b\\\x1b[c", QUERY_TIMEOUT, |bytes| {
        bytes
            .windows(3)
            .position(|w| w == b"\x1b[?")
            .is_some_and(|p| bytes[p..].contains(&b'c'))
    })
    .ok()?;
    parse_reply(&bytes)
}
