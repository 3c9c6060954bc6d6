//! One recording of a report: read it, compute its statistics, every applicable threshold
//! estimate and the fit; what it is made of (its files' hashes, the truth it says it was
//! made with).

use super::inputs::Input;
use super::{Event, Observer, Options, SequenceError, Stage};
use crate::estimate::aps::ApsOptions;
use crate::fit::{FitOptions, FitResult};
use crate::model::{InputFile, MethodResult, PixelData, PixelMaps, SequenceReport, Truth};
use crate::sim::PixelParams;
use crate::stats::{StatsAccumulator, StatsOptions};
use crate::window::{Loaded, Window, load};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// SHA-256 and size of a file.
fn hash(path: &Path) -> Option<InputFile> {
    use std::io::Read;
    let mut file = std::fs::File::open(path).ok()?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = file.read(&mut buffer).ok()?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
        bytes += n as u64;
    }
    Some(InputFile {
        path: path.display().to_string(),
        bytes,
        sha256: hasher
            .finalize()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect(),
    })
}

/// The files a recording is read from.
fn input_files(loaded: &Loaded) -> Vec<InputFile> {
    let recording = &loaded.recording;
    let mut paths = vec![recording.event_file().to_path_buf()];
    if recording.path.is_dir() {
        for index in ["images.txt", "stimulus.txt"] {
            let p = recording.path.join(index);
            if p.is_file() {
                paths.push(p);
            }
        }
    }
    paths.iter().filter_map(|p| hash(p)).collect()
}

/// The parameters a recording says it was made with.
fn truth(path: &Path) -> Option<Truth> {
    let folder = if path.is_dir() { path } else { path.parent()? };
    let read = |name: &str| -> Option<serde_json::Value> {
        let text = crate::files::read_small_text(&folder.join(name), 16 << 20).ok()?;
        serde_json::from_str(&text).ok()
    };
    if let Some(sim) = read("simulation.json")
        && let Ok(params) = serde_json::from_value::<PixelParams>(sim["params"].clone())
    {
        return Some(Truth {
            source: "simulation.json (ctcal simulate)".into(),
            params: crate::configs::numeric_params(&params)
                .into_iter()
                .collect(),
        });
    }
    let oracle = read("params.json")?;
    let args = oracle.get("emulator_args")?;
    let mut params = BTreeMap::new();
    for (from, to) in [
        ("pos_thres", "ct_on"),
        ("neg_thres", "ct_off"),
        ("sigma_thres", "ct_sigma"),
        ("cutoff_hz", "cutoff_hz"),
        ("leak_rate_hz", "leak_rate_hz"),
        ("shot_noise_rate_hz", "shot_noise_rate_hz"),
        ("refractory_period_s", "refractory_s"),
    ] {
        if let Some(v) = args.get(from).and_then(|v| v.as_f64())
            && (v > 0.0 || from.ends_with("thres"))
        {
            params.insert(to.to_string(), v);
        }
    }
    Some(Truth {
        source: "params.json (v2e emulator arguments)".into(),
        params,
    })
}

/// The warnings of reading a recording, passed on as the sequence's events.
struct Warnings<'a> {
    name: &'a str,
    progress: &'a Observer<'a>,
}

impl crate::window::LoadObserver for Warnings<'_> {
    fn warn(&self, message: &crate::hint::Text) {
        (self.progress)(self.name, Event::Warning(&message.to_string()));
    }
}

/// The seconds each stage of a sequence took, by stage name.
struct Laps {
    seconds: BTreeMap<String, f64>,
    clock: Instant,
}

impl Laps {
    fn start() -> Self {
        Laps {
            seconds: BTreeMap::new(),
            clock: Instant::now(),
        }
    }

    /// Records the time since the last lap (or the start) as stage `name`'s.
    fn lap(&mut self, name: &str) {
        self.seconds
            .insert(name.to_string(), self.clock.elapsed().as_secs_f64());
        self.clock = Instant::now();
    }
}

/// The part of a recording a report reads: the options' start and end, at most
/// `max_frames` frames.
fn report_window(options: &Options) -> Window {
    Window {
        start_s: options.start_s,
        end_s: options.end_s,
        frames: Some(options.max_frames),
        events_between_frames: false,
    }
}

/// The recording read in `window`, its warnings passed on to `progress`.
fn read(
    input: &Input,
    window: &Window,
    options: &Options,
    progress: &Observer,
) -> Result<Loaded, SequenceError> {
    Ok(load(
        &input.path,
        &Default::default(),
        window,
        &options.selection,
        options.force,
        &Warnings {
            name: &input.name,
            progress,
        },
    )?)
}

/// The window in blocks of consecutive frames, where it has two frames or more (or why
/// they could not be read).
///
/// The frame-based methods (aps, fit) read the events between the first and last frame,
/// in blocks of consecutive frames where the frames pass the limit (see
/// `ctcal_io::frame_blocks`: their optical flow still holds), as `ctcal estimate aps`
/// and `ctcal fit` read them, so that the report's numbers are theirs (from the events
/// already read: the recording is decoded once).
fn frame_blocks(loaded: &Loaded, window: &Window) -> Option<Result<Loaded, String>> {
    (loaded.frames.len() >= 2)
        .then(|| crate::window::load_blocks(loaded, window, &crate::window::Silent))
        .map(|read| {
            read.map_err(|e| format!("the blocks of consecutive frames could not be read: {e}"))
        })
}

