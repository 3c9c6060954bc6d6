//! `ctcal fit`: every simulator parameter fitted to a recording, effects added where the
//! residuals call for them and the held-out error falls (see `ctcal::fit`).

use super::estimate::{CommonArgs, estimate_failed, stage_spinner};
use super::{BadInput, Global, JsonTarget, check_json, emit_json, output, warn};
use clap::Args;
use ctcal::estimate::aps::ApsOptions;
use ctcal::fit::effects::Effect;
use ctcal::fit::{EffectChoice, FitOptions, FitResult};

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
    /// each effect, the second measures the final error (0.16 to 0.75: at least 3 fit,
    /// one selection and one test block of the 10).
    #[arg(long, value_name = "FRACTION", default_value_t = 0.4)]
    pub holdout: f64,
    /// Use at most this many frames (of a sensor up to 346x260; a larger sensor's frames
    /// count for their pixels: 40 of 1280x720 at 120): a window with more is measured on
    /// blocks of 20 consecutive frames, one in each equal part of it, each where its part
    /// has the most events (only their frames and events are read).
    #[arg(long, value_name = "N", default_value_t = 120)]
    pub max_frames: usize,
    /// Simulate at most this many pixels (0: no pixel limit; at least 64 x 48). A larger sensor is fitted on
    /// the rectangle of this many pixels, of its aspect, where its events are densest (named
    /// in `assumptions`): thresholds and noise are per-pixel, and the fit re-simulates the
    /// frames hundreds of times.
    #[arg(long, value_name = "N", default_value_t = ctcal::fit_region::FIT_PIXELS)]
    pub max_pixels: usize,
    /// Re-simulate about this many events at most (0: no limit). A window with more is
    /// fitted on the rectangle of the sensor's aspect where its events are densest, holding
    /// about this many (named in `assumptions`): each of the fit's 150-300 simulations
    /// makes as many events as the recording.
    #[arg(long, value_name = "N", default_value_t = ctcal::fit_region::FIT_EVENTS)]
    pub max_events: usize,
    /// Exposure time of the frames, where the file does not say.
    #[arg(long, value_name = "S")]
    pub exposure_s: Option<f64>,
    /// Leave the recording's grey frames out and fit from the events alone (as for a
    /// sensor without frames).
    #[arg(long)]
    pub no_frames: bool,
    /// For a fit without frames: take the absolute thresholds from this `estimate --json`
    /// result (e.g. `estimate screen` on the same recording) instead of running eppps.
    #[arg(long, value_name = "ESTIMATE.json")]
    pub thresholds_from: Option<std::path::PathBuf>,
    /// Seed of every simulation of the fit (`ctcal report --seed` gives the same numbers).
    #[arg(long, value_name = "N", default_value_t = ctcal::DEFAULT_SEED)]
    pub seed: u64,
}

/// Reads the thresholds of an `estimate --json` result.
fn thresholds_from(path: &std::path::Path) -> Result<ctcal::estimate::CtEstimate, BadInput> {
    let json = EstimateJson::read(path)?;
    let method = json.method()?;
    let (ct_on, ct_off) = (json.threshold("ct_on")?, json.threshold("ct_off")?);
    if ct_on.is_none() && ct_off.is_none() {
        return Err(json.bad("holds no thresholds (`ct_on` and `ct_off` are null)".into()));
    }
    Ok(ctcal::estimate::CtEstimate {
        method,
        ct_on,
        ct_off,
        ct: ct_on.zip(ct_off).map(|(a, b)| 0.5 * (a + b)),
        ct_on_ci95: json.interval("ct_on_ci95"),
        ct_off_ci95: json.interval("ct_off_ci95"),
        ct_ci95: json.interval("ct_ci95"),
        why: json.why(),
        intervals_used: Vec::new(),
        assumptions: json.strings("assumptions"),
        ct_sigma: None,
        ct_sigma_ci95: None,
        estimators: Vec::new(),
        intervals_dropped: Vec::new(),
        extra: serde_json::Map::new(),
    })
}

/// The error for what is wrong with the `--thresholds-from` file at `path`, with its fix.
fn bad_estimate_json(path: &std::path::Path, what: String) -> BadInput {
    BadInput(format!(
        "{}: {what}\n  fix: give the JSON that `ctcal estimate METHOD INPUT --json FILE` wrote",
        path.display()
    ))
}

/// An `estimate --json` result as read from its file, for `--thresholds-from`.
struct EstimateJson<'a> {
    path: &'a std::path::Path,
    value: serde_json::Value,
}

