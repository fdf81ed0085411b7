//! Which terminal graphics protocol to use, asked of the terminal at start-up, and the three
//! views of the scene pane.
//!
//! # Detection
//!
//! In raw mode, before any event is read, the app writes four queries and reads the answers
//! until the last one comes back (at most [`QUERY_TIMEOUT`]):
//!
//! ```text
//! ESC _Gi=31,s=1,v=1,a=q,t=d,f=24;AAAA ESC \    kitty graphics: "ESC _Gi=31;OK ESC \" if supported
//! ESC [c                                        primary device attributes: parameter 4 = sixel
//! ESC [16t                                      cell size in pixels: "ESC [6;h;wt"
//! ESC [5n                                       device status: "ESC [0n", answered by every terminal
//! ```
//! Kitty wins over sixel; iTerm2's protocol, which has no query, is taken from `TERM_PROGRAM`
//! (`iTerm.app`, `WezTerm`) or `LC_TERMINAL=iTerm2`. WezTerm and Konsole answer the kitty query
//! but do not draw kitty's Unicode placeholders, so they are not given kitty. The cell size comes
//! from the answer to `16t`, else from the kernel's window size in pixels; without a cell size
//! no protocol is used.
//!
//! **tmux** passes escape sequences to the outer terminal only inside its passthrough wrapper
//! (`ESC Ptmux; … ESC \`, escapes doubled), and only when its option `allow-passthrough` is on.
//! The app asks tmux for that option (`tmux show -Apv allow-passthrough`) and does not change it:
//! with passthrough the queries and the images are wrapped, and only kitty's protocol is used
//! (its Unicode placeholders are text that tmux keeps; a sixel or iTerm2 image passed through is
//! wiped by tmux's next redraw); without it only the device attributes are asked of tmux itself
//! (a tmux built with sixel support draws sixel). Otherwise the pane falls back to half-blocks.

use std::time::Duration;

/// Longest wait for the terminal's answers.
pub const QUERY_TIMEOUT: Duration = Duration::from_millis(1000);

/// A terminal graphics protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Protocol {
    /// kitty's graphics protocol (kitty, Ghostty).
    Kitty,
    /// DEC sixel graphics (foot, xterm -ti vt340, Konsole, WezTerm, mlterm, Windows Terminal).
    Sixel,
    /// iTerm2's inline images (iTerm2, WezTerm).
    Iterm2,
}

impl Protocol {
    /// Its name in the status line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Protocol::Kitty => "kitty",
            Protocol::Sixel => "sixel",
            Protocol::Iterm2 => "iTerm2",
        }
    }
}

/// What the terminal can show.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Graphics {
    /// The graphics protocol, if one was detected.
    pub protocol: Option<Protocol>,
    /// Size of a character cell in pixels `(width, height)`.
    pub cell: (u16, u16),
    /// Images must be wrapped for tmux's passthrough.
    pub tmux_wrap: bool,
}

impl Graphics {
    /// No graphics protocol (tests, CI, plain terminals); cells taken as 8 × 16 pixels.
    pub const NONE: Graphics = Graphics {
        protocol: None,
        cell: (8, 16),
        tmux_wrap: false,
    };

