//! The raster view's escape sequences, decoded back by independent decoders written here from
//! the protocols' specifications: DEC sixel (VT330/VT340 programmer reference, chapter 14) and
//! kitty's graphics protocol (direct transmission of 32-bit RGBA, base64, chunked, with a
//! virtual placement shown through Unicode placeholders).

use image::RgbaImage;
use ratatui::buffer::Buffer;
use ratatui::layout::{Rect, Size};
use springlab::tui::Protocol;
use springlab::tui::raster::{encode, show, to_image};

/// A 12 × 18 test image: four flat quadrants (red, green, blue, white) and a grey bottom third.
fn known_image() -> RgbaImage {
    RgbaImage::from_fn(12, 18, |x, y| {
        let c = if y >= 12 {
            [128, 128, 128]
        } else {
            match (x < 6, y < 6) {
                (true, true) => [220, 30, 40],
                (false, true) => [20, 200, 60],
                (true, false) => [30, 60, 210],
                (false, false) => [255, 255, 255],
            }
        };
        image::Rgba([c[0], c[1], c[2], 255])
    })
}

/// The escape data the frame puts into the buffer (its first cell) and the buffer.
fn emitted(protocol: Protocol, tmux: bool) -> (String, Buffer) {
    let cells = Size::new(2, 2);
    let encoded = encode(known_image(), protocol, cells, tmux).expect("encodes");
    let area = Rect::new(0, 0, 4, 3);
    let mut buf = Buffer::empty(area);
    show(&encoded, area, &mut buf);
    (buf[(0, 0)].symbol().to_string(), buf)
}

/// Decodes the first sixel image in `data`: `ESC P … q`, raster attributes `"1;1;W;H`, colour
/// definitions `#n;2;r;g;b` (percent), colour selection `#n`, sixel characters `?`–`~` (six
/// pixels of a column, low bit on top), repeats `!n c`, `$` (back to the band's start) and `-`
/// (next band of six rows). Returns the size and the RGB of every pixel (None where unpainted).
fn decode_sixel(data: &str) -> (usize, usize, Vec<Option<[u8; 3]>>) {
    let start = data.find("\x1bP").expect("DCS");
    let q = start + data[start..].find('q').expect("sixel introducer");
    let end = q + data[q..].find("\x1b\\").expect("string terminator");
    let body: Vec<char> = data[q + 1..end].chars().collect();
    let mut palette = vec![[0u8; 3]; 256];
    let (mut width, mut height) = (0usize, 0usize);
    let mut pixels: Vec<Option<[u8; 3]>> = Vec::new();
    let (mut x, mut band, mut colour) = (0usize, 0usize, 0usize);
    let number = |i: &mut usize| -> usize {
        let mut n = 0;
        while *i < body.len() && body[*i].is_ascii_digit() {
            n = n * 10 + body[*i].to_digit(10).expect("digit") as usize;
            *i += 1;
        }
        n
    };
    let mut i = 0;
    while i < body.len() {
        match body[i] {
            '"' => {
                i += 1;
                let mut v = Vec::new();
                loop {
                    v.push(number(&mut i));
                    if i < body.len() && body[i] == ';' {
                        i += 1;
                    } else {
                        break;
                    }
                }
                width = v[2];
                height = v[3];
                pixels = vec![None; width * height];
            }
            '#' => {
                i += 1;
                let n = number(&mut i);
                if i < body.len() && body[i] == ';' {
                    let mut v = Vec::new();
                    while i < body.len() && body[i] == ';' {
                        i += 1;
                        v.push(number(&mut i));
                    }
                    assert_eq!(v[0], 2, "RGB colour space");
                    let pct = |p: usize| ((p * 255 + 50) / 100) as u8;
                    palette[n] = [pct(v[1]), pct(v[2]), pct(v[3])];
                } else {
                    colour = n;
                }
            }
            '$' => {
                x = 0;
                i += 1;
            }
            '-' => {
                x = 0;
                band += 1;
                i += 1;
            }
            '!' => {
                i += 1;
                let n = number(&mut i);
                let c = body[i];
                for _ in 0..n {
                    paint(&mut pixels, width, height, x, band, c, palette[colour]);
                    x += 1;
                }
                i += 1;
            }
            c @ '?'..='~' => {
                paint(&mut pixels, width, height, x, band, c, palette[colour]);
                x += 1;
                i += 1;
            }
            _ => i += 1,
        }
    }
    (width, height, pixels)
}

