//! `springlab render`: PNG frames, GIF and APNG of a scene, and its energy chart.
//!
//! Frame `k` shows the state after `k · every` steps (frame 0 is the initial state), counted
//! from `--start T` seconds into the run when given. The
//! simulation runs on this thread and draws each frame as soon as its step is reached; the
//! encoder thread compresses and writes while the next frame is simulated and drawn.
//!
//! What is written:
//! - PNG files `frame_00000.png`, … in `--out DIR` when `--out` is given, or in `frames/` when
//!   no other output (`--gif`, `--apng`, `--energy-chart`) is asked for;
//! - `--gif F` and `--apng F`: animations at `--fps` frames per second;
//! - `--energy-chart F.png`: kinetic, gravitational, elastic and total energy (J) against time
//!   (s) over the whole run (sampled at most about 4000 times), at the frames' size but at least
//!   480×320.
//!
//! The run is `--frames N` frames `--every K` steps apart, or `--time T` seconds (then
//! `N = steps / K + 1`), or the scene's duration when only a chart is asked for.

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};

use super::interrupt;
use super::progress::Progress;
use super::run::{apply_methods, check_dt, check_dt_within};
use crate::budget::{self, Limits, short};
use crate::output;
use crate::physics::SpringKind;
use crate::render::chart::{self, Chart, Series};
use crate::render::colour::{self, Colour};
use crate::render::{
    Colouring, FrameEncoder, KindToggles, MAX_SIDE, Outputs, Projection, Renderer, Style,
};
use crate::scene;
use crate::simulation::Simulation;

/// Options of `springlab render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A built-in scene (see `springlab scenes`) or a scene file (.toml).
    pub scene: String,
    /// Number of frames (frame 0 is the initial state).
    #[arg(long, value_name = "N")]
    pub frames: Option<u64>,
    /// Steps between frames (default: the steps of 1/fps seconds, at least 1).
    #[arg(long, value_name = "K")]
    pub every: Option<u64>,
    /// Simulated time in seconds to run before the first frame (default 0: frame 0 is the
    /// initial state); for example `--frames 1 --start 2` draws the scene at t = 2 s.
    #[arg(
        long,
        value_name = "T",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub start: f64,
    /// Simulated time in seconds instead of --frames (frames = steps / every + 1).
    #[arg(long, conflicts_with = "frames", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Image size in pixels, WIDTHxHEIGHT.
    #[arg(
        long,
        default_value = "640x480",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub size: String,
    /// Directory for frame_00000.png, … (default frames/ when nothing else is written).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Remove the frames of an earlier, longer render that this one leaves in the directory
    /// (without it they are left and named on standard error).
    #[arg(long)]
    pub clean_frames: bool,
    /// Write an animated GIF (`-`: standard output, when it is not a terminal).
    #[arg(long, value_name = "FILE")]
    pub gif: Option<PathBuf>,
    /// Write an animated PNG (APNG; `-`: standard output, when it is not a terminal).
    #[arg(long, value_name = "FILE")]
    pub apng: Option<PathBuf>,
    /// Write a chart of the energies against time (PNG; `-`: standard output, when it is not a
    /// terminal).
    #[arg(long, value_name = "FILE")]
    pub energy_chart: Option<PathBuf>,
    /// Playback rate of the GIF and APNG, frames per second.
    #[arg(long, default_value_t = 25.0, allow_negative_numbers = true)]
    pub fps: f64,
    /// Integration method, or one per body separated by commas.
    #[arg(long, short)]
    pub method: Option<String>,
    /// Time step in seconds (default: the scene's).
    #[arg(long, allow_negative_numbers = true)]
    pub dt: Option<f64>,
    /// Set a scene parameter, for example `--set stiffness=500` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Colour springs by kind or by strain.
    #[arg(long, value_enum, default_value_t = ColourBy::Kind)]
    pub colour: ColourBy,
    /// Strain shown at full colour with --colour strain (0.1 = 10 %).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub max_strain: f64,
    /// Spring kinds to draw: a comma-separated list of struct, shear, bend, or `none`.
    #[arg(long, default_value = "struct,shear,bend", value_name = "KINDS")]
    pub springs: String,
    /// Draw cloth and jelly lattices as springs instead of shaded surfaces.
    #[arg(long)]
    pub no_surfaces: bool,
    /// Leave out the text overlay.
    #[arg(long)]
    pub no_overlay: bool,
    /// Leave out the shadows (on the floors and planes, and of spheres on surfaces).
    #[arg(long)]
    pub no_shadows: bool,
    /// Camera orbit angle about the vertical axis in degrees (0: looking from +z).
    #[arg(long, allow_negative_numbers = true)]
    pub orbit: Option<f64>,
    /// Camera elevation in degrees (positive: looking down).
    #[arg(long, allow_negative_numbers = true)]
    pub elevation: Option<f64>,
    /// Orthographic instead of perspective projection.
    #[arg(long)]
    pub ortho: bool,
    /// Render even when the estimated steps, memory, pixels or time are over the limits.
    #[arg(long)]
    pub force: bool,
}

