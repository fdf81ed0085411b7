//! Drawing a scene into a [`Pixmap`]: springs, particles, cloth and jelly surfaces, colliders and
//! the text overlay, back to front. This file turns a scene into shapes and orders them; the
//! shapes are painted by [`super::paint`], floors and bowls are meshed in [`super::terrain`] and
//! what to show is chosen by [`super::style`].
//!
//! # Theory
//!
//! **Painter's algorithm.** Everything is turned into flat shapes — line segments (springs,
//! mesh lines), discs (particles, spheres) and triangles (surfaces, bowls) — each with the depth
//! `z_c` (m) of a representative point: a triangle's centroid, a segment's midpoint, a disc's
//! centre. Shapes are drawn from the farthest to the nearest, so nearer ones cover farther ones
//! (Newell, Newell & Sancha 1972). Ties keep the order the shapes were made in, so a frame is
//! the same every time. A mesh line (an edge of a surface cell) takes the depth of the nearest
//! triangle of the cells beside it, minus a hair, so that it lands right after them.
//!
//! **Floors and planes** are infinite; they are drawn as a square patch around the content (with
//! the hole of a floor with a hole cut out, and a grid of nice spacing), in a layer of their
//! own: first every shape *below* a plane the camera is above (the bowl under the floor's hole,
//! a jelly falling through it), then the planes, then everything else. Seen from the free side
//! of a plane nothing on that side can be behind it, so this order is exact for planes once the
//! shapes that cross a plane are cut along it ([`super::occlude`]): what is below is then seen
//! only through the hole. Spheres hide what is behind them by the same module's ordering.
//! A bowl under a floor's hole (a pit) seen from above shows only its inside through the hole,
//! behind everything in it, so it is drawn first of all, into a picture kept while the camera
//! stays (`pit`), its shadows laid over per pixel ([`super::shadow`]).
//!
//! **Shadows** ([`super::shadow`]) are painted on each plane right after it, under everything
//! above it; shadows on surfaces (a sphere over the cloth, a bowl's rim on its inside) are part
//! of those surfaces' shading.
//!
//! **Spheres** are drawn as discs of the projected radius `r s / z_c` (px) around the projected
//! centre (exact for orthographic views, the usual small-angle approximation for perspective),
//! shaded by a radial gradient whose bright spot sits towards the light.
//!
//! **Triangles** of surfaces are shaded with Lambert's law ([`super::colour`]): a cloth shows
//! [`super::colour::CLOTH_FRONT`] on the side its normal points to and
//! [`super::colour::CLOTH_BACK`] on the other; a jelly's faces that turn away from the camera are
//! hidden (back-face culling on a closed surface). Each projected triangle is grown by half a
//! pixel so that anti-aliased neighbours leave no light seam between them.
//!
//! Reference: M. E. Newell, R. G. Newell, T. L. Sancha, "A solution to the hidden surface
//! problem", Proc. ACM Annual Conference 1972.

use glam::DVec3;
use tiny_skia::{Paint, Pixmap};

use super::camera::{Camera, Projection, View, scene_bounds};
use super::colour::{self, Colour};
use super::occlude::Occluders;
use super::paint::{Item, Shape, draw_background, draw_shapes, point};
use super::shadow::{CastShadows, Lighting, draw_bowl_shadows, draw_plane_shadows, scene_balls};
use super::style::{Colouring, Overlay, Style};
use super::surface::Lattice;
use super::terrain::{Bowl, Floor, bowl_items, draw_floor, push_polygon, static_geometry};
use super::text::vertical_metrics;
use super::{MAX_SIDE, RenderError};

mod casters;
mod overlay;
mod pit;
use crate::physics::SpringKind;
use crate::physics::collide::Collider;
use crate::scene::Scene;
use crate::simulation::Simulation;
use casters::edges_with_quads;
pub(crate) use overlay::font_size;
use pit::PitCache;

/// What is drawn of one body, found once from its springs.
#[derive(Clone, Debug)]
struct BodyGeometry {
    /// Particle count the geometry was made for (a body that changed is drawn as springs).
    particles: usize,
    /// The lattice when the body is drawn as a surface.
    lattice: Option<Lattice>,
    /// Surface quads.
    quads: Vec<[u32; 4]>,
    /// Unique quad edges with their one or two quads.
    edges: Vec<(u32, u32, [u32; 2])>,
    /// Particle disc radius in metres: an eighth of the median spring rest length.
    particle_radius: f64,
    /// A jelly's outer faces whether or not it is drawn as a surface: its shadow is the
    /// shadow of a solid block.
    hull: Vec<[u32; 4]>,
    /// The hull's edges: ends, the two quads beside, and whether the first quad runs from
    /// the first end to the second.
    hull_edges: Vec<(u32, u32, [u32; 2], bool)>,
}

