//! `ctcal report`: statistics, every applicable threshold estimate and the fit of each
//! recording, grouped into datasets, rendered as a report folder (see `ctcal::report`).
//! Sequences are processed in parallel, with a progress bar per stage.

use super::estimate::{default_screen, eppps_of, screen_of};
use super::load::{Loaded, Window, load};
use super::{BadInput, Global, InputArgs, SelectionArgs, output, warn};
use clap::Args;
use ctcal::estimate::aps::{self, ApsInput, ApsOptions};
use ctcal::fit::{FitInput, FitOptions};
use ctcal::report::model::{InputFile, MethodResult, PixelMaps, Report, SequenceReport, Truth};
use ctcal::sim::{DisplayParams, PixelParams};
use ctcal::stats::{StatsAccumulator, StatsOptions};
use rayon::prelude::*;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Recordings, or folders of recordings (each recording inside is a sequence of a
    /// dataset named after the folder).
    #[arg(value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,
    /// Recordings of a named dataset: NAME=INPUT (repeatable; INPUT may be a folder of
    /// recordings).
    #[arg(long = "dataset", value_name = "NAME=INPUT")]
    pub datasets: Vec<String>,
    /// The report folder.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Leave the fit out (faster; no fitted model, residuals or configs).
    #[arg(long)]
    pub no_fit: bool,
    /// Only the part of each recording from S seconds after its first event.
    #[arg(long, value_name = "S")]
    pub start: Option<f64>,
    /// Only the part up to S seconds after the first event.
    #[arg(long, value_name = "S")]
    pub end: Option<f64>,
    /// Use at most this many frames of a recording.
    #[arg(long, value_name = "N", default_value_t = 120)]
    pub max_frames: usize,
    /// The screen model for recordings of an on-screen stimulus (default: a typical 60 Hz
    /// LCD).
    #[arg(long, value_name = "SCREEN.toml")]
    pub screen: Option<PathBuf>,
    /// Seed of every simulation.
    #[arg(long, value_name = "N", default_value_t = 2020)]
    pub seed: u64,
    #[command(flatten)]
    pub selection: SelectionArgs,
}

/// A recording to report on.
#[derive(Clone, Debug)]
struct Input {
    path: PathBuf,
    name: String,
    dataset: String,
}

/// Whether `path` is a recording ctcal reads (an IJRR folder or a file of a known format).
fn is_recording(path: &Path) -> bool {
    if path.is_dir() {
        return path.join("events.txt").is_file();
    }
    path.file_name()
        .is_some_and(|n| !n.to_string_lossy().starts_with('.'))
        && ctcal::io::detect(path).is_ok()
}

