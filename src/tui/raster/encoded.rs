//! An encoded frame and how it is placed in the terminal's cell buffer: the kitty and iTerm2
//! writers (the sixel one is [`super::sixel`]).
//!
//! - **kitty** (graphics protocol, <https://sw.kovidgoyal.net/kitty/graphics-protocol/>): the
//!   32-bit RGBA pixels sent once, base64 in chunks of 4096 characters
//!   (`ESC _G q=2,i=ID,a=T,U=1,f=32,t=d,s=W,v=H,m=1;… ESC \`), as a virtual placement (`U=1`);
//!   every cell of the image then holds the placeholder character U+10EEEE in the colour that
//!   names the image id (red, green, blue = the id's low three bytes) and, in a row's first
//!   cell, diacritics that give the row, the column and the id's high byte. The terminal
//!   draws the image where the placeholders are, so the image moves and clips with the text.
//! - **iTerm2** (inline images, `OSC 1337 ; File=inline=1;size=N;width=Wpx;height=Hpx;
//!   doNotMoveCursor=1 : base64 PNG BEL`), after erasing the image's cells.
//! - **sixel**: the sequence of [`super::sixel`], after erasing the image's cells.
//!
//! Inside tmux each sequence is wrapped in tmux's passthrough (`ESC P tmux; … ESC \`, every
//! escape inside doubled); kitty's in one passthrough per chunk, since tmux limits how much one
//! passthrough may carry.
//!
//! Sixel and iTerm2 images are escape sequences written at the image's top-left cell: that cell
//! holds the whole sequence (one column wide) and the image's other cells are skipped when the
//! buffer is copied to the screen, so text drawn before does not overwrite the image.

use std::fmt::Write as _;
use std::num::NonZeroU16;
use std::sync::atomic::{AtomicBool, Ordering};

use ratatui::buffer::{Buffer, CellDiffOption};
use ratatui::layout::{Rect, Size};
use ratatui::style::Color;

use super::image::RgbaImage;

/// The character kitty reserves for image placeholders.
const PLACEHOLDER: char = '\u{10EEEE}';

/// Base64 characters per kitty chunk (the protocol's limit).
const KITTY_CHUNK: usize = 4096;

/// A cell that holds an escape sequence counts one column, whatever the sequence's text.
const ONE_COLUMN: CellDiffOption = CellDiffOption::ForcedWidth(NonZeroU16::MIN);

/// A frame encoded for the terminal, placed by [`show`].
#[derive(Debug)]
pub enum Encoded {
    /// A sixel sequence (with the erasing of its cells).
    Sixel(Sequence),
    /// An iTerm2 inline image (with the erasing of its cells).
    Iterm2(Sequence),
    /// A kitty image: sent with the first placement, then placeholders only.
    Kitty(Kitty),
}

/// A sequence written at the image's top-left cell, covering `size` cells.
#[derive(Debug)]
pub struct Sequence {
    /// The escape sequence.
    pub data: String,
    /// The cells it covers (columns, rows).
    pub size: Size,
}

/// A kitty image: its transmission, sent with the first placement only, and its id.
#[derive(Debug)]
pub struct Kitty {
    /// The transmission (chunks of `ESC _G … ESC \`).
    pub transmit: String,
    /// True once a placement has carried the transmission.
    sent: AtomicBool,
    /// The image id.
    pub id: u32,
    /// The cells it covers (columns, rows).
    pub size: Size,
}

/// tmux's passthrough: (start, escape, end) around and inside a sequence.
fn tmux_parts(tmux: bool) -> (&'static str, &'static str, &'static str) {
    if tmux {
        ("\x1bPtmux;", "\x1b\x1b", "\x1b\\")
    } else {
        ("", "\x1b", "")
    }
}

/// Erases `width × height` cells from the cursor (ECH on each row, cursor down, then back up).
fn clear_area(out: &mut String, escape: &str, width: u16, height: u16) {
    if height == 1 {
        let _ = write!(out, "{escape}[{width}X");
    } else {
        for _ in 0..height {
            let _ = write!(out, "{escape}[{width}X{escape}[1B");
        }
        let _ = write!(out, "{escape}[{height}A");
    }
}