    /// Asks the terminal (module docs). The terminal must be in raw mode, and nothing else may
    /// read standard input meanwhile.
    #[must_use]
    pub fn detect() -> Graphics {
        if std::env::var("TERM").is_ok_and(|t| t == "dumb") {
            return Graphics::NONE;
        }
        let tmux = std::env::var_os("TMUX").is_some_and(|v| !v.is_empty());
        let passthrough = tmux && tmux_passthrough();
        let queries = if tmux && !passthrough {
            // Only tmux itself answers.
            format!("{DA1}{STATUS}")
        } else {
            wrap(
                &format!("{KITTY_QUERY}{DA1}{CELL_SIZE}{STATUS}"),
                passthrough,
            )
        };
        let answers = ask(&queries).unwrap_or_default();
        let env = |k: &str| std::env::var(k).unwrap_or_default();
        let cell = answers.cell.or_else(window_cell_size);
        let protocol = choose(
            &answers,
            &env("TERM_PROGRAM"),
            &env("LC_TERMINAL"),
            !env("KONSOLE_VERSION").is_empty(),
            match (tmux, passthrough) {
                (false, _) => Tmux::No,
                (true, true) => Tmux::Passthrough,
                (true, false) => Tmux::Alone,
            },
        );
        match (protocol, cell) {
            (Some(p), Some(cell)) if cell.0 > 0 && cell.1 > 0 => Graphics {
                protocol: Some(p),
                cell,
                tmux_wrap: passthrough,
            },
            _ => Graphics {
                cell: cell.unwrap_or(Graphics::NONE.cell),
                ..Graphics::NONE
            },
        }
    }
}

const KITTY_QUERY: &str = "\x1b_Gi=31,s=1,v=1,a=q,t=d,f=24;AAAA\x1b\\";
const DA1: &str = "\x1b[c";
const CELL_SIZE: &str = "\x1b[16t";
const STATUS: &str = "\x1b[5n";

/// `s` inside tmux's passthrough wrapper (escapes doubled) when `wrap` is true.
#[must_use]
pub fn wrap(s: &str, wrap: bool) -> String {
    if wrap {
        format!("\x1bPtmux;{}\x1b\\", s.replace('\x1b', "\x1b\x1b"))
    } else {
        s.to_string()
    }
}

/// Where the app runs, as far as tmux goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tmux {
    /// Not in tmux.
    No,
    /// In tmux with `allow-passthrough`: the outer terminal answered.
    Passthrough,
    /// In tmux without passthrough: tmux itself answered.
    Alone,
}

/// The protocol for the terminal's answers and environment (module docs). Inside tmux only
/// images that tmux keeps on screen count: kitty's, whose Unicode placeholders are text tmux
/// redraws like any other, through passthrough; or sixel drawn by tmux itself. A sixel or
/// iTerm2 image passed through to the outer terminal is wiped by tmux's next redraw of the
/// pane, so there the pane uses half-blocks.
#[must_use]
pub fn choose(
    answers: &Answers,
    term_program: &str,
    lc_terminal: &str,
    konsole: bool,
    tmux: Tmux,
) -> Option<Protocol> {
    let wezterm = term_program.contains("WezTerm");
    let iterm = term_program.contains("iTerm") || lc_terminal.contains("iTerm");
    match tmux {
        Tmux::Alone => return answers.sixel.then_some(Protocol::Sixel),
        Tmux::Passthrough => {
            return (answers.kitty && !wezterm && !konsole).then_some(Protocol::Kitty);
        }
        Tmux::No => {}
    }
    if answers.kitty && !wezterm && !konsole {
        Some(Protocol::Kitty)
    } else if iterm || wezterm {
        Some(Protocol::Iterm2)
    } else if answers.sixel {
        Some(Protocol::Sixel)
    } else {
        None
    }
}

/// True when tmux's `allow-passthrough` is `on` or `all` for this pane.
fn tmux_passthrough() -> bool {
    std::process::Command::new("tmux")
        .args(["show", "-Apv", "allow-passthrough"])
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .output()
        .is_ok_and(|o| {
            let v = String::from_utf8_lossy(&o.stdout);
            o.status.success() && matches!(v.trim(), "on" | "all")
        })
}

/// The cell size from the kernel's window size in pixels, when the terminal reports it.
fn window_cell_size() -> Option<(u16, u16)> {
    let size = ratatui::crossterm::terminal::window_size().ok()?;
    (size.width > 0 && size.height > 0 && size.columns > 0 && size.rows > 0)
        .then(|| (size.width / size.columns, size.height / size.rows))
}

