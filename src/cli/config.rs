//! `ctcal config`: simulator configurations (ESIM flagfile, esim_config_generator JSON, v2e
//! arguments, ctcal PARAMS.toml) from `ctcal fit` results or a report folder (see
//! `ctcal::report::configs`).

use super::{BadInput, Global, output};
use clap::Args;
use ctcal::report::configs::{self, ConfigFormat};
use ctcal::sim::PixelParams;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct ConfigArgs {
    /// `ctcal fit` JSON results, or one report folder (its results.json).
    #[arg(value_name = "FIT.json|REPORT_DIR", required = true)]
    pub inputs: Vec<PathBuf>,
    /// The simulator the configuration is for.
    #[arg(long, value_name = "esim|esim-generator|v2e|v2e-json|ctcal", value_parser = parse_format)]
    pub format: ConfigFormat,
    /// Where to write it (default: stdout).
    #[arg(long, value_name = "PATH")]
    pub out: Option<PathBuf>,
    /// Seed for the simulator (default: the report's seed, else 2020).
    #[arg(long, value_name = "N")]
    pub seed: Option<u64>,
}

fn parse_format(text: &str) -> Result<ConfigFormat, String> {
    ConfigFormat::parse(text).ok_or_else(|| {
        format!(
            "`{text}` is not a configuration format (one of {})",
            ConfigFormat::ALL.map(|f| f.name()).join(", ")
        )
    })
}

/// The fits to configure from: parameters, frame exposures (µs) and the seed they were
/// made with.
#[derive(Default)]
struct Fits {
    params: Vec<PixelParams>,
    exposures_us: Vec<Option<i64>>,
    seed: Option<u64>,
    /// The sensor (`WxH`) of each fit, where a report says it, with the sequence's name.
    sensors: Vec<(String, String)>,
    /// Parameters a fit does not identify, with why (its `why`).
    not_identified: std::collections::BTreeMap<String, String>,
}

impl Fits {
    /// Keeps what the fit `json` says it does not identify.
    fn note_unidentified(&mut self, json: &serde_json::Value) {
        if let Some(why) = json.get("why").and_then(|w| w.as_object()) {
            for (key, reason) in why {
                if let Some(reason) = reason.as_str() {
                    self.not_identified.insert(key.clone(), reason.to_string());
                }
            }
        }
    }
}

/// Refuses fits of different sensors: a configuration describes one camera.
fn one_sensor(fits: &Fits, file: &str) -> Result<Option<(u32, u32)>, BadInput> {
    let mut distinct: Vec<&str> = fits.sensors.iter().map(|(s, _)| s.as_str()).collect();
    distinct.sort();
    distinct.dedup();
    if distinct.len() > 1 {
        let by_sensor: Vec<String> = distinct
            .iter()
            .map(|d| {
                let names: Vec<&str> = fits
                    .sensors
                    .iter()
                    .filter(|(s, _)| s == d)
                    .map(|(_, n)| n.as_str())
                    .collect();
                format!("{d}: {}", names.join(", "))
            })
            .collect();
        return Err(BadInput(format!(
            "{file}: the fitted sequences come from {} sensors ({}); a configuration describes one camera, so none is combined across sensors\n  fix: use the per-sequence configurations in the report's configs/SEQUENCE/, or report each sensor as its own dataset (--dataset NAME=INPUT) and give `ctcal fit` results of one sensor",
            distinct.len(),
            by_sensor.join("; ")
        )));
    }
    Ok(distinct.first().and_then(|d| {
        let (w, h) = d.split_once('x')?;
        Some((w.parse().ok()?, h.parse().ok()?))
    }))
}

/// Refuses a fit whose thresholds the recording does not identify (`null` in `params`).
fn identified(fit: &serde_json::Value, file: &str, prefix: &str) -> Result<(), BadInput> {
    for key in ["ct_on", "ct_off"] {
        if fit["params"].get(key).is_some_and(|v| v.is_null()) {
            let why = fit["why"][key].as_str().unwrap_or("no reason given");
            return Err(BadInput(format!(
                "{file}: `{prefix}params.{key}` is null: the recording does not identify it ({why})\n  fix: configure from a fit of a recording that shows the thresholds (motion, frames that explain its events)"
            )));
        }
    }
    Ok(())
}

fn read_json(path: &Path) -> anyhow::Result<serde_json::Value> {
    let text = ctcal::files::read_small_text(path, 512 << 20)
        .map_err(|e| ctcal::InputError::not_a_file(path, e))?;
    serde_json::from_str(&text).map_err(|e| {
        BadInput(format!(
            "{}: not JSON (line {}, column {}: {e})\n  fix: give the JSON `ctcal fit --json` wrote, or a report folder",
            path.display(),
            e.line(),
            e.column()
        ))
        .into()
    })
}

