//! `ctcal config`: simulator configurations (ESIM flagfile, esim_config_generator JSON, v2e
//! arguments, ctcal PARAMS.toml) from `ctcal fit` results or a report folder (see
//! `ctcal::report::configs`).

use super::{BadInput, Global, output};
use clap::Args;
use ctcal::report::configs::source::FitSet;
use ctcal::report::configs::{self, ConfigFormat};
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

/// The fits in `inputs` (`ctcal fit` JSON files, report folders), checked.
fn gather(inputs: &[PathBuf]) -> anyhow::Result<FitSet> {
    let mut fits = FitSet::default();
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
        fits.add(&results.display().to_string(), &json)
            .map_err(|e| BadInput(e.0))?;
    }
    Ok(fits)
}

pub fn run(args: &ConfigArgs, global: &Global) -> anyhow::Result<()> {
    let fits = gather(&args.inputs)?;
    let files: Vec<String> = args
        .inputs
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let setup = fits
        .setup(&files.join(", "), args.seed)
        .map_err(|e| BadInput(e.0))?;
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