/// A scene renderer: camera, style, image size and the geometry found once from the scene.
#[derive(Clone, Debug)]
pub struct Renderer {
    /// The camera.
    pub camera: Camera,
    /// What to draw.
    pub style: Style,
    width: u32,
    height: u32,
    bodies: Vec<BodyGeometry>,
    floors: Vec<Floor>,
    bowls: Vec<Bowl>,
    /// The share of the sun that reaches each bowl corner past the terrain (its wall, the
    /// floor around a hole).
    bowl_lit: Vec<Vec<f64>>,
    /// The pictures only the camera changes (`pit`).
    pit_cache: PitCache,
    /// The background gradient, drawn once and copied into every frame.
    background: Pixmap,
    /// Line widths and disc radii scale with the image height (1 at 480 px), but never below
    /// this factor.
    min_line_scale: f32,
}

impl Renderer {
    /// A renderer for `scene` on a `width × height` image with the default camera for the scene
    /// ([`Camera::for_scene`]) and projection `projection`.
    ///
    /// # Errors
    /// [`RenderError::Size`] when a side is 0 or larger than [`MAX_SIDE`].
    pub fn new(
        scene: &Scene,
        width: u32,
        height: u32,
        projection: Projection,
        style: Style,
    ) -> Result<Renderer, RenderError> {
        check_size(width, height)?;
        let camera = Camera {
            projection,
            ..Camera::default()
        };
        let mut r = Renderer::with_camera(scene, width, height, camera, style);
        r.camera = r.default_camera(scene, projection);
        Ok(r)
    }

    /// A renderer with a given camera.
    ///
    /// # Panics
    /// If a side is 0 or larger than [`MAX_SIDE`] (use [`Renderer::new`] for user input).
    #[must_use]
    pub fn with_camera(
        scene: &Scene,
        width: u32,
        height: u32,
        camera: Camera,
        style: Style,
    ) -> Renderer {
        assert!(check_size(width, height).is_ok(), "image size out of range");
        let bodies = scene
            .bodies
            .iter()
            .map(|b| {
                let detected = Lattice::detect(&b.model);
                let lattice = detected.filter(|l| match l {
                    Lattice::Grid { .. } => style.cloth_surface,
                    Lattice::Block { .. } => style.jelly_surface,
                });
                let hull = detected
                    .filter(Lattice::is_closed)
                    .map(|l| l.quads())
                    .unwrap_or_default();
                let hull_edges = edges_with_quads(&hull)
                    .into_iter()
                    .map(|(a, b, q)| {
                        let quad = hull[q[0] as usize];
                        let forward = (0..4).any(|k| quad[k] == a && quad[(k + 1) % 4] == b);
                        (a, b, q, forward)
                    })
                    .collect();
                let quads = lattice.map(|l| l.quads()).unwrap_or_default();
                let edges = edges_with_quads(&quads);
                let mut rest: Vec<f64> = b
                    .model
                    .springs()
                    .iter()
                    .map(|s| s.rest_length)
                    .filter(|l| *l > 0.0)
                    .collect();
                rest.sort_by(f64::total_cmp);
                let median = rest.get(rest.len() / 2).copied().unwrap_or(0.8);
                BodyGeometry {
                    particles: b.model.particle_count(),
                    lattice,
                    quads,
                    edges,
                    particle_radius: median / 8.0,
                    hull,
                    hull_edges,
                }
            })
            .collect();
        let (floors, bowls) = static_geometry(scene);
        let terrain = Lighting::terrain(&bowls, &floors);
        let bowl_lit = bowls
            .iter()
            .map(|b| b.vertices.iter().map(|&p| terrain.sun(p)).collect())
            .collect();
        let mut background = Pixmap::new(width, height).expect("size checked");
        let mut paint = Paint {
            anti_alias: style.quality.anti_alias,
            force_hq_pipeline: style.quality.force_hq_pipeline,
            ..Paint::default()
        };
        draw_background(&mut background, &mut paint);
        Renderer {
            camera,
            style,
            width,
            height,
            bodies,
            floors,
            bowls,
            bowl_lit,
            pit_cache: PitCache::default(),
            background,
            min_line_scale: 0.5,
        }
    }