impl<'a> EstimateJson<'a> {
    /// Reads and parses the file at `path`.
    fn read(path: &'a std::path::Path) -> Result<Self, BadInput> {
        let bad = |what: String| bad_estimate_json(path, what);
        let text =
            std::fs::read_to_string(path).map_err(|e| bad(format!("cannot be read: {e}")))?;
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| bad(format!("is not JSON: {e}")))?;
        Ok(Self { path, value })
    }

    /// The error for what is wrong with the file ([`bad_estimate_json`]).
    fn bad(&self, what: String) -> BadInput {
        bad_estimate_json(self.path, what)
    }

    /// The estimate's `method`: screen, aps, eppps or combined.
    fn method(&self) -> Result<&'static str, BadInput> {
        match self.value.get("method").and_then(|m| m.as_str()) {
            Some("screen") => Ok("screen"),
            Some("aps") => Ok("aps"),
            Some("eppps") => Ok("eppps"),
            Some("combined") => Ok("combined"),
            other => Err(self.bad(format!(
                "`method` is {other:?}, not one of screen, aps, eppps"
            ))),
        }
    }

    /// The threshold `key`: `None` where absent or null, an error where not a positive
    /// threshold.
    fn threshold(&self, key: &str) -> Result<Option<f64>, BadInput> {
        match self.value.get(key) {
            None | Some(serde_json::Value::Null) => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x.is_finite() && x > 0.0 && x < 100.0 => Ok(Some(x)),
                _ => Err(self.bad(format!("`{key}` is {v}, not a positive threshold"))),
            },
        }
    }

    /// The interval `key`, where it is an array of two.
    fn interval(&self, key: &str) -> Option<ctcal::estimate::Interval> {
        let v = self.value.get(key)?.as_array()?;
        (v.len() == 2).then(|| [v[0].as_f64(), v[1].as_f64()])
    }

    /// The strings of the array `key` (none where it is not one).
    fn strings(&self, key: &str) -> Vec<String> {
        self.value
            .get(key)
            .and_then(|v| v.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|s| s.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The `why` object's string values, by key.
    fn why(&self) -> std::collections::BTreeMap<String, String> {
        self.value
            .get("why")
            .and_then(|w| w.as_object())
            .map(|w| {
                w.iter()
                    .filter_map(|(k, v)| Some((k.clone(), v.as_str()?.to_string())))
                    .collect()
            })
            .unwrap_or_default()
    }
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
    let effects = checked_options(args)?;
    let log_response = common.log_map()?;
    let policy = global.outputs([common.input.input.as_path()]);
    check_json(common.json.as_deref(), &policy)?;
    let thresholds = args
        .thresholds_from
        .as_deref()
        .map(thresholds_from)
        .transpose()?;
    let loaded = if args.no_frames {
        common.load(None, false, global)?
    } else {
        common.load(Some(args.max_frames), true, global)?
    };
    let path = loaded.recording.path.clone();
    // an on-screen recording's camera frames show the display, whose refresh and response
    // the re-simulation of those frames does not model: its thresholds are the screen
    // method's to measure
    let on_screen = thresholds.is_none() && matches!(loaded.recording.stimulus(), Ok(Some(_)));
    if on_screen {
        warn(global, ON_SCREEN);
    }
    let spinner = stage_spinner(global);
    let progress = |stage: &str, _: f64| spinner.set_message(stage.to_string());
    let options = fit_options(args, effects, log_response, thresholds);
    let result = ctcal::fit_region::fit(
        &loaded,
        &options,
        ctcal::fit_region::FitBudget {
            max_pixels: args.max_pixels,
            max_events: args.max_events,
        },
        &progress,
    );
    spinner.finish_and_clear();
    let mut result = result.map_err(|e| estimate_failed(&path, &e))?;
    if on_screen {
        result.assumptions.push(ON_SCREEN.into());
    }
    present(&result, common.json.as_deref(), &policy)
}

/// Checks `--effects`, `--holdout`, `--max-frames` and `--exposure-s`; returns the effects.
fn checked_options(args: &FitArgs) -> Result<EffectChoice, BadInput> {
    let effects = effect_choice(&args.effects)?;
    let split = FitOptions {
        holdout: args.holdout,
        ..FitOptions::default()
    };
    if let Err(e) = split.check() {
        return Err(BadInput(format!(
            "--holdout {}: {}\n  fix: {}",
            args.holdout, e.problem, e.fix
        )));
    }
    if args.max_frames < 2 {
        return Err(BadInput("--max-frames must be at least 2".into()));
    }
    if let Some(e) = args.exposure_s
        && !(e.is_finite() && (0.0..=10.0).contains(&e))
    {
        return Err(BadInput(format!(
            "--exposure-s {e} must be between 0 and 10 seconds"
        )));
    }
    Ok(effects)
}

/// The fit's options from the command line: the effects, the held-out share, the log
/// response (`(map, name)`), the frames' exposure, the given thresholds and the seed.
fn fit_options(
    args: &FitArgs,
    effects: EffectChoice,
    (log_map, log_name): (ctcal::sim::log_response::LogMap, String),
    thresholds: Option<ctcal::estimate::CtEstimate>,
) -> FitOptions {
    FitOptions {
        effects,
        holdout: args.holdout,
        aps: ApsOptions {
            log_map,
            log_response_name: log_name,
            choose_response: args.common.choose_response(),
            exposure_us: args.exposure_s.map(|s| (s * 1e6).round() as i64),
            ..ApsOptions::default()
        },
        thresholds,
        seed: args.seed,
        ..FitOptions::default()
    }
}

/// Writes the fit as JSON where `--json` asks, and as a table unless the JSON went to
/// stdout.
fn present(
    result: &FitResult,
    json: Option<&std::path::Path>,
    policy: &ctcal::io::write::OutputPolicy,
) -> anyhow::Result<()> {
    let target = json.map(JsonTarget::parse);
    if let Some(target) = &target {
        emit_json(result, target, policy)?;
    }
    if !matches!(target, Some(JsonTarget::Stdout)) {
        print_human(result)?;
    }
    Ok(())
}

/// What a fit of an on-screen recording without the screen method's thresholds says.
const ON_SCREEN: &str = "an on-screen recording (its stimulus.txt is given): the thresholds are fitted to the camera's own frames of the display, whose refresh, response and gamma that re-simulation does not model, so they and their intervals may be off; measure them through the stimulus with `ctcal estimate screen --json SCREEN.json` and fit with --thresholds-from SCREEN.json (as `ctcal report` does)";

/// Prints a fit as a table: its thresholds, the events-only fit's numbers, the other
/// parameters, the effects chosen and the held-out error.
fn print_human(r: &FitResult) -> std::io::Result<()> {
    let mut rows = threshold_rows(r);
    if let Some(e) = &r.events_only {
        push_events_only_rows(e, &mut rows);
    }
    push_parameter_rows(r, &mut rows);
    push_selection_rows(r, &mut rows);
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

/// The table's first rows: the ON and OFF thresholds (or why not) and the biases.
fn threshold_rows(r: &FitResult) -> Vec<(String, String)> {
    let threshold = |key: &str, v: f64| {
        r.why
            .get(key)
            .map_or(format!("{v:.4}"), |why| format!("not determinable ({why})"))
    };
    vec![
        (
            "thresholds".to_string(),
            format!(
                "ON {}, OFF {}",
                threshold("ct_on", r.params.ct_on),
                threshold("ct_off", r.params.ct_off)
            ),
        ),
        output::biases_row(r.biases.as_ref()),
    ]
}

/// The rows of a fit from the events alone: where its thresholds came from, their balance,
/// the isolated-event rates and how the test blocks were judged.
fn push_events_only_rows(
    e: &ctcal::fit::events_only::EventsOnly,
    rows: &mut Vec<(String, String)>,
) {
    rows.push(("thresholds from".into(), e.thresholds_source.clone()));
    if let Some(ratio) = &e.ct_ratio {
        rows.push((
            "Cp/Cn (ON/OFF balance)".into(),
            format!(
                "{:.3} (+- {:.3})",
                ratio.value,
                ratio.standard_error.unwrap_or(f64::NAN)
            ),
        ));
    }
    let rate = |u: &Option<ctcal::fit::Uncertain>| {
        u.as_ref()
            .map_or("-".to_string(), |u| format!("{:.4}", u.value))
    };
    rows.push((
        "isolated events (Hz/px)".into(),
        format!(
            "ON {}, OFF {} (fit blocks); test blocks ON {}, OFF {}",
            rate(&e.noise_on_hz),
            rate(&e.noise_off_hz),
            e.noise_on_test_hz.map_or("-".into(), |v| format!("{v:.4}")),
            e.noise_off_test_hz
                .map_or("-".into(), |v| format!("{v:.4}"))
        ),
    ));
    rows.push((
        "test blocks".into(),
        match &e.simulated_back_why {
            None => format!(
                "model simulated back over the recorded scene (from parameters alone: {:.4} -> {:.4})",
                e.predicted_error_before, e.predicted_error_after
            ),
            Some(why) => format!("errors from the model's parameters: {why}"),
        },
    ));
}

/// The rows of the parameters other than the thresholds: why each not identified was not,
/// then each identified one with its 95 % interval.
fn push_parameter_rows(r: &FitResult, rows: &mut Vec<(String, String)>) {
    for (key, why) in r.why.iter().filter(|(k, _)| !k.starts_with("ct_o")) {
        rows.push((key.clone(), format!("not identified: {why}")));
    }
    // a parameter not identified is shown by its why alone, as on the report page: its
    // interval (kept in the JSON) is the model's setting, not a result
    for (key, u) in &r.uncertainties {
        if key.starts_with("ct_o") || r.why.contains_key(key) {
            continue;
        }
        rows.push((
            key.clone(),
            match u.interval() {
                Some([lo, hi]) => {
                    let side = |b: Option<f64>| b.map_or("open".to_string(), |b| format!("{b:.6}"));
                    format!("{:.6} (95 %: {} to {})", u.value, side(lo), side(hi))
                }
                None => format!("{:.6}", u.value),
            },
        ));
    }
}

/// The rows of the effect selection: the effects added, the pairs not separated, the
/// held-out error before and after, and each step's decision.
fn push_selection_rows(r: &FitResult, rows: &mut Vec<(String, String)>) {
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
    for a in &r.ambiguities {
        rows.push((
            "not separated".into(),
            format!(
                "{} or {} ({} {:.6} in its place): {}",
                a.kept, a.alternative, a.parameter, a.value, a.separated_by
            ),
        ));
    }
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
}
