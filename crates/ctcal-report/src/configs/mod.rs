//! Simulator configurations from fitted parameters, each in the tool's own names and units,
//! for making training data that looks like the fitted sensor:
//!
//! - ESIM (Rebecq et al., CoRL 2018) flagfile, one `--flag=value` a line; what ESIM cannot
//!   express is said in `#` comments: its threshold noise is redrawn at every event rather
//!   than frozen per pixel, and it has no bandwidth, leak or shot noise;
//! - a whole esim_config_generator configuration ([`generator`]);
//! - v2e as a shell script that runs as it is, and as JSON ([`v2e`]);
//! - ctcal's own PARAMS.toml, which `ctcal simulate` reads back unchanged.
//!
//! Several fits (of one sensor) combine into one configuration by the median of each
//! parameter. A parameter the fits do not identify is marked in a comment beside it: its
//! value is the start value the fit simulated, not a measurement.

pub mod files;
pub mod generator;
pub mod source;
pub mod v2e;

pub use generator::{EsimGeneratorCamera, esim_generator};

use crate::sim::PixelParams;
use std::collections::BTreeMap;

/// What a configuration needs besides the parameters.
#[derive(Clone, Debug, Default)]
pub struct Setup {
    /// The APS exposure to simulate (the recording's, where known), milliseconds.
    pub exposure_ms: Option<f64>,
    pub seed: u64,
    /// The sensor, (width, height) in pixels, where known.
    pub sensor: Option<(u32, u32)>,
    /// Parameters (PARAMS.toml keys) the fits do not identify, with why.
    pub not_identified: BTreeMap<String, String>,
    /// Parameters of effects a fit's final model lacks (written as off), with why and the
    /// strength the recording would have shown (the fit's `not_detected`).
    pub not_detected: BTreeMap<String, String>,
}

impl Setup {
    /// This setup for the parameter set `p` written: only the effects `p` lacks are
    /// said to be off (a combined set has an effect when half its fits do).
    fn for_model(&self, p: &PixelParams) -> Setup {
        let set: Vec<String> = numeric_params(p).into_iter().map(|(k, _)| k).collect();
        let mut out = self.clone();
        out.not_detected.retain(|key, _| !set.contains(key));
        out
    }
}

/// The reasons of several fits, by key: one fit's as they are; of several, each named by
/// its fit (a combined configuration's numbers are each one fit's) and joined.
pub fn merged_reasons(per_fit: &[(String, BTreeMap<String, String>)]) -> BTreeMap<String, String> {
    if let [(_, only)] = per_fit {
        return only.clone();
    }
    let mut out: BTreeMap<String, String> = BTreeMap::new();
    for (fit, reasons) in per_fit {
        for (key, why) in reasons {
            let said = format!("{fit}: {why}");
            out.entry(key.clone())
                .and_modify(|r| {
                    r.push_str("; ");
                    r.push_str(&said);
                })
                .or_insert(said);
        }
    }
    out
}

/// One note per parameter the fits do not identify, then one per effect written as off
/// that no fit detected.
pub fn unmeasured_notes(setup: &Setup) -> Vec<String> {
    let unidentified = setup.not_identified.iter().map(|(key, why)| {
        format!(
            "NOT IDENTIFIED: {key}: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement ({why})"
        )
    });
    let undetected = setup.not_detected.iter().map(|(key, why)| {
        format!(
            "NOT DETECTED: {key}: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: {why}"
        )
    });
    unidentified.chain(undetected).collect()
}

/// The notes as `#` comment lines.
fn comments(notes: &[String]) -> String {
    notes
        .iter()
        .map(|n| format!("# {}\n", crate::caveats::one_line(n)))
        .collect()
}

/// The configuration formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigFormat {
    Esim,
    EsimGenerator,
    V2e,
    V2eJson,
    Ctcal,
}

impl ConfigFormat {
    pub const ALL: [ConfigFormat; 5] = [
        ConfigFormat::Esim,
        ConfigFormat::EsimGenerator,
        ConfigFormat::V2e,
        ConfigFormat::V2eJson,
        ConfigFormat::Ctcal,
    ];

