//! Argument parsing and dispatch. Each subcommand lives in its own module; this one holds
//! the shared flags, output helpers and the mapping from errors to exit codes.

mod calib;
mod config;
mod convert;
mod estimate;
mod fit;
mod flags;
mod info;
mod load;
mod output;
mod report;
mod simulate;
mod stats;

use clap::{Args, Parser, Subcommand};
use ctcal::io::write::OutputPolicy;
use ctcal::{Format, OpenOptions, Sensor};
use std::path::{Path, PathBuf};

/// ctcal: contrast thresholds, noise and statistics of event cameras and datasets.
#[derive(Parser, Debug)]
#[command(name = "ctcal", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    #[command(flatten)]
    pub global: Global,
    #[command(subcommand)]
    pub command: Command,
}

/// Flags every command takes.
#[derive(Args, Debug, Clone)]
pub struct Global {
    /// Silence progress bars and warnings (errors still go to stderr).
    #[arg(long, global = true)]
    pub quiet: bool,
    /// Bound the number of worker threads (default: all cores).
    #[arg(long, global = true, value_name = "N")]
    pub threads: Option<usize>,
    /// Write into an existing folder ctcal did not create (replacing only the files ctcal
    /// writes), replace a file ctcal did not write, write inside an input folder, and run
    /// work beyond the stated budgets.
    #[arg(long, global = true)]
    pub force: bool,
}

/// The most worker threads ctcal starts (more only cost memory and scheduling).
pub const MAX_THREADS: usize = 256;

impl Global {
    /// The output rules for a command reading `inputs`.
    pub fn outputs<'a>(&self, inputs: impl IntoIterator<Item = &'a Path>) -> OutputPolicy {
        OutputPolicy::new(self.force).protect_all(inputs)
    }
}

/// How to open an input recording.
#[derive(Args, Debug, Clone)]
pub struct InputArgs {
    /// Recording: an IJRR folder or events.txt, HDF5 (event_utils, v2e, MVSEC, DSEC), AEDAT4,
    /// Prophesee RAW (EVT2/EVT3) or DAT, or a ROS bag.
    pub input: PathBuf,
    /// Read as this format instead of detecting it from the content.
    #[arg(long, value_name = "ijrr|h5|aedat4|evt2|evt3|dat|bag")]
    pub format: Option<Format>,
    /// Sensor size WxH, overriding the file's own metadata.
    #[arg(long, value_name = "WxH", value_parser = parse_sensor)]
    pub sensor: Option<Sensor>,
    /// ROS bags: the dvs_msgs/EventArray topic to read (when there are several).
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
    /// ROS bags: the sensor_msgs/Image topic of the frames (when there are several).
    #[arg(long, value_name = "NAME")]
    pub image_topic: Option<String>,
    /// MVSEC HDF5: which camera of the stereo pair.
    #[arg(long, value_name = "left|right")]
    pub side: Option<ctcal::io::h5::Side>,
}

impl InputArgs {
    pub fn open_options(&self) -> OpenOptions {
        OpenOptions {
            format: self.format,
            sensor: self.sensor,
            topic: self.topic.clone(),
            image_topic: self.image_topic.clone(),
            side: self.side,
        }
    }
}

/// Which pixels to analyse (every command that measures takes these).
#[derive(Args, Debug, Clone, Default)]
pub struct SelectionArgs {
    /// Only the pixels X0 <= x < X1, Y0 <= y < Y1 (X1 and Y1 excluded, as in array slices).
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = ctcal::selection::Roi::parse)]
    pub roi: Option<ctcal::selection::Roi>,
    /// Only the pixels a mask keeps: a PNG or .npy array of the sensor's size (H x W),
    /// non-zero = keep.
    #[arg(long, value_name = "FILE")]
    pub mask: Option<PathBuf>,
    /// Leave out the hot pixels the statistics find (a first pass finds them).
    #[arg(long)]
    pub exclude_hot_pixels: bool,
}

impl SelectionArgs {
    /// Whether anything narrows the sensor.
    pub fn is_set(&self) -> bool {
        self.roi.is_some() || self.mask.is_some() || self.exclude_hot_pixels
    }

    /// The region and mask, as the library takes them.
    pub fn spec(&self) -> ctcal::window::SelectionSpec {
        ctcal::window::SelectionSpec {
            roi: self.roi,
            mask: self.mask.clone(),
        }
    }