fn paint(
    pixels: &mut [Option<[u8; 3]>],
    width: usize,
    height: usize,
    x: usize,
    band: usize,
    c: char,
    rgb: [u8; 3],
) {
    let bits = c as u32 - '?' as u32;
    for k in 0..6 {
        let y = band * 6 + k;
        if bits & (1 << k) != 0 && x < width && y < height {
            pixels[y * width + x] = Some(rgb);
        }
    }
}

#[test]
fn sixel_decodes_back_to_the_image() {
    let (data, buf) = emitted(Protocol::Sixel, false);
    let (w, h, pixels) = decode_sixel(&data);
    let image = known_image();
    assert_eq!((w, h), (12, 18));
    for y in 0..h {
        for x in 0..w {
            let want = image.get_pixel(x as u32, y as u32).0;
            let got = pixels[y * w + x].unwrap_or_else(|| panic!("pixel ({x}, {y}) unpainted"));
            for c in 0..3 {
                // Sixel colours are whole percents: within 255/200 + rounding of the truth.
                assert!(
                    got[c].abs_diff(want[c]) <= 3,
                    "pixel ({x}, {y}): {got:?} vs {want:?}"
                );
            }
        }
    }
    // The other cells of the image's area are left to the image (skipped when drawing).
    assert!(buf[(1, 1)].symbol().is_empty() || buf[(1, 1)].symbol() == " ");
}

#[test]
fn sixel_in_tmux_is_wrapped_with_doubled_escapes() {
    let (plain, _) = emitted(Protocol::Sixel, false);
    let (wrapped, _) = emitted(Protocol::Sixel, true);
    assert!(wrapped.starts_with("\x1bPtmux;") && wrapped.ends_with("\x1b\\"));
    let inner = &wrapped["\x1bPtmux;".len()..wrapped.len() - 2];
    assert_eq!(inner.replace("\x1b\x1b", "\x1b"), plain);
}

/// Standard base64 (RFC 4648) without line breaks.
fn base64_decode(s: &str) -> Vec<u8> {
    let value = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let bytes: Vec<u8> = s.bytes().filter(|&c| c != b'=').collect();
    let mut out = Vec::new();
    for chunk in bytes.chunks(4) {
        let mut n = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            n |= value(c) << (18 - 6 * k);
        }
        let keep = chunk.len() * 6 / 8;
        out.extend_from_slice(&n.to_be_bytes()[1..1 + keep]);
    }
    out
}

#[test]
fn kitty_transmits_the_exact_pixels_and_places_them_with_placeholders() {
    let (data, buf) = emitted(Protocol::Kitty, false);
    // Chunks: ESC _G <control> ; <base64> ESC \
    let mut payload = String::new();
    let mut controls = Vec::new();
    for chunk in data.split("\x1b_G").skip(1) {
        let end = chunk.find("\x1b\\").expect("terminator");
        let (control, base64) = chunk[..end].split_once(';').expect("control;payload");
        controls.push(control.to_string());
        payload.push_str(base64);
    }
    let first: Vec<&str> = controls[0].split(',').collect();
    for key in ["a=T", "U=1", "f=32", "t=d", "s=12", "v=18"] {
        assert!(first.contains(&key), "{key} in {first:?}");
    }
    assert!(controls.last().expect("chunks").contains("m=0"));
    // On exit the app deletes that image by its id (and the plots' picture, the next id).
    let id = first
        .iter()
        .find(|k| k.starts_with("i="))
        .expect("an image id");
    let next: u32 = id[2..].parse::<u32>().expect("a number") + 1;
    assert_eq!(
        springlab::tui::raster::kitty_delete(false),
        format!("\x1b_Ga=d,d=I,{id}\x1b\\\x1b_Ga=d,d=I,i={next}\x1b\\")
    );
    let rgba = base64_decode(&payload);
    assert_eq!(rgba, known_image().into_raw(), "the pixels, bit for bit");
    // Every cell of the 2 × 2 placement holds the placeholder U+10EEEE in the id's colour.
    let fg = buf[(0, 0)].fg;
    for (x, y) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        assert!(
            buf[(x, y)].symbol().contains('\u{10EEEE}'),
            "cell ({x}, {y})"
        );
        assert_eq!(buf[(x, y)].fg, fg);
    }
    assert!(!buf[(2, 0)].symbol().contains('\u{10EEEE}'));
}

