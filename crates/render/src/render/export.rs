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
//! Every file is complete or absent ([`crate::output`]): the GIF and the APNG are written to
//! temporary files and put at their targets by [`FrameEncoder::finish`]; the PNG frames are
//! staged in a hidden folder `.springlab-frames.XXXXXX` inside the frames' directory and moved
//! into it, frame by frame, only by [`FrameEncoder::finish`], so a run stopped early leaves no
//! partial frame set mixed with the directory's files (after a `kill -9`, at most the hidden
//! folder). [`FrameEncoder::abort`] (Ctrl-C, a terminating signal) and an error remove the
//! temporary files and the staged frames. [`stale_frames`] names the frames of an earlier
//! render that a shorter one would leave beside its own.
//!
//! All pixmaps drawn by this crate are opaque, so their premultiplied colours are the plain
//! colours; a translucent pixel is un-premultiplied (`c · 255 / α`) before encoding.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use tiny_skia::Pixmap;

use super::RenderError;
use crate::output::AtomicFile;

/// Frames that may wait for the encoder before the drawing thread blocks.
pub const QUEUE: usize = 3;

/// Bytes per pixel while rendering, for the budget: the frame being drawn and the frames queued
/// for the encoder (4 × RGBA each), the RGB copy, and the GIF encoder's RGBA copy and palette
/// indices.
pub const PIXEL_BYTES: f64 = (4 * (2 + QUEUE) + 3 + 4 + 1) as f64;

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
    handle: Option<JoinHandle<Encoded>>,
    /// The frames' directory and the hidden folder inside it where the frames are staged
    /// (removed with everything in it when dropped).
    frames: Option<(PathBuf, tempfile::TempDir)>,
}

/// What the encoder thread hands back: the frames written, the animations not yet renamed into
/// place, and the first error.
struct Encoded {
    frames: u32,
    pending: Vec<AtomicFile>,
    error: Option<RenderError>,
}

impl FrameEncoder {
    /// Creates the output directory and the animations' temporary files and starts the encoder
    /// thread for frames of `width × height` pixels.
    ///
    /// # Errors
    /// [`RenderError::Io`] when the directory or a file cannot be created (for example the
    /// directory's path is a file), [`RenderError::Encode`] when a GIF cannot have that size.
    pub fn start(
        mut outputs: Outputs,
        width: u32,
        height: u32,
    ) -> Result<FrameEncoder, RenderError> {
        let frames = match outputs.frames_dir.take() {
            Some(dir) => {
                create_dir(&dir)?;
                let staging = tempfile::Builder::new()
                    .prefix(".springlab-frames.")
                    .tempdir_in(&dir)
                    .map_err(|e| io_error(&dir, e))?;
                // The encoder writes into the hidden folder.
                outputs.frames_dir = Some(staging.path().to_path_buf());
                Some((dir, staging))
            }
            None => None,
        };
        let gif = match &outputs.gif {
            Some(path) => Some(gif_encoder(path, width, height, outputs.fps)?),
            None => None,
        };
        let apng = match &outputs.apng {
            Some(path) => Some(BufWriter::new(create(path)?)),
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
            frames,
        })
    }

    /// Queues a frame; blocks while [`QUEUE`] frames are waiting.
    ///
    /// # Errors
    /// The encoder's error when it has stopped (a file could not be written); the outputs are
    /// then removed as by [`FrameEncoder::abort`].
    pub fn send(&mut self, frame: Pixmap) -> Result<(), RenderError> {
        let failed = match &self.sender {
            Some(s) => s.send(frame).is_err(),
            None => true,
        };
        if failed {
            // The encoder hung up: it failed; its error says why.
            self.sender = None;
            let error = self.join().and_then(|e| e.error);
            self.frames = None;
            return Err(error.unwrap_or_else(|| RenderError::Encode {
                path: "frames".into(),
                message: "the encoder stopped early".into(),
            }));
        }
        Ok(())
    }

    /// Waits until every queued frame is written, then puts the GIF and the APNG at their
    /// targets and moves the staged frames into the frames' directory.
    ///
    /// # Errors
    /// The first error of the encoder (the outputs are then removed), or a frame that cannot
    /// be moved in (a `frame_NNNNN.png` there that is not a regular file is never replaced).
    pub fn finish(mut self) -> Result<Written, RenderError> {
        self.sender = None;
        let encoded = self.join().ok_or_else(|| RenderError::Encode {
            path: "frames".into(),
            message: "the encoder thread panicked".into(),
        })?;
        if let Some(e) = encoded.error {
            self.frames = None;
            return Err(e);
        }
        for file in encoded.pending {
            let path = file.path().to_path_buf();
            file.commit().map_err(|e| io_error(&path, e))?;
        }
        if let Some((dir, staging)) = self.frames.take() {
            for index in 0..encoded.frames {
                let to = frame_path(&dir, index);
                if let Ok(m) = fs::symlink_metadata(&to)
                    && !m.is_file()
                {
                    return Err(io_error(
                        &to,
                        std::io::Error::other("it is not a regular file; it was not replaced"),
                    ));
                }
                fs::rename(frame_path(staging.path(), index), &to).map_err(|e| io_error(&to, e))?;
            }
        }
        Ok(Written {
            frames: encoded.frames,
        })
    }

    /// Stops encoding and removes every output of this run: the animations' temporary files
    /// and the staged PNG frames (Ctrl-C, a terminating signal, or an error elsewhere).
    pub fn abort(mut self) {
        self.sender = None;
        drop(self.join());
        self.frames = None;
    }

    fn join(&mut self) -> Option<Encoded> {
        self.handle.take().and_then(|h| h.join().ok())
    }
}

