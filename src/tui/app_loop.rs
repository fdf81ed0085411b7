//! The app's event loop: draw, wait for input or the next frame, tick.

use std::time::{Duration, Instant};

use ratatui::DefaultTerminal;
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use ratatui::layout::Rect;

use super::raster::Encoder;

use super::{App, FRAME, RASTER_FRAME, STEP_BUDGET, Screen, ViewMode, lesson_view};

impl App {
    /// The event loop: draw, wait for input or the next frame, tick; until the user quits.
    ///
    /// # Errors
    /// Only when the terminal cannot be read or written.
    pub fn run(&mut self, terminal: &mut DefaultTerminal) -> anyhow::Result<()> {
        let mut last_tick = Instant::now();
        let mut next_frame = Instant::now();
        let mut fps_window = (Instant::now(), 0u32);
        let mut images = 0u32;
        let mut dirty = true;
        if let Ok(size) = terminal.size() {
            self.resize(size.width, size.height);
        }
        // From here no key waits for a computation: new steps and exports go to other threads.
        self.deferred = true;
        if let Some(run) = self.lesson_mut() {
            run.set_deferred(true);
        }
        while !self.quit {
            dirty |= self.poll_background();
            self.submit_raster();
            if let Some(encoder) = &mut self.encoder
                && encoder.poll()
            {
                dirty = true;
                images += 1;
            }
            if dirty {
                if std::mem::take(&mut self.clear) {
                    terminal.clear()?;
                }
                terminal.draw(|frame| frame.render_widget(&*self, frame.area()))?;
                fps_window.1 += 1;
                dirty = false;
            }
            let animating = self.is_animating();
            if animating {
                // Frames on a fixed schedule; a late frame (stepping and drawing took longer than
                // a period: the run is behind) is due at once, after one look at the input.
                // Waiting a whole period after it would leave the CPU idle while the run falls
                // behind (a third of the time on the full jelly).
                let now = Instant::now();
                // The raster view redraws the screen at the images' rate: the CPU the text and
                // plots would take at 60 frames a second goes to stepping and encoding.
                let period = if self.view == ViewMode::Raster && self.encoder.is_some() {
                    RASTER_FRAME
                } else {
                    FRAME
                };
                next_frame = (next_frame + period).max(now);
                while !self.quit {
                    let timeout = next_frame.saturating_duration_since(Instant::now());
                    if timeout.is_zero() {
                        if event::poll(WAITING)? {
                            dirty |= self.handle_pending_events()?;
                        }
                        break;
                    }
                    // While an image is being encoded, look for it every 2 ms: the next one is
                    // sent as soon as the encoder is free, not at the next frame.
                    let slice = if self.encoder.as_ref().is_some_and(Encoder::busy) {
                        timeout.min(Duration::from_millis(2))
                    } else {
                        timeout
                    };
                    if !event::poll(slice)? {
                        if let Some(encoder) = &mut self.encoder
                            && encoder.poll()
                        {
                            images += 1;
                            dirty = true;
                            self.submit_raster();
                        }
                        continue;
                    }
                    dirty |= self.handle_pending_events()?;
                    if !self.is_animating() {
                        break;
                    }
                }
            } else if self.raster_in_flight() || self.background_pending() {
                // A frame is being encoded or the limit recomputed: wait for it or for input,
                // whichever comes first.
                if event::poll(Duration::from_millis(5))? {
                    dirty |= self.handle_pending_events()?;
                }
            } else {
                // Nothing moves: block until the user does something (no CPU while paused).
                let event = event::read()?;
                dirty |= self.handle_event(&event);
                dirty |= self.drain_events()?;
            }
            let now = Instant::now();
            // Wall time counts only while the simulation was running before this wait.
            let wall = if animating {
                (now - last_tick).as_secs_f64()
            } else {
                0.0
            };
            last_tick = now;
            if animating {
                self.tick_until(wall, Some(now + STEP_BUDGET));
                dirty = true;
                let elapsed = now - fps_window.0;
                if elapsed >= Duration::from_millis(500) {
                    self.fps = Some(f64::from(fps_window.1) / elapsed.as_secs_f64());
                    self.raster_fps = Some(f64::from(images) / elapsed.as_secs_f64());
                    fps_window = (now, 0);
                    images = 0;
                }
            } else {
                fps_window = (now, 0);
                images = 0;
                next_frame = now;
                self.fps = None;
                self.raster_fps = None;
            }
        }
        Ok(())
    }