    /// The format's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ConfigFormat::Esim => "esim",
            ConfigFormat::EsimGenerator => "esim-generator",
            ConfigFormat::V2e => "v2e",
            ConfigFormat::V2eJson => "v2e-json",
            ConfigFormat::Ctcal => "ctcal",
        }
    }

    /// The file name a report gives it.
    pub fn file_name(self) -> &'static str {
        match self {
            ConfigFormat::Esim => "esim.flagfile",
            ConfigFormat::EsimGenerator => "esim_config_generator.json",
            ConfigFormat::V2e => "v2e_args.sh",
            ConfigFormat::V2eJson => "v2e_args.json",
            ConfigFormat::Ctcal => "params.toml",
        }
    }

    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// Every numeric PARAMS.toml key that is set, as (key, value).
pub fn numeric_params(p: &PixelParams) -> Vec<(String, f64)> {
    let optional = [
        ("ct_sigma", p.ct_sigma),
        ("ct_sigma_temporal", p.ct_sigma_temporal),
        ("refractory_s", p.refractory_s),
        ("cutoff_hz", p.cutoff_hz),
        ("leak_rate_hz", p.leak_rate_hz),
        ("leak_rate_hz_per_dn", p.leak_rate_hz_per_dn),
        ("leak_spread_decades", p.leak_spread_decades),
        ("shot_noise_rate_hz", p.shot_noise_rate_hz),
        ("shot_noise_bright_factor", p.shot_noise_bright_factor),
        ("hot_pixel_fraction", p.hot_pixel_fraction),
        ("hot_pixel_rate_hz", p.hot_pixel_rate_hz),
        ("timestamp_jitter_s", p.timestamp_jitter_s),
    ];
    let mut out = vec![
        ("ct_on".to_string(), p.ct_on),
        ("ct_off".to_string(), p.ct_off),
    ];
    out.extend(
        optional
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| (k.to_string(), v))),
    );
    out
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// One parameter set for several fits: the median of each parameter (an effect counts
/// when at least half the fits have it; absent ones count as zero), the first fit's log
/// response and display.
pub fn combine(fits: &[PixelParams]) -> Option<PixelParams> {
    let first = fits.first()?;
    let mut out = first.clone();
    out.seed = None;
    out.ct_on = median(&mut fits.iter().map(|p| p.ct_on).collect::<Vec<_>>());
    out.ct_off = median(&mut fits.iter().map(|p| p.ct_off).collect::<Vec<_>>());
    type Slot = fn(&mut PixelParams) -> &mut Option<f64>;
    let slots: [Slot; 7] = [
        |p| &mut p.ct_sigma,
        |p| &mut p.refractory_s,
        |p| &mut p.cutoff_hz,
        |p| &mut p.shot_noise_rate_hz,
        |p| &mut p.hot_pixel_fraction,
        |p| &mut p.hot_pixel_rate_hz,
        |p| &mut p.timestamp_jitter_s,
    ];
    for slot in slots {
        let mut values: Vec<f64> = fits
            .iter()
            .map(|p| slot(&mut p.clone()).unwrap_or(0.0))
            .collect();
        let present = fits
            .iter()
            .filter(|p| slot(&mut (*p).clone()).is_some())
            .count();
        *slot(&mut out) = (2 * present >= fits.len() && present > 0).then(|| median(&mut values));
    }
    (out.leak_rate_hz, out.leak_rate_hz_per_dn) = combined_leak(fits);
    Some(out)
}

/// The leak of several fits, counted as every other effect (present when at least half the
/// fits have it; absent ones count as zero), its parts taken together: a flat leak's rate
/// is its whole rate at every brightness, a growing leak's `leak_rate_hz` only its dark
/// part, so the fits of the form fewer leaky fits have (flat on a tie: growing) are left
/// out of the medians.
fn combined_leak(fits: &[PixelParams]) -> (Option<f64>, Option<f64>) {
    let leaky = fits.iter().filter(|p| p.has_leak()).count();
    if leaky == 0 || 2 * leaky < fits.len() {
        return (None, None);
    }
    let growing = fits
        .iter()
        .filter(|p| p.leak_rate_hz_per_dn.is_some())
        .count();
    let grows = 2 * growing >= leaky;
    let pool: Vec<&PixelParams> = fits
        .iter()
        .filter(|p| !p.has_leak() || p.leak_rate_hz_per_dn.is_some() == grows)
        .collect();
    let mut dark: Vec<f64> = pool.iter().map(|p| p.leak_rate_hz()).collect();
    let mut per_dn: Vec<f64> = pool.iter().map(|p| p.leak_rate_hz_per_dn()).collect();
    (Some(median(&mut dark)), grows.then(|| median(&mut per_dn)))
}