    /// Keeps lines and particles at least `scale` times their size at 480 px high (default
    /// 0.5): small images, such as a terminal pane of half-blocks, need thicker lines to show.
    pub fn set_min_line_scale(&mut self, scale: f32) {
        if scale.is_finite() && scale > 0.0 {
            self.min_line_scale = scale;
        }
    }

    /// Lays the floor and plane patches out again around `scene` as it is now (the patches of
    /// a new renderer surround the scene as it was then): content that slid away stays on a
    /// drawn floor.
    pub fn refit_floors(&mut self, scene: &Scene) {
        self.floors = static_geometry(scene).0;
        self.pit_cache.clear();
    }

    /// The default camera for `scene` ([`Camera::for_scene_window`]) with `projection`, keeping
    /// the overlay's band at the top and the legend's at the bottom free when the style shows
    /// them.
    #[must_use]
    pub fn default_camera(&self, scene: &Scene, projection: Projection) -> Camera {
        let (top, bottom) = self.overlay_bands();
        Camera::for_scene_window(scene, self.aspect(), projection, top, bottom)
    }

    /// Moves the camera's target and distance so that `scene` fits, keeping its orbit,
    /// elevation and kind of projection (after changing the angles, say).
    pub fn refit(&mut self, scene: &Scene) {
        let (top, bottom) = self.overlay_bands();
        self.camera = self
            .camera
            .fit_window(&scene_bounds(scene), self.aspect(), top, bottom);
    }

    fn aspect(&self) -> f64 {
        f64::from(self.width) / f64::from(self.height)
    }

    /// Fractions of the image height taken by the overlay (top) and the legend (bottom).
    fn overlay_bands(&self) -> (f64, f64) {
        if !self.style.overlay {
            return (0.0, 0.0);
        }
        let px = font_size(self.height);
        let (ascent, descent) = vertical_metrics(px);
        let line_h = (ascent + descent) * 1.15;
        // Two lines, or three when the image is narrow and the first line wraps.
        let lines = if self.width < 480 { 3.0 } else { 2.0 };
        let h = self.height as f32;
        let top = (0.5 * px + lines * line_h + 0.5 * px) / h;
        let bottom = (1.5 * px + line_h) / h;
        (f64::from(top), f64::from(bottom))
    }

    /// Image width (px).
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height (px).
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Draws the current state of `sim`, with its overlay when the style asks for one.
    #[must_use]
    pub fn draw_simulation(&self, sim: &Simulation) -> Pixmap {
        let overlay = self.style.overlay.then(|| Overlay::of(sim));
        self.draw(&sim.scene, overlay.as_ref())
    }

