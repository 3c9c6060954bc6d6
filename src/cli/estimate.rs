//! `ctcal estimate aps|eppps|screen`: contrast thresholds three ways (see `ctcal::estimate`).

use super::load::{Loaded, Window, load};
use super::{
    BadInput, Global, InputArgs, JsonTarget, SelectionArgs, check_json, emit_json, output,
};
use clap::{Args, Subcommand, ValueEnum};
use ctcal::estimate::CtEstimate;
use ctcal::estimate::aps::ApsOptions;
use ctcal::estimate::eppps;
use ctcal::estimate::timing::ThresholdMaps;
use ctcal::sim::DisplayParams;
use ctcal::sim::LogResponse;
use ctcal::sim::log_response::LogMap;
use std::path::{Path, PathBuf};

/// `estimate eppps` and `estimate screen` of a loaded recording, and the built-in screen
/// model, as the report uses them.
pub(super) use ctcal::window::{eppps_of, screen_of};

#[derive(Subcommand, Debug)]
pub enum EstimateCommand {
    /// From the recording's grey frames: re-simulation and event timing, per-pixel maps.
    Aps(ApsArgs),
    /// From events per pixel of travel, against line scans through the frames or natural images.
    Eppps(EpppsArgs),
    /// From a recording of the `calib checkerboard` stimulus on a monitor.
    Screen(ScreenArgs),
}

#[derive(Args, Debug)]
pub struct EpppsArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Measure the flow from the events and use the natural-image prior even when the
    /// recording has frames.
    #[arg(long)]
    pub ignore_frames: bool,
    /// Natural images of the prior to calibrate against (without frames), at most all of
    /// them.
    #[arg(long, value_name = "N", default_value_t = ctcal::estimate::eppps::prior::COUNT)]
    pub scenes: usize,
    /// Use at most this many frames for the dynamics (of a sensor up to 346x260; fewer of a
    /// larger one).
    #[arg(long, value_name = "N", default_value_t = 120)]
    pub max_frames: usize,
    /// Seed of the calibration simulations (`ctcal report --seed` gives the same numbers).
    #[arg(long, value_name = "N", default_value_t = ctcal::DEFAULT_SEED)]
    pub seed: u64,
}

#[derive(Args, Debug)]
pub struct ScreenArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// A folder with the stimulus's `stimulus.txt` (default: the recording folder's own).
    #[arg(long, value_name = "DIR")]
    pub stimulus: Option<PathBuf>,
    /// The screen model to start from (refresh_hz, gamma, black_level, white_dn, blur_px;
    /// see calib/screens/); default a typical 60 Hz LCD.
    #[arg(long, value_name = "SCREEN.toml")]
    pub screen: Option<PathBuf>,
    /// The monitor's refresh rate, when not the stimulus's frame rate.
    #[arg(long, value_name = "HZ")]
    pub refresh_hz: Option<f64>,
}

/// How the sensor maps intensity to the log domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LogResponseArg {
    /// ln(DN) above 20 DN, linear below (v2e).
    V2e,
    /// ln(DN / 255 + eps).
    Eps,
}

/// Options every estimate takes.
#[derive(Args, Debug)]
pub struct CommonArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Write the estimate as JSON to PATH (`-` for stdout).
    #[arg(long, value_name = "PATH")]
    pub json: Option<PathBuf>,
    /// Only the part of the recording from S seconds after its first event.
    #[arg(long, value_name = "S")]
    pub start: Option<f64>,
    /// Only the part up to S seconds after the first event.
    #[arg(long, value_name = "S")]
    pub end: Option<f64>,
    /// The sensor's log response (default: v2e's lin-log, or a pure ln(DN + b) where the
    /// events' timing says it fits better; `estimate screen` fits both and reports the
    /// better, the other in its intervals when it fits as well).
    #[arg(long, value_enum)]
    pub log_response: Option<LogResponseArg>,
    /// The offset of the `eps` log response.
    #[arg(long, value_name = "EPS", default_value_t = 0.001)]
    pub log_eps: f64,
    /// Which pixels to use (hot pixels are always left out of estimates).
    #[command(flatten)]
    pub selection: SelectionArgs,
}

