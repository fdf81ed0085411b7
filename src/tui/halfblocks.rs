//! The half-block view: a rasterised frame shown as text cells, two pixels a cell.
//!
//! Each cell is `▀` (U+2580, upper half block) with the foreground colour of the upper pixel and
//! the background colour of the lower one, so a pane of `w × h` cells shows a `w × 2h` image
//! whose pixels are square on a font cell of aspect 1 : 2.
//!
//! **Colours.** Terminals that announce 24-bit colour (`COLORTERM=truecolor` or `24bit`) get the
//! pixels' colours exactly. Others get the nearest entry of the xterm 256-colour palette: the
//! 6 × 6 × 6 colour cube (indices 16–231, levels 0, 95, 135, 175, 215, 255) or the grey ramp
//! (232–255, `8 + 10 k`), whichever is nearer in RGB (squared Euclidean distance). The first 16
//! entries are left out: each terminal chooses its own. With `NO_COLOR` set, the view uses no
//! colour at all: each cell shows the darkness of its two pixels as one of ` ░▒▓█`.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use tiny_skia::Pixmap;

/// How many colours the terminal shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColourDepth {
    /// 24-bit RGB.
    TrueColour,
    /// The xterm 256-colour palette.
    Palette256,
    /// No colours (`NO_COLOR`).
    None,
}

impl ColourDepth {
    /// From the environment: `NO_COLOR` (non-empty) turns colours off; `COLORTERM` of
    /// `truecolor` or `24bit` gives 24-bit colour; anything else the 256-colour palette.
    #[must_use]
    pub fn from_env() -> ColourDepth {
        let no_color = std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty());
        let colorterm = std::env::var("COLORTERM").unwrap_or_default();
        ColourDepth::from_values(no_color, &colorterm)
    }

    /// The depth for a `NO_COLOR` flag and a `COLORTERM` value.
    #[must_use]
    pub fn from_values(no_color: bool, colorterm: &str) -> ColourDepth {
        if no_color {
            ColourDepth::None
        } else if matches!(
            colorterm.trim().to_ascii_lowercase().as_str(),
            "truecolor" | "24bit"
        ) {
            ColourDepth::TrueColour
        } else {
            ColourDepth::Palette256
        }
    }
}

/// The six levels of each channel in the xterm colour cube.
const CUBE: [u8; 6] = [0, 95, 135, 175, 215, 255];

/// The RGB value of xterm palette entry `index` (16–255).
#[must_use]
pub fn palette_rgb(index: u8) -> (u8, u8, u8) {
    if index >= 232 {
        let v = 8 + 10 * (index - 232);
        (v, v, v)
    } else {
        let i = index.saturating_sub(16);
        (
            CUBE[usize::from(i / 36)],
            CUBE[usize::from(i / 6 % 6)],
            CUBE[usize::from(i % 6)],
        )
    }
}

/// The index of the cube level nearest to `v`.
fn nearest_level(v: u8) -> usize {
    let mut best = 0;
    for (i, &l) in CUBE.iter().enumerate() {
        if v.abs_diff(l) < v.abs_diff(CUBE[best]) {
            best = i;
        }
    }
    best
}

/// The xterm palette entry (16–255) nearest to `(r, g, b)` (module docs).
#[must_use]
pub fn nearest_256(r: u8, g: u8, b: u8) -> u8 {
    let dist = |(x, y, z): (u8, u8, u8)| {
        let d = |p: u8, q: u8| (i32::from(p) - i32::from(q)).pow(2);
        d(x, r) + d(y, g) + d(z, b)
    };
    // The nearest cube entry is the nearest level in each channel (the cube is separable).
    let (ri, gi, bi) = (nearest_level(r), nearest_level(g), nearest_level(b));
    let cube = 16 + 36 * ri as u8 + 6 * gi as u8 + bi as u8;
    // The nearest grey: the ramp value nearest to the mean, then its neighbours.
    let mean = (u32::from(r) + u32::from(g) + u32::from(b)) / 3;
    let k = ((mean.saturating_sub(8) + 5) / 10).min(23) as u8;
    let mut grey = 232 + k;
    for candidate in [k.saturating_sub(1), (k + 1).min(23)] {
        if dist(palette_rgb(232 + candidate)) < dist(palette_rgb(grey)) {
            grey = 232 + candidate;
        }
    }
    if dist(palette_rgb(grey)) < dist(palette_rgb(cube)) {
        grey
    } else {
        cube
    }
}