    /// Draws `scene` (the one the renderer was made for, in any state) with an optional
    /// overlay.
    #[must_use]
    pub fn draw(&self, scene: &Scene, overlay: Option<&Overlay>) -> Pixmap {
        let view = View::new(&self.camera, self.width, self.height);
        // The pit bowls come drawn in the kept pictures (`pit`).
        let pits = self.pits(&view);
        let layers = (!pits.is_empty()).then(|| self.pit_layers(&view, &pits));
        let mut pixmap = match &layers {
            Some(l) => l.under.clone(),
            None => self.background.clone(),
        };
        // Line widths and text grow with the image: 1 at 480 px high.
        let s = (self.height as f32 / 480.0).max(self.min_line_scale);
        let mut paint = Paint {
            anti_alias: self.style.quality.anti_alias,
            force_hq_pipeline: self.style.quality.force_hq_pipeline,
            ..Paint::default()
        };

        // Planes the camera is above cut the shapes into two layers; balls order the shapes
        // around them (`occlude`).
        let balls: Vec<(DVec3, f64)> = if self.style.colliders {
            scene_balls(scene)
        } else {
            Vec::new()
        };
        let occ = Occluders::new(
            &view,
            self.floors.iter().map(|f| (f.point, f.normal)),
            balls.iter().copied(),
        );
        // What casts shadows on the planes and bowls, once per frame.
        let casters = (self.style.shadows
            && self.style.colliders
            && !(self.floors.is_empty() && self.bowls.is_empty()))
        .then(|| self.casters(scene));
        let lights_on = self.style.shadows && self.style.colliders;
        let lights = Lighting::new(scene, &self.bowls, &self.floors, lights_on);

        let mut items = Vec::new();
        let mut any_springs = [false; 3];
        for (body, geom) in scene.bodies.iter().zip(&self.bodies) {
            let x = &body.state.x;
            let surface = geom.lattice.is_some() && geom.particles == x.len();
            if surface {
                self.surface_items(&view, body, geom, s, &occ, &lights, &mut items);
            } else {
                self.spring_items(&view, body, s, &occ, &mut items, &mut any_springs);
            }
            self.particle_items(&view, body, geom, surface, s, &occ, &mut items);
            if self.style.colliders {
                for sphere in &body.state.spheres {
                    if let Some(item) =
                        ball_item(&view, sphere.center, sphere.radius, colour::BALL, &occ)
                    {
                        items.push(item);
                    }
                }
            }
        }
        if self.style.colliders {
            for body in &scene.bodies {
                for c in &body.model.colliders {
                    if let Collider::Sphere { center, radius } = *c
                        && let Some(item) = ball_item(&view, center, radius, colour::SPHERE, &occ)
                    {
                        items.push(item);
                    }
                }
            }
            // Bodies and spheres shade the other bowls corner by corner.
            let cast = casters
                .as_ref()
                .filter(|_| self.bowls.len() > pits.len())
                .map(CastShadows::new);
            for (b, bowl) in self.bowls.iter().enumerate() {
                if pits.contains(&b) {
                    continue;
                }
                let sun: Option<Vec<f64>> = lights_on.then(|| {
                    bowl.vertices
                        .iter()
                        .zip(&self.bowl_lit[b])
                        .map(|(&p, &lit)| lit * cast.as_ref().map_or(1.0, |c| c.sun(p)))
                        .collect()
                });
                bowl_items(&view, bowl, &occ, sun.as_deref(), false, &mut items);
            }
        }
        // Back to front; a stable sort keeps creation order on ties.
        items.sort_by(|a, b| {
            a.layer
                .cmp(&b.layer)
                .then_with(|| b.depth.total_cmp(&a.depth))
        });
        let split = items.partition_point(|i| i.layer == 0);

        // The bodies' shadows inside the pits, over the kept bowls and under everything else.
        if let (Some(l), Some(c)) = (&layers, &casters)
            && let (Some(dark), Some(holes)) = (&l.dark, &l.holes)
        {
            for &b in &l.bowls {
                draw_bowl_shadows(
                    &mut pixmap,
                    paint.anti_alias,
                    &view,
                    &self.bowls[b],
                    c,
                    holes,
                    dark,
                );
            }
        }

        draw_shapes(&mut pixmap, &mut paint, &items[..split]);
        if self.style.colliders {
            for floor in &self.floors {
                draw_floor(&mut pixmap, &mut paint, &view, floor, s);
                if let Some(casters) = &casters {
                    draw_plane_shadows(&mut pixmap, &mut paint, &view, floor, casters);
                }
            }
        }
        draw_shapes(&mut pixmap, &mut paint, &items[split..]);
        if let Some(o) = overlay.filter(|_| self.style.overlay) {
            self.draw_overlay(&mut pixmap, &mut paint, o, any_springs);
        }
        pixmap
    }

    /// Spring segments of a body drawn as springs.
    fn spring_items(
        &self,
        view: &View,
        body: &crate::scene::Body,
        s: f32,
        occ: &Occluders,
        items: &mut Vec<Item>,
        any: &mut [bool; 3],
    ) {
        let x = &body.state.x;
        let many = body.model.springs().len() > 2000;
        for spring in body.model.springs() {
            if !self.style.springs.shows(spring.kind) {
                continue;
            }
            let (a, b) = (spring.a as usize, spring.b as usize);
            if a >= x.len() || b >= x.len() {
                continue;
            }
            let k = kind_index(spring.kind);
            let (mut colour, width): (Colour, f32) = match spring.kind {
                SpringKind::Struct => (colour::STRUCT, 1.5),
                SpringKind::Shear => (colour::SHEAR, 0.9),
                SpringKind::Bend => (colour::BEND, 0.9),
            };
            if let Colouring::ByStrain { max_strain } = self.style.colouring {
                colour = colour::strain_colour(strain(spring.rest_length, x[a], x[b]), max_strain);
            }
            if many && spring.kind != SpringKind::Struct {
                colour = colour.with_alpha(110);
            }
            // Dense lattices: at most 1 px, which tiny-skia draws as a fast hairline.
            let width = if many {
                width.min(1.0) * s
            } else {
                width * s * self.style.line_weight
            };
            occ.split_segment(x[a], x[b], |layer, wa, wb| {
                let (ca, cb) = (view.to_camera(wa), view.to_camera(wb));
                let Some((ca, cb)) = view.clip_segment(ca, cb) else {
                    return;
                };
                let (Some(pa), Some(pb)) = (view.project_camera(ca), view.project_camera(cb))
                else {
                    return;
                };
                any[k] = true;
                items.push(Item {
                    layer,
                    depth: occ.key(0.5 * (wa + wb), 0.5 * (ca.z + cb.z)),
                    shape: Shape::Line {
                        a: point(pa.x, pa.y),
                        b: point(pb.x, pb.y),
                        width,
                        colour,
                    },
                });
            });
        }
    }