impl CommonArgs {
    /// Whether the response may be chosen from the data (none was named).
    pub(super) fn choose_response(&self) -> bool {
        self.log_response.is_none()
    }

    pub(super) fn log_map(&self) -> Result<(LogMap, String), BadInput> {
        if !(self.log_eps.is_finite() && self.log_eps > 0.0) {
            return Err(BadInput(format!(
                "--log-eps {} must be positive",
                self.log_eps
            )));
        }
        Ok(match self.log_response.unwrap_or(LogResponseArg::V2e) {
            LogResponseArg::V2e => (
                LogMap::new(LogResponse::V2e, self.log_eps),
                "v2e lin-log: ln(DN) above 20 DN, linear below".into(),
            ),
            LogResponseArg::Eps => (
                LogMap::new(LogResponse::Eps, self.log_eps),
                format!("ln(DN / 255 + {})", self.log_eps),
            ),
        })
    }

    /// Reads the recording in `--start`/`--end` and the selected pixels, with at most
    /// `frames` frames (none if `None`).
    pub(super) fn load(
        &self,
        frames: Option<usize>,
        events_between_frames: bool,
        global: &Global,
    ) -> anyhow::Result<Loaded> {
        load(
            &self.input,
            &Window {
                start_s: self.start,
                end_s: self.end,
                frames,
                events_between_frames,
            },
            &self.selection,
            global,
        )
    }
}

#[derive(Args, Debug)]
pub struct ApsArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Write the per-pixel maps (ct_on.npy, ct_off.npy, ct_count.npy) to this folder.
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,
    /// Exposure time of the frames, where the file does not say.
    #[arg(long, value_name = "S")]
    pub exposure_s: Option<f64>,
    /// Use at most this many frames (of a sensor up to 346x260; a larger sensor's frames
    /// count for their pixels: 40 of 1280x720 at 120): a window with more is measured on
    /// blocks of 20 consecutive frames, one in each equal part of it, each where its part
    /// has the most events (only their frames and events are read).
    #[arg(long, value_name = "N", default_value_t = 120)]
    pub max_frames: usize,
    /// Seconds to add to the frames' times (default: found where the events agree best with
    /// the frames).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub frame_time_offset_s: Option<f64>,
    /// DN to add to the frames before the log (a subtracted black level); default:
    /// estimated when frames have pixels clipped at 0.
    #[arg(long, value_name = "DN")]
    pub frame_offset_dn: Option<f64>,
    /// Measure at most this many pixels (0: no pixel limit; at least 64 x 48). A larger
    /// sensor is measured on the rectangle of this many pixels, of its aspect, where its
    /// events are densest (named in `assumptions`; the maps NaN outside it).
    #[arg(long, value_name = "N", default_value_t = ctcal::fit_region::FIT_PIXELS)]
    pub max_pixels: usize,
    /// Measure about this many events (0: no limit). A window with more is measured on the
    /// rectangle of the sensor's aspect where its events are densest, holding about this
    /// many (at least 64 x 48 pixels; named in `assumptions`): the timing and the
    /// re-simulations of the frames grow with the events.
    #[arg(long, value_name = "N", default_value_t = ctcal::fit_region::FIT_EVENTS)]
    pub max_events: usize,
}

/// An estimate's error for `path`, its fix in the command's flags.
pub(super) fn estimate_failed(path: &Path, error: &ctcal::estimate::EstimateError) -> BadInput {
    BadInput(format!(
        "{}: {}",
        path.display(),
        super::flags::render(&error.message())
    ))
}

pub fn run(command: &EstimateCommand, global: &Global) -> anyhow::Result<()> {
    match command {
        EstimateCommand::Aps(args) => run_aps(args, global),
        EstimateCommand::Eppps(args) => run_eppps(args, global),
        EstimateCommand::Screen(args) => run_screen(args, global),
    }
}