    /// The region and mask for `sensor` (hot pixels are left out by the caller, who finds
    /// them); `input` names the recording in errors. A selection holds a flag per pixel: a
    /// sensor over the pixel budget is refused unless `force`. A selection that keeps no
    /// pixel is an error naming what emptied it.
    pub fn build(
        &self,
        sensor: Sensor,
        input: &Path,
        force: bool,
    ) -> anyhow::Result<ctcal::selection::PixelSelection> {
        self.spec()
            .build(sensor, input, force)
            .map_err(load::hinted)
    }
}

fn parse_sensor(text: &str) -> Result<Sensor, String> {
    Sensor::parse(text).ok_or_else(|| format!("`{text}` is not WxH (e.g. 346x260)"))
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Format, sensor size, event count, time span and frame count of a recording.
    Info(info::InfoArgs),
    /// Rewrite a recording as an IJRR folder, an event_utils HDF5 file or Prophesee EVT3.
    Convert(convert::ConvertArgs),
    /// Event statistics: rates, timeline, hot pixels, background rate, intervals.
    Stats(stats::StatsArgs),
    /// Simulate events from frames or a scene through the pixel model.
    Simulate(simulate::SimulateArgs),
    /// Calibration stimuli to play on a monitor.
    #[command(subcommand)]
    Calib(calib::CalibCommand),
    /// Contrast thresholds: from grey frames (aps), event rate (eppps) or a screen (screen).
    #[command(subcommand)]
    Estimate(estimate::EstimateCommand),
    /// Fit every simulator parameter; add the effects the residuals call for.
    Fit(fit::FitArgs),
    /// A paper-style report: statistics, every estimate and the fit of each recording,
    /// plots, tables and simulator configurations.
    Report(report::ReportArgs),
    /// Simulator configurations (ESIM, esim_config_generator, v2e, ctcal) from fits or a
    /// report.
    Config(config::ConfigArgs),
}

/// A problem with the command line or the input that the user can fix (exit code 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// Runs the command line; returns the process exit code.
pub fn run() -> i32 {
    let cli = Cli::parse();
    if let Some(n) = cli.global.threads {
        if n == 0 || n > MAX_THREADS {
            eprintln!(
                "error: --threads {n} is outside 1..={MAX_THREADS}\n  fix: give a number of threads up to the machine's cores ({})",
                std::thread::available_parallelism().map_or(1, |n| n.get())
            );
            return 2;
        }
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            eprintln!("error: cannot start {n} threads: {e}");
            return 1;
        }
    }
    let result = match &cli.command {
        Command::Info(args) => info::run(args, &cli.global),
        Command::Convert(args) => convert::run(args, &cli.global),
        Command::Stats(args) => stats::run(args, &cli.global),
        Command::Simulate(args) => simulate::run(args, &cli.global),
        Command::Calib(command) => calib::run(command, &cli.global),
        Command::Estimate(command) => estimate::run(command, &cli.global),
        Command::Fit(args) => fit::run(args, &cli.global),
        Command::Report(args) => report::run(args, &cli.global),
        Command::Config(args) => config::run(args, &cli.global),
    };
    match result {
        Ok(()) => 0,
        // the reader of stdout went away (`ctcal stats ... | head`): nothing is wrong
        Err(error) if is_broken_pipe(&error) => 0,
        Err(error) => {
            eprintln!("error: {}", flags::message(&error));
            exit_code(&error)
        }
    }
}

fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// 2 for problems with the input or usage, 1 for everything else.
fn exit_code(error: &anyhow::Error) -> i32 {
    for cause in error.chain() {
        if let Some(e) = cause.downcast_ref::<ctcal::InputError>() {
            return if e.is_bad_input() { 2 } else { 1 };
        }
        if cause.is::<BadInput>() {
            return 2;
        }
        if cause.is::<ctcal::sim::SimError>()
            || cause.is::<ctcal::sim::ParamsError>()
            || cause.is::<ctcal::estimate::EstimateError>()
        {
            return 2;
        }
    }
    1
}

/// Prints a warning to stderr unless quiet.
pub fn warn(global: &Global, message: &str) {
    if !global.quiet {
        eprintln!("warning: {message}");
    }
}

/// A progress bar over bytes (or rows) of input on stderr; hidden when quiet or not a TTY.
pub fn progress_bar(global: &Global, total: u64, what: &str) -> indicatif::ProgressBar {
    if global.quiet {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(total),
        indicatif::ProgressDrawTarget::stderr(),
    );
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {percent}% {elapsed_precise}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

pub use output::{JsonTarget, check_json, emit_json};