    /// Particle discs and pin markers.
    #[allow(clippy::too_many_arguments)]
    fn particle_items(
        &self,
        view: &View,
        body: &crate::scene::Body,
        geom: &BodyGeometry,
        surface: bool,
        s: f32,
        occ: &Occluders,
        items: &mut Vec<Item>,
    ) {
        for (i, &p) in body.state.x.iter().enumerate() {
            let pinned = i < body.model.particle_count() && body.model.is_pinned(i);
            if !pinned && (surface || !self.style.particles) {
                continue;
            }
            let Some(q) = view.project(p) else { continue };
            let r = (geom.particle_radius * view.pixels_per_metre(q.depth)) as f32;
            let w = s * self.style.line_weight;
            let r = r.clamp(1.2 * w, 5.0 * w);
            let c = point(q.x, q.y);
            items.push(Item {
                layer: occ.layer(p),
                // Slightly in front of the springs that end here.
                depth: occ.key(p, q.depth - 1e-6 * q.depth.abs().max(1.0)),
                shape: if pinned {
                    Shape::Pin {
                        c,
                        r: r.max(2.5 * w),
                    }
                } else {
                    Shape::Disc {
                        c,
                        r,
                        colour: colour::PARTICLE,
                    }
                },
            });
        }
    }

    /// Shaded triangles and mesh lines of a body drawn as a surface.
    #[allow(clippy::too_many_arguments)]
    fn surface_items(
        &self,
        view: &View,
        body: &crate::scene::Body,
        geom: &BodyGeometry,
        s: f32,
        occ: &Occluders,
        lights: &Lighting,
        items: &mut Vec<Item>,
    ) {
        let x = &body.state.x;
        let closed = geom.lattice.is_some_and(|l| l.is_closed());
        let (front, back) = if closed {
            (colour::JELLY, colour::JELLY)
        } else {
            (colour::CLOTH_FRONT, colour::CLOTH_BACK)
        };
        let vertex_strain = match self.style.colouring {
            Colouring::ByStrain { .. } => Some(vertex_strains(body)),
            Colouring::ByKind => None,
        };
        // The sun's share at each particle, when something can shade the surface.
        let sun: Option<Vec<f64>> =
            (!lights.is_empty()).then(|| x.iter().map(|&p| lights.sun(p)).collect());
        let mut visible = vec![!closed; geom.quads.len()];
        // Nearest depth of each quad's drawn triangles: its mesh lines go just in front of it.
        let mut quad_depth = vec![f64::INFINITY; geom.quads.len()];
        for (qi, q) in geom.quads.iter().enumerate() {
            for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let [a, b, c] = tri.map(|i| x[i as usize]);
                let mut n = (b - a).cross(c - a);
                let centroid = (a + b + c) / 3.0;
                let to_eye = if view.perspective {
                    view.eye - centroid
                } else {
                    -view.forward
                };
                let facing = n.dot(to_eye) >= 0.0;
                if closed && !facing {
                    continue;
                }
                visible[qi] = true;
                let mut base = if facing { front } else { back };
                if !facing {
                    n = -n;
                }
                if let (Some(vs), Colouring::ByStrain { max_strain }) =
                    (&vertex_strain, self.style.colouring)
                {
                    let e = tri.iter().map(|&i| vs[i as usize]).sum::<f64>() / 3.0;
                    base = colour::strain_colour(e, max_strain);
                }
                let n = n.try_normalize().unwrap_or(to_eye.normalize());
                let colour = match &sun {
                    Some(v) => {
                        let sun = tri.iter().map(|&i| v[i as usize]).sum::<f64>() / 3.0;
                        colour::shade_lit(base, n, sun, lights.sky(centroid, n))
                    }
                    None => colour::shade(base, n),
                };
                let depth = push_polygon(view, occ, &[a, b, c], colour, items);
                quad_depth[qi] = quad_depth[qi].min(depth);
            }
        }
        if !self.style.mesh_lines {
            return;
        }
        let line = if closed {
            colour::JELLY.scaled(0.3).with_alpha(160)
        } else {
            colour::CLOTH_FRONT.scaled(0.4).with_alpha(90)
        };
        for &(a, b, quads) in &geom.edges {
            if !quads.iter().any(|&q| visible[q as usize]) {
                continue;
            }
            // Just in front of the nearest triangle of the quads beside it (module docs).
            let near = quads
                .iter()
                .map(|&q| quad_depth[q as usize])
                .fold(f64::INFINITY, f64::min);
            if !near.is_finite() {
                continue;
            }
            let depth = near - 1e-9 * near.abs().max(1.0);
            occ.split_segment(x[a as usize], x[b as usize], |layer, xa, xb| {
                let (ca, cb) = (view.to_camera(xa), view.to_camera(xb));
                let Some((ca, cb)) = view.clip_segment(ca, cb) else {
                    return;
                };
                let (Some(pa), Some(pb)) = (view.project_camera(ca), view.project_camera(cb))
                else {
                    return;
                };
                items.push(Item {
                    layer,
                    depth,
                    shape: Shape::Line {
                        a: point(pa.x, pa.y),
                        b: point(pb.x, pb.y),
                        width: 0.6 * s,
                        colour: line,
                    },
                });
            });
        }
    }
}