/// The fitted leak's parts, where it has any: the dark rate and the growth per DN.
fn leak_parts(p: &PixelParams) -> Option<String> {
    let parts: Vec<String> = [
        p.leak_rate_hz.map(|r| format!("leak_rate_hz {r:.4}")),
        p.leak_rate_hz_per_dn
            .map(|g| format!("leak_rate_hz_per_dn {g:.3e}")),
    ]
    .into_iter()
    .flatten()
    .collect();
    (!parts.is_empty()).then(|| parts.join(" + "))
}

/// A line of an ESIM flagfile: ESIM's flag `name` set to `value`.
fn esim_flag(name: &str, value: impl std::fmt::Display) -> String {
    format!("--{name}={value}")
}

/// An ESIM flagfile.
pub fn esim_flagfile(p: &PixelParams, setup: &Setup) -> String {
    let mut lines = esim_header(setup);
    lines.extend(esim_threshold_flags(p));
    lines.extend(esim_response_flags(p, setup));
    if let Some(missing) = esim_inexpressible(p) {
        lines.push(missing);
    }
    lines.join("\n") + "\n"
}

/// The flagfile's opening comments: where it comes from, the sensor's size, the parameters
/// the fits do not identify.
fn esim_header(setup: &Setup) -> Vec<String> {
    let mut lines = vec![
        "# ESIM flagfile written by ctcal from a fit of the simulator to a recording".to_string(),
    ];
    if let Some((w, h)) = setup.sensor {
        lines.push(format!(
            "# the fitted sensor is {w}x{h}: give ESIM a camera of that size (its calibration file)"
        ));
    }
    lines.extend(
        comments(&unmeasured_notes(setup))
            .lines()
            .map(str::to_string),
    );
    lines
}

/// The thresholds, their mismatch (frozen per pixel in the fit, redrawn per event by ESIM)
/// and the refractory period.
fn esim_threshold_flags(p: &PixelParams) -> Vec<String> {
    let mut lines = Vec::new();
    let sigma = p.ct_sigma.unwrap_or(0.0);
    lines.push(esim_flag(
        "contrast_threshold_pos",
        format!("{:.6}", p.ct_on),
    ));
    lines.push(esim_flag(
        "contrast_threshold_neg",
        format!("{:.6}", p.ct_off),
    ));
    if sigma > 0.0 {
        lines.push(format!(
            "# the fitted mismatch ({sigma:.4}) is frozen per pixel; ESIM redraws its threshold noise at every event"
        ));
    }
    lines.push(esim_flag(
        "contrast_threshold_sigma_pos",
        format!("{sigma:.6}"),
    ));
    lines.push(esim_flag(
        "contrast_threshold_sigma_neg",
        format!("{sigma:.6}"),
    ));
    lines.push(esim_flag(
        "refractory_period_ns",
        (p.refractory_s.unwrap_or(0.0) * 1e9).round() as i64,
    ));
    lines
}

/// The log response (ESIM's log(I + eps), the nearest to a lin-log fit), the frame
/// exposure and the seed.
fn esim_response_flags(p: &PixelParams, setup: &Setup) -> Vec<String> {
    let mut lines = Vec::new();
    let eps = p.log_eps();
    match p.log_response() {
        crate::sim::LogResponse::Eps => {}
        crate::sim::LogResponse::V2e => lines.push(format!(
            "# fitted with the lin-log response (ln DN above 20 DN, linear below); ESIM takes log(I + eps), I in [0, 1]: eps {eps} is the nearest"
        )),
    }
    lines.push(esim_flag("log_eps", eps));
    lines.push(esim_flag("use_log_image", true));
    match setup.exposure_ms {
        Some(e) => lines.push(esim_flag("exposure_time_ms", format!("{e:.3}"))),
        None => {
            lines.push("# the recording does not state its frame exposure".to_string());
            lines.push(esim_flag("exposure_time_ms", "0.0"));
        }
    }
    lines.push(esim_flag("random_seed", setup.seed));
    lines
}

