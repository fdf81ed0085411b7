//! The pictures of a frame that only the camera changes, kept between frames: the background
//! with the pit bowls (bowls under a floor's hole, seen from above the floor) drawn in, lit and
//! in shadow, and the hole's region on the screen. Nothing a body does changes them, so a frame
//! starts from a copy instead of drawing the bowl's triangles again.

use std::sync::{Arc, Mutex};

use tiny_skia::{FillRule, Mask, Paint, Pixmap, Transform};

use super::Renderer;
use crate::render::camera::View;
use crate::render::occlude::Occluders;
use crate::render::paint::{Item, draw_shapes};
use crate::render::shadow::draw_pit_shade;
use crate::render::style::Style;
use crate::render::terrain::{add_ring, bowl_items};

/// The kept pictures for one view and style.
#[derive(Debug)]
pub(super) struct PitLayers {
    view: View,
    style: Style,
    /// The bowls drawn: indices into the renderer's bowls.
    pub(super) bowls: Vec<usize>,
    /// The background with the pit bowls drawn in, the floor's shadow inside them laid over.
    pub(super) under: Pixmap,
    /// The background with the pit bowls drawn in shadow (none without shadows).
    pub(super) dark: Option<Pixmap>,
    /// The holes of the pits' floors on the screen.
    pub(super) holes: Option<Mask>,
}

/// The last [`PitLayers`] made, shared by the renderer's clones until the view changes.
#[derive(Default)]
pub(super) struct PitCache(Mutex<Option<Arc<PitLayers>>>);

impl Clone for PitCache {
    fn clone(&self) -> PitCache {
        PitCache(Mutex::new(self.get()))
    }
}

impl std::fmt::Debug for PitCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PitCache")
    }
}

impl PitCache {
    fn get(&self) -> Option<Arc<PitLayers>> {
        self.0.lock().map(|g| g.clone()).unwrap_or_default()
    }

    /// Forgets the kept pictures (the floors or bowls changed).
    pub(super) fn clear(&self) {
        if let Ok(mut g) = self.0.lock() {
            *g = None;
        }
    }
}

impl Renderer {
    /// The pit bowls seen from above their floor in `view`.
    pub(super) fn pits(&self, view: &View) -> Vec<usize> {
        if !self.style.colliders {
            return Vec::new();
        }
        (0..self.bowls.len())
            .filter(|&b| {
                self.bowls[b].pit.is_some_and(|f| {
                    let floor = &self.floors[f];
                    (view.eye - floor.point).dot(floor.normal) > 0.0
                })
            })
            .collect()
    }

    /// The kept pictures for `view` and the pits `bowls`, made when the view, the style or the
    /// pits changed.
    pub(super) fn pit_layers(&self, view: &View, bowls: &[usize]) -> Arc<PitLayers> {
        if let Some(l) = self.pit_cache.get()
            && l.view == *view
            && l.style == self.style
            && l.bowls == bowls
        {
            return l;
        }
        let layers = Arc::new(self.make_pit_layers(view, bowls));
        if let Ok(mut g) = self.pit_cache.0.lock() {
            *g = Some(Arc::clone(&layers));
        }
        layers
    }

    fn make_pit_layers(&self, view: &View, bowls: &[usize]) -> PitLayers {
        let mut paint = Paint {
            anti_alias: self.style.quality.anti_alias,
            force_hq_pipeline: self.style.quality.force_hq_pipeline,
            ..Paint::default()
        };
        // Everything here is below the floors: one layer, ordered by depth alone.
        let occ = Occluders::new(view, std::iter::empty(), std::iter::empty());
        let draw = |sun: Option<f64>, paint: &mut Paint| {
            let mut pixmap = self.background.clone();
            let mut items: Vec<Item> = Vec::new();
            for &b in bowls {
                let bowl = &self.bowls[b];
                let share = sun.map(|s| vec![s; bowl.vertices.len()]);
                bowl_items(view, bowl, &occ, share.as_deref(), true, &mut items);
            }
            items.sort_by(|a, b| b.depth.total_cmp(&a.depth));
            draw_shapes(&mut pixmap, paint, &items);
            pixmap
        };
        let shadows = self.style.shadows;
        let mut under = draw(shadows.then_some(1.0), &mut paint);
        let dark = shadows.then(|| draw(Some(0.0), &mut paint));
        let holes = Mask::new(self.width, self.height).map(|mut mask| {
            for &b in bowls {
                if let Some(f) = self.bowls[b].pit
                    && let Some(path) = hole_path(view, &self.floors[f].hole)
                {
                    mask.fill_path(
                        &path,
                        FillRule::Winding,
                        paint.anti_alias,
                        Transform::identity(),
                    );
                }
            }
            mask
        });
        if let (Some(dark), Some(holes)) = (&dark, &holes) {
            for &b in bowls {
                let bowl = &self.bowls[b];
                if let Some(f) = bowl.pit {
                    draw_pit_shade(
                        &mut under,
                        paint.anti_alias,
                        view,
                        bowl,
                        &self.floors[f],
                        holes,
                        dark,
                    );
                }
            }
        }
        PitLayers {
            view: *view,
            style: self.style,
            bowls: bowls.to_vec(),
            under,
            dark,
            holes,
        }
    }
}

/// The hole's outline `ring` on the screen as a path.
fn hole_path(view: &View, ring: &[glam::DVec3]) -> Option<tiny_skia::Path> {
    let mut pb = tiny_skia::PathBuilder::new();
    add_ring(&mut pb, view, ring);
    pb.finish()
}