#[test]
fn iterm2_sends_a_png_of_the_image() {
    let (data, _) = emitted(Protocol::Iterm2, false);
    let start = data.find("\x1b]1337;File=").expect("OSC 1337");
    let colon = start + data[start..].find(':').expect("arguments end");
    let end = colon + data[colon..].find('\x07').expect("BEL");
    let png = base64_decode(&data[colon + 1..end]);
    let decoded = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
        .expect("a PNG")
        .to_rgba8();
    assert_eq!(decoded, known_image());
}

#[test]
fn premultiplied_pixmaps_become_straight_alpha() {
    let mut pixmap = tiny_skia::Pixmap::new(2, 1).expect("pixmap");
    pixmap.pixels_mut()[0] =
        tiny_skia::PremultipliedColorU8::from_rgba(100, 50, 0, 128).expect("valid");
    pixmap.pixels_mut()[1] =
        tiny_skia::PremultipliedColorU8::from_rgba(10, 20, 30, 255).expect("valid");
    let image = to_image(&pixmap);
    assert_eq!(image.get_pixel(0, 0).0, [199, 100, 0, 128]);
    assert_eq!(image.get_pixel(1, 0).0, [10, 20, 30, 255]);
}

/// The rope of lesson 1 drawn in the raster pane at `w × h` pixels, with the renderer's
/// default camera for that aspect.
fn rope_pane(w: u32, h: u32) -> tiny_skia::Pixmap {
    use springlab::render::{Camera, Projection};
    use springlab::tui::pane::SpringFilter;
    use springlab::tui::raster::PaneRenderer;
    let scene = springlab::scene::load("rope", &[]).expect("the rope");
    let camera = Camera::for_scene(&scene, f64::from(w) / f64::from(h), Projection::default());
    PaneRenderer::default().draw(&scene, 0, &camera, SpringFilter::All, (w, h), None)
}

/// Coverage of colour `c` in pixel `p`: 1 for the colour itself, 0 for anything at least 120
/// away in some channel, linear between (anti-aliased edges count in part).
fn coverage(p: tiny_skia::PremultipliedColorU8, c: springlab::render::Colour) -> f64 {
    let q = p.demultiply();
    let d = [
        (i32::from(q.red()) - i32::from(c.r)).abs(),
        (i32::from(q.green()) - i32::from(c.g)).abs(),
        (i32::from(q.blue()) - i32::from(c.b)).abs(),
    ]
    .into_iter()
    .max()
    .unwrap_or(0);
    (1.0 - f64::from(d) / 120.0).max(0.0)
}

/// The rope's line width in pixels: per column crossed by the (near horizontal) rope the
/// summed coverage of the struct-spring colour, the median over those columns.
fn rope_width(p: &tiny_skia::Pixmap) -> f64 {
    use springlab::render::colour::STRUCT;
    let mut per_column: Vec<f64> = (0..p.width())
        .map(|x| {
            (0..p.height())
                .map(|y| coverage(p.pixel(x, y).expect("pixel"), STRUCT))
                .sum::<f64>()
        })
        .filter(|&s| s > 0.5)
        .collect();
    assert!(per_column.len() > 20, "the rope crosses the image");
    per_column.sort_by(f64::total_cmp);
    per_column[per_column.len() / 2]
}

#[test]
fn the_rope_line_grows_with_the_pane_and_pins_are_marked() {
    let small = rope_width(&rope_pane(420, 240));
    let medium = rope_width(&rope_pane(560, 320));
    let large = rope_width(&rope_pane(1120, 640));
    // A typical raster pane (70 × 20 cells of 8 × 16 px): more than a hairline.
    assert!(medium >= 2.0, "rope {medium:.2} px wide at 560 × 320");
    assert!(small < medium && medium < large, "{small} {medium} {large}");
    assert!(large > 1.6 * medium, "{medium} → {large}");
    // Pinned particles: red squares; free ones: dark discs. Both there, told apart by colour.
    use springlab::render::colour::{PARTICLE, PINNED};
    let p = rope_pane(560, 320);
    let pin: f64 = p.pixels().iter().map(|&q| coverage(q, PINNED)).sum();
    let free: f64 = p.pixels().iter().map(|&q| coverage(q, PARTICLE)).sum();
    // The marker is at least 5 × 5 px (a square of side ≥ 2 × 2.5 × line scale).
    assert!(pin >= 25.0, "pin marker: {pin:.1} px");
    assert!(free >= 9.0, "free particles: {free:.1} px");
}