/// The comment naming the fitted effects ESIM has no flag for (bandwidth, leak, shot
/// noise, hot pixels, timestamp jitter) with their values, if any.
fn esim_inexpressible(p: &PixelParams) -> Option<String> {
    let missing: Vec<String> = [
        (
            "photoreceptor bandwidth",
            p.cutoff_hz.map(|c| format!("cutoff_hz {c:.1}")),
        ),
        ("leak", leak_parts(p)),
        (
            "shot noise",
            p.shot_noise_rate_hz
                .map(|r| format!("shot_noise_rate_hz {r:.4}")),
        ),
        (
            "hot pixels",
            p.hot_pixel_fraction
                .map(|f| format!("hot_pixel_fraction {f:.2e}")),
        ),
        (
            "timestamp jitter",
            p.timestamp_jitter_s
                .map(|j| format!("timestamp_jitter_s {j:.2e}")),
        ),
    ]
    .into_iter()
    .filter_map(|(what, value)| value.map(|v| format!("{what} ({v})")))
    .collect();
    (!missing.is_empty()).then(|| {
        format!(
            "# ESIM cannot express: {} (use v2e or ctcal simulate for them)",
            missing.join(", ")
        )
    })
}

/// ctcal's PARAMS.toml (read back by `ctcal simulate --params`).
pub fn ctcal_params(p: &PixelParams, setup: &Setup) -> String {
    let mut p = p.clone();
    p.seed = Some(setup.seed);
    let mut notes = Vec::new();
    if let Some((w, h)) = setup.sensor {
        notes.push(format!(
            "the fitted sensor is {w}x{h}: simulate a sensor of that size"
        ));
    }
    notes.extend(unmeasured_notes(setup));
    format!(
        "# ctcal PARAMS.toml written from a fit of the simulator to a recording\n{}{}",
        comments(&notes),
        p.to_toml()
    )
}

