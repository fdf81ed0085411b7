//! Checks by hand (in tmux) that a panic inside the lesson app's terminal set-up leaves the
//! terminal clean: the same `init_terminal` as the app, a screen drawn, then a panic.
//!
//! `cargo run --release --example tui_panic`; resize the window while it waits if you like.

use std::time::Duration;

use ratatui::widgets::{Paragraph, Widget};

fn main() {
    let mut terminal = springlab::tui::init_terminal().expect("a terminal");
    terminal
        .draw(|frame| {
            Paragraph::new("springlab: this screen panics in 3 s".repeat(200))
                .wrap(ratatui::widgets::Wrap { trim: false })
                .render(frame.area(), frame.buffer_mut());
        })
        .expect("draw");
    std::thread::sleep(Duration::from_secs(3));
    panic!("a deliberate panic to check that the terminal is restored");
}