fn run_eppps(args: &EpppsArgs, global: &Global) -> anyhow::Result<()> {
    let common = &args.common;
    let (log_map, log_name) = common.log_map()?;
    let most = ctcal::estimate::eppps::prior::COUNT;
    if args.scenes == 0 || args.scenes > most {
        return Err(BadInput(format!(
            "--scenes {} must be between 1 and {most}",
            args.scenes
        ))
        .into());
    }
    let policy = global.outputs([common.input.input.as_path()]);
    check_json(common.json.as_deref(), &policy)?;
    let loaded = common.load(
        (!args.ignore_frames).then_some(args.max_frames.max(2)),
        false,
        global,
    )?;
    let path = loaded.recording.path.clone();
    let spinner = stage_spinner(global);
    let progress = |stage: &str, _: f64| spinner.set_message(stage.to_string());
    let options = ApsOptions {
        log_map,
        log_response_name: log_name,
        choose_response: common.choose_response(),
        ..ApsOptions::default()
    };
    let result = eppps_of(
        &loaded,
        &options,
        eppps::EpppsOptions {
            scenes: args.scenes,
            seed: args.seed,
            ..eppps::EpppsOptions::default()
        },
        &progress,
    );
    spinner.finish_and_clear();
    let mut estimate = result.map_err(|e| estimate_failed(&path, &e))?;
    if args.ignore_frames {
        estimate
            .assumptions
            .push("frames ignored (--ignore-frames)".into());
    }
    for said in &mut estimate.assumptions {
        if said.starts_with(eppps::RESPONSE_NOT_MEASURED) {
            said.push_str("; give it with --log-response");
        }
    }
    present(&estimate, &loaded, common, &policy)
}

fn run_screen(args: &ScreenArgs, global: &Global) -> anyhow::Result<()> {
    let common = &args.common;
    if let Some(r) = args.refresh_hz
        && !(r.is_finite() && (1.0..=1000.0).contains(&r))
    {
        return Err(BadInput(format!("--refresh-hz {r} must be between 1 and 1000")).into());
    }
    let mut inputs = vec![common.input.input.as_path()];
    inputs.extend(args.stimulus.as_deref());
    inputs.extend(args.screen.as_deref());
    let policy = global.outputs(inputs);
    check_json(common.json.as_deref(), &policy)?;
    let screen = args.screen.as_deref().map(screen_model).transpose()?;
    // --log-eps is checked whether or not a response is named
    let (log, _) = common.log_map()?;
    let response = (!common.choose_response()).then_some(log);
    let loaded = common.load(None, false, global)?;
    let path = loaded.recording.path.clone();
    let frames = stimulus_frames(args.stimulus.as_deref(), &loaded)?;
    let spinner = stage_spinner(global);
    let progress = |stage: &str, _: f64| spinner.set_message(stage.to_string());
    let result = screen_of(
        &loaded,
        &frames,
        (screen, response),
        args.refresh_hz,
        &progress,
    );
    spinner.finish_and_clear();
    let estimate = result.map_err(|e| estimate_failed(&path, &e))?;
    present(&estimate, &loaded, common, &policy)
}

/// The screen model of `--screen` (a SCREEN.toml).
fn screen_model(path: &Path) -> anyhow::Result<DisplayParams> {
    let text = ctcal::files::read_small_text(path, 1 << 20)
        .map_err(|e| ctcal::InputError::not_a_file(path, e))?;
    Ok(DisplayParams::from_toml(
        &text,
        &path.display().to_string(),
    )?)
}

/// The frames of the stimulus that was played: `--stimulus` (a folder with its
/// `stimulus.txt`, or that file), else the recording's own; refused where there is none,
/// or where it has fewer than 2 or more than 100000 frames.
fn stimulus_frames(
    stimulus: Option<&Path>,
    loaded: &Loaded,
) -> anyhow::Result<Vec<ctcal::events::Frame>> {
    let path = &loaded.recording.path;
    let stimulus = match stimulus {
        Some(dir) => {
            let index = if dir.is_dir() {
                dir.join("stimulus.txt")
            } else {
                dir.to_path_buf()
            };
            Some(ctcal::io::FrameList::read(&index)?)
        }
        None => loaded.recording.stimulus()?,
    };
    let Some(stimulus) = stimulus else {
        return Err(BadInput(format!(
            "{}: `estimate screen` needs the stimulus that was played; the recording has no stimulus.txt\n  fix: pass --stimulus DIR (the folder `ctcal calib checkerboard` wrote)",
            path.display()
        ))
        .into());
    };
    if stimulus.len() < 2 || stimulus.len() > 100_000 {
        return Err(BadInput(format!(
            "{}: the stimulus has {} frames; a stimulus has 2 to 100000",
            stimulus.index_path.display(),
            stimulus.len()
        ))
        .into());
    }
    Ok(stimulus.load_all()?)
}

