//! Writing frames: numbered PNG files, an animated GIF and an animated PNG (APNG), encoded on a
//! thread of their own.
//!
//! The drawing thread hands each finished [`Pixmap`] to a [`FrameEncoder`] through a bounded
//! channel ([`std::sync::mpsc::sync_channel`] with [`QUEUE`] slots): drawing the next frame
//! overlaps with compressing the last one, and a slow encoder holds the drawing thread back
//! after a few frames instead of filling the memory. Frames are encoded one at a time in the
//! order they were sent, so the files are the same bytes on every run.
//!
//! - PNG: 8-bit RGB, `frame_00000.png`, `frame_00001.png`, … (png crate, fast deflate).
//! - GIF: each frame quantised to its own 256-colour palette by NeuQuant (gif crate,
//!   `Frame::from_rgb_speed`), delay `round(100 / fps)` hundredths of a second, looping.
//! - APNG: 8-bit RGB frames with delay `round(1000 / fps)` ms, looping. Its header (`acTL`)
//!   names the frame count before any frame is written; when fewer frames arrive (the run
//!   diverged) the count is corrected in the finished file and its checksum recomputed.
//!
//! All pixmaps drawn by this crate are opaque, so their premultiplied colours are the plain
//! colours; a translucent pixel is un-premultiplied (`c · 255 / α`) before encoding.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use tiny_skia::Pixmap;

use super::RenderError;

/// Frames that may wait for the encoder before the drawing thread blocks.
pub const QUEUE: usize = 3;

/// Where the frames go.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outputs {
    /// Directory for `frame_NNNNN.png` files (created if missing), or none.
    pub frames_dir: Option<PathBuf>,
    /// Animated GIF file, or none.
    pub gif: Option<PathBuf>,
    /// Animated PNG file, or none.
    pub apng: Option<PathBuf>,
    /// Playback rate of the GIF and APNG (frames per second), > 0.
    pub fps: f64,
    /// Frames expected (written into the APNG header; fewer may arrive).
    pub expected_frames: u32,
}

/// What the encoder wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Written {
    /// Frames encoded.
    pub frames: u32,
}

/// The path of frame `index` in `dir`: `dir/frame_00042.png`.
#[must_use]
pub fn frame_path(dir: &Path, index: u32) -> PathBuf {
    dir.join(format!("frame_{index:05}.png"))
}

/// Encodes frames on a background thread (module docs).
pub struct FrameEncoder {
    sender: Option<SyncSender<Pixmap>>,
    handle: Option<JoinHandle<Result<Written, RenderError>>>,
}

impl FrameEncoder {
    /// Creates the output directory and files and starts the encoder thread for frames of
    /// `width × height` pixels.
    ///
    /// # Errors
    /// [`RenderError::Io`] when the directory or a file cannot be created (for example the
    /// directory's path is a file), [`RenderError::Encode`] when a GIF cannot have that size.
    pub fn start(outputs: Outputs, width: u32, height: u32) -> Result<FrameEncoder, RenderError> {
        if let Some(dir) = &outputs.frames_dir {
            create_dir(dir)?;
        }
        let gif = match &outputs.gif {
            Some(path) => Some(gif_encoder(path, width, height, outputs.fps)?),
            None => None,
        };
        let apng = match &outputs.apng {
            Some(path) => Some((path.clone(), create(path)?)),
            None => None,
        };
        let (sender, receiver) = sync_channel::<Pixmap>(QUEUE);
        let handle = std::thread::Builder::new()
            .name("springlab-encoder".into())
            .spawn(move || encode_all(&receiver, &outputs, gif, apng, width, height))
            .map_err(|e| RenderError::Io {
                path: "encoder thread".into(),
                source: e,
            })?;
        Ok(FrameEncoder {
            sender: Some(sender),
            handle: Some(handle),
        })
    }