    /// True while the raster view waits for a frame: one is being encoded, or the pane changed
    /// since the last one was sent.
    fn raster_in_flight(&self) -> bool {
        let Some(encoder) = &self.encoder else {
            return false;
        };
        if encoder.busy() {
            return true;
        }
        match &self.screen {
            Screen::Lesson(run) if self.view == ViewMode::Raster && !self.help => {
                let inner =
                    lesson_view::scene_inner(run, Rect::new(0, 0, self.size.0, self.size.1));
                run.sim().diverged.is_none() && self.submitted != Some((run.version(), inner))
            }
            _ => false,
        }
    }

    fn handle_pending_events(&mut self) -> anyhow::Result<bool> {
        let event = event::read()?;
        let mut dirty = self.handle_event(&event);
        dirty |= self.drain_events()?;
        Ok(dirty)
    }

    /// Handles every event already waiting (a mouse drag sends many, a paste or a fast typist
    /// hundreds) before the next draw. All of them are read first: a Ctrl-C among them quits at
    /// once, whatever comes before it.
    fn drain_events(&mut self) -> anyhow::Result<bool> {
        let mut waiting = Vec::new();
        while event::poll(WAITING)? {
            waiting.push(event::read()?);
        }
        if waiting.iter().any(is_ctrl_c) {
            self.quit = true;
            return Ok(true);
        }
        // Keys come faster than they can be handled only in a paste or a burst: past the
        // budget, only the keys that leave are handled, so that `q` is answered at once
        // whatever came before it; the status line says how many were dropped.
        let started = Instant::now();
        let mut dropped = 0usize;
        let mut dirty = false;
        for event in &waiting {
            if self.quit {
                break;
            }
            if started.elapsed() > KEY_BUDGET && !leaves(event) {
                dropped += 1;
                continue;
            }
            dirty |= self.handle_event(event);
        }
        if dropped > 0 {
            let note =
                format!("{dropped} keys dropped: they came faster than the app could follow them");
            match self.lesson_mut() {
                Some(run) => run.set_message(note),
                None => self.menu_message = Some(note),
            }
            dirty = true;
        }
        Ok(dirty)
    }
}

/// How long [`App::drain_events`] asks whether another event waits. Not zero: with the poll(2)
/// input source (`use-dev-tty`, see Cargo.toml) crossterm 0.29's `poll(Duration::ZERO)` never
/// looks at the events it has already read and parsed (its loop runs only while time is left:
/// crossterm issue 839), so a burst read in one go came out one event per loop turn, each
/// followed by a whole draw (a picture of the scene on the cloth: tens of milliseconds), and 2,000
/// keys then `q` took seconds. With time left, waiting events come back at once; only the last
/// poll waits, for at most this long.
const WAITING: Duration = Duration::from_millis(1);

/// How long the events read in one go are handled before only the keys that leave are (issue
/// 27: `q` answered within 100 ms, whatever the queue). A typist or a held key sends one or two
/// keys per loop turn, far below it; a paste of thousands of keys passes it (on a 2-core machine
/// loaded ten times over, 2,000 random keys on the cloth took about 0.15 s of the drawing
/// thread's CPU and so over a second).
const KEY_BUDGET: Duration = Duration::from_millis(50);

/// `q`, Esc (they close an overlay, leave the lesson, leave the app) and a resize, which are
/// never dropped.
fn leaves(event: &Event) -> bool {
    match event {
        Event::Key(k) => matches!(k.code, KeyCode::Char('q') | KeyCode::Esc),
        Event::Resize(..) => true,
        _ => false,
    }
}

/// Ctrl-C, which raw mode delivers as a key.
fn is_ctrl_c(event: &Event) -> bool {
    matches!(event, Event::Key(k) if k.modifiers.contains(KeyModifiers::CONTROL)
        && matches!(k.code, KeyCode::Char('c' | 'C'))
        && k.kind != KeyEventKind::Release)
}