/// `--colour` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColourBy {
    /// Struct, shear and bend springs each their own colour.
    Kind,
    /// Blue compressed, grey at rest, red stretched.
    Strain,
}

/// Parses `WIDTHxHEIGHT` (`x`, `X` or `×`), each side 1 ..= 8192.
///
/// # Errors
/// A message naming the expected form or the allowed range.
pub fn parse_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let parts: Vec<&str> = text.trim().split(['x', 'X', '×']).collect();
    let [w, h] = parts.as_slice() else {
        bail!("--size {text}: expected WIDTHxHEIGHT in pixels, for example 640x480");
    };
    let parse = |s: &str| s.trim().parse::<u64>().ok();
    let (Some(w), Some(h)) = (parse(w), parse(h)) else {
        bail!("--size {text}: expected WIDTHxHEIGHT in pixels, for example 640x480");
    };
    if w == 0 || h == 0 {
        bail!("--size {text}: width and height must be at least 1 pixel");
    }
    if w > u64::from(MAX_SIDE) || h > u64::from(MAX_SIDE) {
        bail!("--size {text}: width and height must be at most {MAX_SIDE} pixels");
    }
    Ok((w as u32, h as u32))
}

/// Parses `--springs`: `none` or a comma-separated list of kinds.
///
/// # Errors
/// An unknown kind, with the known ones.
pub fn parse_kinds(text: &str) -> anyhow::Result<KindToggles> {
    let text = text.trim();
    if text == "none" {
        return Ok(KindToggles::NONE);
    }
    let mut toggles = KindToggles::NONE;
    for name in text.split(',').map(str::trim) {
        let Some(kind) = SpringKind::from_name(name) else {
            bail!(
                "--springs {text}: unknown spring kind `{name}`; expected struct, shear, bend (comma-separated) or none"
            );
        };
        toggles = toggles.with(kind, true);
    }
    Ok(toggles)
}

/// The validated plan of a render.
#[derive(Debug)]
struct Plan {
    frames: u64,
    every: u64,
    steps: u64,
    outputs: Outputs,
    chart: Option<PathBuf>,
    /// The frames' directory when this render created it: removed again (when still empty)
    /// if the render stops early.
    created_dir: Option<PathBuf>,
}

