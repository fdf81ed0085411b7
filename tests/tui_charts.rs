//! The plots as pictures in the raster view: the chart renderer puts a series where its axes
//! say, in the theme's colours, with the legend above the data; the app sends the plots as a
//! second image beside the scene, and only when they changed; the braille plots stay for the
//! other views; `x` switches the exact-vs-simulated plot to the whole run.

use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use ratatui::layout::Rect;
use springlab::lesson::{self, Plot};
use springlab::render::chart::{self, Chart, Ink, Series};
use springlab::render::colour::Colour;
use springlab::tui::chart_feed;
use springlab::tui::plots::Data;
use springlab::tui::plots::picture::{self as pic, Picture};
use springlab::tui::theme as palette;
use springlab::tui::{App, ColourDepth, Graphics, LessonRun, Protocol, Theme, ViewMode};
use tiny_skia::Pixmap;

/// True when the pixel at `(x, y)` is within `tol` of `c` in every channel.
fn near(p: &Pixmap, x: u32, y: u32, c: Colour, tol: i32) -> bool {
    p.pixel(x, y).is_some_and(|q| {
        let q = q.demultiply();
        (i32::from(q.red()) - i32::from(c.r)).abs() <= tol
            && (i32::from(q.green()) - i32::from(c.g)).abs() <= tol
            && (i32::from(q.blue()) - i32::from(c.b)).abs() <= tol
    })
}

/// Pixels within `tol` of `c` in rows `y0..y1`, columns `x0..x1`.
fn count(p: &Pixmap, (x0, x1): (u32, u32), (y0, y1): (u32, u32), c: Colour, tol: i32) -> usize {
    (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| near(p, x, y, c, tol))
        .count()
}

#[test]
fn a_chart_draws_its_series_where_its_axes_put_it_with_the_legend_above_the_data() {
    let red = Colour::rgb(230, 20, 20);
    for ink in [Ink::DARK, Ink::LIGHT] {
        let mut c = Chart::new("known", "time t (s)", "x (m)")
            .with(Series::line("a quarter up", vec![(0.0, 0.25), (1.0, 0.25)]).with_colour(red));
        c.x_range = Some((0.0, 1.0));
        c.y_range = Some((0.0, 1.0));
        c.ink = ink;
        let (w, h) = (960, 720);
        let p = chart::draw(&c, w, h);
        let (left, top, right, bottom) = chart::plot_rect(&c, w, h);
        assert!(left > 20.0 && top > 20.0 && right < w as f32 - 5.0 && bottom < h as f32 - 20.0);
        // The background is the ink's.
        assert!(near(&p, 1, 1, ink.background, 0));
        let mid = ((left + right) / 2.0) as u32;
        // The frame: the axis colour on the plot rectangle's top and bottom edges.
        for y in [top, bottom] {
            let rows = (y.floor() as u32 - 1, y.ceil() as u32 + 2);
            assert!(
                count(&p, (mid - 50, mid + 50), rows, ink.axis, 60) >= 80,
                "frame at y = {y}"
            );
        }
        // The series: a line at a quarter of the height from the bottom, across the plot.
        let y_line = bottom - 0.25 * (bottom - top);
        let band = (y_line as u32 - 3, y_line as u32 + 4);
        let inside = ((left + 10.0) as u32, (right - 10.0) as u32);
        let across = count(&p, inside, band, red, 40);
        assert!(
            across as f32 >= 0.9 * (inside.1 - inside.0) as f32,
            "{across} red pixels at y = {y_line}"
        );
        // Nowhere else in the plot.
        let y_mirror = bottom - 0.75 * (bottom - top);
        let mirror = (y_mirror as u32 - 3, y_mirror as u32 + 4);
        assert_eq!(count(&p, inside, mirror, red, 40), 0);
        // The legend's sample line in the series' colour is above the plot, over no data.
        assert!(count(&p, (0, w), (0, top as u32 - 1), red, 40) > 10);
        // Labelled axes: text below the plot (tick labels and the x label) and left of it.
        assert!(count(&p, (0, w), (bottom as u32 + 3, h), ink.text, 60) > 100);
        assert!(count(&p, (0, left as u32 - 3), (0, h), ink.text, 60) > 100);
    }
}

fn lesson(slug: &str) -> lesson::Lesson {
    lesson::builtin()
        .into_iter()
        .flatten()
        .find(|l| l.slug == slug)
        .expect("a built-in lesson")
}

