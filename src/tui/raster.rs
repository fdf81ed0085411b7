//! Frames of the scene pane drawn by the rasteriser (`crate::render`, tiny-skia) and encoded for
//! the terminal: half-blocks on the UI thread, sixel / kitty / iTerm2 on an encoder thread.
//!
//! ```text
//! UI thread:  scene + camera ──PaneRenderer──▶ Pixmap ──halfblocks──▶ cells          (half-blocks)
//!             scene + camera ──Job (channel)──▶ encoder thread                          (raster)
//! encoder:    PaneRenderer ──▶ Pixmap ──▶ RgbaImage ──▶ sixel / kitty / iTerm2 (encoded, sixel)
//!             ──Frame (channel)──▶ UI thread: drawn into the pane as one escape sequence
//! ```
//! A job may carry the plots as a picture ([`super::plots::picture`]): the encoder draws and
//! encodes it after the scene, as a second image with its own cells (and kitty id).
//!
//! The encoder always takes the newest job and drops older ones, so the picture never lags the
//! simulation by more than one frame; when drawing and encoding take longer than
//! [`FRAME_BUDGET`], the next frames are drawn at a lower resolution and enlarged to the pane
//! (nearest pixel) before encoding.

use std::sync::mpsc::{Receiver, SyncSender, TryRecvError, sync_channel};
use std::time::{Duration, Instant};

use ratatui::layout::{Rect, Size};
use tiny_skia::Pixmap;

use super::graphics::{Graphics, Protocol};
use super::pane::SpringFilter;
use super::plots::picture::Picture;
use crate::physics::SpringKind;
use crate::render::{Camera, KindToggles, MAX_SIDE, Renderer, Style};
use crate::scene::Scene;

mod encoded;
mod image;
pub mod sixel;

pub use encoded::{Encoded, Kitty, Sequence, base64_append, show};
pub use image::RgbaImage;

/// Time the encoder may spend on one frame (draw + encode) before it lowers the resolution: a
/// thirtieth of a second, the rate the app sends frames at while the simulation runs.
pub const FRAME_BUDGET: Duration = Duration::from_millis(33);

/// The kitty image id of the pane (one image, replaced by every frame).
const KITTY_ID: u32 = 0x0053_4c42;

/// The kitty image id of the plots' picture.
const KITTY_PLOTS_ID: u32 = KITTY_ID + 1;

/// What decides a renderer's geometry: rebuilt when any of it changes.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Key {
    generation: u64,
    width: u32,
    height: u32,
    filter: SpringFilter,
    overlay: bool,
}

/// The rasteriser set up for one lesson scene at one image size, kept between frames.
#[derive(Debug, Default)]
pub struct PaneRenderer {
    cached: Option<(Key, Renderer)>,
}

/// The line weight of a `height` px high picture of the pane: [`Style::PANE_LINE_WEIGHT`] from
/// 160 px up (the raster view, the export), 1 below (the half-block view's few pixels, where a
/// 1 px line is already half a cell).
#[must_use]
pub fn pane_line_weight(height: u32) -> f32 {
    if height >= 160 {
        Style::PANE_LINE_WEIGHT
    } else {
        1.0
    }
}

/// The style of the terminal's frames: springs by `filter`, no overlay unless `overlay`.
#[must_use]
pub fn pane_style(filter: SpringFilter, overlay: bool) -> Style {
    let springs = [SpringKind::Struct, SpringKind::Shear, SpringKind::Bend]
        .into_iter()
        .fold(KindToggles::NONE, |t, k| t.with(k, filter.shows(k)));
    Style {
        springs,
        overlay,
        ..Style::default()
    }
}