/// `springlab render`.
///
/// # Errors
/// Bad scene, parameters or options; an unwritable output.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let limits = Limits::forced(args.force);
    // Before anything is estimated from them (a zero would price the render as endless).
    if args.frames == Some(0) {
        bail!("--frames 0: expected at least 1 frame");
    }
    if args.every == Some(0) {
        bail!("--every 0: expected a number of steps >= 1");
    }
    if !(args.start >= 0.0 && args.start.is_finite()) {
        bail!(
            "--start {}: expected a time in seconds >= 0",
            short(args.start)
        );
    }
    let (width, height) = parse_size(&args.size)?;
    let toggles = parse_kinds(&args.springs)?;
    if !(args.fps.is_finite() && (0.1..=100.0).contains(&args.fps)) {
        bail!(
            "--fps {}: expected a frame rate from 0.1 to 100",
            short(args.fps)
        );
    }
    // Checked with either colouring: a bad value is refused, not ignored.
    if !(args.max_strain.is_finite() && args.max_strain > 0.0) {
        bail!(
            "--max-strain {}: expected a strain > 0 (0.1 = 10 %)",
            short(args.max_strain)
        );
    }
    let colouring = match args.colour {
        ColourBy::Kind => Colouring::ByKind,
        ColourBy::Strain => Colouring::ByStrain {
            max_strain: args.max_strain,
        },
    };
    let (scene, dt, estimate) = prepare(args, &limits)?;
    estimate.enforce(&limits)?;
    let plan = plan(args, dt, scene.duration)?;
    let result = render(args, scene, dt, &plan, colouring, toggles, width, height);
    if result.is_err()
        && let Some(dir) = &plan.created_dir
    {
        // Only an empty directory is removed: nothing of anyone else's.
        let _ = std::fs::remove_dir(dir);
    }
    result
}

/// The render itself, once every input is checked.
#[allow(clippy::too_many_arguments)]
fn render(
    args: &RenderArgs,
    scene: crate::scene::Scene,
    dt: f64,
    plan: &Plan,
    colouring: Colouring,
    toggles: KindToggles,
    width: u32,
    height: u32,
) -> anyhow::Result<()> {
    let style = Style {
        springs: toggles,
        colouring,
        cloth_surface: !args.no_surfaces,
        jelly_surface: !args.no_surfaces,
        overlay: !args.no_overlay,
        shadows: !args.no_shadows,
        ..Style::default()
    };
    let projection = if args.ortho {
        Projection::Orthographic { height: 1.0 }
    } else {
        Projection::default()
    };
    let mut renderer = Renderer::new(&scene, width, height, projection, style)?;
    if args.orbit.is_some() || args.elevation.is_some() {
        let mut camera = renderer.camera;
        if let Some(a) = args.orbit {
            camera.orbit = finite_degrees("--orbit", a)?;
        }
        if let Some(e) = args.elevation {
            camera.elevation = finite_degrees("--elevation", e)?
                .clamp(-89.0f64.to_radians(), 89.0f64.to_radians());
        }
        renderer.camera = camera;
        renderer.refit(&scene);
    }

    let mut sim = Simulation::new(scene);
    sim.set_dt(dt);
    let any_frames = plan.outputs.frames_dir.is_some()
        || plan.outputs.gif.is_some()
        || plan.outputs.apng.is_some();
    // Before any output exists: a signal from here on stops the loop, which removes them.
    interrupt::install(interrupt::Mode::Flag);
    let mut encoder = if any_frames {
        Some(FrameEncoder::start(plan.outputs.clone(), width, height)?)
    } else {
        None
    };
    let mut progress = Progress::new(
        if any_frames { plan.frames } else { plan.steps },
        &format!("render {}", args.scene),
    );

    // One loop over the whole run: `--start` steps first, then the frames. Frame k is drawn at
    // step start + k·every (frame 0 before any step when there is no --start). Within the
    // budget, the step counts fit in u64.
    let start_steps = (args.start / dt).round() as u64;
    let total = start_steps + plan.steps;
    // Energy samples: at most about 4000 over the run, and the last step.
    let stride = total.div_ceil(4000).max(1);
    let mut energies: Vec<EnergySample> = Vec::new();
    let mut drawn = 0u64;
    for step in 0..=total {
        if interrupt::requested() {
            // Ctrl-C: no output is kept (frames of this run, the animations' temporary files).
            progress.finish();
            if let Some(enc) = encoder {
                enc.abort();
            }
            return Err(interrupt::Interrupted.into());
        }
        if step > 0 && sim.step().is_some() {
            break;
        }
        if plan.chart.is_some() && (step.is_multiple_of(stride) || step == total) {
            energies.push(EnergySample {
                t: sim.time(),
                energy: sim.energy(),
                dissipated: sim.dissipated().total,
            });
        }
        if step >= start_steps
            && (step - start_steps).is_multiple_of(plan.every)
            && let Some(enc) = encoder.as_mut()
        {
            enc.send(renderer.draw_simulation(&sim))?;
            drawn += 1;
            progress.inc(1);
        }
        if !any_frames && step.is_multiple_of(1000) {
            progress.set(step.saturating_sub(start_steps));
        }
    }
    progress.finish();
    let written = match encoder {
        Some(enc) => enc.finish()?.frames,
        None => 0,
    };
    debug_assert_eq!(u64::from(written), drawn);
    if let Some(dir) = &plan.outputs.frames_dir {
        stale(dir, written, args.clean_frames)?;
    }

    if let Some(path) = &plan.chart {
        let chart = energy_chart(&sim, &energies);
        chart::save_png(&chart, path, width.max(480), height.max(320))
            .with_context(|| format!("cannot write the energy chart {}", path.display()))?;
    }
    report(&sim, plan, written, width, height)
}