/// The largest magnitude each numeric fit parameter may have (the PARAMS.toml keys; the
/// `display` table's as `display.KEY`): what a camera can have, far beyond what a fit finds,
/// so that a damaged or hand-edited fit never reaches a simulator's configuration.
const PLAUSIBLE: [(&str, f64); 20] = [
    // contrast thresholds and their spreads, natural-log units
    ("ct_on", 10.0),
    ("ct_off", 10.0),
    ("ct_sigma", 10.0),
    ("ct_sigma_temporal", 10.0),
    ("refractory_s", 10.0),
    ("cutoff_hz", 1e6),
    ("leak_rate_hz", 1e6),
    ("leak_spread_decades", 10.0),
    ("shot_noise_rate_hz", 1e6),
    ("shot_noise_bright_factor", 100.0),
    ("hot_pixel_fraction", 1.0),
    ("hot_pixel_rate_hz", 1e6),
    ("timestamp_jitter_s", 10.0),
    ("log_eps", 1e3),
    ("display.refresh_hz", 1e5),
    ("display.gamma", 10.0),
    ("display.black_level", 1.0),
    ("display.white_dn", 1e6),
    ("display.blur_px", 4096.0),
    ("display.time_offset_s", 1e3),
];

/// The longest frame exposure a fit may state, microseconds (10 s).
const MAX_EXPOSURE_US: i64 = 10_000_000;

/// Checks a fit result's values before they are parsed into parameters: `params` an object
/// of numbers within [`PLAUSIBLE`], `frame_exposure_us` a positive whole number of
/// microseconds. Errors name `file` and the JSON path of the bad value (`prefix` is where
/// the fit lies in the file, e.g. `sequences[0].fit.`).
fn validate_fit_json(fit: &serde_json::Value, file: &str, prefix: &str) -> Result<(), BadInput> {
    let bad = |path: &str, problem: String, fix: &str| {
        BadInput(format!("{file}: `{prefix}{path}` {problem}\n  fix: {fix}"))
    };
    const UNEDITED: &str = "give an unedited `ctcal fit` result (or correct this value)";
    let Some(params) = fit.get("params") else {
        return Err(BadInput(format!(
            "{file}: {}has no `params` (not a `ctcal fit` result)\n  fix: give the JSON `ctcal fit INPUT --json FIT.json` writes, or a report folder",
            if prefix.is_empty() {
                String::new()
            } else {
                format!("`{}` ", prefix.trim_end_matches('.'))
            }
        )));
    };
    let describe = |v: &serde_json::Value| match v {
        serde_json::Value::Array(_) => "a list".to_string(),
        serde_json::Value::Object(_) => "an object".to_string(),
        serde_json::Value::String(s) => format!("the string {s:?}"),
        other => other.to_string(),
    };
    let Some(object) = params.as_object() else {
        return Err(bad(
            "params",
            format!(
                "is {}; a fit's parameters are an object of PARAMS.toml keys",
                describe(params)
            ),
            UNEDITED,
        ));
    };
    let mut values: Vec<(String, &serde_json::Value)> = Vec::new();
    for (key, value) in object {
        if key == "display" {
            let Some(display) = value.as_object() else {
                return Err(bad(
                    "params.display",
                    format!("is {}; the display is an object", describe(value)),
                    UNEDITED,
                ));
            };
            values.extend(display.iter().map(|(k, v)| (format!("display.{k}"), v)));
        } else {
            values.push((key.clone(), value));
        }
    }
    for (key, value) in values {
        let Some(&(_, max)) = PLAUSIBLE.iter().find(|(k, _)| *k == key) else {
            continue;
        };
        let path = format!("params.{key}");
        // a parameter the fit says it does not identify is null, with its reason
        if value.is_null() && fit["why"][key.as_str()].is_string() {
            continue;
        }
        let Some(v) = value.as_f64() else {
            return Err(bad(
                &path,
                format!("is {}, not a number", describe(value)),
                UNEDITED,
            ));
        };
        if !(v.is_finite() && v.abs() <= max) {
            return Err(bad(
                &path,
                format!("is {v:e}, beyond any camera (at most {max:e} in magnitude)"),
                UNEDITED,
            ));
        }
    }
    match fit.get("frame_exposure_us") {
        None | Some(serde_json::Value::Null) => {}
        Some(value) => match value.as_i64() {
            Some(us) if us > 0 && us <= MAX_EXPOSURE_US => {}
            _ => {
                return Err(bad(
                    "frame_exposure_us",
                    format!(
                        "is {}; an exposure is a whole number of microseconds, 1..={MAX_EXPOSURE_US}",
                        describe(value)
                    ),
                    UNEDITED,
                ));
            }
        },
    }
    Ok(())
}

