//! The text overlay: the box of lines in the top-left corner and the colour legend in the
//! bottom-left; or, captioned ([`Renderer::draw_captioned`]), the same in bands above and below
//! the picture, where they cover none of it.

use tiny_skia::{Paint, Pixmap, PixmapPaint, Transform};

use super::{Renderer, kind_index};
use crate::physics::SpringKind;
use crate::render::colour::{self, Colour};
use crate::render::paint::{fill_rect, point, stroke_line};
use crate::render::style::{Colouring, Overlay};
use crate::render::text::{Align, draw_text, text_width, vertical_metrics};
use crate::scene::Scene;

impl Renderer {
    /// The heights (px) of the bands above and below the picture that
    /// [`Renderer::draw_captioned`] adds: the overlay's text box and the colour legend, each
    /// with its margin.
    #[must_use]
    pub fn caption_bands(&self, o: &Overlay) -> (u32, u32) {
        let px = font_size(self.height);
        let (ascent, descent) = vertical_metrics(px);
        let line_h = (ascent + descent) * 1.15;
        let pad = 0.5 * px;
        let lines = self.overlay_lines(o, px).len() as f32;
        let top = pad + line_h * lines + pad + pad;
        let bottom = pad + line_h + pad + pad;
        (top.ceil() as u32, bottom.ceil() as u32)
    }

    /// `scene` with the overlay `o` outside the picture: the text in a band above, the legend
    /// in a band below (heights [`Renderer::caption_bands`]), the picture itself as
    /// [`Renderer::draw`] draws it without an overlay, so no body is ever covered.
    #[must_use]
    pub fn draw_captioned(&self, scene: &Scene, o: &Overlay) -> Pixmap {
        let picture = self.draw(scene, None);
        let (top, bottom) = self.caption_bands(o);
        let height = (self.height + top + bottom).min(crate::render::MAX_SIDE);
        let mut out = Pixmap::new(self.width, height).expect("sides checked");
        out.fill(colour::SKY_TOP.to_skia());
        out.draw_pixmap(
            0,
            top as i32,
            picture.as_ref(),
            &PixmapPaint::default(),
            Transform::identity(),
            None,
        );
        // The kinds drawn as springs (bodies drawn as surfaces have none).
        let mut kinds = [false; 3];
        for (body, geom) in scene.bodies.iter().zip(&self.bodies) {
            let surface = geom.lattice.is_some() && geom.particles == body.state.x.len();
            if surface {
                continue;
            }
            for spring in body.model.springs() {
                if self.style.springs.shows(spring.kind) {
                    kinds[kind_index(spring.kind)] = true;
                }
            }
        }
        let mut paint = Paint {
            anti_alias: self.style.quality.anti_alias,
            ..Paint::default()
        };
        self.draw_overlay(&mut out, &mut paint, o, kinds);
        out
    }

    /// The overlay's lines, broken at their " · " separators where wider than the image.
    fn overlay_lines(&self, o: &Overlay, px: f32) -> Vec<String> {
        let pad = 0.5 * px;
        let room = self.width as f32 - 4.0 * pad;
        o.lines()
            .iter()
            .flat_map(|l| wrap(l, " · ", room, px))
            .collect()
    }

