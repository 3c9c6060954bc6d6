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
    #[arg(long, value_name = "esim|esim-generator|v2e|ctcal", value_parser = parse_format)]
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

/// The parameters of one fit result (`place` names it in errors).
fn fit_params(fit: &serde_json::Value, place: &str) -> anyhow::Result<(PixelParams, Option<i64>)> {
    let params = fit.get("params").ok_or_else(|| {
        BadInput(format!(
            "{place}: has no `params` (not a `ctcal fit` result)\n  fix: give the JSON `ctcal fit INPUT --json FIT.json` writes, or a report folder"
        ))
    })?;
    let params: PixelParams = serde_json::from_value(params.clone()).map_err(|e| {
        BadInput(format!(
            "{place}: `params`: {e}\n  fix: give an unedited `ctcal fit` result"
        ))
    })?;
    params.validate(place)?;
    Ok((
        params,
        fit.get("frame_exposure_us").and_then(|v| v.as_i64()),
    ))
}

fn gather(inputs: &[PathBuf]) -> anyhow::Result<Fits> {
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
                        &format!("{}: sequence {i} ({name})", results.display()),
                    )?;
                    fits.params.push(p);
                    fits.exposures_us.push(exposure);
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
            let (p, exposure) = fit_params(&json, &results.display().to_string())?;
            fits.params.push(p);
            fits.exposures_us.push(exposure);
        }
    }
    Ok(fits)
}

pub fn run(args: &ConfigArgs, global: &Global) -> anyhow::Result<()> {
    let fits = gather(&args.inputs)?;
    // one exposure where every fit agrees on it
    let exposure_ms = match fits.exposures_us.as_slice() {
        [first, rest @ ..] if rest.iter().all(|e| e == first) => first.map(|e| e as f64 / 1e3),
        _ => None,
    };
    let seed = args.seed.or(fits.seed).unwrap_or(2020);
    let text = configs::render(args.format, &fits.params, exposure_ms, seed).ok_or_else(|| {
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