/// Checks an image size: each side 1 ..= [`MAX_SIDE`].
///
/// # Errors
/// [`RenderError::Size`] naming the allowed range.
pub fn check_size(width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(RenderError::Size { width, height });
    }
    Ok(())
}

fn kind_index(kind: SpringKind) -> usize {
    match kind {
        SpringKind::Struct => 0,
        SpringKind::Shear => 1,
        SpringKind::Bend => 2,
    }
}

/// Engineering strain `(L - L0)/L0` of a spring between `a` and `b` (0 for `L0 = 0`).
fn strain(rest_length: f64, a: DVec3, b: DVec3) -> f64 {
    if rest_length > 0.0 {
        ((b - a).length() - rest_length) / rest_length
    } else {
        0.0
    }
}

/// Mean strain of the struct springs at each particle (0 where there are none).
fn vertex_strains(body: &crate::scene::Body) -> Vec<f64> {
    let x = &body.state.x;
    let mut sum = vec![0.0; x.len()];
    let mut count = vec![0u32; x.len()];
    for s in body.model.springs() {
        let (a, b) = (s.a as usize, s.b as usize);
        if s.kind != SpringKind::Struct || a >= x.len() || b >= x.len() {
            continue;
        }
        let e = strain(s.rest_length, x[a], x[b]);
        for p in [a, b] {
            sum[p] += e;
            count[p] += 1;
        }
    }
    sum.iter()
        .zip(&count)
        .map(|(s, &c)| if c > 0 { s / f64::from(c) } else { 0.0 })
        .collect()
}

/// A shaded disc for a sphere of `radius` (m) at `center`.
fn ball_item(
    view: &View,
    center: DVec3,
    radius: f64,
    base: Colour,
    occ: &Occluders,
) -> Option<Item> {
    let q = view.project(center)?;
    let r = (radius * view.pixels_per_metre(q.depth)) as f32;
    if !(r > 0.0 && r.is_finite()) {
        return None;
    }
    // The light seen on the screen: (L·r̂, -L·û), towards the bright spot.
    let l = colour::LIGHT.normalize();
    let (lx, ly) = (l.dot(view.right) as f32, -(l.dot(view.up)) as f32);
    let len = (lx * lx + ly * ly).sqrt().max(1e-6);
    Some(Item {
        layer: occ.layer(center),
        depth: q.depth,
        shape: Shape::Ball {
            c: point(q.x, q.y),
            r,
            base,
            highlight: (0.4 * r * lx / len.max(1.0), 0.4 * r * ly / len.max(1.0)),
        },
    })
}