fn data(run: &LessonRun, theme: Theme) -> Data<'_> {
    Data {
        history: run.history(),
        oscillator: run.oscillator(),
        studies: run.studies(),
        shown: run.shown_methods(),
        now: run.sim().time(),
        theme,
    }
}

fn running(slug: &str, step: usize, seconds: f64) -> LessonRun {
    let mut run = LessonRun::new(lesson(slug), step).expect("the step opens");
    run.handle_key(KeyCode::Char(' '));
    for _ in 0..(seconds / 0.05).round() as usize {
        run.tick(0.05);
    }
    run
}

#[test]
fn the_energy_picture_explains_d_and_res_and_every_series_reads_on_both_backgrounds() {
    let run = running("rope", 0, 1.0);
    let area = Rect::new(60, 20, 60, 14);
    for theme in [Theme::DARK, Theme::LIGHT] {
        let d = data(&run, theme);
        let p: Picture = d
            .picture(&[Plot::Energy], area, (8, 16))
            .expect("a picture");
        assert_eq!(p.area, area);
        let [(c, cells)] = &p.charts[..] else {
            panic!("one chart")
        };
        assert_eq!(*cells, 60);
        let names: Vec<&str> = c.series.iter().map(|s| s.name.as_str()).collect();
        assert!(
            names
                .iter()
                .any(|n| n.starts_with("+D = total + dissipated")),
            "{names:?}"
        );
        assert!(names.iter().any(|n| n.starts_with("res = E + D - E0")));
        let bg = theme.background.rgb();
        for s in &c.series {
            let col = s.colour.expect("a colour");
            let k = palette::contrast((col.r, col.g, col.b), bg);
            assert!(k >= 3.0, "{} on {bg:?}: contrast {k:.2}", s.name);
        }
        let text = c.ink.text;
        assert!(palette::contrast((text.r, text.g, text.b), bg) >= 7.0);
        // The picture itself is on the theme's background.
        let pixmap = pic::draw(&p, 480, 224);
        let px = pixmap.pixel(0, 0).expect("pixel").demultiply();
        assert_eq!((px.red(), px.green(), px.blue()), bg);
        // The samples of the run are all in it: time from 0 to the present.
        assert_eq!(c.x_range.expect("fixed").0, 0.0);
    }
}

#[test]
fn the_stability_table_stays_text_and_the_pictures_cover_the_other_plot() {
    let area = Rect::new(50, 10, 61, 20);
    let rects = pic::plot_rects(2, area);
    assert_eq!(rects[0].width + rects[1].width, 61);
    assert_eq!(
        pic::picture_area(&[Plot::Stability, Plot::Convergence], area),
        Some(rects[1])
    );
    assert_eq!(
        pic::picture_area(&[Plot::Convergence, Plot::Stability], area),
        Some(rects[0])
    );
    assert_eq!(pic::picture_area(&[Plot::Stability], area), None);
    assert_eq!(
        pic::picture_area(&[Plot::Energy, Plot::Speed], area),
        Some(area)
    );
}

#[test]
fn x_switches_the_exact_plot_to_the_whole_run() {
    // Lesson 2, step 1: the oscillator beside its exact solution; 6 s is several periods.
    let mut run = running("hooke", 0, 6.0);
    let now = run.sim().time();
    let area = Rect::new(0, 0, 60, 14);
    let window = |run: &LessonRun| {
        let d = data(run, Theme::DARK);
        let p = d.picture(&[Plot::Exact], area, (8, 16)).expect("a picture");
        p.charts[0].0.x_range.expect("fixed")
    };
    let (start, end) = window(&run);
    assert!(start > 0.0, "the last periods: from {start} s");
    assert!(end >= now - 1e-9);
    run.handle_key(KeyCode::Char('x'));
    let (start, end) = window(&run);
    assert_eq!(start, 0.0, "the whole run");
    assert!(end >= now - 1e-9);
    let d = data(&run, Theme::DARK);
    let p = d.picture(&[Plot::Exact], area, (8, 16)).expect("a picture");
    let sim = p.charts[0]
        .0
        .series
        .iter()
        .find(|s| s.name == "simulated")
        .expect("the simulated series");
    assert!(sim.points.first().expect("points").0 < 0.1 * now);
    run.handle_key(KeyCode::Char('x'));
    assert!(window(&run).0 > 0.0, "back to the last periods");
}