/// Standard base64 (RFC 4648, with `=` padding) of `bytes`, appended to `out`.
pub fn base64_append(bytes: &[u8], out: &mut String) {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let sextet = |n: u32, k: u32| ALPHABET[(n >> (18 - 6 * k)) as usize & 63];
    let mut buf = Vec::with_capacity(bytes.len().div_ceil(3) * 4);
    let mut chunks = bytes.chunks_exact(3);
    for c in &mut chunks {
        let n = u32::from(c[0]) << 16 | u32::from(c[1]) << 8 | u32::from(c[2]);
        buf.extend_from_slice(&[sextet(n, 0), sextet(n, 1), sextet(n, 2), sextet(n, 3)]);
    }
    match *chunks.remainder() {
        [a] => {
            let n = u32::from(a) << 16;
            buf.extend_from_slice(&[sextet(n, 0), sextet(n, 1), b'=', b'=']);
        }
        [a, b] => {
            let n = u32::from(a) << 16 | u32::from(b) << 8;
            buf.extend_from_slice(&[sextet(n, 0), sextet(n, 1), sextet(n, 2), b'=']);
        }
        _ => {}
    }
    out.push_str(std::str::from_utf8(&buf).expect("base64 is ASCII"));
}

/// `image` as a kitty image with id `id` on `size` cells (module docs).
#[must_use]
pub fn kitty(image: &RgbaImage, size: Size, id: u32, tmux: bool) -> Kitty {
    let (start, escape, end) = tmux_parts(tmux);
    let raw = image.as_raw();
    let chunk_bytes = KITTY_CHUNK / 4 * 3;
    let count = raw.len().div_ceil(chunk_bytes).max(1);
    let mut data = String::with_capacity(count * (KITTY_CHUNK + 40) + 64);
    for i in 0..count {
        let chunk = &raw[(i * chunk_bytes).min(raw.len())..((i + 1) * chunk_bytes).min(raw.len())];
        data.push_str(start);
        let _ = write!(data, "{escape}_Gq=2,");
        if i == 0 {
            let _ = write!(
                data,
                "i={id},a=T,U=1,f=32,t=d,s={},v={},",
                image.width(),
                image.height()
            );
        }
        let _ = write!(data, "m={};", u8::from(i + 1 < count));
        base64_append(chunk, &mut data);
        let _ = write!(data, "{escape}\\");
        data.push_str(end);
    }
    Kitty {
        transmit: data,
        sent: AtomicBool::new(false),
        id,
        size,
    }
}

/// `image` as an iTerm2 inline image (a PNG) on `size` cells (module docs).
///
/// # Errors
/// The PNG encoder's message.
pub fn iterm2(image: &RgbaImage, size: Size, tmux: bool) -> Result<Sequence, String> {
    let mut png = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png, image.width(), image.height());
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder
            .write_header()
            .map_err(|e| format!("PNG encoding: {e}"))?;
        writer
            .write_image_data(image.as_raw())
            .map_err(|e| format!("PNG encoding: {e}"))?;
    }
    let (start, escape, end) = tmux_parts(tmux);
    let mut data = String::with_capacity(png.len() * 4 / 3 + 128);
    data.push_str(start);
    clear_area(&mut data, escape, size.width, size.height);
    let _ = write!(
        data,
        "{escape}]1337;File=inline=1;size={};width={}px;height={}px;doNotMoveCursor=1:",
        png.len(),
        image.width(),
        image.height()
    );
    base64_append(&png, &mut data);
    data.push('\x07');
    data.push_str(end);
    Ok(Sequence { data, size })
}

/// Places `frame` with its top-left corner at `area`'s: a sixel or iTerm2 image only when it
/// fits in `area`; a kitty image clipped to `area`.
pub fn show(frame: &Encoded, area: Rect, buf: &mut Buffer) {
    if area.width == 0 || area.height == 0 {
        return;
    }
    match frame {
        Encoded::Sixel(s) | Encoded::Iterm2(s) => place_sequence(s, area, buf),
        Encoded::Kitty(k) => place_kitty(k, area, buf),
    }
}

/// The sequence at the top-left cell, the image's other cells skipped.
fn place_sequence(s: &Sequence, area: Rect, buf: &mut Buffer) {
    if s.size.width > area.width || s.size.height > area.height {
        return;
    }
    let image = Rect::new(area.x, area.y, s.size.width, s.size.height);
    for y in image.top()..image.bottom() {
        for x in image.left()..image.right() {
            let Some(cell) = buf.cell_mut((x, y)) else {
                continue;
            };
            if (x, y) == (image.x, image.y) {
                cell.set_symbol(&s.data).set_diff_option(ONE_COLUMN);
            } else {
                cell.set_diff_option(CellDiffOption::Skip);
            }
        }
    }
}

