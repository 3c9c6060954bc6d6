//! `ctcal calib checkerboard`: writes an on-screen calibration stimulus (Stoffregen et al.
//! 2020, method 3) as `stimulus.txt` + `stimulus/frame_XXXXXXXX.png`.

use super::{BadInput, Global, warn};
use clap::{Args, Subcommand};
use ctcal::io::write::{format_seconds, save_png};
use ctcal::sim::budget::{MAX_SIDE, Work};
use ctcal::sim::scene::stimulus::StimulusSpec;
use std::path::PathBuf;

#[derive(Subcommand, Debug)]
pub enum CalibCommand {
    /// A moving checkerboard on grey, to play full-screen on a monitor.
    Checkerboard(CheckerboardArgs),
}

#[derive(Args, Debug)]
pub struct CheckerboardArgs {
    /// Output folder.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Monitor refresh rate (one stimulus frame per refresh).
    #[arg(long, value_name = "N", default_value_t = 75.0)]
    pub refresh_hz: f64,
    /// Screen width in pixels.
    #[arg(long, value_name = "W", default_value_t = 240)]
    pub width: usize,
    /// Screen height in pixels.
    #[arg(long, value_name = "H", default_value_t = 180)]
    pub height: usize,
    /// Square size in screen pixels.
    #[arg(long, value_name = "N", default_value_t = 15.0)]
    pub square_px: f64,
    /// Squares across x down (the board is centred on the screen).
    #[arg(long, value_name = "NxM", default_value = "8x6")]
    pub squares: String,
    /// Board speed in screen pixels per second.
    #[arg(long, value_name = "V", default_value_t = 40.0)]
    pub speed_px_s: f64,
    /// Length of the stimulus.
    #[arg(long, value_name = "D", default_value_t = 1.0)]
    pub duration_s: f64,
}

pub fn run(command: &CalibCommand, global: &Global) -> anyhow::Result<()> {
    let CalibCommand::Checkerboard(args) = command;
    let squares = parse_squares(&args.squares)?;
    check_ranges(args)?;
    let spec = StimulusSpec {
        width: args.width,
        height: args.height,
        refresh_hz: args.refresh_hz,
        duration_s: args.duration_s,
        square_px: args.square_px,
        squares: [squares.width as usize, squares.height as usize],
        speed_px_s: args.speed_px_s,
    };
    check_board(args, squares, global)?;
    Work::new(spec.frame_count() as f64, args.width, args.height).check(
        "the stimulus",
        "lower --duration-s, --refresh-hz or the screen size",
        global.force,
    )?;
    write_stimulus(args, global, &spec)?;
    if !global.quiet {
        super::output::stdout(&format!(
            "wrote {} frames at {} Hz to {}\n",
            spec.frame_count(),
            args.refresh_hz,
            args.out.display()
        ))?;
    }
    Ok(())
}

/// `--squares NxM`: the board's squares across and down (read as a sensor size is).
fn parse_squares(squares: &str) -> Result<ctcal::Sensor, BadInput> {
    ctcal::Sensor::parse(squares)
        .ok_or_else(|| BadInput(format!("--squares `{squares}` is not NxM (e.g. 8x6)")))
}

/// Every number within its range: `--refresh-hz`, `--square-px` and `--duration-s`
/// positive and at most 1000 Hz, [`MAX_SIDE`] pixels and a day; `--speed-px-s` from 0 to
/// 100,000 pixels per second; the screen 1 to [`MAX_SIDE`] pixels a side.
fn check_ranges(args: &CheckerboardArgs) -> Result<(), BadInput> {
    for (name, value, max) in [
        ("--refresh-hz", args.refresh_hz, 1000.0),
        ("--square-px", args.square_px, MAX_SIDE as f64),
        ("--duration-s", args.duration_s, 86_400.0),
    ] {
        if !(value.is_finite() && value > 0.0 && value <= max) {
            return Err(BadInput(format!(
                "{name} {value} must be a positive number up to {max}\n  fix: give {name} in its unit (Hz, pixels or seconds)"
            )));
        }
    }
    if !(args.speed_px_s.is_finite() && args.speed_px_s >= 0.0 && args.speed_px_s <= 1e5) {
        return Err(BadInput(format!(
            "--speed-px-s {} must be between 0 and 100000 pixels per second",
            args.speed_px_s
        )));
    }
    if args.width == 0 || args.height == 0 || args.width > MAX_SIDE || args.height > MAX_SIDE {
        return Err(BadInput(format!(
            "the screen is {}x{}; --width and --height must be 1..={MAX_SIDE} pixels",
            args.width, args.height
        )));
    }
    Ok(())
}

/// The board (`squares` of `--square-px` each) must fit the screen; where it fills the
/// screen along an axis it cannot move along that axis (a warning, not a refusal).
fn check_board(
    args: &CheckerboardArgs,
    squares: ctcal::Sensor,
    global: &Global,
) -> Result<(), BadInput> {
    let board = (
        squares.width as f64 * args.square_px,
        squares.height as f64 * args.square_px,
    );
    if board.0 > args.width as f64 || board.1 > args.height as f64 {
        return Err(BadInput(format!(
            "the {}x{} px board does not fit the {}x{} screen\n  fix: use fewer or smaller squares",
            board.0, board.1, args.width, args.height
        )));
    }
    if board.0 == args.width as f64 || board.1 == args.height as f64 {
        warn(
            global,
            "the board fills the screen along one axis, so it cannot move along it",
        );
    }
    Ok(())
}

/// Writes the stimulus (Stoffregen et al. 2020's method 3 checkerboard) into `--out`
/// (staged, then committed whole): one PNG per monitor refresh (`stimulus/frame_XXXXXXXX.png`), `stimulus.txt` listing each frame as `t path`
/// (t in seconds to the microsecond, as an IJRR `images.txt`) and `stimulus.json` (the
/// spec it was rendered from).
fn write_stimulus(
    args: &CheckerboardArgs,
    global: &Global,
    spec: &StimulusSpec,
) -> anyhow::Result<()> {
    let staged = global.outputs([]).folder(&args.out)?;
    let write_error = |e: std::io::Error| ctcal::InputError::write(&args.out, e);
    std::fs::create_dir_all(staged.dir().join("stimulus")).map_err(write_error)?;
    let mut index = Vec::new();
    for k in 0..spec.frame_count() {
        let frame = spec.render(k);
        let name = format!("stimulus/frame_{k:08}.png");
        save_png(&staged.dir().join(&name), &frame).map_err(write_error)?;
        format_seconds(frame.t, &mut index);
        index.extend_from_slice(format!(" {name}\n").as_bytes());
    }
    staged.write("stimulus.txt", &index)?;
    staged.write("stimulus.json", super::output::json_text(spec)?.as_bytes())?;
    staged.commit()?;
    Ok(())
}