/// What the frame-based methods read: the blocks of frames where there are any, else the
/// window as loaded; or why the blocks could not be read.
fn framed_window<'a>(
    loaded: &'a Loaded,
    blocks: &'a Option<Result<Loaded, String>>,
) -> Result<&'a Loaded, String> {
    match blocks {
        None => Ok(loaded),
        Some(Ok(read)) => Ok(read),
        Some(Err(why)) => Err(why.clone()),
    }
}

/// The thresholds of the screen method, where it measured either: an on-screen
/// recording's thresholds come from the screen method (measured through the display
/// model), not from eppps's prior, where a fit has no frames to measure them.
fn screen_thresholds(methods: &[MethodResult]) -> Option<&crate::estimate::CtEstimate> {
    methods
        .iter()
        .find(|m| m.method == "screen")
        .and_then(|m| m.estimate.as_ref())
        .filter(|e| e.ct_on.is_some() || e.ct_off.is_some())
}

/// The recording's format as the report names it, with its layout where it has one.
fn format_name(loaded: &Loaded) -> String {
    match loaded.recording.layout() {
        Some(layout) => format!("{} ({layout})", loaded.recording.format),
        None => loaded.recording.format.to_string(),
    }
}

/// Everything reported of one recording, and its per-pixel data; `progress` hears of each
/// stage done and of what reading the recording warned of.
pub fn sequence(
    input: &Input,
    options: &Options,
    progress: &Observer,
) -> Result<(SequenceReport, PixelData), SequenceError> {
    let mut laps = Laps::start();
    let window = report_window(options);
    let loaded = read(input, &window, options, progress)?;
    let blocks = frame_blocks(&loaded, &window);
    let framed = framed_window(&loaded, &blocks);
    let inputs = input_files(&loaded);
    laps.lap("reading");
    progress(&input.name, Event::Done(Stage::Reading));

    let (mut stats, pixel_counts) = statistics(&loaded, &input.path)?;
    // the sensor biases saved in or beside the recording (as `ctcal stats` shows them)
    stats.biases = loaded.recording.biases();
    laps.lap("statistics");
    progress(&input.name, Event::Done(Stage::Statistics));

    let (methods, maps) = estimates(&loaded, framed.clone(), options)?;
    laps.lap("estimates");
    progress(&input.name, Event::Done(Stage::Estimates));

    let (fit, fit_not_applied) = match framed {
        Ok(framed) => fit_of(framed, options, screen_thresholds(&methods)),
        Err(why) => (None, Some(why)),
    };
    laps.lap("fit");
    progress(&input.name, Event::Done(Stage::Fit));
    let report = SequenceReport {
        name: input.name.clone(),
        // named once every sequence's sensor is known (see `grouping`)
        dataset: String::new(),
        format: format_name(&loaded),
        inputs,
        stats,
        methods,
        fit,
        fit_not_applied,
        truth: truth(&loaded.recording.path),
        warnings: loaded.notes.clone(),
        outputs: Default::default(),
        seconds: laps.seconds,
    };
    let pixels = PixelData {
        counts: pixel_counts,
        maps,
    };
    Ok((report, pixels))
}

/// Every applicable threshold estimate of a recording, and the per-pixel maps of `aps`
/// (from `framed`: the window read in blocks of consecutive frames where it has more frames
/// than the limit, else `loaded` itself; or why the blocks could not be read).
fn estimates(
    loaded: &Loaded,
    framed: Result<&Loaded, String>,
    options: &Options,
) -> Result<(Vec<MethodResult>, Option<PixelMaps>), SequenceError> {
    let aps_options = ApsOptions::default();
    let mut methods = Vec::new();
    let (aps, maps) = aps_method(framed, &aps_options, options);
    methods.push(aps);
    let stimulus = loaded.recording.stimulus()?;
    methods.push(eppps_method(
        loaded,
        stimulus.is_some(),
        &aps_options,
        options,
    ));
    methods.push(screen_method(loaded, stimulus, options)?);
    Ok((methods, maps))
}

/// A method that could not be applied, and why.
fn not_applied(method: &'static str, why: String) -> MethodResult {
    MethodResult {
        method,
        estimate: None,
        not_applied: Some(why),
    }
}

/// A method's estimate, or its error's message as why it could not be applied.
fn outcome(
    method: &'static str,
    found: Result<crate::estimate::CtEstimate, impl std::fmt::Display>,
) -> MethodResult {
    MethodResult {
        method,
        not_applied: found.as_ref().err().map(|e| e.to_string()),
        estimate: found.ok(),
    }
}

