//! `ctcal fit`: every simulator parameter fitted to a recording, effects added where the
//! residuals call for them and the held-out error falls (see `ctcal::fit`).

use super::estimate::{CommonArgs, stage_spinner};
use super::{BadInput, Global, JsonTarget, emit_json, output};
use clap::Args;
use ctcal::estimate::aps::ApsOptions;
use ctcal::fit::effects::Effect;
use ctcal::fit::{EffectChoice, FitInput, FitOptions, FitResult};

#[derive(Args, Debug)]
pub struct FitArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Which effects to consider: `auto` (every effect, each tried when the residuals call
    /// for it), `none` (the ideal pixel), or a comma-separated list to try in that order
    /// (mismatch, refractory, bandwidth, leak, shot_noise, hot_pixels, timestamp_jitter,
    /// display).
    #[arg(long, value_name = "auto|none|LIST", default_value = "auto")]
    pub effects: String,
    /// Fraction of the recording held out of the fit, at its end: the first half judges
    /// each effect, the second measures the final error.
    #[arg(long, value_name = "FRACTION", default_value_t = 0.4)]
    pub holdout: f64,
    /// Use at most this many frames (evenly spread over the window).
    #[arg(long, value_name = "N", default_value_t = 120)]
    pub max_frames: usize,
    /// Exposure time of the frames, where the file does not say.
    #[arg(long, value_name = "S")]
    pub exposure_s: Option<f64>,
}

/// Parses `--effects`.
fn effect_choice(text: &str) -> Result<EffectChoice, BadInput> {
    match text.trim() {
        "auto" => Ok(EffectChoice::Auto),
        "none" => Ok(EffectChoice::None),
        list => {
            let mut effects = Vec::new();
            for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
                let effect = Effect::parse(name).ok_or_else(|| {
                    BadInput(format!(
                        "--effects: `{name}` is not an effect\n  fix: use auto, none, or a list of {}",
                        Effect::ALL.map(|e| e.name()).join(", ")
                    ))
                })?;
                if !effects.contains(&effect) {
                    effects.push(effect);
                }
            }
            Ok(EffectChoice::List(effects))
        }
    }
}

pub fn run(args: &FitArgs, global: &Global) -> anyhow::Result<()> {
    let common = &args.common;
    let effects = effect_choice(&args.effects)?;
    if !(args.holdout.is_finite() && (0.0..=0.7).contains(&args.holdout)) {
        return Err(BadInput(format!(
            "--holdout {} must be a fraction between 0 and 0.7",
            args.holdout
        ))
        .into());
    }
    if args.max_frames < 2 {
        return Err(BadInput("--max-frames must be at least 2".into()).into());
    }
    if let Some(e) = args.exposure_s
        && !(e.is_finite() && (0.0..=10.0).contains(&e))
    {
        return Err(BadInput(format!("--exposure-s {e} must be between 0 and 10 seconds")).into());
    }
    let (log_map, log_name) = common.log_map()?;
    let policy = global.outputs([common.input.input.as_path()]);
    let loaded = common.load(Some(args.max_frames), true, global)?;
    let path = loaded.recording.path.clone();
    let spinner = stage_spinner(global);
    let progress = |stage: &str, _: f64| spinner.set_message(stage.to_string());
    let options = FitOptions {
        effects,
        holdout: args.holdout,
        aps: ApsOptions {
            log_map,
            log_response_name: log_name,
            choose_response: args.common.choose_response(),
            exposure_us: args.exposure_s.map(|s| (s * 1e6).round() as i64),
            ..ApsOptions::default()
        },
        ..FitOptions::default()
    };
    let result = ctcal::fit::fit(
        &FitInput {
            sensor: loaded.sensor,
            events: &loaded.events,
            frames: &loaded.frames,
            excluded: &loaded.excluded,
        },
        &options,
        &progress,
    );
    spinner.finish_and_clear();
    let mut result = result.map_err(|e| BadInput(format!("{}: {e}", path.display())))?;
    result.assumptions.extend(loaded.notes.iter().cloned());
    result.biases = loaded.recording.biases();
    let target = common.json.as_deref().map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(&result, target, &policy)?;
    }
    if !matches!(target, Some(JsonTarget::Stdout)) {
        print_human(&result)?;
    }
    Ok(())
}

fn print_human(r: &FitResult) -> std::io::Result<()> {
    let mut rows = vec![
        (
            "thresholds".to_string(),
            format!("ON {:.4}, OFF {:.4}", r.params.ct_on, r.params.ct_off),
        ),
        output::biases_row(r.biases.as_ref()),
    ];
    for (key, u) in &r.uncertainties {
        if key.starts_with("ct_o") {
            continue;
        }
        rows.push((
            key.clone(),
            match u.standard_error {
                Some(se) => format!("{:.6} (+- {se:.2e})", u.value),
                None => format!("{:.6}", u.value),
            },
        ));
    }
    rows.push((
        "effects added".into(),
        if r.effects_added.is_empty() {
            "none".into()
        } else {
            r.effects_added
                .iter()
                .map(|e| e.effect.name())
                .collect::<Vec<_>>()
                .join(", ")
        },
    ));
    rows.push((
        "held-out error".into(),
        format!(
            "{:.4} (ideal model) -> {:.4} ({:+.1} %)",
            r.error_before,
            r.error_after,
            100.0 * (r.error_after / r.error_before - 1.0)
        ),
    ));
    for step in &r.steps {
        rows.push((
            format!("step {}", step.effect),
            format!(
                "{}: {}",
                if step.kept { "kept" } else { "not added" },
                step.reason
            ),
        ));
    }
    if !r.hot_pixels_masked.is_empty() {
        rows.push((
            "hot pixels masked".into(),
            r.hot_pixels_masked
                .iter()
                .map(|h| format!("({}, {})", h.x, h.y))
                .collect::<Vec<_>>()
                .join(" "),
        ));
    }
    rows.push(("simulations".into(), r.simulations.to_string()));
    output::print_table(&rows)
}