fn wait(app: &mut App) {
    for _ in 0..4000 {
        if app.poll_raster() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    panic!("no frame within 4 s");
}

fn cell_symbol(app: &App, x: u16, y: u16) -> String {
    let mut terminal =
        ratatui::Terminal::new(ratatui::backend::TestBackend::new(100, 32)).expect("test terminal");
    terminal
        .draw(|f| f.render_widget(&*app, f.area()))
        .expect("draw");
    terminal.backend().buffer()[(x, y)].symbol().to_string()
}

#[test]
fn the_raster_view_sends_the_plots_as_a_second_image_only_when_they_change() {
    let kitty = Graphics {
        protocol: Some(Protocol::Kitty),
        ..Graphics::NONE
    };
    let mut app = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::Raster,
        kitty,
        ColourDepth::TrueColour,
    );
    app.resize(100, 32);
    app.open_lesson(0).expect("opens");
    assert!(
        app.submit_raster(),
        "the scene and the plots go to the encoder"
    );
    wait(&mut app);
    let encoder = app.encoder().expect("an encoder");
    assert!(encoder.latest().is_some(), "the scene's image");
    let picture = encoder.latest_picture().expect("the plots' image");
    let run = app.lesson().expect("a lesson");
    let screen = Rect::new(0, 0, 100, 32);
    assert_eq!(chart_feed::area(run, screen), Some(picture.area));
    let area = picture.area;
    // The plot area holds kitty's placeholders, not braille.
    assert!(cell_symbol(&app, area.x + 3, area.y + 3).contains('\u{10EEEE}'));
    // Nothing changed: nothing is sent.
    assert!(!app.submit_raster());
    // In the half-block view the braille plots are back.
    app.handle_key(KeyEvent {
        code: KeyCode::Char('v'),
        modifiers: KeyModifiers::NONE,
        kind: KeyEventKind::Press,
        state: ratatui::crossterm::event::KeyEventState::NONE,
    });
    assert_eq!(app.view(), ViewMode::HalfBlocks);
    assert!(!cell_symbol(&app, area.x + 3, area.y + 3).contains('\u{10EEEE}'));
}

#[test]
fn the_plots_without_a_picture_stay_braille() {
    // No protocol: no encoder, the plots are braille characters.
    let mut app = App::new(lesson::builtin(), Theme::DARK).with_display(
        ViewMode::Raster,
        Graphics::NONE,
        ColourDepth::TrueColour,
    );
    app.resize(100, 32);
    app.open_lesson(0).expect("opens");
    assert!(app.encoder().is_none());
    let run = app.lesson().expect("a lesson");
    let (plots, area) = springlab::tui::lesson_view::plots_area(run, Rect::new(0, 0, 100, 32))
        .expect("lesson 1 has a plot");
    assert_eq!(plots, vec![Plot::Energy]);
    let mut terminal =
        ratatui::Terminal::new(ratatui::backend::TestBackend::new(100, 32)).expect("test terminal");
    terminal
        .draw(|f| f.render_widget(&app, f.area()))
        .expect("draw");
    let buf = terminal.backend().buffer();
    let title: String = (area.x..area.x + area.width)
        .map(|x| buf[(x, area.y)].symbol().to_string())
        .collect();
    assert!(title.contains("E (J)"), "{title}");
}

#[test]
fn lesson_7s_convergence_picture_names_each_method_with_its_fitted_order() {
    let run = LessonRun::new(lesson("speed-accuracy"), 0).expect("lesson 7 opens");
    let d = data(&run, Theme::LIGHT);
    let area = Rect::new(0, 0, 60, 20);
    let p = d
        .picture(&[Plot::Convergence], area, (8, 16))
        .expect("a picture");
    let c = &p.charts[0].0;
    assert_eq!(c.x_scale, springlab::render::Scale::Log);
    // "4 RK4 3.97": the key, the label and the order fitted by the study.
    let rk4 = c
        .series
        .iter()
        .find(|s| s.name.starts_with("4 RK4 "))
        .expect("RK4's entry");
    let order: f64 = rk4.name["4 RK4 ".len()..].parse().expect("an order");
    assert!((order - 4.0).abs() < 0.2, "RK4's fitted order {order}");
    let ee = c
        .series
        .iter()
        .find(|s| s.name.starts_with("1 EE "))
        .expect("explicit Euler's entry");
    let order: f64 = ee.name["1 EE ".len()..].parse().expect("an order");
    assert!(
        (order - 1.0).abs() < 0.2,
        "explicit Euler's fitted order {order}"
    );
    // The errors are the study's, on log axes: every point positive.
    assert!(rk4.points.iter().all(|&(dt, e)| dt > 0.0 && e > 0.0));
    assert!(c.series.iter().any(|s| s.name == "slopes 1 2 4"));
}