impl PaneRenderer {
    /// Draws `scene` seen by `camera` on a `width × height` image (each side clamped to
    /// 1 … [`MAX_SIDE`]). `generation` names the scene's structure: the renderer's geometry
    /// (surfaces, bowls) is rebuilt when it changes. Small images get thicker lines. With
    /// `overlay` the image is taller: the overlay's bands above and below
    /// ([`Renderer::draw_captioned`]).
    pub fn draw(
        &mut self,
        scene: &Scene,
        generation: u64,
        camera: &Camera,
        filter: SpringFilter,
        size: (u32, u32),
        overlay: Option<&crate::render::Overlay>,
    ) -> Pixmap {
        let key = Key {
            generation,
            width: size.0.clamp(1, MAX_SIDE),
            height: size.1.clamp(1, MAX_SIDE),
            filter,
            overlay: overlay.is_some(),
        };
        if self.cached.as_ref().is_none_or(|(k, _)| *k != key) {
            let mut r = Renderer::with_camera(
                scene,
                key.width,
                key.height,
                *camera,
                Style {
                    line_weight: pane_line_weight(key.height),
                    ..pane_style(filter, overlay.is_some())
                },
            );
            // A line at least ~1.2 px wide at any size.
            r.set_min_line_scale(0.6 * (120.0 / key.height as f32).clamp(0.3, 1.0));
            self.cached = Some((key, r));
        }
        let (_, r) = self.cached.as_mut().expect("set above");
        r.camera = *camera;
        r.refit_floors(scene);
        match overlay {
            // The overlay in bands above and below the picture (the export), never on it.
            Some(o) => r.draw_captioned(scene, o),
            None => r.draw(scene, None),
        }
    }
}

/// `pixmap` (premultiplied RGBA, opaque background) as an image with straight alpha.
#[must_use]
pub fn to_image(pixmap: &Pixmap) -> RgbaImage {
    let mut out = RgbaImage::new(pixmap.width(), pixmap.height());
    for (dst, src) in out.as_raw_mut().chunks_exact_mut(4).zip(pixmap.pixels()) {
        let c = src.demultiply();
        dst.copy_from_slice(&[c.red(), c.green(), c.blue(), c.alpha()]);
    }
    out
}

/// Encodes `image` for `protocol`, to be shown on `cells` (columns, rows).
///
/// # Errors
/// The encoder's message.
pub fn encode(
    image: RgbaImage,
    protocol: Protocol,
    cells: Size,
    tmux_wrap: bool,
) -> Result<Encoded, String> {
    encode_as(image, protocol, cells, tmux_wrap, KITTY_ID)
}

/// [`encode`] with the kitty image id `id`.
fn encode_as(
    image: RgbaImage,
    protocol: Protocol,
    cells: Size,
    tmux_wrap: bool,
    id: u32,
) -> Result<Encoded, String> {
    if image.width() == 0 || image.height() == 0 {
        return Err(format!(
            "cannot encode an empty image ({} × {} pixels)",
            image.width(),
            image.height()
        ));
    }
    match protocol {
        Protocol::Sixel => Ok(Encoded::Sixel(Sequence {
            data: sixel_sequence(&image, cells, tmux_wrap),
            size: cells,
        })),
        Protocol::Kitty => Ok(Encoded::Kitty(encoded::kitty(&image, cells, id, tmux_wrap))),
        Protocol::Iterm2 => encoded::iterm2(&image, cells, tmux_wrap).map(Encoded::Iterm2),
    }
}

/// `image` as a sixel sequence for `cells` ([`sixel::encode`]), preceded by erasing those cells
/// (so that nothing of the text under the image shows where it is transparent), wrapped for
/// tmux when asked.
fn sixel_sequence(image: &RgbaImage, cells: Size, tmux_wrap: bool) -> String {
    let encoded = sixel::encode(image);
    let mut data = String::with_capacity(encoded.len() + 16 * usize::from(cells.height));
    // ECH (erase w characters), then down a line; back up at the end.
    for _ in 0..cells.height {
        data.push_str(&format!("\x1b[{}X\x1b[1B", cells.width));
    }
    data.push_str(&format!("\x1b[{}A", cells.height));
    data.push_str(&encoded);
    super::graphics::wrap(&data, tmux_wrap)
}

/// The kitty command that deletes the pane's image and frees its memory in the terminal (sent
/// on exit), wrapped for tmux when `tmux_wrap`.
#[must_use]
pub fn kitty_delete(tmux_wrap: bool) -> String {
    let mut out = String::new();
    for id in [KITTY_ID, KITTY_PLOTS_ID] {
        out.push_str(&super::graphics::wrap(
            &format!("\x1b_Ga=d,d=I,i={id}\x1b\\"),
            tmux_wrap,
        ));
    }
    out
}