/// A spinner on stderr showing the stage (hidden when quiet).
pub(super) fn stage_spinner(global: &Global) -> indicatif::ProgressBar {
    if global.quiet {
        return indicatif::ProgressBar::hidden();
    }
    let bar =
        indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .expect("valid template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// `estimate aps`: the arguments checked, the recording's frames loaded, the thresholds
/// estimated and the maps written (`--maps`), then the result presented.
fn run_aps(args: &ApsArgs, global: &Global) -> anyhow::Result<()> {
    let common = &args.common;
    let (log_map, log_name) = common.log_map()?;
    check_aps_args(args)?;
    let policy = global.outputs([common.input.input.as_path()]);
    check_json(common.json.as_deref(), &policy)?;
    if let Some(dir) = &args.maps {
        policy.check_folder(dir)?;
        check_json_beside_maps(common.json.as_deref(), dir)?;
    }
    let loaded = common.load(Some(args.max_frames), true, global)?;
    let path = loaded.recording.path.clone();
    if loaded.frames.len() < 2 {
        return Err(too_few_frames(&loaded, common).into());
    }
    let options = ApsOptions {
        log_map,
        log_response_name: log_name,
        choose_response: common.choose_response(),
        exposure_us: args.exposure_s.map(|s| (s * 1e6).round() as i64),
        frame_offset_dn: args.frame_offset_dn,
        frame_time_offset_s: args.frame_time_offset_s,
        ..ApsOptions::default()
    };
    let spinner = stage_spinner(global);
    let result = ctcal::aps_region::aps(
        &loaded,
        &options,
        ctcal::fit_region::FitBudget {
            max_pixels: args.max_pixels,
            max_events: args.max_events,
        },
        &|stage, _| spinner.set_message(stage.to_string()),
    );
    spinner.finish_and_clear();
    let result = result.map_err(|e| estimate_failed(&path, &e))?;
    if let Some(dir) = &args.maps {
        write_maps(dir, &result.maps, &policy)?;
    }
    present(&result.estimate, &loaded, common, &policy)
}

/// Refuses `estimate aps` arguments out of range: the exposure, the frames' offsets in
/// level and time, and a `--max-frames` under 2.
fn check_aps_args(args: &ApsArgs) -> Result<(), BadInput> {
    if let Some(e) = args.exposure_s
        && !(e.is_finite() && (0.0..=10.0).contains(&e))
    {
        return Err(BadInput(format!(
            "--exposure-s {e} must be between 0 and 10 seconds"
        )));
    }
    if let Some(o) = args.frame_offset_dn
        && !(o.is_finite() && (-250.0..=1000.0).contains(&o))
    {
        return Err(BadInput(format!(
            "--frame-offset-dn {o} must be between -250 and 1000"
        )));
    }
    if let Some(s) = args.frame_time_offset_s
        && !(s.is_finite() && s.abs() <= 10.0)
    {
        return Err(BadInput(format!(
            "--frame-time-offset-s {s} must be within 10 seconds"
        )));
    }
    if args.max_frames < 2 {
        return Err(BadInput("--max-frames must be at least 2".into()));
    }
    Ok(())
}

/// The refusal of a recording (or window of it) with fewer than two grey frames, naming
/// the method to use instead.
fn too_few_frames(loaded: &Loaded, common: &CommonArgs) -> BadInput {
    let windowed = common.start.is_some() || common.end.is_some();
    let on_screen = matches!(loaded.recording.stimulus(), Ok(Some(_)));
    BadInput(format!(
        "{}: `estimate aps` needs grey frames (two or more); {} holds {}\n  fix: {}use {}",
        loaded.recording.path.display(),
        if windowed {
            "the window --start/--end selects"
        } else {
            "the recording"
        },
        if loaded.frames.len() == 1 {
            "only one"
        } else {
            "none"
        },
        if windowed {
            "widen the window to hold two frames, or "
        } else {
            ""
        },
        if on_screen {
            "`ctcal estimate screen`, which measures through the stimulus played"
        } else {
            "`ctcal estimate eppps`, which needs no frames"
        }
    ))
}

/// The files `--maps` writes into its folder.
const MAP_FILES: [&str; 3] = ["ct_on.npy", "ct_off.npy", "ct_count.npy"];

/// Refuses a `--json` path that is the `--maps` folder or one of its maps, before anything
/// is written (the maps are written first).
fn check_json_beside_maps(json: Option<&Path>, dir: &Path) -> anyhow::Result<()> {
    let Some(JsonTarget::File(path)) = json.map(JsonTarget::parse) else {
        return Ok(());
    };
    let is_map = path.parent().is_some_and(|p| same_path(p, dir))
        && path
            .file_name()
            .is_some_and(|n| MAP_FILES.iter().any(|m| n == *m));
    if same_path(&path, dir) || is_map {
        return Err(BadInput(format!(
            "{}: --json names {}, which --maps {} writes\n  fix: give --json another path",
            path.display(),
            if is_map {
                "a map file"
            } else {
                "the maps folder"
            },
            dir.display()
        ))
        .into());
    }
    Ok(())
}

/// Whether `a` and `b` name one path: made absolute against the working folder (`.`
/// dropped), and resolved where both exist (links).
fn same_path(a: &Path, b: &Path) -> bool {
    let clean = |p: &Path| {
        std::path::absolute(p).map(|p| {
            p.components()
                .filter(|c| *c != std::path::Component::CurDir)
                .collect::<PathBuf>()
        })
    };
    matches!((clean(a), clean(b)), (Ok(x), Ok(y)) if x == y)
        || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// Writes the threshold maps as NumPy arrays (H x W): `ct_on.npy`, `ct_off.npy` (float32,
/// NaN without evidence) and `ct_count.npy` (uint32, samples per pixel).
fn write_maps(
    dir: &Path,
    maps: &ThresholdMaps,
    policy: &ctcal::io::write::OutputPolicy,
) -> anyhow::Result<()> {
    use ndarray_npy::WriteNpyExt;
    let staged = policy.folder(dir)?;
    let shape = (maps.height, maps.width);
    let write = |name: &str, bytes: Vec<u8>| staged.write(name, &bytes);
    let [on, off, count] = MAP_FILES;
    for (name, values) in [(on, &maps.ct_on), (off, &maps.ct_off)] {
        let array = ndarray::Array2::from_shape_vec(shape, values.clone())?;
        let mut bytes = Vec::new();
        array.write_npy(&mut bytes)?;
        write(name, bytes)?;
    }
    let counts = ndarray::Array2::from_shape_vec(shape, maps.count.clone())?;
    let mut bytes = Vec::new();
    counts.write_npy(&mut bytes)?;
    write(count, bytes)?;
    staged.commit()?;
    Ok(())
}

/// JSON and/or the human summary.
fn present(
    estimate: &CtEstimate,
    loaded: &Loaded,
    common: &CommonArgs,
    policy: &ctcal::io::write::OutputPolicy,
) -> anyhow::Result<()> {
    let biases = loaded.recording.biases();
    let estimate = with_biases(estimate, biases.as_ref())?;
    let target = common.json.as_deref().map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(&*estimate, target, policy)?;
    }
    if matches!(target, Some(JsonTarget::Stdout)) {
        return Ok(());
    }
    let mut rows = headline_rows(&estimate, loaded, biases.as_ref());
    push_detail_rows(&estimate, &mut rows);
    for a in &estimate.assumptions {
        rows.push(("assumes".into(), a.clone()));
    }
    output::print_table(&rows)?;
    Ok(())
}

/// The estimate with the recording's biases (if it has them) among its extra fields.
fn with_biases<'a>(
    estimate: &'a CtEstimate,
    biases: Option<&ctcal::io::Biases>,
) -> anyhow::Result<std::borrow::Cow<'a, CtEstimate>> {
    Ok(match biases {
        Some(b) => {
            let mut e = estimate.clone();
            e.extra.insert("biases".into(), serde_json::to_value(b)?);
            std::borrow::Cow::Owned(e)
        }
        None => std::borrow::Cow::Borrowed(estimate),
    })
}