/// The recordings of an input: itself, or the recordings in a folder of them.
fn expand(path: &Path, dataset: Option<&str>) -> Result<Vec<Input>, BadInput> {
    let folder_name = |p: &Path| {
        p.canonicalize()
            .ok()
            .and_then(|c| c.file_name().map(|n| n.to_string_lossy().into_owned()))
            .unwrap_or_else(|| "recordings".into())
    };
    if !path.exists() {
        return Err(BadInput(format!(
            "{}: no such file or directory\n  fix: check the path",
            path.display()
        )));
    }
    if is_recording(path) {
        let parent = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        return Ok(vec![Input {
            path: path.to_path_buf(),
            name: folder_name(path),
            dataset: dataset.map_or_else(|| folder_name(parent), str::to_string),
        }]);
    }
    if !path.is_dir() {
        return Err(BadInput(format!(
            "{}: not a recording ctcal reads\n  fix: give recordings (IJRR folders, HDF5, AEDAT4, RAW, DAT, ROS bags) or folders of them",
            path.display()
        )));
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| BadInput(format!("{}: cannot list: {e}", path.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_recording(p))
        .collect();
    entries.sort();
    if entries.is_empty() {
        return Err(BadInput(format!(
            "{}: holds no recording ctcal reads\n  fix: give recordings or folders of them (an IJRR folder has events.txt)",
            path.display()
        )));
    }
    let dataset = dataset.map_or_else(|| folder_name(path), str::to_string);
    Ok(entries
        .into_iter()
        .map(|p| Input {
            name: folder_name(&p),
            path: p,
            dataset: dataset.clone(),
        })
        .collect())
}

/// The inputs of the command line, named uniquely (file names made safe for paths).
fn inputs(args: &ReportArgs) -> Result<Vec<Input>, BadInput> {
    let mut all = Vec::new();
    for path in &args.inputs {
        all.extend(expand(path, None)?);
    }
    for spec in &args.datasets {
        let Some((name, path)) = spec.split_once('=') else {
            return Err(BadInput(format!(
                "--dataset `{spec}` is not NAME=INPUT\n  fix: e.g. --dataset ijrr=recordings/ijrr"
            )));
        };
        all.extend(expand(Path::new(path), Some(name.trim()))?);
    }
    if all.is_empty() {
        return Err(BadInput(
            "no recordings given\n  fix: ctcal report INPUT... --out DIR (or --dataset NAME=INPUT)"
                .into(),
        ));
    }
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for input in &mut all {
        let safe = path_safe(&input.name);
        let n = seen.entry(safe.clone()).or_insert(0);
        *n += 1;
        input.name = if *n == 1 { safe } else { format!("{safe}_{n}") };
        input.dataset = path_safe(&input.dataset);
    }
    Ok(all)
}

/// A name usable as a file or folder name: ASCII letters, digits and `-`, the rest `_`.
fn path_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

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
        let text = ctcal::files::read_small_text(&folder.join(name), 16 << 20).ok()?;
        serde_json::from_str(&text).ok()
    };
    if let Some(sim) = read("simulation.json")
        && let Ok(params) = serde_json::from_value::<PixelParams>(sim["params"].clone())
    {
        return Some(Truth {
            source: "simulation.json (ctcal simulate)".into(),
            params: ctcal::report::configs::numeric_params(&params)
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

/// The progress bars, one per stage.
struct Bars {
    _multi: indicatif::MultiProgress,
    stages: [indicatif::ProgressBar; 4],
}

fn bars(global: &Global, sequences: usize) -> Bars {
    let multi = indicatif::MultiProgress::with_draw_target(if global.quiet {
        indicatif::ProgressDrawTarget::hidden()
    } else {
        indicatif::ProgressDrawTarget::stderr()
    });
    let style =
        indicatif::ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed}")
            .expect("valid template")
            .progress_chars("=> ");
    let stages = ["reading", "statistics", "estimates", "fit"].map(|name| {
        let bar = multi.add(indicatif::ProgressBar::new(sequences as u64));
        bar.set_style(style.clone());
        bar.set_message(name);
        bar
    });
    Bars {
        _multi: multi,
        stages,
    }
}

/// Everything reported of one recording.
fn sequence(
    input: &Input,
    args: &ReportArgs,
    screen: &DisplayParams,
    global: &Global,
    bars: &Bars,
) -> anyhow::Result<SequenceReport> {
    let mut seconds = BTreeMap::new();
    let mut clock = Instant::now();
    let mut lap = |name: &str, seconds: &mut BTreeMap<String, f64>| {
        seconds.insert(name.to_string(), clock.elapsed().as_secs_f64());
        clock = Instant::now();
    };
    let input_args = InputArgs {
        input: input.path.clone(),
        format: None,
        sensor: None,
        topic: None,
        image_topic: None,
        side: None,
    };
    let loaded = load(
        &input_args,
        &Window {
            start_s: args.start,
            end_s: args.end,
            frames: Some(args.max_frames),
            events_between_frames: false,
        },
        &args.selection,
        global,
    )?;
    let inputs = input_files(&loaded);
    lap("reading", &mut seconds);
    bars.stages[0].inc(1);

    // statistics of the events in memory
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
        .ok_or_else(|| {
            BadInput(format!(
                "{}: no events in the selected pixels",
                input.path.display()
            ))
        })?;
    let width = loaded.sensor.width as usize;
    let mut pixel_counts = vec![0u32; loaded.sensor.pixels()];
    for i in 0..loaded.events.len() {
        let p = loaded.events.y[i] as usize * width + loaded.events.x[i] as usize;
        if !loaded.excluded[p] {
            pixel_counts[p] += 1;
        }
    }
    lap("statistics", &mut seconds);
    bars.stages[1].inc(1);

    // every applicable threshold estimate
    let quiet = |_: &str, _: f64| {};
    let options = ApsOptions::default();
    let mut methods = Vec::new();
    let mut maps = None;
    if loaded.frames.len() >= 2 {
        match aps::estimate(
            &ApsInput {
                sensor: loaded.sensor,
                events: &loaded.events,
                frames: &loaded.frames,
                excluded: &loaded.excluded,
            },
            &options,
            &quiet,
        ) {
            Ok(mut result) => {
                result
                    .estimate
                    .assumptions
                    .extend(loaded.notes.iter().cloned());
                maps = Some(PixelMaps {
                    width: result.maps.width,
                    height: result.maps.height,
                    ct_on: result.maps.ct_on,
                    ct_off: result.maps.ct_off,
                });
                methods.push(MethodResult {
                    method: "aps",
                    estimate: Some(result.estimate),
                    not_applied: None,
                });
            }
            Err(e) => methods.push(MethodResult {
                method: "aps",
                estimate: None,
                not_applied: Some(e.to_string()),
            }),
        }
    } else {
        methods.push(MethodResult {
            method: "aps",
            estimate: None,
            not_applied: Some("the recording has no grey frames".into()),
        });
    }
    let eppps = eppps_of(
        &loaded,
        &options,
        ctcal::estimate::eppps::EpppsOptions {
            seed: args.seed,
            ..Default::default()
        },
        &quiet,
    );
    methods.push(MethodResult {
        method: "eppps",
        not_applied: eppps.as_ref().err().map(|e| e.to_string()),
        estimate: eppps.ok(),
    });
    match loaded.recording.stimulus()? {
        Some(list) if list.len() >= 2 => {
            let frames = list.load_all()?;
            let found = screen_of(&loaded, &frames, screen.clone(), None, &quiet);
            methods.push(MethodResult {
                method: "screen",
                not_applied: found.as_ref().err().map(|e| e.to_string()),
                estimate: found.ok(),
            });
        }
        _ => methods.push(MethodResult {
            method: "screen",
            estimate: None,
            not_applied: Some(
                "the recording has no stimulus.txt (not an on-screen recording)".into(),
            ),
        }),
    }
    lap("estimates", &mut seconds);
    bars.stages[2].inc(1);

    // the fit
    let (fit, fit_not_applied) = if args.no_fit {
        (None, Some("left out (--no-fit)".to_string()))
    } else if loaded.frames.len() < 2 {
        (
            None,
            Some("the fit simulates grey frames; the recording has none".to_string()),
        )
    } else {
        match ctcal::fit::fit(
            &FitInput {
                sensor: loaded.sensor,
                events: &loaded.events,
                frames: &loaded.frames,
                excluded: &loaded.excluded,
            },
            &FitOptions {
                seed: args.seed,
                ..FitOptions::default()
            },
            &quiet,
        ) {
            Ok(mut f) => {
                f.assumptions.extend(loaded.notes.iter().cloned());
                (Some(f), None)
            }
            Err(e) => (None, Some(e.to_string())),
        }
    };
    lap("fit", &mut seconds);
    bars.stages[3].inc(1);
    Ok(SequenceReport {
        name: input.name.clone(),
        dataset: input.dataset.clone(),
        format: match loaded.recording.layout() {
            Some(layout) => format!("{} ({layout})", loaded.recording.format),
            None => loaded.recording.format.to_string(),
        },
        inputs,
        stats,
        methods,
        fit,
        fit_not_applied,
        truth: truth(&loaded.recording.path),
        pixel_counts,
        maps,
        seconds,
    })
}

pub fn run(args: &ReportArgs, global: &Global) -> anyhow::Result<()> {
    super::load::check_window(args.start, args.end)?;
    if args.max_frames < 2 {
        return Err(BadInput("--max-frames must be at least 2".into()).into());
    }
    let inputs = inputs(args)?;
    // the recordings, and the folders of them as given: a report inside `INPUT/` is refused
    let mut protected: Vec<&Path> = inputs.iter().map(|i| i.path.as_path()).collect();
    protected.extend(args.inputs.iter().map(PathBuf::as_path));
    protected.extend(
        args.datasets
            .iter()
            .filter_map(|d| d.split_once('=').map(|(_, path)| Path::new(path))),
    );
    protected.extend(args.screen.as_deref());
    let policy = global.outputs(protected);
    // refuse a bad output before the work
    policy.check_folder(&args.out)?;
    let screen = match &args.screen {
        Some(path) => {
            let text = ctcal::files::read_small_text(path, 1 << 20)
                .map_err(|e| ctcal::InputError::not_a_file(path, e))?;
            DisplayParams::from_toml(&text, &path.display().to_string())?
        }
        None => default_screen(),
    };
    let bars = bars(global, inputs.len());
    let (presets, sequences) = rayon::join(
        || ctcal::report::presets::simulate(args.seed),
        || {
            inputs
                .par_iter()
                .map(|input| sequence(input, args, &screen, global, &bars))
                .collect::<anyhow::Result<Vec<_>>>()
        },
    );
    for bar in &bars.stages {
        bar.finish_and_clear();
    }
    let sequences = sequences?;
    let report = Report {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        // the program as `ctcal`, wherever it was run from
        command_line: std::iter::once("ctcal".to_string())
            .chain(std::env::args().skip(1))
            .collect(),
        seed: args.seed,
        datasets: ctcal::report::model::datasets(&sequences),
        sequences,
        presets: presets?,
        presets_scene: ctcal::report::presets::DESCRIPTION.into(),
    };
    let files = ctcal::report::render(&report);
    let staged = policy.folder(&args.out)?;
    for f in &files {
        staged.write(&f.path, &f.bytes)?;
    }
    staged.commit()?;
    if !global.quiet {
        let mut rows = vec![(
            "report".to_string(),
            args.out.join("index.html").display().to_string(),
        )];
        for s in &report.sequences {
            let thresholds = s
                .best_thresholds()
                .map_or("-".to_string(), |(on, off, method)| {
                    format!("ON {on:.3}, OFF {off:.3} ({method})")
                });
            rows.push((format!("{} ({})", s.name, s.dataset), thresholds));
        }
        rows.push(("files".into(), files.len().to_string()));
        output::print_table(&rows)?;
    }
    for s in &report.sequences {
        for m in &s.methods {
            if let Some(why) = &m.not_applied
                && m.method != "screen"
                && m.method != "aps"
            {
                warn(
                    global,
                    &format!(
                        "{}: estimate {}: {}",
                        s.name,
                        m.method,
                        why.lines().next().unwrap_or("")
                    ),
                );
            }
        }
    }
    Ok(())
}
