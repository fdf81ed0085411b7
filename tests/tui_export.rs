//! `e` in a lesson writes the scene pane's view as a PNG: same camera, same framing, at 1280
//! pixels across and the pane's aspect ratio, the text overlay and the legend in bands above
//! and below the picture (never over a body).

use springlab::lesson;
use springlab::tui::LessonRun;
use springlab::tui::export::{export_png, export_size};
use springlab::tui::raster::PaneRenderer;

/// Exports what `run` shows (its simulation, camera, spring filter and aspect) to `path`.
pub(crate) fn export_run(
    run: &LessonRun,
    path: &std::path::Path,
) -> Result<std::path::PathBuf, String> {
    export_png(
        run.sim(),
        run.generation(),
        run.camera(),
        run.spring_filter(),
        run.aspect(),
        path,
    )
}

pub(crate) fn read_png(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).expect("png"),
    ));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("frame");
    buf.truncate(info.buffer_size());
    let rgba = match info.color_type {
        png::ColorType::Rgba => buf,
        png::ColorType::Rgb => buf
            .chunks(3)
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect(),
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    (info.width, info.height, rgba)
}

/// The heights of the bands above and below an export of `run` at `size` (pixels).
pub(crate) fn bands(run: &LessonRun, size: (u32, u32)) -> (u32, u32) {
    use springlab::render::{Overlay, Renderer};
    let r = Renderer::with_camera(
        &run.sim().scene,
        size.0,
        size.1,
        *run.camera(),
        springlab::tui::raster::pane_style(run.spring_filter(), true),
    );
    r.caption_bands(&Overlay::of(run.sim()))
}

/// Rows `top .. top + height` of an RGBA image.
fn crop_rows(img: &(u32, u32, Vec<u8>), top: u32, height: u32) -> (u32, u32, Vec<u8>) {
    let w = img.0 as usize;
    let start = top as usize * w * 4;
    let end = start + height as usize * w * 4;
    (img.0, height, img.2[start..end].to_vec())
}

/// The fraction of pixels (below the top fifth, where the export's text overlay sits) at which
/// the exported image, averaged down to `w × h` blocks, and `small` (opaque) differ clearly:
/// by more than 40 of 255 in some channel.
fn difference(big: &(u32, u32, Vec<u8>), small: &tiny_skia::Pixmap) -> f64 {
    let (bw, bh, data) = big;
    let (w, h) = (small.width(), small.height());
    let mut total = 0.0;
    let mut count = 0.0;
    for y in h / 5..h {
        for x in 0..w {
            let (x0, x1) = (x * bw / w, (x + 1) * bw / w);
            let (y0, y1) = (y * bh / h, (y + 1) * bh / h);
            let mut sum = [0.0f64; 3];
            for yy in y0..y1 {
                for xx in x0..x1 {
                    let i = ((yy * bw + xx) * 4) as usize;
                    for c in 0..3 {
                        sum[c] += f64::from(data[i + c]);
                    }
                }
            }
            let n = f64::from((x1 - x0) * (y1 - y0));
            let p = small.pixel(x, y).expect("pixel");
            let worst = [p.red(), p.green(), p.blue()]
                .into_iter()
                .enumerate()
                .map(|(c, v)| (sum[c] / n - f64::from(v)).abs())
                .fold(0.0, f64::max);
            total += f64::from(u8::from(worst > 40.0));
            count += 1.0;
        }
    }
    total / count
}

#[test]
fn export_writes_the_view_on_screen() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let dir = tmp.path();
    let cloth = lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.slug == "cloth")
        .expect("lesson 6");
    let mut run = LessonRun::new(cloth, 1).expect("step 2");
    run.set_aspect(2.0);
    run.handle_key(ratatui::crossterm::event::KeyCode::Right);
    run.handle_key(ratatui::crossterm::event::KeyCode::Char('i'));
    run.handle_key(ratatui::crossterm::event::KeyCode::Char(' '));
    run.tick(0.3);
    let path = dir.join("frame.png");
    let written = export_run(&run, &path).expect("export");
    assert_eq!(written, path);
    let whole = read_png(&path);
    assert_eq!(export_size(2.0), (1280, 640));
    let (top, bottom) = bands(&run, export_size(2.0));
    assert_eq!((whole.0, whole.1), (1280, 640 + top + bottom));
    let big = crop_rows(&whole, top, 640);
    // The pane's own frame: a 160 × 80 image through the same camera.
    let draw = |camera: &springlab::render::Camera| {
        PaneRenderer::default().draw(
            &run.sim().scene,
            run.generation(),
            camera,
            run.spring_filter(),
            (160, 80),
            None,
        )
    };
    let same = difference(&big, &draw(run.camera()));
    // The same scene with the view moved by a tenth of its height, or from the step's first
    // view, differs.
    let mut turned = *run.camera();
    turned.pan(0.1, 0.0);
    let other = difference(&big, &draw(&turned));
    let home = difference(&big, &draw(run.home_camera()));
    assert!(
        same < 0.04,
        "export and pane differ at {:.1} % of pixels",
        100.0 * same
    );
    assert!(
        other > 0.05 && home > 0.05,
        "other views differ at {:.1} % and {:.1} %",
        100.0 * other,
        100.0 * home
    );
    // An unwritable path gives a message, not a panic.
    let err = export_run(&run, &dir.join("no/such/dir/x.png")).expect_err("unwritable");
    assert!(err.starts_with("cannot write"), "{err}");
}

#[test]
fn the_export_overlay_covers_no_body() {
    // Lesson 1's rope: its pinned end sits in the top-left corner, where the overlay's box was.
    let tmp = tempfile::tempdir().expect("temp dir");
    let rope = lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.slug == "rope")
        .expect("lesson 1");
    let mut run = LessonRun::new(rope, 1).expect("step 2");
    run.set_aspect(2.0);
    let path = tmp.path().join("rope.png");
    export_run(&run, &path).expect("export");
    let whole = read_png(&path);
    let size = export_size(2.0);
    let (top, bottom) = bands(&run, size);
    assert!(top > 20 && bottom > 10, "bands {top} and {bottom} px");
    // The picture between the bands is the pane's own frame, pixel for pixel: nothing of the
    // overlay lies on it, so no body (whose projection is inside the picture) is covered.
    let picture = crop_rows(&whole, top, size.1);
    let pane = PaneRenderer::default().draw(
        &run.sim().scene,
        run.generation(),
        run.camera(),
        run.spring_filter(),
        size,
        None,
    );
    let same = springlab::tui::raster::to_image(&pane);
    assert_eq!(picture.2, same.into_raw(), "the picture is untouched");
    // The text is in the top band: dark pixels there.
    let dark = (0..top as usize * whole.0 as usize)
        .filter(|i| whole.2[4 * i] < 80 && whole.2[4 * i + 1] < 80)
        .count();
    assert!(dark > 200, "{dark} dark pixels of text above the picture");
}
