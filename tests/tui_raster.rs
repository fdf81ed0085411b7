//! The raster view's escape sequences, decoded back by independent decoders written here from
//! the protocols' specifications: DEC sixel (VT330/VT340 programmer reference, chapter 14) and
//! kitty's graphics protocol (direct transmission of 32-bit RGBA, base64, chunked, with a
//! virtual placement shown through Unicode placeholders).

use ratatui::buffer::Buffer;
use ratatui::layout::{Rect, Size};
use springlab::tui::Protocol;
use springlab::tui::raster::{RgbaImage, encode, show, to_image};

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
        [c[0], c[1], c[2], 255]
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
            let want = image.pixel(x as u32, y as u32);
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

/// A PNG's size and RGBA pixels (the `png` crate's decoder, expanded to 8-bit RGBA).
fn decode_png(png: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(png));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().expect("a PNG");
    let mut out = vec![0; reader.output_buffer_size().expect("fits")];
    let info = reader.next_frame(&mut out).expect("a frame");
    assert_eq!(info.color_type, png::ColorType::Rgba, "RGBA");
    out.truncate(info.buffer_size());
    (info.width, info.height, out)
}

#[test]
fn iterm2_sends_a_png_of_the_image() {
    let (data, _) = emitted(Protocol::Iterm2, false);
    let start = data.find("\x1b]1337;File=").expect("OSC 1337");
    let colon = start + data[start..].find(':').expect("arguments end");
    let end = colon + data[colon..].find('\x07').expect("BEL");
    let png = base64_decode(&data[colon + 1..end]);
    let (w, h, rgba) = decode_png(&png);
    assert_eq!((w, h), (12, 18));
    assert_eq!(rgba, known_image().into_raw());
}

#[test]
fn premultiplied_pixmaps_become_straight_alpha() {
    let mut pixmap = tiny_skia::Pixmap::new(2, 1).expect("pixmap");
    pixmap.pixels_mut()[0] =
        tiny_skia::PremultipliedColorU8::from_rgba(100, 50, 0, 128).expect("valid");
    pixmap.pixels_mut()[1] =
        tiny_skia::PremultipliedColorU8::from_rgba(10, 20, 30, 255).expect("valid");
    let image = to_image(&pixmap);
    assert_eq!(image.pixel(0, 0), [199, 100, 0, 128]);
    assert_eq!(image.pixel(1, 0), [10, 20, 30, 255]);
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

/// The golden files' second image: 40 × 30, a gradient in every channel, its first column
/// transparent (kitty sends it in two chunks).
fn gradient_image() -> RgbaImage {
    RgbaImage::from_fn(40, 30, |x, y| {
        let a = if x == 0 { 0 } else { 255 };
        [(x * 6) as u8, (y * 8) as u8, ((x * y) % 256) as u8, a]
    })
}

/// The golden files' third image: 9 × 4 on a single row of cells.
fn strip_image() -> RgbaImage {
    RgbaImage::from_fn(9, 4, |x, y| [(x * 28) as u8, 200, (y * 60) as u8, 255])
}

/// The buffer, a cell a line: column, row, foreground, diff option, symbol (escaped).
fn dump(buf: &Buffer) -> Vec<String> {
    let mut out = Vec::new();
    for y in 0..buf.area.height {
        for x in 0..buf.area.width {
            let c = &buf[(x, y)];
            out.push(format!(
                "{x} {y} {:?} {:?} {}",
                c.fg,
                c.diff_option,
                c.symbol().escape_debug()
            ));
        }
    }
    out
}

/// The text of `line` between `from` and `to` (both found after `from`'s end).
fn between<'a>(line: &'a str, from: &str, to: &str) -> &'a str {
    let start = line.find(from).expect("start marker") + from.len();
    let end = start + line[start..].find(to).expect("end marker");
    &line[start..end]
}