/// The terminal colour of `(r, g, b)` at `depth`.
#[must_use]
pub fn colour(r: u8, g: u8, b: u8, depth: ColourDepth) -> Color {
    match depth {
        ColourDepth::TrueColour => Color::Rgb(r, g, b),
        ColourDepth::Palette256 => Color::Indexed(nearest_256(r, g, b)),
        ColourDepth::None => Color::Reset,
    }
}

/// Shade characters from light to dark, for `NO_COLOR`.
const SHADES: [&str; 5] = [" ", "░", "▒", "▓", "█"];

/// Straight-alpha RGB of pixel `(x, y)`, composited over white where transparent.
fn rgb(pixmap: &Pixmap, x: u32, y: u32) -> (u8, u8, u8) {
    let Some(p) = pixmap.pixel(x, y) else {
        return (255, 255, 255);
    };
    // Premultiplied over white: c + (1 - a) · 255.
    let a = 255 - u16::from(p.alpha());
    let over = |c: u8| (u16::from(c) + a).min(255) as u8;
    (over(p.red()), over(p.green()), over(p.blue()))
}

/// Draws `pixmap` (`area.width × 2 area.height` pixels; larger ones are cut, smaller ones leave
/// the rest of the area untouched) into `area` as half blocks at colour depth `depth`.
pub fn render(pixmap: &Pixmap, depth: ColourDepth, area: Rect, buf: &mut Buffer) {
    let w = u32::from(area.width).min(pixmap.width());
    let rows = u32::from(area.height).min(pixmap.height().div_ceil(2));
    for row in 0..rows {
        for x in 0..w {
            let top = rgb(pixmap, x, 2 * row);
            let bottom = if 2 * row + 1 < pixmap.height() {
                rgb(pixmap, x, 2 * row + 1)
            } else {
                top
            };
            let Some(cell) = buf.cell_mut((area.x + x as u16, area.y + row as u16)) else {
                continue;
            };
            if depth == ColourDepth::None {
                let lum = |(r, g, b): (u8, u8, u8)| {
                    0.2126 * f64::from(r) + 0.7152 * f64::from(g) + 0.0722 * f64::from(b)
                };
                let dark = 1.0 - 0.5 * (lum(top) + lum(bottom)) / 255.0;
                let i = ((dark * 5.0) as usize).min(4);
                cell.set_symbol(SHADES[i])
                    .set_fg(Color::Reset)
                    .set_bg(Color::Reset);
            } else {
                cell.set_symbol("▀")
                    .set_fg(colour(top.0, top.1, top.2, depth))
                    .set_bg(colour(bottom.0, bottom.1, bottom.2, depth));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_palette_entry_maps_to_itself() {
        for i in 16..=255u8 {
            let (r, g, b) = palette_rgb(i);
            assert_eq!(nearest_256(r, g, b), i, "entry {i} = ({r}, {g}, {b})");
        }
    }

    #[test]
    fn known_entries() {
        // Standard xterm values: 16 black, 21 blue, 196 red, 231 white, 244 = grey 128.
        assert_eq!(palette_rgb(21), (0, 0, 255));
        assert_eq!(palette_rgb(196), (255, 0, 0));
        assert_eq!(palette_rgb(67), (95, 135, 175));
        assert_eq!(palette_rgb(244), (128, 128, 128));
        assert_eq!(nearest_256(0, 0, 0), 16);
        assert_eq!(nearest_256(255, 255, 255), 231);
        assert_eq!(nearest_256(250, 5, 3), 196);
        // 130 grey is nearer the ramp's 128 than the cube's 135.
        assert_eq!(nearest_256(130, 130, 130), 244);
        // The sky of the renderer, (246, 248, 252): the cube's white is nearer than the ramp's
        // lightest grey, 238.
        assert_eq!(nearest_256(246, 248, 252), 231);
        assert_eq!(nearest_256(236, 236, 236), 255);
    }

    #[test]
    fn depth_from_environment_values() {
        assert_eq!(
            ColourDepth::from_values(false, "truecolor"),
            ColourDepth::TrueColour
        );
        assert_eq!(
            ColourDepth::from_values(false, "24bit"),
            ColourDepth::TrueColour
        );
        assert_eq!(ColourDepth::from_values(false, ""), ColourDepth::Palette256);
        assert_eq!(
            ColourDepth::from_values(true, "truecolor"),
            ColourDepth::None
        );
    }
}