/// A threshold with its 95 % interval (an open side shown as such), or why it is not
/// determinable (the estimate's `why` under `key`).
fn threshold_value(
    estimate: &CtEstimate,
    key: &str,
    v: Option<f64>,
    ci: Option<ctcal::estimate::Interval>,
) -> String {
    match v {
        Some(v) => {
            let [lo, hi] = ci.unwrap_or([None, None]);
            let side = |b: Option<f64>| b.map_or("open".to_string(), |b| format!("{b:.4}"));
            format!("{v:.4}  (95 % {} .. {})", side(lo), side(hi))
        }
        None => format!(
            "not determinable: {}",
            estimate
                .why
                .get(key)
                .map_or("no reason given", |w| w.as_str())
        ),
    }
}

/// The summary's first rows: the method, the recording, the three thresholds, the biases
/// and the mismatch (where estimated).
fn headline_rows(
    estimate: &CtEstimate,
    loaded: &Loaded,
    biases: Option<&ctcal::io::Biases>,
) -> Vec<(String, String)> {
    let value = |key: &str, v: Option<f64>, ci: Option<ctcal::estimate::Interval>| {
        threshold_value(estimate, key, v, ci)
    };
    let mut rows = vec![
        ("method".to_string(), estimate.method.to_string()),
        (
            "recording".into(),
            format!(
                "{} ({}: {}; {} events)",
                loaded.recording.path.display(),
                loaded.sensor,
                loaded.sensor_source,
                loaded.events.len()
            ),
        ),
        (
            "ct_on".into(),
            value("ct_on", estimate.ct_on, estimate.ct_on_ci95),
        ),
        (
            "ct_off".into(),
            value("ct_off", estimate.ct_off, estimate.ct_off_ci95),
        ),
        ("ct".into(), value("ct", estimate.ct, estimate.ct_ci95)),
        output::biases_row(biases),
    ];
    if let (Some(s), Some(ci)) = (estimate.ct_sigma, estimate.ct_sigma_ci95) {
        rows.push((
            "ct_sigma (mismatch)".into(),
            value("ct_sigma", Some(s), Some(ci.map(Some))),
        ));
    }
    rows
}

