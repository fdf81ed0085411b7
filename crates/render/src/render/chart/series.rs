//! A chart's series: bands, lines and points, drawn inside the plot rectangle only.

use tiny_skia::{
    FillRule, LineCap, LineJoin, Mask, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform,
};

use super::{Layout, Metrics, Plot, Series};
use crate::render::colour::Colour;

/// The clip mask of the plot rectangle: series are drawn inside it only.
pub(super) fn plot_mask(width: u32, height: u32, layout: &Layout) -> Mask {
    let mut mask = Mask::new(width, height).expect("size checked");
    if let Some(rect) = Rect::from_xywh(layout.left, layout.top, layout.pw, layout.ph) {
        mask.fill_path(
            &PathBuilder::from_rect(rect),
            FillRule::Winding,
            false,
            Transform::identity(),
        );
    }
    mask
}

/// What every series is drawn with: the image, its paint, the sizes, the plot and the clip mask
/// of the plot rectangle.
pub(super) struct SeriesCanvas<'a, 'p> {
    pub(super) pixmap: &'a mut Pixmap,
    pub(super) paint: &'a mut Paint<'p>,
    pub(super) m: &'a Metrics,
    pub(super) plot: &'a Plot<'a>,
    pub(super) mask: &'a Mask,
}

impl SeriesCanvas<'_, '_> {
    /// Fills `path` with `colour`, inside the plot.
    fn fill(&mut self, path: &tiny_skia::Path, colour: tiny_skia::Color) {
        self.paint.set_color(colour);
        self.pixmap.fill_path(
            path,
            self.paint,
            FillRule::Winding,
            Transform::identity(),
            Some(self.mask),
        );
    }

    /// Strokes `path` with `colour` and `stroke`, inside the plot.
    fn stroke(&mut self, path: &tiny_skia::Path, colour: tiny_skia::Color, stroke: &Stroke) {
        self.paint.set_color(colour);
        self.pixmap.stroke_path(
            path,
            self.paint,
            stroke,
            Transform::identity(),
            Some(self.mask),
        );
    }

    /// A shaded band: the polygon along the series' points and back along `lower`.
    pub(super) fn band(&mut self, series: &Series, lower: &[(f64, f64)], c: Colour) {
        let mut pb = PathBuilder::new();
        let mut started = false;
        for &(x, y) in series.points.iter().chain(lower.iter().rev()) {
            if let Some((u, v)) = self.plot.to_px(x, y)
                && u.is_finite()
                && v.is_finite()
            {
                if started {
                    pb.line_to(u, v);
                } else {
                    pb.move_to(u, v);
                    started = true;
                }
            }
        }
        pb.close();
        if let Some(path) = pb.finish() {
            let mut fill = c.to_skia();
            fill.set_alpha(0.25);
            self.fill(&path, fill);
        }
    }

    /// The series as a polyline; the pen lifts over points that cannot be placed.
    pub(super) fn line(&mut self, series: &Series, c: Colour) {
        let mut pb = PathBuilder::new();
        let mut pen_down = false;
        for &(x, y) in &series.points {
            match self.plot.to_px(x, y) {
                Some((u, v)) if u.is_finite() && v.is_finite() => {
                    if pen_down {
                        pb.line_to(u, v);
                    } else {
                        pb.move_to(u, v);
                        pen_down = true;
                    }
                }
                _ => pen_down = false,
            }
        }
        if let Some(path) = pb.finish() {
            let stroke = Stroke {
                width: 2.0 * self.m.s,
                line_cap: LineCap::Round,
                line_join: LineJoin::Round,
                ..Stroke::default()
            };
            self.stroke(&path, c.to_skia(), &stroke);
        }
    }

    /// The series' points as discs with a white outline.
    pub(super) fn points(&mut self, series: &Series, c: Colour) {
        for &(x, y) in &series.points {
            if let Some((u, v)) = self.plot.to_px(x, y)
                && let Some(path) = PathBuilder::from_circle(u, v, 3.2 * self.m.s)
            {
                self.fill(&path, c.to_skia());
                let stroke = Stroke {
                    width: 0.9 * self.m.s,
                    ..Stroke::default()
                };
                self.stroke(&path, self.m.ink.background.to_skia(), &stroke);
            }
        }
    }
}