/// The scene and time step (s) of `springlab render`, and its budget estimate (not yet
/// checked): steps (`--start` included), memory, frames and pixels, from the inputs alone.
///
/// # Errors
/// Bad scene, parameters, `--start`, `--size` or `--dt`.
pub fn prepare(
    args: &RenderArgs,
    limits: &Limits,
) -> anyhow::Result<(crate::scene::Scene, f64, budget::Estimate)> {
    if !(args.start >= 0.0 && args.start.is_finite()) {
        bail!(
            "--start {}: expected a time in seconds >= 0",
            short(args.start)
        );
    }
    let (width, height) = parse_size(&args.size)?;
    let mut scene = scene::load_with(&args.scene, &args.sets, limits)?;
    if let Some(m) = &args.method {
        apply_methods(&mut scene, m)?;
    }
    let dt = check_dt(args.dt.unwrap_or(scene.dt))?;
    if let Some(t) = args.time {
        check_dt_within(dt, t, "--time")?;
    }
    // The budget, from the inputs alone: steps (--start included), memory, pixels.
    let every = every(args, dt);
    let start_steps = (args.start / dt).round();
    let run_steps = match (args.frames, args.time) {
        (Some(n), _) => n.saturating_sub(1) as f64 * every as f64,
        (None, Some(t)) => (t / dt).round(),
        (None, None) => (scene.duration / dt).round(),
    };
    let frames = args
        .frames
        .map_or_else(|| (run_steps / every as f64).floor() + 1.0, |n| n as f64);
    let steps = start_steps + run_steps;
    let mut estimate = budget::run(format!("render {}", args.scene), &scene, dt, steps);
    let draws_frames = args.out.is_some()
        || args.gif.is_some()
        || args.apng.is_some()
        || args.energy_chart.is_none();
    if draws_frames {
        budget::add_frames(
            &mut estimate,
            frames,
            (width, height),
            crate::render::export::PIXEL_BYTES,
            &format!("--size {}", args.size.trim()),
        );
    }
    Ok((scene, dt, estimate))
}

