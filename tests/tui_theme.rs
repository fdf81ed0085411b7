//! Both palettes are legible: every named colour the lesson screen draws with (series, legends,
//! labels, marks) has a WCAG contrast ratio of at least 3:1 against its background, on black
//! with the dark palette and on white with the light one; the background query's reply is read
//! at every channel width; two bodies' series and E1/K1 vs E2/K2 get distinct colours.

use ratatui::style::Color;
use springlab::tui::theme::{self, Background};

#[test]
fn every_colour_has_three_to_one_contrast_on_both_backgrounds() {
    // Black is the background itself on a dark terminal: the screen draws no series with it.
    for background in [Background::Dark, Background::Light] {
        for c in theme::named() {
            if c == Color::Black {
                continue;
            }
            let drawn = theme::for_background(c, background);
            let rgb = theme::rgb(drawn).expect("a named or RGB colour");
            let ratio = theme::contrast(rgb, background.rgb());
            assert!(
                ratio >= 3.0,
                "{c:?} on {background:?} is drawn {rgb:?}: contrast {ratio:.2}"
            );
        }
    }
}

#[test]
fn the_contrast_formula_matches_known_values() {
    // WCAG's end points and a classic mid grey.
    assert!((theme::contrast((0, 0, 0), (255, 255, 255)) - 21.0).abs() < 1e-9);
    assert!((theme::contrast((10, 20, 30), (10, 20, 30)) - 1.0).abs() < 1e-12);
    // #777777 on white: 4.48 (the usual "fails AA for small text" example).
    let grey = theme::contrast((0x77, 0x77, 0x77), (255, 255, 255));
    assert!((grey - 4.48).abs() < 0.01, "{grey}");
}

#[test]
fn the_background_reply_is_read() {
    let light = b"\x1b]11;rgb:ffff/ffff/ffff\x1b\\\x1b[?64;4c";
    assert_eq!(theme::parse_reply(light), Some(Background::Light));
    let dark = b"\x1b]11;rgb:0000/0000/0000\x07";
    assert_eq!(theme::parse_reply(dark), Some(Background::Dark));
    // Two hex digits a channel; a beige (light) background.
    assert_eq!(
        theme::parse_reply(b"\x1b]11;rgb:f5/f5/dc\x1b\\"),
        Some(Background::Light)
    );
    assert_eq!(theme::parse_reply(b"\x1b[?64;4c"), None);
    assert_eq!(Background::parse("Light"), Ok(Background::Light));
    assert!(Background::parse("blue").is_err());
}

#[test]
fn light_palette_keeps_named_colours_apart() {
    // The light palette maps the 16 names to distinct colours, except white, which becomes
    // black (the foreground of a light terminal).
    let drawn: Vec<Color> = theme::named()
        .iter()
        .filter(|&&c| c != Color::White)
        .map(|&c| theme::for_background(c, Background::Light))
        .collect();
    for (i, a) in drawn.iter().enumerate() {
        for b in &drawn[i + 1..] {
            assert_ne!(a, b);
        }
    }
}
