//! Text with the bundled font (DejaVu Sans Mono, rasterised by fontdue): no system font is read
//! at run time, so every machine draws the same pixels.
//!
//! Glyphs are placed at whole pixels and blended over the image with "source over":
//!
//! ```text
//! α   = coverage / 255 · colour.a / 255
//! dst = α · colour + (1 - α) · dst           per premultiplied channel, alpha included
//! ```
//! where `coverage` is fontdue's 8-bit glyph coverage of the pixel.
//!
//! The font's licence (Bitstream Vera / public domain for the DejaVu changes) is in
//! `assets/fonts/LICENSE-DejaVu.txt`.

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use fontdue::{Font, FontSettings, Metrics};
use tiny_skia::Pixmap;

use super::colour::Colour;

/// The bundled TrueType font.
static FONT_BYTES: &[u8] = include_bytes!("../../../../assets/fonts/DejaVuSansMono.ttf");

/// The parsed font, loaded once.
#[must_use]
pub fn font() -> &'static Font {
    static FONT: OnceLock<Font> = OnceLock::new();
    FONT.get_or_init(|| {
        Font::from_bytes(FONT_BYTES, FontSettings::default())
            .expect("the bundled DejaVu Sans Mono parses")
    })
}

type Glyph = (Metrics, Vec<u8>);

/// Rasterised glyphs by character and size (the size's f32 bits).
type GlyphCache = Mutex<HashMap<(char, u32), std::sync::Arc<Glyph>>>;

/// A rasterised glyph from the cache (rasterised on first use).
fn glyph(c: char, px: f32) -> std::sync::Arc<Glyph> {
    static CACHE: OnceLock<GlyphCache> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    let key = (c, px.to_bits());
    if let Some(g) = cache.lock().ok().and_then(|m| m.get(&key).cloned()) {
        return g;
    }
    let g = std::sync::Arc::new(font().rasterize(c, px));
    if let Ok(mut m) = cache.lock() {
        m.insert(key, g.clone());
    }
    g
}

/// Horizontal placement of a text relative to its anchor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// The anchor is the left end.
    Left,
    /// The anchor is the middle.
    Centre,
    /// The anchor is the right end.
    Right,
}

/// Width of `text` at size `px` (px): the sum of the advance widths.
#[must_use]
pub fn text_width(text: &str, px: f32) -> f32 {
    text.chars()
        .map(|c| font().metrics(c, px).advance_width)
        .sum()
}

/// Ascent (above the baseline, > 0) and descent (below, > 0) of the font at size `px` (px).
#[must_use]
pub fn vertical_metrics(px: f32) -> (f32, f32) {
    font()
        .horizontal_line_metrics(px)
        .map_or((0.8 * px, 0.2 * px), |m| (m.ascent, -m.descent))
}

/// Draws `text` with its baseline at `baseline` (px from the top) and anchored at `x` (px from
/// the left) as `align` says. Characters the font lacks draw as its missing-glyph box.
pub fn draw_text(
    pixmap: &mut Pixmap,
    text: &str,
    x: f32,
    baseline: f32,
    px: f32,
    colour: Colour,
    align: Align,
) {
    let width = text_width(text, px);
    let left = match align {
        Align::Left => x,
        Align::Centre => x - 0.5 * width,
        Align::Right => x - width,
    };
    let mut pen = left;
    let by = baseline.round() as i64;
    for c in text.chars() {
        let g = glyph(c, px);
        let (m, bitmap) = (&g.0, &g.1);
        let gx = pen.round() as i64 + i64::from(m.xmin);
        // Top row of the bitmap: baseline - (ymin + height).
        let gy = by - i64::from(m.ymin) - m.height as i64;
        blend_coverage(pixmap, bitmap, m.width, m.height, gx, gy, colour);
        pen += m.advance_width;
    }
}

/// Draws `text` turned 90° counter-clockwise (reading upwards), centred vertically on `y` with
/// its baseline at `x` (px): the y-axis label of a chart.
pub fn draw_text_vertical(
    pixmap: &mut Pixmap,
    text: &str,
    x: f32,
    y: f32,
    px: f32,
    colour: Colour,
) {
    let width = text_width(text, px).ceil().max(1.0) as usize;
    let (ascent, descent) = vertical_metrics(px);
    let height = (ascent + descent).ceil().max(1.0) as usize;
    // Horizontal coverage first, then copied turned.
    let mut cov = vec![0u8; width * height];
    let mut pen = 0.0f32;
    for c in text.chars() {
        let g = glyph(c, px);
        let (m, bitmap) = (&g.0, &g.1);
        let gx = pen.round() as i64 + i64::from(m.xmin);
        let gy = ascent.round() as i64 - i64::from(m.ymin) - m.height as i64;
        for row in 0..m.height {
            for col in 0..m.width {
                let (tx, ty) = (gx + col as i64, gy + row as i64);
                if tx >= 0 && ty >= 0 && (tx as usize) < width && (ty as usize) < height {
                    let t = &mut cov[ty as usize * width + tx as usize];
                    *t = (*t).max(bitmap[row * m.width + col]);
                }
            }
        }
        pen += m.advance_width;
    }
    // Turned: horizontal pixel (col, row) goes to (row, width - 1 - col).
    let mut turned = vec![0u8; width * height];
    for row in 0..height {
        for col in 0..width {
            turned[(width - 1 - col) * height + row] = cov[row * width + col];
        }
    }
    let left = (x - ascent).round() as i64;
    let top = (y - 0.5 * width as f32).round() as i64;
    blend_coverage(pixmap, &turned, height, width, left, top, colour);
}

/// Blends a `w × h` coverage bitmap at `(x0, y0)` (module docs).
fn blend_coverage(
    pixmap: &mut Pixmap,
    coverage: &[u8],
    w: usize,
    h: usize,
    x0: i64,
    y0: i64,
    colour: Colour,
) {
    let (pw, ph) = (i64::from(pixmap.width()), i64::from(pixmap.height()));
    let data = pixmap.data_mut();
    let src = [
        u32::from(colour.r),
        u32::from(colour.g),
        u32::from(colour.b),
        255,
    ];
    for row in 0..h {
        let y = y0 + row as i64;
        if y < 0 || y >= ph {
            continue;
        }
        for col in 0..w {
            let x = x0 + col as i64;
            let c = u32::from(coverage[row * w + col]);
            if x < 0 || x >= pw || c == 0 {
                continue;
            }
            // α in 0..=255: coverage · colour alpha / 255.
            let a = (c * u32::from(colour.a) + 127) / 255;
            let i = ((y * pw + x) * 4) as usize;
            for k in 0..4 {
                let d = u32::from(data[i + k]);
                data[i + k] = ((src[k] * a + d * (255 - a) + 127) / 255) as u8;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_has_width_and_ink() {
        assert!(text_width("energy", 12.0) > 30.0);
        let mut p = Pixmap::new(80, 20).expect("size");
        p.fill(tiny_skia::Color::WHITE);
        draw_text(
            &mut p,
            "t = 1 s",
            2.0,
            15.0,
            12.0,
            Colour::rgb(0, 0, 0),
            Align::Left,
        );
        let dark = p.pixels().iter().filter(|c| c.red() < 128).count();
        assert!(dark > 20);
    }
}