/// Validates the frame counts and outputs.
fn plan(args: &RenderArgs, dt: f64, duration: f64) -> anyhow::Result<Plan> {
    let every = every(args, dt);
    let (frames, steps) = match (args.frames, args.time) {
        (Some(n), _) => (
            n,
            (n - 1)
                .checked_mul(every)
                .context("--frames × --every is too many steps")?,
        ),
        (None, Some(t)) => {
            if !(t.is_finite() && t >= 0.0) {
                bail!("--time {}: expected a duration in seconds >= 0", short(t));
            }
            let steps = (t / dt).round() as u64;
            (steps / every + 1, steps)
        }
        (None, None) if args.energy_chart.is_some() => {
            let steps = (duration / dt).round() as u64;
            (steps / every + 1, steps)
        }
        (None, None) => bail!(
            "render needs --frames N (or --time T); for example `springlab render {} --frames 60 --gif out.gif`",
            args.scene
        ),
    };
    let frames_dir = match &args.out {
        Some(dir) => Some(dir.clone()),
        None if args.gif.is_none() && args.apng.is_none() && args.energy_chart.is_none() => {
            Some(PathBuf::from("frames"))
        }
        None => None,
    };
    let expected_frames = u32::try_from(frames)
        .ok()
        .filter(|&f| f <= 1_000_000)
        .with_context(|| format!("{frames} frames: at most 1000000 frames are allowed"))?;
    // Fail before the simulation when any output cannot be written.
    let files: Vec<(&str, &PathBuf)> = [
        ("--gif", &args.gif),
        ("--apng", &args.apng),
        ("--energy-chart", &args.energy_chart),
    ]
    .into_iter()
    .filter_map(|(flag, path)| Some((flag, path.as_ref()?)))
    .collect();
    for (i, (flag, file)) in files.iter().enumerate() {
        output::check_file(file)?;
        if output::is_stdout(file) && std::io::stdout().is_terminal() {
            bail!(
                "{flag} {}: standard output is a terminal; give a file, or pipe the image to a \
                 program",
                file.display()
            );
        }
        if let Some((other, _)) = files[..i]
            .iter()
            .find(|(_, earlier)| output::same_target(earlier, file))
        {
            bail!(
                "{other} and {flag} both write {}; give each output its own file",
                file.display()
            );
        }
    }
    let mut created_dir = None;
    if let Some(dir) = &frames_dir {
        if dir.as_os_str() == output::STDOUT {
            bail!("--out -: frames go to a directory, not to standard output");
        }
        if !dir.exists() {
            created_dir = Some(dir.clone());
        }
        output::check_dir(dir)?;
    }
    Ok(Plan {
        frames,
        every,
        steps,
        outputs: Outputs {
            frames_dir,
            gif: args.gif.clone(),
            apng: args.apng.clone(),
            fps: args.fps,
            expected_frames,
        },
        chart: args.energy_chart.clone(),
        created_dir,
    })
}

/// Steps between frames: `--every`, or the steps of 1/fps seconds of simulated time (real-time
/// playback), at least 1.
fn every(args: &RenderArgs, dt: f64) -> u64 {
    args.every
        .unwrap_or_else(|| ((1.0 / args.fps) / dt).round().clamp(1.0, 1e18) as u64)
}

fn finite_degrees(flag: &str, degrees: f64) -> anyhow::Result<f64> {
    if degrees.is_finite() {
        Ok(degrees.to_radians())
    } else {
        bail!("{flag} {}: expected an angle in degrees", short(degrees))
    }
}

/// One sample of the energy chart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergySample {
    /// Simulated time (s).
    pub t: f64,
    /// The energy terms (J).
    pub energy: crate::physics::Energy,
    /// Energy dissipated since the start (J).
    pub dissipated: f64,
}