/// One frame to draw and encode.
#[derive(Clone, Debug)]
pub struct Job {
    /// The scene at the moment to show.
    pub scene: Scene,
    /// Its structure's generation (see [`PaneRenderer::draw`]).
    pub generation: u64,
    /// The camera.
    pub camera: Camera,
    /// Springs shown.
    pub filter: SpringFilter,
    /// The pane's inner size in cells.
    pub cells: Size,
    /// The protocol, cell size and tmux wrapping.
    pub graphics: Graphics,
    /// Increases with every job; the frame carries it back.
    pub stamp: u64,
    /// Draw at full resolution whatever the last frames took (the simulation is paused).
    pub full: bool,
    /// The plots to draw as a second image, when they changed.
    pub picture: Option<Picture>,
}

/// The plots' picture, drawn and encoded.
pub struct PictureFrame {
    /// The encoded image.
    pub encoded: Encoded,
    /// The cells it covers.
    pub area: Rect,
    /// The stamp of the job that carried it.
    pub stamp: u64,
}

impl std::fmt::Debug for PictureFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PictureFrame")
            .field("area", &self.area)
            .field("stamp", &self.stamp)
            .finish_non_exhaustive()
    }
}

/// A drawn and encoded frame.
pub struct Frame {
    /// The encoded image.
    pub encoded: Encoded,
    /// The cells it covers.
    pub cells: Size,
    /// The job's stamp.
    pub stamp: u64,
    /// Wall time of drawing and encoding.
    pub took: Duration,
    /// Resolution it was drawn at, as a fraction of the pane's pixels (1 = full).
    pub scale: f64,
}

impl std::fmt::Debug for Frame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Frame")
            .field("cells", &self.cells)
            .field("stamp", &self.stamp)
            .field("took", &self.took)
            .field("scale", &self.scale)
            .finish_non_exhaustive()
    }
}

/// What the encoder thread sends back for a job: the scene's frame and, when the job carried
/// one, the plots' picture.
type Encoded2 = (Result<Frame, String>, Option<Result<PictureFrame, String>>);

/// The encoder thread and what is in flight.
#[derive(Debug)]
pub struct Encoder {
    jobs: SyncSender<Job>,
    frames: Receiver<Encoded2>,
    /// A job waiting for the encoder to be free (only the newest is kept).
    pending: Option<Job>,
    busy: bool,
    latest: Option<Frame>,
    /// The newest picture of the plots.
    latest_picture: Option<PictureFrame>,
    /// The last error, shown instead of a frame.
    error: Option<String>,
}

impl Encoder {
    /// Starts the encoder thread (it ends when the encoder is dropped); `None` when the system
    /// cannot start a thread.
    #[must_use]
    pub fn new() -> Option<Encoder> {
        let (jobs, job_rx) = sync_channel::<Job>(1);
        let (frame_tx, frames) = sync_channel(1);
        std::thread::Builder::new()
            .name("springlab-raster".into())
            .spawn(move || {
                let mut renderer = PaneRenderer::default();
                let mut scale = 1.0f64;
                while let Ok(job) = job_rx.recv() {
                    let started = Instant::now();
                    let result = encode_job(&mut renderer, &job, scale);
                    let took = started.elapsed();
                    scale = next_scale(scale, took);
                    let picture = job.picture.as_ref().map(|p| encode_picture(p, &job));
                    let frame = result.map(|(encoded, used)| Frame {
                        encoded,
                        cells: job.cells,
                        stamp: job.stamp,
                        took,
                        scale: used,
                    });
                    let sent = frame_tx.send((frame, picture));
                    if sent.is_err() {
                        break;
                    }
                }
            })
            .ok()?;
        Some(Encoder {
            jobs,
            frames,
            pending: None,
            busy: false,
            latest: None,
            latest_picture: None,
            error: None,
        })
    }

    /// Queues `job`: sent at once when the encoder is free, else kept (replacing an older one).
    pub fn submit(&mut self, mut job: Job) {
        if self.busy {
            // A newer job without a picture keeps the waiting one's.
            if job.picture.is_none() {
                job.picture = self.pending.take().and_then(|p| p.picture);
            }
            self.pending = Some(job);
        } else if self.jobs.try_send(job).is_ok() {
            self.busy = true;
        }
    }