/// The parameters of one fit result in `file`, at JSON path `prefix` (`place` names it in
/// errors).
fn fit_params(
    fit: &serde_json::Value,
    file: &str,
    prefix: &str,
) -> anyhow::Result<(PixelParams, Option<i64>)> {
    identified(fit, file, prefix)?;
    validate_fit_json(fit, file, prefix)?;
    let params: PixelParams = serde_json::from_value(fit["params"].clone()).map_err(|e| {
        BadInput(format!(
            "{file}: `{prefix}params`: {e}\n  fix: give an unedited `ctcal fit` result"
        ))
    })?;
    params.validate(file).map_err(|e| {
        BadInput(format!(
            "{file}: `{prefix}params.{}` {}\n  fix: {}",
            e.key, e.problem, e.fix
        ))
    })?;
    Ok((
        params,
        fit.get("frame_exposure_us").and_then(|v| v.as_i64()),
    ))
}

fn gather(inputs: &[PathBuf]) -> anyhow::Result<(Fits, Option<(u32, u32)>)> {
    let mut fits = Fits::default();
    for path in inputs {
        let results = if path.is_dir() {
            let results = path.join("results.json");
            if !results.is_file() {
                return Err(BadInput(format!(
                    "{}: a folder without results.json (not a ctcal report)\n  fix: give a folder `ctcal report` wrote, or `ctcal fit` JSON files",
                    path.display()
                ))
                .into());
            }
            results
        } else {
            path.clone()
        };
        let json = read_json(&results)?;
        if let Some(sequences) = json.get("sequences").and_then(|s| s.as_array()) {
            fits.seed = fits.seed.or(json.get("seed").and_then(|s| s.as_u64()));
            let before = fits.params.len();
            for (i, s) in sequences.iter().enumerate() {
                if let Some(fit) = s.get("fit") {
                    let name = s.get("name").and_then(|n| n.as_str()).unwrap_or("?");
                    let (p, exposure) = fit_params(
                        fit,
                        &format!("{} (sequence {name})", results.display()),
                        &format!("sequences[{i}].fit."),
                    )?;
                    fits.params.push(p);
                    fits.exposures_us.push(exposure);
                    fits.note_unidentified(fit);
                    let (w, h) = (&s["stats"]["width"], &s["stats"]["height"]);
                    if let (Some(w), Some(h)) = (w.as_u64(), h.as_u64()) {
                        fits.sensors.push((format!("{w}x{h}"), name.to_string()));
                    }
                }
            }
            if fits.params.len() == before {
                return Err(BadInput(format!(
                    "{}: the report has no fitted sequence\n  fix: run `ctcal report` without --no-fit on recordings with grey frames",
                    results.display()
                ))
                .into());
            }
        } else {
            let (p, exposure) = fit_params(&json, &results.display().to_string(), "")?;
            fits.note_unidentified(&json);
            fits.params.push(p);
            fits.exposures_us.push(exposure);
        }
    }
    let files: Vec<String> = inputs.iter().map(|p| p.display().to_string()).collect();
    let sensor = one_sensor(&fits, &files.join(", "))?;
    Ok((fits, sensor))
}

pub fn run(args: &ConfigArgs, global: &Global) -> anyhow::Result<()> {
    let (fits, sensor) = gather(&args.inputs)?;
    // one exposure where every fit agrees on it
    let exposure_ms = match fits.exposures_us.as_slice() {
        [first, rest @ ..] if rest.iter().all(|e| e == first) => first.map(|e| e as f64 / 1e3),
        _ => None,
    };
    let seed = args.seed.or(fits.seed).unwrap_or(2020);
    let setup = configs::Setup {
        exposure_ms,
        seed,
        sensor,
        not_identified: fits.not_identified.clone(),
    };
    let text = configs::render(args.format, &fits.params, &setup).ok_or_else(|| {
        BadInput("no fits given\n  fix: give `ctcal fit` JSON files or a report folder".into())
    })?;
    match &args.out {
        None => output::stdout(&text)?,
        Some(path) => {
            let policy = global.outputs(args.inputs.iter().map(PathBuf::as_path));
            policy.file(path)?.write_all(text.as_bytes())?;
        }
    }
    Ok(())
}