    /// Queues a frame; blocks while [`QUEUE`] frames are waiting.
    ///
    /// # Errors
    /// The encoder's error when it has stopped (a file could not be written).
    pub fn send(&mut self, frame: Pixmap) -> Result<(), RenderError> {
        let failed = match &self.sender {
            Some(s) => s.send(frame).is_err(),
            None => true,
        };
        if failed {
            // The encoder hung up: it failed; its error says why.
            self.sender = None;
            return match self.join() {
                Err(e) => Err(e),
                Ok(_) => Err(RenderError::Encode {
                    path: "frames".into(),
                    message: "the encoder stopped early".into(),
                }),
            };
        }
        Ok(())
    }

    /// Waits until every queued frame is written and the files are closed.
    ///
    /// # Errors
    /// The first error of the encoder.
    pub fn finish(mut self) -> Result<Written, RenderError> {
        self.sender = None;
        self.join()
    }

    fn join(&mut self) -> Result<Written, RenderError> {
        match self.handle.take() {
            Some(h) => h.join().unwrap_or_else(|_| {
                Err(RenderError::Encode {
                    path: "frames".into(),
                    message: "the encoder thread panicked".into(),
                })
            }),
            None => Ok(Written::default()),
        }
    }
}

impl Drop for FrameEncoder {
    fn drop(&mut self) {
        self.sender = None;
        let _ = self.join();
    }
}

type GifEncoder = (PathBuf, gif::Encoder<BufWriter<File>>, u16);

/// The encoder thread: every frame into every output, then the APNG file.
fn encode_all(
    receiver: &Receiver<Pixmap>,
    outputs: &Outputs,
    mut gif: Option<GifEncoder>,
    apng: Option<(PathBuf, File)>,
    width: u32,
    height: u32,
) -> Result<Written, RenderError> {
    let mut apng_bytes = Vec::new();
    let mut frames = 0u32;
    {
        let mut apng_writer = match &apng {
            Some((path, _)) => Some(apng_writer(
                &mut apng_bytes,
                path,
                width,
                height,
                outputs.fps,
                outputs.expected_frames.max(1),
            )?),
            None => None,
        };
        for pixmap in receiver {
            let rgb = to_rgb(&pixmap);
            if let Some(dir) = &outputs.frames_dir {
                let path = frame_path(dir, frames);
                write_png(&path, &rgb, width, height)?;
            }
            if let Some((path, encoder, delay)) = gif.as_mut() {
                let mut frame = gif::Frame::from_rgb_speed(width as u16, height as u16, &rgb, 10);
                frame.delay = *delay;
                encoder
                    .write_frame(&frame)
                    .map_err(|e| encode_error(path, e))?;
            }
            if let (Some(w), Some((path, _))) = (apng_writer.as_mut(), &apng) {
                w.write_image_data(&rgb)
                    .map_err(|e| encode_error(path, e))?;
            }
            frames += 1;
        }
        if let (Some(w), Some((path, _))) = (apng_writer, &apng) {
            w.finish().map_err(|e| encode_error(path, e))?;
        }
    }
    if let Some((path, encoder, _)) = gif {
        let mut out = encoder.into_inner().map_err(|e| encode_error(&path, e))?;
        out.flush().map_err(|e| io_error(&path, e))?;
    }
    if let Some((path, mut file)) = apng {
        if frames < outputs.expected_frames {
            set_apng_frame_count(&mut apng_bytes, frames);
        }
        file.write_all(&apng_bytes)
            .and_then(|()| file.flush())
            .map_err(|e| io_error(&path, e))?;
    }
    Ok(Written { frames })
}