/// The summary's rows of how the thresholds were reached: each estimator, the frame
/// intervals used, and the screen method's display model and its placing among the
/// paper's presets.
fn push_detail_rows(estimate: &CtEstimate, rows: &mut Vec<(String, String)>) {
    for e in &estimate.estimators {
        rows.push((
            format!("  {}", e.name),
            format!(
                "ON {:.4} +- {:.4}, OFF {:.4} +- {:.4}",
                e.ct_on.value,
                e.ct_on.total_error(),
                e.ct_off.value,
                e.ct_off.total_error()
            ),
        ));
    }
    if !estimate.intervals_used.is_empty() {
        rows.push((
            "frame intervals".into(),
            format!(
                "{} used, {} dropped",
                estimate.intervals_used.len(),
                estimate.intervals_dropped.len()
            ),
        ));
    }
    if let Some(naive) = estimate.extra.get("naive_ct").and_then(|v| v.as_f64()) {
        rows.push(("naive_ct (no display)".into(), format!("{naive:.4}")));
    }
    if let Some(d) = estimate.extra.get("display") {
        rows.push((
            "display".into(),
            format!(
                "gamma {:.3}, black level {:.4}, refresh {:.2} Hz, stimulus at {:.6} s",
                d["gamma"].as_f64().unwrap_or(f64::NAN),
                d["black_level"].as_f64().unwrap_or(f64::NAN),
                d["refresh_hz"].as_f64().unwrap_or(f64::NAN),
                d["time_offset_s"].as_f64().unwrap_or(f64::NAN)
            ),
        ));
    }
    if let Some(text) = estimate
        .extra
        .get("display_explains")
        .and_then(|v| v.as_str())
    {
        rows.push(("explains".into(), text.to_string()));
    }
    if let Some(position) = estimate
        .extra
        .get("preset_position")
        .and_then(|v| v.as_str())
    {
        rows.push(("vs the paper's presets".into(), position.to_string()));
    }
}