/// The configuration of `format` for `fits` (combined by median where the format takes
/// one parameter set).
pub fn render(format: ConfigFormat, fits: &[PixelParams], setup: &Setup) -> Option<String> {
    let setup = &setup.for_model(&combine(fits)?);
    match format {
        ConfigFormat::EsimGenerator => esim_generator(fits, setup),
        ConfigFormat::Esim => combine(fits).map(|p| esim_flagfile(&p, setup)),
        ConfigFormat::V2e => combine(fits).map(|p| v2e::script(&p, setup)),
        ConfigFormat::V2eJson => combine(fits).map(|p| v2e::json(&p, setup)),
        ConfigFormat::Ctcal => combine(fits).map(|p| ctcal_params(&p, setup)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 ms exposure, seed 7, a 240x180 sensor whose ON threshold is not identified.
    fn setup() -> Setup {
        Setup {
            exposure_ms: Some(4.0),
            seed: 7,
            sensor: Some((240, 180)),
            not_identified: [("ct_on".to_string(), "a static scene".to_string())].into(),
            not_detected: BTreeMap::new(),
        }
    }

    fn fitted() -> PixelParams {
        PixelParams {
            ct_sigma: Some(0.03),
            refractory_s: Some(0.0005),
            cutoff_hz: Some(300.0),
            shot_noise_rate_hz: Some(1.0),
            ..PixelParams::ideal(0.35, 0.45)
        }
    }

    #[test]
    fn esim_uses_its_names_and_units() {
        let text = esim_flagfile(&fitted(), &setup());
        for (name, value) in [
            ("contrast_threshold_pos", "0.350000"),
            ("contrast_threshold_neg", "0.450000"),
            ("contrast_threshold_sigma_pos", "0.030000"),
            ("refractory_period_ns", "500000"),
            ("log_eps", "0.001"),
            ("use_log_image", "true"),
            ("exposure_time_ms", "4.000"),
            ("random_seed", "7"),
        ] {
            let line = format!("--{name}={value}");
            assert!(text.lines().any(|l| l == line), "{line} in\n{text}");
        }
        assert!(text.contains(
            "# ESIM cannot express: photoreceptor bandwidth (cutoff_hz 300.0), shot noise"
        ));
    }

    /// An effect no fit detected is written as off with a note saying that the zero is
    /// not a measurement; an effect the combined set has (half the fits detected it) is
    /// not called off.
    #[test]
    fn effects_written_as_off_are_said_to_be_undetected() {
        let mut setup = setup();
        setup.not_detected = [
            ("leak_rate_hz", "leak not kept: not called for"),
            ("shot_noise_rate_hz", "shot_noise not kept: not called for"),
        ]
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .into();
        // fitted() has shot noise, no leak
        for format in ConfigFormat::ALL {
            let text = render(format, &[fitted()], &setup).unwrap();
            assert!(
                text.contains(
                    "NOT DETECTED: leak_rate_hz: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: leak not kept: not called for"
                ),
                "{format:?}:\n{text}"
            );
            assert!(
                !text.contains("NOT DETECTED: shot_noise_rate_hz"),
                "{format:?}"
            );
        }
        let json: serde_json::Value =
            serde_json::from_str(&render(ConfigFormat::V2eJson, &[fitted()], &setup).unwrap())
                .unwrap();
        assert_eq!(
            json["not_detected"],
            serde_json::json!({"leak_rate_hz": "leak not kept: not called for"})
        );
    }

    #[test]
    fn medians_combine_fits() {
        let mut a = fitted();
        a.ct_on = 0.2;
        let mut b = PixelParams::ideal(0.3, 0.4);
        b.cutoff_hz = Some(100.0);
        let c = combine(&[a, b, fitted()]).unwrap();
        // medians of ON 0.2, 0.3, 0.35 and OFF 0.45, 0.4, 0.45
        assert_eq!((c.ct_on, c.ct_off), (0.3, 0.45));
        assert_eq!(c.cutoff_hz, Some(300.0));
        // two of three fits have shot noise (median of 1, 0, 1)
        assert_eq!(c.shot_noise_rate_hz, Some(1.0));
        // a flat leak (0.4 Hz) among two that grow with the light (dark 0.1 and 0.3 Hz,
        // 0.01 and 0.03 Hz per DN) is left out of the medians of both parts, and a fit
        // without leak counts as none
        let leak = |dark: f64, per_dn: Option<f64>| PixelParams {
            leak_rate_hz: Some(dark),
            leak_rate_hz_per_dn: per_dn,
            ..fitted()
        };
        let fits = [
            leak(0.1, Some(0.01)),
            leak(0.4, None),
            leak(0.3, Some(0.03)),
            fitted(),
        ];
        let c = combine(&fits).unwrap();
        assert_eq!(
            (c.leak_rate_hz, c.leak_rate_hz_per_dn),
            (Some(0.1), Some(0.01))
        );
        let c = combine(&[leak(0.4, None), leak(0.2, None), fitted()]).unwrap();
        assert_eq!((c.leak_rate_hz, c.leak_rate_hz_per_dn), (Some(0.2), None));
        let generator =
            esim_generator(&[PixelParams::ideal(0.2, 0.3), fitted()], &setup()).unwrap();
        let v: serde_json::Value = serde_json::from_str(&generator).unwrap();
        let camera = &v["camera_params"];
        assert!((camera["contrast_threshold_mean"].as_f64().unwrap() - 0.325).abs() < 1e-12);
        assert!((camera["ct_diff_sigma"].as_f64().unwrap() - (1.5f64).ln()).abs() < 1e-12);
        assert_eq!(camera["min_C"], 0.1667);
        assert_eq!(camera["max_C"], 0.54);
    }

    #[test]
    fn ctcal_params_read_back_unchanged() {
        let text = ctcal_params(&fitted(), &Setup { seed: 3, ..setup() });
        let back = PixelParams::from_toml(&text, "params.toml").unwrap();
        let mut expected = fitted();
        expected.seed = Some(3);
        assert_eq!(back, expected);
    }

    /// Every format of one hand-made fit (thresholds 0.35/0.45, mismatch 0.03, refractory
    /// 0.5 ms, 300 Hz bandwidth, 1 Hz shot noise, 4 ms exposure, 240x180, ON threshold not
    /// identified), as a reviewer reads it.
    #[test]
    fn every_format_of_a_fit() {
        let mut with_leak = fitted();
        with_leak.leak_rate_hz = Some(0.1);
        for format in ConfigFormat::ALL {
            let text = render(format, &[with_leak.clone()], &setup()).unwrap();
            insta::assert_snapshot!(format.name(), text);
        }
    }
}