    /// The text box in the top-left corner and the colour legend in the bottom-left.
    pub(super) fn draw_overlay(
        &self,
        pixmap: &mut Pixmap,
        paint: &mut Paint,
        o: &Overlay,
        kinds: [bool; 3],
    ) {
        let px = font_size(self.height);
        let (ascent, descent) = vertical_metrics(px);
        let line_h = (ascent + descent) * 1.15;
        let pad = 0.5 * px;
        let lines = self.overlay_lines(o, px);
        let w = lines
            .iter()
            .map(|l| text_width(l, px))
            .fold(0.0f32, f32::max);
        fill_rect(
            pixmap,
            paint,
            pad,
            pad,
            w + 2.0 * pad,
            line_h * lines.len() as f32 + pad,
            colour::OVERLAY_BOX,
        );
        for (k, line) in lines.iter().enumerate() {
            let baseline = pad + 0.5 * pad + ascent + k as f32 * line_h;
            draw_text(
                pixmap,
                line,
                2.0 * pad,
                baseline,
                px,
                colour::TEXT,
                Align::Left,
            );
        }
        // Legend at the bottom left (of the captioned picture, in its lower band).
        let h = pixmap.height() as f32;
        match self.style.colouring {
            Colouring::ByKind => {
                let entries: Vec<(&str, Colour)> = SpringKind::ALL
                    .iter()
                    .filter(|k| kinds[kind_index(**k)])
                    .map(|k| {
                        (
                            k.name(),
                            match k {
                                SpringKind::Struct => colour::STRUCT,
                                SpringKind::Shear => colour::SHEAR,
                                SpringKind::Bend => colour::BEND,
                            },
                        )
                    })
                    .collect();
                if entries.is_empty() {
                    return;
                }
                let sample = 1.6 * px;
                let total: f32 = entries
                    .iter()
                    .map(|(n, _)| sample + 0.4 * px + text_width(n, px) + px)
                    .sum();
                fill_rect(
                    pixmap,
                    paint,
                    pad,
                    h - pad - line_h - pad,
                    total + pad,
                    line_h + pad,
                    colour::OVERLAY_BOX,
                );
                let baseline = h - pad - 0.5 * pad - descent;
                let mut x = 1.5 * pad;
                for (name, c) in entries {
                    let y = baseline - 0.35 * ascent;
                    stroke_line(pixmap, paint, point(x, y), point(x + sample, y), 2.0, c);
                    x += sample + 0.4 * px;
                    draw_text(pixmap, name, x, baseline, px, colour::TEXT, Align::Left);
                    x += text_width(name, px) + px;
                }
            }
            Colouring::ByStrain { max_strain } => {
                let bar_w = (12.0 * px).min(0.4 * self.width as f32);
                let bar_h = 0.7 * px;
                let label = |v: f64| format!("{:+.0}%", 100.0 * v);
                let (lo, hi) = (label(-max_strain), label(max_strain));
                let title = "strain";
                let total = text_width(title, px) + px + bar_w + text_width(&hi, px) * 2.0 + px;
                fill_rect(
                    pixmap,
                    paint,
                    pad,
                    h - pad - line_h - pad,
                    total + 2.0 * pad,
                    line_h + pad,
                    colour::OVERLAY_BOX,
                );
                let baseline = h - pad - 0.5 * pad - descent;
                let mut x = 1.5 * pad;
                draw_text(pixmap, title, x, baseline, px, colour::TEXT, Align::Left);
                x += text_width(title, px) + 0.5 * px;
                draw_text(pixmap, &lo, x, baseline, px, colour::TEXT, Align::Left);
                x += text_width(&lo, px) + 0.3 * px;
                let steps = 32;
                for k in 0..steps {
                    let t = (k as f64 + 0.5) / steps as f64 * 2.0 - 1.0;
                    let c = colour::strain_colour(t * max_strain, max_strain);
                    let seg = bar_w / steps as f32;
                    fill_rect(
                        pixmap,
                        paint,
                        x + k as f32 * seg,
                        baseline - 0.5 * ascent - 0.5 * bar_h,
                        seg + 0.5,
                        bar_h,
                        c,
                    );
                }
                x += bar_w + 0.3 * px;
                draw_text(pixmap, &hi, x, baseline, px, colour::TEXT, Align::Left);
            }
        }
    }
}

/// `line` split at `separator` into pieces no wider than `room` px where possible.
fn wrap(line: &str, separator: &str, room: f32, px: f32) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for part in line.split(separator) {
        match out.last_mut() {
            Some(last) if text_width(&format!("{last}{separator}{part}"), px) <= room => {
                last.push_str(separator);
                last.push_str(part);
            }
            _ => out.push(part.to_string()),
        }
    }
    out
}

/// Text size (px) for an image `height` px high.
pub(crate) fn font_size(height: u32) -> f32 {
    (height as f32 / 32.0).clamp(10.0, 48.0).round()
}
