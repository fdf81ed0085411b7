//! Drawing and encoding one frame of the lesson app's scene pane, per view, at 120 × 40 cells
//! (8 × 16-pixel cells): lesson 6, step 2 (the cloth with four spheres) after 1.5 s.
//!
//! `cargo bench -p springlab-benches --bench tui_view`. Each case is what one frame costs:
//! - `braille`: the line drawing into the cell buffer;
//! - `halfblocks-24bit`, `halfblocks-256`: the rasteriser at 2 pixels a cell and the cells;
//! - `sixel`, `kitty`, `iterm2`: the rasteriser at the pane's pixel size, the conversion to an
//!   RGBA image and the protocol's encoding (done on the encoder thread in the app);
//! - `app-halfblocks`: the whole lesson screen (text, plots, status, the half-block pane), what
//!   the UI thread draws each frame.

use criterion::{Criterion, criterion_group, criterion_main};
use ratatui::buffer::Buffer;
use ratatui::layout::{Rect, Size};
use ratatui::widgets::Widget;
use springlab::lesson;
use springlab::tui::halfblocks::{self, ColourDepth};
use springlab::tui::lesson_view::scene_inner;
use springlab::tui::raster::{PaneRenderer, encode, pixel_size, show, to_image};
use springlab::tui::sim_view::{self, Painter};
use springlab::tui::{App, Graphics, LessonRun, Protocol, Theme, ViewMode};

const CELL: (u16, u16) = (8, 16);

fn cloth_run() -> LessonRun {
    let l = lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.slug == "cloth")
        .expect("lesson 6");
    let mut run = LessonRun::new(l, 1).expect("step 2");
    run.handle_key(ratatui::crossterm::event::KeyCode::Char(' '));
    for _ in 0..15 {
        run.tick(0.1);
    }
    assert!(run.sim().diverged.is_none());
    run
}

fn bench_views(c: &mut Criterion) {
    let screen = Rect::new(0, 0, 120, 40);
    let mut run = cloth_run();
    let inner = scene_inner(&run, screen);
    run.set_aspect(
        f64::from(inner.width) * f64::from(CELL.0) / (f64::from(inner.height) * f64::from(CELL.1)),
    );
    let cells = Size::new(inner.width, inner.height);
    let mut group = c.benchmark_group(format!("pane/{}x{}-cells", inner.width, inner.height));
    let mut buf = Buffer::empty(screen);
    group.bench_function("braille", |b| {
        b.iter(|| sim_view::Braille.paint(&run, Theme::DARK, inner, &mut buf));
    });
    for (name, depth) in [
        ("halfblocks-24bit", ColourDepth::TrueColour),
        ("halfblocks-256", ColourDepth::Palette256),
    ] {
        let mut pane = PaneRenderer::default();
        group.bench_function(name, |b| {
            b.iter(|| {
                let pixmap = pane.draw(
                    &run.sim().scene,
                    run.generation(),
                    run.camera(),
                    run.spring_filter(),
                    (u32::from(inner.width), 2 * u32::from(inner.height)),
                    None,
                );
                halfblocks::render(&pixmap, depth, inner, &mut buf);
            });
        });
    }
    for (name, protocol) in [
        ("sixel", Protocol::Sixel),
        ("kitty", Protocol::Kitty),
        ("iterm2", Protocol::Iterm2),
    ] {
        let mut pane = PaneRenderer::default();
        group.bench_function(name, |b| {
            b.iter(|| {
                let pixmap = pane.draw(
                    &run.sim().scene,
                    run.generation(),
                    run.camera(),
                    run.spring_filter(),
                    pixel_size(cells, CELL, 1.0),
                    None,
                );
                let encoded = encode(to_image(&pixmap), protocol, cells, false).expect("encodes");
                show(&encoded, inner, &mut buf);
            });
        });
    }
    let mut app = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::HalfBlocks,
        Graphics::NONE,
        ColourDepth::TrueColour,
    );
    app.resize(120, 40);
    app.open_lesson(app.find_lesson("cloth").expect("lesson 6"))
        .expect("opens");
    app.handle_key(ratatui::crossterm::event::KeyEvent::from(
        ratatui::crossterm::event::KeyCode::Char('n'),
    ));
    group.bench_function("app-halfblocks", |b| {
        b.iter(|| (&app).render(screen, &mut buf));
    });
    group.finish();
}

criterion_group!(benches, bench_views);
criterion_main!(benches);
