//! The run's camera: the step's first view framed for the pane, following the bodies, zoom,
//! pan and the way back to the first view.

use glam::DVec3;

use super::{FOLLOW_MAX_ZOOM_OUT, FOLLOW_ZONE, LessonRun, TRACK_RATE};
use crate::render::{Camera, Projection};

impl LessonRun {
    /// The camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The step's initial camera (what `r` and `c` return to).
    #[must_use]
    pub fn home_camera(&self) -> &Camera {
        &self.home
    }

    /// True while the camera follows the bodies.
    #[must_use]
    pub fn follows(&self) -> bool {
        self.follow
    }

    /// Width / height of the scene pane in pixels, as last reported.
    #[must_use]
    pub fn aspect(&self) -> f64 {
        self.aspect
    }

    /// Tells the run the scene pane's aspect ratio (width / height in pixels). The step's
    /// initial view is framed for it; a camera the user has not moved follows the new framing.
    pub fn set_aspect(&mut self, aspect: f64) {
        if !(aspect.is_finite() && aspect > 0.0) || (aspect / self.aspect - 1.0).abs() < 1e-3 {
            return;
        }
        self.aspect = aspect;
        self.version += 1;
        let untouched = self.camera == self.home;
        self.home = self.first_view(aspect);
        if untouched {
            self.camera = self.home;
        }
    }

    /// The step's first view for a pane of aspect `aspect`: its scene at the start, or only the
    /// body its front matter names (`camera = { body = 2 }`), framed.
    pub(super) fn first_view(&self, aspect: f64) -> Camera {
        let mut scene = self.scene_at_start();
        if let Some(b) = self.target_body() {
            let body = scene.bodies.swap_remove(b);
            scene.bodies = vec![body];
        }
        Camera::for_scene(&scene, aspect, Projection::default())
    }

    /// The body (0-based) the camera frames and follows, when the step names one.
    fn target_body(&self) -> Option<usize> {
        let b = self.lesson.steps[self.step].camera_body?.checked_sub(1)?;
        (b < self.sim.scene.bodies.len()).then_some(b)
    }

    /// The scene with the bodies' initial states.
    pub(super) fn scene_at_start(&self) -> crate::scene::Scene {
        let mut scene = self.sim.scene.clone();
        for (body, initial) in scene.bodies.iter_mut().zip(&self.initial) {
            body.state = initial.clone();
        }
        scene
    }

    /// Turns following on or off.
    pub fn set_follow(&mut self, on: bool) {
        self.follow = on;
        if on {
            self.follow_bodies();
        }
    }

    /// Moves the camera so that every followed body is in view (see [`Camera::follow`]).
    pub(super) fn follow_bodies(&mut self) {
        self.follow_bodies_after(0.0);
    }

    /// As [`LessonRun::follow_bodies`] after `elapsed` seconds of simulated time: while the
    /// camera tracks the bodies it first moves its target towards
    ///
    /// ```text
    /// aim = c + v̄ / λ,     target ← target + (1 - e^(-λ Δt)) (aim - target)
    /// ```
    /// where
    /// - `c` is the followed particles' centroid (m) and `v̄` their mean velocity (m/s),
    /// - `λ` is [`TRACK_RATE`] (1/s) and `Δt` the simulated time elapsed (s).
    ///
    /// Aiming `v̄/λ` ahead cancels the lag of the exponential approach for a body moving at a
    /// steady velocity (its lag would be `v̄/λ`), so a sliding cube sits in the middle of the pane
    /// at the distance of the first view. Tracking starts the first time following has to move
    /// the view for bodies without a pinned particle, and stops at `r`, `c`, a pan or a new step.
    pub(super) fn follow_bodies_after(&mut self, elapsed: f64) {
        if self.sim.diverged.is_some() {
            return;
        }
        let target = self.target_body();
        let followed = || {
            self.sim
                .scene
                .bodies
                .iter()
                .enumerate()
                .filter(move |(i, _)| target.is_none_or(|t| t == *i))
                .map(|(_, b)| b)
        };
        let mut points: Vec<DVec3> = Vec::new();
        for body in followed() {
            points.extend(body.state.x.iter().copied());
            for s in &body.state.spheres {
                points.extend([-1.0, 1.0].map(|k| s.center + k * s.radius * DVec3::X));
                points.extend([-1.0, 1.0].map(|k| s.center + k * s.radius * DVec3::Y));
                points.extend([-1.0, 1.0].map(|k| s.center + k * s.radius * DVec3::Z));
            }
        }
        let free = followed().all(|b| b.model.inv_mass.iter().all(|&w| w > 0.0));
        if self.tracking && elapsed > 0.0 {
            let (mut sum_x, mut sum_v, mut n) = (DVec3::ZERO, DVec3::ZERO, 0.0);
            for body in followed() {
                sum_x += body.state.x.iter().sum::<DVec3>();
                sum_v += body.state.v.iter().sum::<DVec3>();
                n += body.state.x.len() as f64;
            }
            let aim = (sum_x + sum_v / TRACK_RATE) / n;
            if n > 0.0 && aim.is_finite() {
                let k = 1.0 - (-TRACK_RATE * elapsed).exp();
                self.camera.target += k * (aim - self.camera.target);
            }
        }
        let max_distance = self.home.distance * FOLLOW_MAX_ZOOM_OUT;
        let max_height = self.home.visible_height() * FOLLOW_MAX_ZOOM_OUT;
        let moved = self
            .camera
            .follow(&points, self.aspect, FOLLOW_ZONE, max_distance, max_height);
        if moved && free {
            self.tracking = true;
        }
    }

    pub(super) fn zoom(&mut self, factor: f64) {
        let before = self.camera;
        self.camera.zoom(factor);
        if self.follow {
            self.follow_bodies();
            if factor > 1.0 && self.camera.distance >= before.distance {
                self.message = Some(
                    "following keeps every body in view: f stops following, to zoom closer".into(),
                );
            }
        }
    }

    pub(super) fn pan(&mut self, right: f64, up: f64) {
        self.camera.pan(right, up);
        self.tracking = false;
        if self.follow {
            self.follow_bodies();
        }
    }

    /// Back to the step's initial view.
    pub fn reset_camera(&mut self) {
        self.camera = self.home;
        self.tracking = false;
        self.pan_drag = None;
    }
}
