//! v2e (Hu, Liu & Delbruck, CVPR workshops 2021) configurations: a shell script that runs
//! v2e with the fitted parameters and the sensor size as it is (`sh v2e_args.sh -i IN ...`,
//! v2e's own input and output arguments appended), and the same arguments as JSON.

use super::{Setup, unmeasured_notes};
use crate::sim::PixelParams;
use serde_json::json;

/// v2e's arguments as (flag without `--`, value); absent effects switched off explicitly.
pub fn arguments(p: &PixelParams, setup: &Setup) -> Vec<(&'static str, f64)> {
    let mut args = vec![
        ("pos_thres", p.ct_on),
        ("neg_thres", p.ct_off),
        ("sigma_thres", p.ct_sigma.unwrap_or(0.0)),
        ("cutoff_hz", p.cutoff_hz.unwrap_or(0.0)),
        ("leak_rate_hz", p.leak_rate_hz.unwrap_or(0.0)),
        ("shot_noise_rate_hz", p.shot_noise_rate_hz.unwrap_or(0.0)),
        ("refractory_period", p.refractory_s.unwrap_or(0.0)),
        ("leak_jitter_fraction", 0.1),
        ("noise_rate_cov_decades", p.leak_spread_decades()),
        ("dvs_emulator_seed", setup.seed as f64),
    ];
    if let Some((w, h)) = setup.sensor {
        args.push(("output_width", w as f64));
        args.push(("output_height", h as f64));
    }
    args
}

/// v2e's flag of the argument `name`.
fn flag(name: &str) -> String {
    format!("--{name}")
}

/// A value as v2e reads it: whole numbers without a decimal point, the rest to six
/// significant places.
fn value(v: f64) -> String {
    if v == v.trunc() && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:.6}")
    }
}

/// The notes every v2e form carries.
fn notes(p: &PixelParams, setup: &Setup) -> Vec<String> {
    let mut notes = Vec::new();
    if p.hot_pixel_fraction.is_some() || p.timestamp_jitter_s.is_some() {
        notes.push("v2e has no hot pixels or timestamp jitter; ctcal simulate has both".into());
    }
    if let Some(g) = p.leak_rate_hz_per_dn.filter(|&g| g > 0.0) {
        let dark = match p.leak_rate_hz {
            Some(r) => format!("{} is its dark part ({r:.4} Hz)", flag("leak_rate_hz")),
            None => format!(
                "its dark part is not identified, so {} is 0",
                flag("leak_rate_hz")
            ),
        };
        notes.push(format!(
            "v2e's leak does not grow with the light: {dark}; the fitted growth, {g:.3e} Hz per DN ({:.3} Hz more at 128 DN), is not in these arguments (ctcal simulate has it)",
            g * 128.0
        ));
    }
    if setup.sensor.is_none() {
        notes.push(format!(
            "the sensor size is not known: add {} and {}",
            flag("output_width"),
            flag("output_height")
        ));
    }
    notes.extend(unmeasured_notes(setup));
    notes
}

/// `v2e_args.sh`: runs v2e (or `$V2E`) with the arguments, then the caller's.
pub fn script(p: &PixelParams, setup: &Setup) -> String {
    let mut text = format!(
        "#!/bin/sh\n# v2e with the parameters ctcal fitted to a recording. Run it as it is, with v2e's\n# input and output arguments after it:\n#   sh v2e_args.sh -i video.mp4 {} out\n# (V2E=/path/to/v2e.py sh v2e_args.sh ... runs another v2e.)\n",
        flag("output_folder")
    );
    for note in notes(p, setup) {
        text.push_str(&format!("# {}\n", super::super::caveats::one_line(&note)));
    }
    text.push_str("exec \"${V2E:-v2e}\" \\\n");
    for (name, v) in arguments(p, setup) {
        text.push_str(&format!("  {} {} \\\n", flag(name), value(v)));
    }
    text.push_str("  \"$@\"\n");
    text
}

/// `v2e_args.json`, `ctcal_version` first (how ctcal knows a file it may replace).
#[derive(serde::Serialize)]
struct V2eJson {
    ctcal_version: &'static str,
    program: &'static str,
    arguments: serde_json::Map<String, serde_json::Value>,
    argv: Vec<String>,
    not_identified: std::collections::BTreeMap<String, String>,
    /// Effects written as off that no fit detected, with why (the fit's `not_detected`).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    not_detected: std::collections::BTreeMap<String, String>,
    notes: Vec<String>,
}

/// `v2e_args.json`: the arguments by name (numbers), as an argument list, and the notes.
pub fn json(p: &PixelParams, setup: &Setup) -> String {
    let args = arguments(p, setup);
    let by_name: serde_json::Map<String, serde_json::Value> = args
        .iter()
        .map(|(name, v)| {
            let v = if v.fract() == 0.0 && v.abs() < 1e15 {
                json!(*v as i64)
            } else {
                json!(v)
            };
            (name.to_string(), v)
        })
        .collect();
    let argv: Vec<String> = args
        .iter()
        .flat_map(|(name, v)| [flag(name), value(*v)])
        .collect();
    let doc = V2eJson {
        ctcal_version: env!("CARGO_PKG_VERSION"),
        program: "v2e",
        arguments: by_name,
        argv,
        not_identified: setup.not_identified.clone(),
        not_detected: setup.not_detected.clone(),
        notes: notes(p, setup),
    };
    serde_json::to_string_pretty(&doc).expect("JSON of numbers and strings") + "\n"
}
