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
                // Frames on a fixed schedule; a late frame starts the schedule again from now.
                let now = Instant::now();
                // The raster view redraws the screen at the images' rate: the CPU the text and
                // plots would take at 60 frames a second goes to stepping and encoding.
                let period = if self.view == ViewMode::Raster && self.encoder.is_some() {
                    RASTER_FRAME
                } else {
                    FRAME
                };
                next_frame = if next_frame + period < now {
                    now + period
                } else {
                    next_frame + period
                };
                while !self.quit {
                    let timeout = next_frame.saturating_duration_since(Instant::now());
                    if timeout.is_zero() {
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

    /// Handles every event already waiting (a mouse drag sends many) before the next draw. All
    /// of them are read first: a Ctrl-C among them quits at once, whatever comes before it.
    fn drain_events(&mut self) -> anyhow::Result<bool> {
        let mut waiting = Vec::new();
        while event::poll(Duration::ZERO)? {
            waiting.push(event::read()?);
        }
        if waiting.iter().any(is_ctrl_c) {
            self.quit = true;
            return Ok(true);
        }
        let mut dirty = false;
        for event in &waiting {
            if self.quit {
                break;
            }
            dirty |= self.handle_event(event);
        }
        Ok(dirty)
    }
}

/// Ctrl-C, which raw mode delivers as a key.
fn is_ctrl_c(event: &Event) -> bool {
    matches!(event, Event::Key(k) if k.modifiers.contains(KeyModifiers::CONTROL)
        && matches!(k.code, KeyCode::Char('c' | 'C'))
        && k.kind != KeyEventKind::Release)
}