/// The terminal's answers to the queries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Answers {
    /// The kitty graphics query was answered OK.
    pub kitty: bool,
    /// The device attributes include 4 (sixel).
    pub sixel: bool,
    /// The cell size in pixels `(width, height)`.
    pub cell: Option<(u16, u16)>,
    /// The device status answer arrived (the last one).
    pub status: bool,
}

impl Answers {
    /// Parses the bytes read so far (module docs).
    #[must_use]
    pub fn parse(bytes: &[u8]) -> Answers {
        let mut a = Answers::default();
        let mut i = 0;
        while i + 1 < bytes.len() {
            if bytes[i] != 0x1b {
                i += 1;
                continue;
            }
            match bytes[i + 1] {
                b'[' => {
                    // CSI: parameters up to a final byte in 0x40..=0x7e.
                    let start = i + 2;
                    let Some(end) =
                        (start..bytes.len()).find(|&k| (0x40..=0x7e).contains(&bytes[k]))
                    else {
                        break;
                    };
                    let params = String::from_utf8_lossy(&bytes[start..end]);
                    match bytes[end] {
                        b'c' if params.starts_with('?') => {
                            a.sixel |= params[1..].split(';').any(|p| p == "4");
                        }
                        b't' => {
                            let v: Vec<u16> =
                                params.split(';').filter_map(|p| p.parse().ok()).collect();
                            if let [6, h, w] = v[..] {
                                a.cell = Some((w, h));
                            }
                        }
                        b'n' if params == "0" || params == "3" => a.status = true,
                        _ => {}
                    }
                    i = end + 1;
                }
                b'_' => {
                    // APC up to ESC \.
                    let start = i + 2;
                    let Some(end) = (start..bytes.len().saturating_sub(1))
                        .find(|&k| bytes[k] == 0x1b && bytes[k + 1] == b'\\')
                    else {
                        break;
                    };
                    let body = String::from_utf8_lossy(&bytes[start..end]);
                    if body.starts_with('G') && body.contains("i=31") && body.ends_with(";OK") {
                        a.kitty = true;
                    }
                    i = end + 2;
                }
                _ => i += 1,
            }
        }
        a
    }
}

/// Writes `queries` and reads standard input until the status answer or the timeout.
fn ask(queries: &str) -> std::io::Result<Answers> {
    let bytes = super::query::ask(queries.as_bytes(), QUERY_TIMEOUT, |bytes| {
        Answers::parse(bytes).status
    })?;
    Ok(Answers::parse(&bytes))
}

/// How the scene pane draws the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewMode {
    /// The rasterised frame through the terminal's graphics protocol.
    Raster,
    /// The rasterised frame as colour half-blocks, two pixels a cell.
    HalfBlocks,
    /// A braille line drawing.
    Braille,
}