/// The `aps` method (thresholds from the grey frames, Stoffregen et al. 2020 Sec. 3.1: event
/// timing and re-simulation combined) on `framed`, with its per-pixel threshold maps; not
/// applied without two frames or where the blocks of frames could not be read.
fn aps_method(
    framed: Result<&Loaded, String>,
    aps_options: &ApsOptions,
    options: &Options,
) -> (MethodResult, Option<PixelMaps>) {
    let quiet = |_: &str, _: f64| {};
    let framed = match framed {
        Err(why) => return (not_applied("aps", why), None),
        Ok(framed) if framed.frames.len() >= 2 => framed,
        Ok(_) => {
            let why = "the recording has no grey frames".into();
            return (not_applied("aps", why), None);
        }
    };
    match ctcal_io::aps_region::aps(framed, aps_options, options.fit_budget, &quiet) {
        Ok(result) => {
            let maps = PixelMaps {
                width: result.maps.width,
                height: result.maps.height,
                ct_on: result.maps.ct_on,
                ct_off: result.maps.ct_off,
            };
            let aps = MethodResult {
                method: "aps",
                estimate: Some(result.estimate),
                not_applied: None,
            };
            (aps, Some(maps))
        }
        Err(e) => (not_applied("aps", e.to_string()), None),
    }
}

/// The `eppps` method (events per pixel per second against simulated scenes, Stoffregen
/// et al. 2020 Sec. 3.1 and Fig. 2); not applied to an on-screen recording (`on_screen`:
/// it has a stimulus) without grey frames, whose scene is no natural one.
fn eppps_method(
    loaded: &Loaded,
    on_screen: bool,
    aps_options: &ApsOptions,
    options: &Options,
) -> MethodResult {
    let quiet = |_: &str, _: f64| {};
    if on_screen && loaded.frames.len() < 2 {
        // without frames eppps compares the events with natural images (its prior); an
        // on-screen recording's scene is the stimulus, whose contrast the display sets
        return not_applied(
            "eppps",
            "an on-screen recording without grey frames: its scene is the stimulus on a display, not a natural scene, so the events-only prior (natural images) does not describe it; the screen method measures the thresholds through the stimulus".into(),
        );
    }
    let eppps = crate::window::eppps_of(
        loaded,
        aps_options,
        crate::estimate::eppps::EpppsOptions {
            seed: options.seed,
            ..Default::default()
        },
        &quiet,
    );
    outcome("eppps", eppps)
}

/// The `screen` method (an on-screen stimulus's frames simulated through a fitted display
/// model, Stoffregen et al. 2020 Sec. 3.1's on-screen checkerboard) where the recording
/// has a stimulus of at least two frames.
fn screen_method(
    loaded: &Loaded,
    stimulus: Option<ctcal_io::FrameList>,
    options: &Options,
) -> Result<MethodResult, SequenceError> {
    let quiet = |_: &str, _: f64| {};
    Ok(match stimulus {
        Some(list) if list.len() >= 2 => {
            let frames = list.load_all()?;
            let found = crate::window::screen_of(
                loaded,
                &frames,
                (options.screen.clone(), None),
                None,
                &quiet,
            );
            outcome("screen", found)
        }
        _ => not_applied(
            "screen",
            "the recording has no stimulus.txt (not an on-screen recording)".into(),
        ),
    })
}

/// The fit of a recording, or why there is none.
fn fit_of(
    loaded: &Loaded,
    options: &Options,
    screen: Option<&crate::estimate::CtEstimate>,
) -> (Option<FitResult>, Option<String>) {
    let quiet = |_: &str, _: f64| {};
    if let Some(why) = &options.fit_left_out {
        (None, Some(why.clone()))
    } else {
        match crate::fit_region::fit(
            loaded,
            &FitOptions {
                seed: options.seed,
                thresholds: screen.cloned(),
                ..FitOptions::default()
            },
            options.fit_budget,
            &quiet,
        ) {
            Ok(f) => (Some(f), None),
            Err(e) => (None, Some(e.to_string())),
        }
    }
}

/// The statistics of the events in memory, and the events of each kept pixel.
fn statistics(
    loaded: &Loaded,
    path: &Path,
) -> Result<(crate::stats::SequenceStats, Vec<u32>), SequenceError> {
    let selection = loaded.selection.clone();
    let mut accumulator = StatsAccumulator::new(
        StatsOptions {
            selection: (!selection.is_all()).then_some(selection),
            ..StatsOptions::default()
        },
        Some(loaded.sensor),
    );
    accumulator.add(&loaded.events);
    let stats = accumulator
        .finish(
            loaded.sensor,
            &loaded.sensor_source,
            &loaded.recording.frame_times()?,
        )
        .ok_or_else(|| SequenceError::NoEvents(path.to_path_buf()))?;
    let width = loaded.sensor.width as usize;
    let mut pixel_counts = vec![0u32; loaded.sensor.pixels()];
    for i in 0..loaded.events.len() {
        let p = loaded.events.y[i] as usize * width + loaded.events.x[i] as usize;
        if !loaded.excluded[p] {
            pixel_counts[p] += 1;
        }
    }
    Ok((stats, pixel_counts))
}