/// What the kitty, iTerm2 and sixel frames put into the cell buffer, drawn twice (kitty sends
/// its pixels only the first time), against golden files recorded from the writers springlab
/// used before its own (ratatui-image 11.1 and icy_sixel 0.5): kitty byte for byte; iTerm2 byte
/// for byte but for the PNG inside (another PNG encoder; its pixels decoded and compared) and
/// its length; sixel byte for byte but for the sixel data itself (another palette; decoded
/// back by the tests above).
#[test]
fn frames_are_placed_as_the_recorded_golden_files() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/images/protocols");
    type Case = (&'static str, fn() -> RgbaImage, Size, Rect);
    let cases: [Case; 3] = [
        ("a", known_image, Size::new(2, 2), Rect::new(0, 0, 4, 3)),
        ("b", gradient_image, Size::new(5, 2), Rect::new(1, 1, 6, 3)),
        ("c", strip_image, Size::new(3, 1), Rect::new(0, 0, 3, 1)),
    ];
    let protocols = [
        ("kitty", Protocol::Kitty),
        ("iterm2", Protocol::Iterm2),
        ("sixel", Protocol::Sixel),
    ];
    let mut compared = 0;
    for (name, image, cells, area) in cases {
        for (pname, protocol) in protocols {
            for tmux in [false, true] {
                let file = format!("{pname}-{name}{}.txt", if tmux { "-tmux" } else { "" });
                let golden = std::fs::read_to_string(dir.join(&file)).expect("golden file");
                let encoded = encode(image(), protocol, cells, tmux).expect("encodes");
                let whole = Rect::new(0, 0, area.right() + 1, area.bottom() + 1);
                let mut lines = Vec::new();
                for pass in 0..2 {
                    if pass == 1 {
                        lines.push("--- again".to_string());
                    }
                    let mut buf = Buffer::empty(whole);
                    show(&encoded, area, &mut buf);
                    lines.extend(dump(&buf));
                }
                let want: Vec<&str> = golden.lines().collect();
                assert_eq!(lines.len(), want.len(), "{file}: cells");
                for (got, want) in lines.iter().zip(&want) {
                    if got == want {
                        continue;
                    }
                    match protocol {
                        Protocol::Kitty => panic!("{file}: {got}\nwant {want}"),
                        Protocol::Iterm2 => {
                            let head = |l: &str| l[..l.find("size=").expect("size")].to_string();
                            let tail = |l: &str| l[l.find(";width=").expect("w")..].to_string();
                            let args = |l: &str| between(l, ";width=", ":").to_string();
                            assert_eq!(head(got), head(want), "{file}");
                            assert_eq!(args(got), args(want), "{file}");
                            let end = |l: &str| {
                                let t = tail(l);
                                t[t.find("\\u{7}").expect("BEL")..].to_string()
                            };
                            assert_eq!(end(got), end(want), "{file}");
                            let pixels =
                                |l: &str| decode_png(&base64_decode(between(l, "=1:", "\\u{7}")));
                            assert_eq!(pixels(got), pixels(want), "{file}: the PNG's pixels");
                        }
                        Protocol::Sixel => {
                            let head = |l: &str| l[..l.find("q\\\"").expect("q")].to_string();
                            assert_eq!(head(got), head(want), "{file}");
                            let raster = |l: &str| between(l, "q\\\"", "#").to_string();
                            assert_eq!(raster(got), raster(want), "{file}: raster attributes");
                            let end = |l: &str| l[l.rfind('-').expect("a band")..].to_string();
                            assert_eq!(end(got), end(want), "{file}");
                        }
                    }
                }
                compared += 1;
            }
        }
    }
    assert_eq!(compared, 18);
}

/// Mean and largest channel difference between `image` (opaque) and a decoded sixel.
fn colour_error(image: &RgbaImage, pixels: &[Option<[u8; 3]>]) -> (f64, u8) {
    let mut sum = 0.0;
    let mut largest = 0;
    for (i, got) in pixels.iter().enumerate() {
        let (x, y) = (
            (i % image.width() as usize) as u32,
            (i / image.width() as usize) as u32,
        );
        let want = image.pixel(x, y);
        let got = got.unwrap_or_else(|| panic!("pixel ({x}, {y}) unpainted"));
        for c in 0..3 {
            let d = got[c].abs_diff(want[c]);
            sum += f64::from(d);
            largest = largest.max(d);
        }
    }
    (sum / (3 * pixels.len()) as f64, largest)
}