/// The placeholders of a kitty image (module docs), the transmission in the first cell the
/// first time.
fn place_kitty(k: &Kitty, area: Rect, buf: &mut Buffer) {
    let [high, r, g, b] = k.id.to_be_bytes();
    let fg = Color::Rgb(r, g, b);
    let most = DIACRITICS.len() as u16;
    let width = area.width.min(k.size.width).min(most);
    let height = area.height.min(k.size.height).min(most);
    let mut transmit = (!k.sent.swap(true, Ordering::SeqCst)).then_some(k.transmit.as_str());
    let mut symbol = String::with_capacity(64);
    for y in 0..height {
        for x in 0..width {
            let Some(cell) = buf.cell_mut((area.left() + x, area.top() + y)) else {
                continue;
            };
            symbol.clear();
            if let Some(t) = transmit.take() {
                symbol.push_str(t);
            }
            symbol.push(PLACEHOLDER);
            if x == 0 {
                symbol.push(DIACRITICS[usize::from(y)]);
                symbol.push(DIACRITICS[0]);
                symbol.push(DIACRITICS[usize::from(high)]);
            }
            cell.set_symbol(&symbol)
                .set_fg(fg)
                .set_diff_option(ONE_COLUMN);
        }
    }
}

/// The combining characters that number rows, columns and the id's high byte in kitty's
/// placeholders, in order (the protocol's `rowcolumn-diacritics.txt`): the n-th stands for n.
static DIACRITICS: [char; 297] = [
    '\u{305}',
    '\u{30D}',
    '\u{30E}',
    '\u{310}',
    '\u{312}',
    '\u{33D}',
    '\u{33E}',
    '\u{33F}',
    '\u{346}',
    '\u{34A}',
    '\u{34B}',
    '\u{34C}',
    '\u{350}',
    '\u{351}',
    '\u{352}',
    '\u{357}',
    '\u{35B}',
    '\u{363}',
    '\u{364}',
    '\u{365}',
    '\u{366}',
    '\u{367}',
    '\u{368}',
    '\u{369}',
    '\u{36A}',
    '\u{36B}',
    '\u{36C}',
    '\u{36D}',
    '\u{36E}',
    '\u{36F}',
    '\u{483}',
    '\u{484}',
    '\u{485}',
    '\u{486}',
    '\u{487}',
    '\u{592}',
    '\u{593}',
    '\u{594}',
    '\u{595}',
    '\u{597}',
    '\u{598}',
    '\u{599}',
    '\u{59C}',
    '\u{59D}',
    '\u{59E}',
    '\u{59F}',
    '\u{5A0}',
    '\u{5A1}',
    '\u{5A8}',
    '\u{5A9}',
    '\u{5AB}',
    '\u{5AC}',
    '\u{5AF}',
    '\u{5C4}',
    '\u{610}',
    '\u{611}',
    '\u{612}',
    '\u{613}',
    '\u{614}',
    '\u{615}',
    '\u{616}',
    '\u{617}',
    '\u{657}',
    '\u{658}',
    '\u{659}',
    '\u{65A}',
    '\u{65B}',
    '\u{65D}',
    '\u{65E}',
    '\u{6D6}',
    '\u{6D7}',
    '\u{6D8}',
    '\u{6D9}',
    '\u{6DA}',
    '\u{6DB}',
    '\u{6DC}',
    '\u{6DF}',
    '\u{6E0}',
    '\u{6E1}',
    '\u{6E2}',
    '\u{6E4}',
    '\u{6E7}',
    '\u{6E8}',
    '\u{6EB}',
    '\u{6EC}',
    '\u{730}',
    '\u{732}',
    '\u{733}',
    '\u{735}',
    '\u{736}',
    '\u{73A}',
    '\u{73D}',
    '\u{73F}',
    '\u{740}',
    '\u{741}',
    '\u{743}',
    '\u{745}',
    '\u{747}',
    '\u{749}',
    '\u{74A}',
    '\u{7EB}',
    '\u{7EC}',
    '\u{7ED}',
    '\u{7EE}',
    '\u{7EF}',
    '\u{7F0}',
    '\u{7F1}',
    '\u{7F3}',
    '\u{816}',
    '\u{817}',
    '\u{818}',
    '\u{819}',
    '\u{81B}',
    '\u{81C}',
    '\u{81D}',
    '\u{81E}',
    '\u{81F}',
    '\u{820}',
    '\u{821}',
    '\u{822}',
    '\u{823}',
    '\u{825}',
    '\u{826}',
    '\u{827}',
    '\u{829}',
    '\u{82A}',
    '\u{82B}',
    '\u{82C}',
    '\u{82D}',
    '\u{951}',
    '\u{953}',
    '\u{954}',
    '\u{F82}',
    '\u{F83}',
    '\u{F86}',
    '\u{F87}',
    '\u{135D}',
    '\u{135E}',
    '\u{135F}',
    '\u{17DD}',
    '\u{193A}',
    '\u{1A17}',
    '\u{1A75}',
    '\u{1A76}',
    '\u{1A77}',
    '\u{1A78}',
    '\u{1A79}',
    '\u{1A7A}',
    '\u{1A7B}',
    '\u{1A7C}',
    '\u{1B6B}',
    '\u{1B6D}',
    '\u{1B6E}',
    '\u{1B6F}',
    '\u{1B70}',
    '\u{1B71}',
    '\u{1B72}',
    '\u{1B73}',
    '\u{1CD0}',
    '\u{1CD1}',
    '\u{1CD2}',
    '\u{1CDA}',
    '\u{1CDB}',
    '\u{1CE0}',
    '\u{1DC0}',
    '\u{1DC1}',
    '\u{1DC3}',
    '\u{1DC4}',
    '\u{1DC5}',
    '\u{1DC6}',
    '\u{1DC7}',
    '\u{1DC8}',
    '\u{1DC9}',
    '\u{1DCB}',
    '\u{1DCC}',
    '\u{1DD1}',
    '\u{1DD2}',
    '\u{1DD3}',
    '\u{1DD4}',
    '\u{1DD5}',
    '\u{1DD6}',
    '\u{1DD7}',
    '\u{1DD8}',
    '\u{1DD9}',
    '\u{1DDA}',
    '\u{1DDB}',
    '\u{1DDC}',
    '\u{1DDD}',
    '\u{1DDE}',
    '\u{1DDF}',
    '\u{1DE0}',
    '\u{1DE1}',
    '\u{1DE2}',
    '\u{1DE3}',
    '\u{1DE4}',
    '\u{1DE5}',
    '\u{1DE6}',
    '\u{1DFE}',
    '\u{20D0}',
    '\u{20D1}',
    '\u{20D4}',
    '\u{20D5}',
    '\u{20D6}',
    '\u{20D7}',
    '\u{20DB}',
    '\u{20DC}',
    '\u{20E1}',
    '\u{20E7}',
    '\u{20E9}',
    '\u{20F0}',
    '\u{2CEF}',
    '\u{2CF0}',
    '\u{2CF1}',
    '\u{2DE0}',
    '\u{2DE1}',
    '\u{2DE2}',
    '\u{2DE3}',
    '\u{2DE4}',
    '\u{2DE5}',
    '\u{2DE6}',
    '\u{2DE7}',
    '\u{2DE8}',
    '\u{2DE9}',
    '\u{2DEA}',
    '\u{2DEB}',
    '\u{2DEC}',
    '\u{2DED}',
    '\u{2DEE}',
    '\u{2DEF}',
    '\u{2DF0}',
    '\u{2DF1}',
    '\u{2DF2}',
    '\u{2DF3}',
    '\u{2DF4}',
    '\u{2DF5}',
    '\u{2DF6}',
    '\u{2DF7}',
    '\u{2DF8}',
    '\u{2DF9}',
    '\u{2DFA}',
    '\u{2DFB}',
    '\u{2DFC}',
    '\u{2DFD}',
    '\u{2DFE}',
    '\u{2DFF}',
    '\u{A66F}',
    '\u{A67C}',
    '\u{A67D}',
    '\u{A6F0}',
    '\u{A6F1}',
    '\u{A8E0}',
    '\u{A8E1}',
    '\u{A8E2}',
    '\u{A8E3}',
    '\u{A8E4}',
    '\u{A8E5}',
    '\u{A8E6}',
    '\u{A8E7}',
    '\u{A8E8}',
    '\u{A8E9}',
    '\u{A8EA}',
    '\u{A8EB}',
    '\u{A8EC}',
    '\u{A8ED}',
    '\u{A8EE}',
    '\u{A8EF}',
    '\u{A8F0}',
    '\u{A8F1}',
    '\u{AAB0}',
    '\u{AAB2}',
    '\u{AAB3}',
    '\u{AAB7}',
    '\u{AAB8}',
    '\u{AABE}',
    '\u{AABF}',
    '\u{AAC1}',
    '\u{FE20}',
    '\u{FE21}',
    '\u{FE22}',
    '\u{FE23}',
    '\u{FE24}',
    '\u{FE25}',
    '\u{FE26}',
    '\u{10A0F}',
    '\u{10A38}',
    '\u{1D185}',
    '\u{1D186}',
    '\u{1D187}',
    '\u{1D188}',
    '\u{1D189}',
    '\u{1D1AA}',
    '\u{1D1AB}',
    '\u{1D1AC}',
    '\u{1D1AD}',
    '\u{1D242}',
    '\u{1D243}',
    '\u{1D244}',
];
