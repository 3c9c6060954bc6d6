//! One recording of `ctcal report`: read it, compute its statistics, every applicable
//! threshold estimate and the fit; what it is made of (its files' hashes, the truth it says
//! it was made with).

use super::super::BadInput;
use super::super::estimate::{eppps_of, screen_of};
use super::super::load::{Loaded, Window, load};
use super::super::{Global, InputArgs};
use super::ReportArgs;
use super::inputs::Input;
use super::progress::Progress;
use ctcal::estimate::aps::{self, ApsInput, ApsOptions};
use ctcal::fit::{FitInput, FitOptions, FitResult};
use ctcal::report::model::{InputFile, MethodResult, PixelData, PixelMaps, SequenceReport, Truth};
use ctcal::sim::{DisplayParams, PixelParams};
use ctcal::stats::{StatsAccumulator, StatsOptions};
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

/// Everything reported of one recording.
pub(super) fn sequence(
    input: &Input,
    args: &ReportArgs,
    screen: &DisplayParams,
    global: &Global,
    progress: &Progress,
) -> anyhow::Result<(SequenceReport, PixelData)> {
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
    progress.stage(&input.name, "reading");

    let (stats, pixel_counts) = statistics(&loaded, &input.path)?;
    lap("statistics", &mut seconds);
    progress.stage(&input.name, "statistics");

    let (methods, maps) = estimates(&loaded, args, screen)?;
    lap("estimates", &mut seconds);
    progress.stage(&input.name, "estimates");

    let (fit, fit_not_applied) = fit_of(&loaded, args);
    lap("fit", &mut seconds);
    progress.stage(&input.name, "fit");
    let report = SequenceReport {
        name: input.name.clone(),
        // named once every sequence's sensor is known (see `grouping`)
        dataset: String::new(),
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
        warnings: loaded.notes.clone(),
        outputs: Default::default(),
        seconds,
    };
    let pixels = PixelData {
        counts: pixel_counts,
        maps,
    };
    Ok((report, pixels))
}

/// Every applicable threshold estimate of a recording, and the per-pixel maps of `aps`.
fn estimates(
    loaded: &Loaded,
    args: &ReportArgs,
    screen: &DisplayParams,
) -> anyhow::Result<(Vec<MethodResult>, Option<PixelMaps>)> {
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
        loaded,
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
            let found = screen_of(loaded, &frames, screen.clone(), None, &quiet);
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
    Ok((methods, maps))
}

/// The fit of a recording, or why there is none.
fn fit_of(loaded: &Loaded, args: &ReportArgs) -> (Option<FitResult>, Option<String>) {
    let quiet = |_: &str, _: f64| {};
    if args.no_fit {
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
    }
}

/// The statistics of the events in memory, and the events of each kept pixel.
fn statistics(
    loaded: &Loaded,
    path: &Path,
) -> anyhow::Result<(ctcal::stats::SequenceStats, Vec<u32>)> {
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
                path.display()
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
    Ok((stats, pixel_counts))
}