/// The energy chart of a run: kinetic, gravitational, elastic and total energy against time,
/// the dissipated energy as a band on top of the total (total + dissipated stays at `E_0` for an
/// exact integrator), and the residual `E + D - E_0`, the method's own energy error.
#[must_use]
pub fn energy_chart(sim: &Simulation, samples: &[EnergySample]) -> Chart {
    let series = |name: &str, c: Colour, f: &dyn Fn(&EnergySample) -> f64| {
        Series::line(name, samples.iter().map(|s| (s.t, f(s))).collect()).with_colour(c)
    };
    let mut title = format!(
        "Energy: {} ({}, dt = {} s)",
        sim.scene.name,
        sim.scene.method_label(),
        sim.dt()
    );
    if let Some(d) = &sim.diverged {
        title.push_str(&format!(", diverged at t = {:.3} s", d.time));
    }
    let e0 = sim.energy_initial();
    let total: Vec<(f64, f64)> = samples.iter().map(|s| (s.t, s.energy.total)).collect();
    let mut chart = Chart::new(title, "time t (s)", "energy E (J)")
        .with(series("kinetic", colour::SERIES[1], &|s| s.energy.kinetic))
        .with(series("gravitational", colour::SERIES[2], &|s| {
            s.energy.gravity
        }))
        .with(series("elastic", colour::SERIES[4], &|s| s.energy.elastic));
    if sim.accounting() {
        chart = chart
            .with(
                series("total + dissipated", Colour::rgb(70, 110, 200), &|s| {
                    s.energy.total + s.dissipated
                })
                .with_band(total),
            )
            .with(series(
                "residual E + D - E0",
                Colour::rgb(200, 30, 30),
                &|s| s.energy.total + s.dissipated - e0,
            ));
    }
    chart.with(series("total", Colour::rgb(30, 30, 30), &|s| {
        s.energy.total
    }))
}

/// Names (or with `--clean-frames` removes) the frames of an earlier, longer render that this
/// render of `written` frames left in `dir`: never mixed in silently.
fn stale(dir: &std::path::Path, written: u32, clean: bool) -> anyhow::Result<()> {
    let stale = crate::render::export::stale_frames(dir, written);
    let (Some(first), Some(last)) = (stale.first(), stale.last()) else {
        return Ok(());
    };
    let name = |p: &std::path::Path| {
        p.file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    };
    let range = if stale.len() == 1 {
        name(first)
    } else {
        format!("{} … {}", name(first), name(last))
    };
    if clean {
        for path in &stale {
            std::fs::remove_file(path)
                .with_context(|| format!("cannot remove {}", path.display()))?;
        }
        eprintln!(
            "springlab: removed {} frames of an earlier render from {} ({range})",
            stale.len(),
            dir.display()
        );
    } else {
        eprintln!(
            "springlab: {} also holds {} frames of an earlier render ({range}), left in place; \
             --clean-frames removes them",
            dir.display(),
            stale.len()
        );
    }
    Ok(())
}

/// One line per output, and the divergence if any.
fn report(
    sim: &Simulation,
    plan: &Plan,
    written: u32,
    width: u32,
    height: u32,
) -> anyhow::Result<()> {
    use std::io::Write;
    // An image on standard output: the report goes to standard error.
    let on_stdout = [&plan.outputs.gif, &plan.outputs.apng, &plan.chart]
        .into_iter()
        .flatten()
        .any(|p| output::is_stdout(p));
    let mut out: Box<dyn Write> = if on_stdout {
        Box::new(std::io::stderr().lock())
    } else {
        Box::new(std::io::stdout().lock())
    };
    if let Some(dir) = &plan.outputs.frames_dir {
        let dir = dir.display();
        if written == 1 {
            writeln!(
                out,
                "wrote 1 frame of {width}x{height} to {dir}/frame_00000.png"
            )?;
        } else {
            let last = written.saturating_sub(1);
            writeln!(
                out,
                "wrote {written} frames of {width}x{height} to {dir}/frame_00000.png … frame_{last:05}.png"
            )?;
        }
    }
    if let Some(f) = &plan.outputs.gif {
        writeln!(
            out,
            "wrote GIF {} ({written} frames, {} fps)",
            f.display(),
            plan.outputs.fps
        )?;
    }
    if let Some(f) = &plan.outputs.apng {
        writeln!(
            out,
            "wrote APNG {} ({written} frames, {} fps)",
            f.display(),
            plan.outputs.fps
        )?;
    }
    if let Some(f) = &plan.chart {
        writeln!(out, "wrote energy chart {}", f.display())?;
    }
    if let Some(d) = &sim.diverged {
        eprintln!(
            "springlab: the run diverged at step {} (t = {} s): {}; max speed {:.4e} m/s. Rendering stopped after {written} of {} frames.",
            d.step, d.time, d.reason, d.max_speed, plan.frames
        );
    }
    Ok(())
}