impl ViewMode {
    /// Its name in the status line and on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ViewMode::Raster => "raster",
            ViewMode::HalfBlocks => "halfblocks",
            ViewMode::Braille => "braille",
        }
    }

    /// Parses `raster`, `halfblocks` (or `half-blocks`) or `braille`.
    ///
    /// # Errors
    /// Any other word; the message lists the three.
    pub fn parse(s: &str) -> Result<ViewMode, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "raster" => Ok(ViewMode::Raster),
            "halfblocks" | "half-blocks" => Ok(ViewMode::HalfBlocks),
            "braille" => Ok(ViewMode::Braille),
            other => Err(format!(
                "unknown view `{other}`: expected raster, halfblocks or braille"
            )),
        }
    }

    /// The next view of the cycle raster → half-blocks → braille → raster, skipping the raster
    /// view when there is no graphics protocol.
    #[must_use]
    pub fn next(self, raster_available: bool) -> ViewMode {
        match self {
            ViewMode::Raster => ViewMode::HalfBlocks,
            ViewMode::HalfBlocks => ViewMode::Braille,
            ViewMode::Braille if raster_available => ViewMode::Raster,
            ViewMode::Braille => ViewMode::HalfBlocks,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answers_of_known_terminals() {
        // xterm -ti vt340: sixel in the device attributes, no kitty, a cell size.
        let xterm = Answers::parse(b"\x1b[?63;1;2;4;6;9;15;16;22;28c\x1b[6;17;9t\x1b[0n");
        assert_eq!(
            xterm,
            Answers {
                kitty: false,
                sixel: true,
                cell: Some((9, 17)),
                status: true
            }
        );
        // kitty: the graphics answer first.
        let kitty = Answers::parse(b"\x1b_Gi=31;OK\x1b\\\x1b[?62;c\x1b[6;20;10t\x1b[0n");
        assert!(kitty.kitty && !kitty.sixel && kitty.status);
        // tmux 3.3 alone: no sixel (parameter 4 absent; 14 is not 4).
        let tmux = Answers::parse(b"\x1b[?1;2;14c\x1b[0n");
        assert!(!tmux.sixel && !tmux.kitty && tmux.status && tmux.cell.is_none());
        // Cut short: nothing is invented.
        assert_eq!(Answers::parse(b"\x1b[?63;4"), Answers::default());
        // A kitty error is not support.
        assert!(!Answers::parse(b"\x1b_Gi=31;ENOTSUPPORTED\x1b\\").kitty);
    }

    #[test]
    fn protocol_choice() {
        let kitty = Answers {
            kitty: true,
            sixel: true,
            ..Answers::default()
        };
        let sixel = Answers {
            sixel: true,
            ..Answers::default()
        };
        let none = Answers::default();
        assert_eq!(
            choose(&kitty, "", "", false, Tmux::No),
            Some(Protocol::Kitty)
        );
        assert_eq!(
            choose(&kitty, "WezTerm", "", false, Tmux::No),
            Some(Protocol::Iterm2)
        );
        assert_eq!(
            choose(&kitty, "", "", true, Tmux::No),
            Some(Protocol::Sixel)
        );
        assert_eq!(
            choose(&sixel, "", "", false, Tmux::No),
            Some(Protocol::Sixel)
        );
        assert_eq!(
            choose(&none, "iTerm.app", "", false, Tmux::No),
            Some(Protocol::Iterm2)
        );
        assert_eq!(choose(&none, "", "", false, Tmux::No), None);
        // tmux without passthrough: the outer terminal's environment does not count.
        assert_eq!(choose(&none, "iTerm.app", "", false, Tmux::Alone), None);
        assert_eq!(
            choose(&sixel, "", "", false, Tmux::Alone),
            Some(Protocol::Sixel)
        );
        // tmux with passthrough: kitty only.
        assert_eq!(
            choose(&kitty, "", "", false, Tmux::Passthrough),
            Some(Protocol::Kitty)
        );
        assert_eq!(choose(&sixel, "", "", false, Tmux::Passthrough), None);
        assert_eq!(
            choose(&none, "iTerm.app", "", false, Tmux::Passthrough),
            None
        );
    }

    #[test]
    fn tmux_wrapping_doubles_escapes() {
        assert_eq!(wrap("\x1b[c", true), "\x1bPtmux;\x1b\x1b[c\x1b\\");
        assert_eq!(wrap("\x1b[c", false), "\x1b[c");
    }

    #[test]
    fn view_cycle_skips_raster_without_a_protocol() {
        assert_eq!(ViewMode::HalfBlocks.next(false), ViewMode::Braille);
        assert_eq!(ViewMode::Braille.next(false), ViewMode::HalfBlocks);
        assert_eq!(ViewMode::Braille.next(true), ViewMode::Raster);
        assert_eq!(ViewMode::Raster.next(true), ViewMode::HalfBlocks);
        assert_eq!(ViewMode::parse("half-blocks"), Ok(ViewMode::HalfBlocks));
        assert!(ViewMode::parse("ascii").is_err());
    }
}