    /// Takes a finished frame, if any, and sends the pending job; true when a frame arrived.
    pub fn poll(&mut self) -> bool {
        match self.frames.try_recv() {
            Ok((result, picture)) => {
                match picture {
                    Some(Ok(p)) => self.latest_picture = Some(p),
                    Some(Err(e)) => self.error = Some(e),
                    None => {}
                }
                match result {
                    Ok(frame) => {
                        self.latest = Some(frame);
                        self.error = None;
                    }
                    Err(e) => self.error = Some(e),
                }
                self.busy = false;
                if let Some(job) = self.pending.take() {
                    self.submit(job);
                }
                true
            }
            Err(TryRecvError::Empty | TryRecvError::Disconnected) => false,
        }
    }

    /// Waits up to `timeout` for a frame (for tests and for a paused app); true when one came.
    pub fn wait(&mut self, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        loop {
            if self.poll() {
                return true;
            }
            if !self.busy || Instant::now() >= deadline {
                return false;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// True while a job is being encoded.
    #[must_use]
    pub fn busy(&self) -> bool {
        self.busy
    }

    /// The newest frame.
    #[must_use]
    pub fn latest(&self) -> Option<&Frame> {
        self.latest.as_ref()
    }

    /// The newest picture of the plots.
    #[must_use]
    pub fn latest_picture(&self) -> Option<&PictureFrame> {
        self.latest_picture.as_ref()
    }

    /// The last encoding error, if the last frame failed.
    #[must_use]
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Forgets the newest frame (the pane changed size or the screen was left).
    pub fn clear(&mut self) {
        self.latest = None;
        self.latest_picture = None;
    }
}

/// The pane's image size in pixels for `cells` at `cell` pixels a cell, times `scale`.
#[must_use]
pub fn pixel_size(cells: Size, cell: (u16, u16), scale: f64) -> (u32, u32) {
    let w = f64::from(cells.width) * f64::from(cell.0) * scale;
    let h = f64::from(cells.height) * f64::from(cell.1) * scale;
    (
        (w.round() as u32).clamp(1, MAX_SIDE),
        (h.round() as u32).clamp(1, MAX_SIDE),
    )
}

/// Draws and encodes `job` at `scale` of the pane's resolution (sixel always at full size).
fn encode_job(
    renderer: &mut PaneRenderer,
    job: &Job,
    scale: f64,
) -> Result<(Encoded, f64), String> {
    let protocol = job.graphics.protocol.ok_or("no graphics protocol")?;
    let scale = if job.full { 1.0 } else { scale };
    let full = pixel_size(job.cells, job.graphics.cell, 1.0);
    let size = pixel_size(job.cells, job.graphics.cell, scale);
    let pixmap = renderer.draw(
        &job.scene,
        job.generation,
        &job.camera,
        job.filter,
        size,
        None,
    );
    let mut image = to_image(&pixmap);
    if size != full {
        image = image.resize_nearest(full.0, full.1);
    }
    let encoded = encode(image, protocol, job.cells, job.graphics.tmux_wrap)?;
    Ok((encoded, scale))
}

/// Draws and encodes the plots' `picture` of `job` at full resolution.
fn encode_picture(picture: &Picture, job: &Job) -> Result<PictureFrame, String> {
    let protocol = job.graphics.protocol.ok_or("no graphics protocol")?;
    let cells = Size::new(picture.area.width, picture.area.height);
    let (w, h) = pixel_size(cells, job.graphics.cell, 1.0);
    let image = to_image(&super::plots::picture::draw(picture, w, h));
    let encoded = encode_as(
        image,
        protocol,
        cells,
        job.graphics.tmux_wrap,
        KITTY_PLOTS_ID,
    )?;
    Ok(PictureFrame {
        encoded,
        area: picture.area,
        stamp: job.stamp,
    })
}

/// The resolution of the next frame: 20 % lower after a frame over [`FRAME_BUDGET`], back up
/// by 10 % after one under half of it; between 0.3 and 1.
fn next_scale(scale: f64, took: Duration) -> f64 {
    if took > FRAME_BUDGET {
        (scale * 0.8).max(0.3)
    } else if took < FRAME_BUDGET / 2 {
        (scale * 1.1).min(1.0)
    } else {
        scale
    }
}