/// A real frame (the rope of lesson 1 at 560 × 320 pixels, anti-aliased) decodes back to its
/// own size, in ⌈320 / 6⌉ = 54 bands, every pixel painted, within the palette's bound: a
/// frame with at most 256 histogram bins (32 levels a channel) keeps one entry per bin, the
/// mean of its pixels, so no channel is off by more than a bin's width (7) plus the whole
/// percents' rounding (2), and on average by less than 2 (measured: 1.2; the background's
/// shading puts several colours in one bin).
#[test]
fn a_frame_in_sixel_keeps_its_size_bands_and_colours() {
    let image = to_image(&rope_pane(560, 320));
    let encoded = encode(image.clone(), Protocol::Sixel, Size::new(70, 20), false).expect("ok");
    let springlab::tui::raster::Encoded::Sixel(s) = &encoded else {
        panic!("a sixel frame")
    };
    let sixel = &s.data[s.data.find("\x1bP").expect("DCS")..];
    assert_eq!(sixel.matches('-').count(), 54, "bands");
    let (w, h, pixels) = decode_sixel(sixel);
    assert_eq!((w, h), (560, 320));
    let palette = springlab::tui::raster::sixel::palette(&image);
    let bins: std::collections::HashSet<[u8; 3]> = image
        .as_raw()
        .chunks_exact(4)
        .map(|p| [p[0] >> 3, p[1] >> 3, p[2] >> 3])
        .collect();
    assert!(bins.len() <= 256, "{} bins", bins.len());
    assert_eq!(palette.colours.len(), bins.len(), "one entry per bin");
    let (mean, largest) = colour_error(&image, &pixels);
    assert!(largest <= 9, "largest difference {largest}");
    assert!(mean < 2.0, "mean difference {mean:.3}");
}

/// More colours than a palette holds: a 64 × 64 image of 4096 colours (red and green in
/// 16 levels, blue from both). The median cut's 256 entries must each stand for about 16 of
/// them: every channel within 1/16 of its range, on average within 1/50 (measured: 7 and 3.5).
#[test]
fn many_colours_are_cut_to_256_entries() {
    let image = RgbaImage::from_fn(64, 64, |x, y| {
        [(x * 4) as u8, (y * 4) as u8, ((x + y) * 2) as u8, 255]
    });
    let palette = springlab::tui::raster::sixel::palette(&image);
    assert_eq!(palette.colours.len(), 256);
    let encoded = encode(image.clone(), Protocol::Sixel, Size::new(8, 4), false).expect("ok");
    let springlab::tui::raster::Encoded::Sixel(s) = &encoded else {
        panic!("a sixel frame")
    };
    let (w, h, pixels) = decode_sixel(&s.data);
    assert_eq!((w, h), (64, 64));
    assert_eq!(s.data.matches('-').count(), 11, "⌈64 / 6⌉ bands");
    let (mean, largest) = colour_error(&image, &pixels);
    assert!(largest <= 16, "largest difference {largest}");
    assert!(mean <= 5.1, "mean difference {mean:.3}");
}

/// Transparent pixels (alpha < 128) are left unpainted: the terminal's background shows.
#[test]
fn transparent_pixels_stay_unpainted_in_sixel() {
    let image = gradient_image();
    let encoded = encode(image.clone(), Protocol::Sixel, Size::new(5, 2), false).expect("ok");
    let springlab::tui::raster::Encoded::Sixel(s) = &encoded else {
        panic!("a sixel frame")
    };
    let (w, h, pixels) = decode_sixel(&s.data);
    for y in 0..h {
        for x in 0..w {
            assert_eq!(pixels[y * w + x].is_none(), x == 0, "({x}, {y})");
        }
    }
}

/// A frame drawn at a lower resolution is enlarged by the nearest pixel: each target pixel
/// takes the source pixel under its centre.
#[test]
fn nearest_enlargement_takes_the_pixel_under_each_centre() {
    let small = RgbaImage::from_fn(3, 2, |x, y| [(10 * x) as u8, (100 * y) as u8, 7, 255]);
    let big = small.resize_nearest(7, 5);
    for y in 0..5 {
        for x in 0..7 {
            // Centre (x + ½) · 3/7 and (y + ½) · 2/5, floored.
            let (sx, sy) = ((2 * x + 1) * 3 / 14, (2 * y + 1) * 2 / 10);
            assert_eq!(big.pixel(x, y), small.pixel(sx, sy), "({x}, {y})");
        }
    }
}