impl Drop for FrameEncoder {
    /// Dropped without [`FrameEncoder::finish`]: nothing is kept (as [`FrameEncoder::abort`]).
    fn drop(&mut self) {
        self.sender = None;
        drop(self.join());
        self.frames = None;
    }
}

/// The frames `frame_NNNNN.png` in `dir` numbered `written` or more, in order: what an earlier,
/// longer render left that a render of `written` frames does not replace.
#[must_use]
pub fn stale_frames(dir: &Path, written: u32) -> Vec<PathBuf> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut stale: Vec<(u64, PathBuf)> = entries
        .filter_map(Result::ok)
        .filter_map(|e| {
            let name = e.file_name();
            let digits = name
                .to_str()?
                .strip_prefix("frame_")?
                .strip_suffix(".png")?;
            let index = (digits.len() >= 5 && digits.bytes().all(|b| b.is_ascii_digit()))
                .then(|| digits.parse::<u64>().ok())??;
            (index >= u64::from(written)).then(|| (index, e.path()))
        })
        .collect();
    stale.sort();
    stale.into_iter().map(|(_, p)| p).collect()
}

type GifEncoder = (PathBuf, gif::Encoder<BufWriter<AtomicFile>>, u16);

/// The encoder thread: every frame into every output; the animations stay at their temporary
/// paths until [`FrameEncoder::finish`] renames them.
fn encode_all(
    receiver: &Receiver<Pixmap>,
    outputs: &Outputs,
    gif: Option<GifEncoder>,
    apng: Option<BufWriter<AtomicFile>>,
    width: u32,
    height: u32,
) -> Encoded {
    let mut encoded = Encoded {
        frames: 0,
        pending: Vec::new(),
        error: None,
    };
    if let Err(e) = encode_frames(receiver, outputs, gif, apng, width, height, &mut encoded) {
        encoded.error = Some(e);
        encoded.pending.clear();
    }
    encoded
}

fn encode_frames(
    receiver: &Receiver<Pixmap>,
    outputs: &Outputs,
    mut gif: Option<GifEncoder>,
    mut apng: Option<BufWriter<AtomicFile>>,
    width: u32,
    height: u32,
    encoded: &mut Encoded,
) -> Result<(), RenderError> {
    let apng_path = outputs.apng.clone().unwrap_or_default();
    {
        let mut apng_writer = match apng.as_mut() {
            Some(w) => Some(apng_writer(
                w,
                &apng_path,
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
                let path = frame_path(dir, encoded.frames);
                write_png(&path, &rgb, width, height)?;
            }
            if let Some((path, encoder, delay)) = gif.as_mut() {
                let mut frame = gif::Frame::from_rgb_speed(width as u16, height as u16, &rgb, 10);
                frame.delay = *delay;
                encoder
                    .write_frame(&frame)
                    .map_err(|e| encode_error(path, e))?;
            }
            if let Some(w) = apng_writer.as_mut() {
                w.write_image_data(&rgb)
                    .map_err(|e| encode_error(&apng_path, e))?;
            }
            encoded.frames += 1;
        }
        if let Some(w) = apng_writer {
            w.finish().map_err(|e| encode_error(&apng_path, e))?;
        }
    }
    if let Some((path, encoder, _)) = gif {
        let out = encoder.into_inner().map_err(|e| encode_error(&path, e))?;
        let file = out
            .into_inner()
            .map_err(|e| io_error(&path, e.into_error()))?;
        encoded.pending.push(file);
    }
    if let Some(w) = apng {
        let mut file = w
            .into_inner()
            .map_err(|e| io_error(&apng_path, e.into_error()))?;
        if encoded.frames < outputs.expected_frames {
            set_apng_frame_count(&mut file, encoded.frames).map_err(|e| io_error(&apng_path, e))?;
        }
        encoded.pending.push(file);
    }
    Ok(())
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

/// A temporary file beside `path`, renamed over it when complete ([`AtomicFile`]).
fn create(path: &Path) -> Result<AtomicFile, RenderError> {
    AtomicFile::create(path).map_err(|e| io_error(path, e))
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
    out: &'a mut BufWriter<AtomicFile>,
    path: &Path,
    width: u32,
    height: u32,
    fps: f64,
    frames: u32,
) -> Result<png::Writer<&'a mut BufWriter<AtomicFile>>, RenderError> {
    let mut encoder = png::Encoder::new(out, width, height);
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

/// Rewrites the frame count of the `acTL` chunk in the head of an APNG file, and its CRC.
fn set_apng_frame_count(file: &mut AtomicFile, frames: u32) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut head = vec![0u8; 256];
    file.seek(SeekFrom::Start(0))?;
    let n = file.file().read(&mut head)?;
    head.truncate(n);
    set_apng_frame_count_bytes(&mut head, frames);
    file.seek(SeekFrom::Start(0))?;
    file.write_all(&head)?;
    file.flush()
}

/// Rewrites the frame count of an APNG's `acTL` chunk and its CRC (module docs).
fn set_apng_frame_count_bytes(bytes: &mut [u8], frames: u32) {
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
    let mut out = BufWriter::new(create(path)?);
    {
        let mut encoder = png::Encoder::new(&mut out, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header().map_err(|e| encode_error(path, e))?;
        writer
            .write_image_data(rgb)
            .map_err(|e| encode_error(path, e))?;
        writer.finish().map_err(|e| encode_error(path, e))?;
    }
    out.into_inner()
        .map_err(std::io::IntoInnerError::into_error)
        .and_then(AtomicFile::commit)
        .map_err(|e| io_error(path, e))
}

/// Writes a pixmap as a PNG file.
///
/// # Errors
/// As [`write_png`].
pub fn save_png(pixmap: &Pixmap, path: &Path) -> Result<(), RenderError> {
    write_png(path, &to_rgb(pixmap), pixmap.width(), pixmap.height())
}