fn io_error(path: &Path, source: std::io::Error) -> RenderError {
    RenderError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn encode_error(path: &Path, e: impl std::fmt::Display) -> RenderError {
    RenderError::Encode {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Creates `dir` and its parents; an existing directory is fine, a file is not.
fn create_dir(dir: &Path) -> Result<(), RenderError> {
    fs::create_dir_all(dir).map_err(|e| io_error(dir, e))?;
    if !dir.is_dir() {
        return Err(io_error(
            dir,
            std::io::Error::new(std::io::ErrorKind::NotADirectory, "not a directory"),
        ));
    }
    Ok(())
}

fn create(path: &Path) -> Result<File, RenderError> {
    File::create(path).map_err(|e| io_error(path, e))
}

fn gif_encoder(path: &Path, width: u32, height: u32, fps: f64) -> Result<GifEncoder, RenderError> {
    let (w, h) = (
        u16::try_from(width).map_err(|e| encode_error(path, e))?,
        u16::try_from(height).map_err(|e| encode_error(path, e))?,
    );
    let file = create(path)?;
    let mut encoder =
        gif::Encoder::new(BufWriter::new(file), w, h, &[]).map_err(|e| encode_error(path, e))?;
    encoder
        .set_repeat(gif::Repeat::Infinite)
        .map_err(|e| encode_error(path, e))?;
    // GIF delays are in hundredths of a second.
    let delay = (100.0 / fps).round().clamp(1.0, f64::from(u16::MAX)) as u16;
    Ok((path.to_path_buf(), encoder, delay))
}

fn apng_writer<'a>(
    bytes: &'a mut Vec<u8>,
    path: &Path,
    width: u32,
    height: u32,
    fps: f64,
    frames: u32,
) -> Result<png::Writer<&'a mut Vec<u8>>, RenderError> {
    let mut encoder = png::Encoder::new(bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder
        .set_animated(frames, 0)
        .map_err(|e| encode_error(path, e))?;
    let delay_ms = (1000.0 / fps).round().clamp(1.0, f64::from(u16::MAX)) as u16;
    encoder
        .set_frame_delay(delay_ms, 1000)
        .map_err(|e| encode_error(path, e))?;
    encoder.write_header().map_err(|e| encode_error(path, e))
}

/// Rewrites the frame count of an APNG's `acTL` chunk and its CRC (module docs).
fn set_apng_frame_count(bytes: &mut [u8], frames: u32) {
    let Some(at) = bytes.windows(4).position(|w| w == b"acTL") else {
        return;
    };
    // Chunk: length (4) | type "acTL" (4) | num_frames (4) | num_plays (4) | CRC of type+data (4).
    if at + 16 > bytes.len() {
        return;
    }
    bytes[at + 4..at + 8].copy_from_slice(&frames.to_be_bytes());
    let crc = crc32fast::hash(&bytes[at..at + 12]);
    bytes[at + 12..at + 16].copy_from_slice(&crc.to_be_bytes());
}

/// The pixmap as 8-bit RGB rows, un-premultiplied.
#[must_use]
pub fn to_rgb(pixmap: &Pixmap) -> Vec<u8> {
    let mut rgb = Vec::with_capacity(pixmap.width() as usize * pixmap.height() as usize * 3);
    for p in pixmap.pixels() {
        let a = p.alpha();
        if a == 255 {
            rgb.extend_from_slice(&[p.red(), p.green(), p.blue()]);
        } else {
            let c = p.demultiply();
            rgb.extend_from_slice(&[c.red(), c.green(), c.blue()]);
        }
    }
    rgb
}

/// Writes 8-bit RGB rows as a PNG file (fast deflate).
///
/// # Errors
/// [`RenderError::Io`] or [`RenderError::Encode`] naming `path`.
pub fn write_png(path: &Path, rgb: &[u8], width: u32, height: u32) -> Result<(), RenderError> {
    let file = create(path)?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(|e| encode_error(path, e))?;
    writer
        .write_image_data(rgb)
        .map_err(|e| encode_error(path, e))?;
    writer.finish().map_err(|e| encode_error(path, e))
}

/// Writes a pixmap as a PNG file.
///
/// # Errors
/// As [`write_png`].
pub fn save_png(pixmap: &Pixmap, path: &Path) -> Result<(), RenderError> {
    write_png(path, &to_rgb(pixmap), pixmap.width(), pixmap.height())
}
