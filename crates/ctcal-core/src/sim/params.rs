//! `PixelParams`: the simulator's parameters, exactly the PARAMS.toml keys of the CLI
//! contract. Thresholds are required; every other absent key means that effect is off.
//! Contrast thresholds and all "log" quantities are natural-log units of intensity.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// How intensity (camera DN, 0..255) maps to the log domain the pixel compares.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LogResponse {
    /// v2e's lin-log: `ln(DN)` above 20 DN, linear below (continuous at 20 DN).
    #[default]
    V2e,
    /// `ln(DN / 255 + log_eps)`.
    Eps,
}

/// A screen between the scene and the camera (on-screen calibration stimuli).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisplayParams {
    /// Refresh rate; each stimulus frame is held until the next refresh (sample and hold).
    pub refresh_hz: f64,
    /// Luminance = black_level + (1 - black_level) * (DN / 255)^gamma.
    pub gamma: f64,
    /// Luminance of DN 0 as a fraction of white.
    pub black_level: f64,
    /// Camera DN of full white.
    pub white_dn: f64,
    /// Gaussian optical blur, sigma in pixels (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blur_px: Option<f64>,
    /// Time from a refresh to the camera seeing it, seconds (absent: 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_offset_s: Option<f64>,
}

impl DisplayParams {
    /// Parses a screen model (the `[display]` table's keys, as in `calib/screens/`).
    pub fn from_toml(text: &str, source_name: &str) -> Result<Self, ParamsError> {
        let display: DisplayParams = toml::from_str(text).map_err(|e| ParamsError {
            source_name: source_name.to_string(),
            key: "display".into(),
            problem: format!("cannot be read: {}", e.message()),
            fix: "a screen model has refresh_hz, gamma, black_level, white_dn and optionally blur_px and time_offset_s".into(),
        })?;
        let mut check = PixelParams::ideal(1.0, 1.0);
        check.display = Some(display);
        check.validate(source_name)?;
        Ok(check.display.expect("set above"))
    }
}

/// The highest event rate of one pixel a parameter may give (one event a microsecond, the
/// time resolution of events).
pub const MAX_PIXEL_RATE_HZ: f64 = 1e6;
/// The widest display blur (sigma, pixels): the largest sensor side.
pub const MAX_BLUR_PX: f64 = 4096.0;

/// The pixel model's parameters (PARAMS.toml).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PixelParams {
    /// ON contrast threshold (log units).
    pub ct_on: f64,
    /// OFF contrast threshold (log units, positive).
    pub ct_off: f64,
    /// Frozen per-pixel threshold mismatch: standard deviation (log units), both polarities.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ct_sigma: Option<f64>,
    /// Threshold noise redrawn after every event: standard deviation (log units).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ct_sigma_temporal: Option<f64>,
    /// Refractory period, seconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refractory_s: Option<f64>,
    /// Photoreceptor cutoff at full white (255 DN), Hz; scales as (DN + 20) / 275. 0: no
    /// bandwidth limit, as v2e's `cutoff_hz = 0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cutoff_hz: Option<f64>,
    /// Leak: the reference drifts down by `leak_rate_hz * ct_on` per second.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leak_rate_hz: Option<f64>,
    /// Leak that grows with the light: ON leak events per second for each DN of the
    /// pixel's present intensity, beside `leak_rate_hz` (parasitic photocurrent in the
    /// reset switch, Nozaki & Delbruck, IEEE TED 2017; DVS-Voltmeter's `k5`). The
    /// reference falls by `(leak_rate_hz + leak_rate_hz_per_dn * DN) * ct_on` per second.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leak_rate_hz_per_dn: Option<f64>,
    /// Pixel-to-pixel spread of the leak rate, decades (log10 standard deviation; default
    /// 0.1 as v2e's `noise_rate_cov_decades`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leak_spread_decades: Option<f64>,
    /// Shot-noise events (ON + OFF) per pixel per second in the dark.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shot_noise_rate_hz: Option<f64>,
    /// Shot-noise rate at full white as a fraction of the dark rate (default 0.25, as v2e).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shot_noise_bright_factor: Option<f64>,
    /// Fraction of pixels that are hot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hot_pixel_fraction: Option<f64>,
    /// Event rate of a hot pixel, Hz.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hot_pixel_rate_hz: Option<f64>,
    /// Gaussian timestamp jitter, standard deviation in seconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timestamp_jitter_s: Option<f64>,
    /// Log response (default v2e).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub log_response: Option<LogResponse>,
    /// Offset of the `eps` log response (default 0.001).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub log_eps: Option<f64>,
    /// Seed of every random draw (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// A screen between scene and camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub display: Option<DisplayParams>,
}

/// A parameter problem: which key, what is wrong, how to fix it.
#[derive(Debug, thiserror::Error)]
#[error("{source_name}: `{key}` {problem}\n  fix: {fix}")]
pub struct ParamsError {
    pub source_name: String,
    pub key: String,
    pub problem: String,
    pub fix: String,
}

/// The largest timestamp jitter (standard deviation, seconds) a parameter file may ask for.
pub const MAX_JITTER_S: f64 = 1.0;

impl PixelParams {
    /// Ideal pixel with these thresholds (every effect off).
    pub fn ideal(ct_on: f64, ct_off: f64) -> Self {
        Self {
            ct_on,
            ct_off,
            ct_sigma: None,
            ct_sigma_temporal: None,
            refractory_s: None,
            cutoff_hz: None,
            leak_rate_hz: None,
            leak_rate_hz_per_dn: None,
            leak_spread_decades: None,
            shot_noise_rate_hz: None,
            shot_noise_bright_factor: None,
            hot_pixel_fraction: None,
            hot_pixel_rate_hz: None,
            timestamp_jitter_s: None,
            log_response: None,
            log_eps: None,
            seed: None,
            display: None,
        }
    }

    /// Parses PARAMS.toml text; `source_name` names it in errors.
    pub fn from_toml(text: &str, source_name: &str) -> Result<Self, ParamsError> {
        if let Some(key) = first_non_finite(text) {
            return Err(ParamsError {
                source_name: source_name.to_string(),
                key,
                problem: "is not a finite number".into(),
                fix: "give a real number (nan and inf are not parameter values)".into(),
            });
        }
        let params: PixelParams = toml::from_str(text).map_err(|e| ParamsError {
            source_name: source_name.to_string(),
            // the whole line the error is on, numbered (a span may be an empty value)
            key: e
                .span()
                .map(|s| {
                    let start = text[..s.start].rfind('\n').map_or(0, |i| i + 1);
                    let line = text[start..].lines().next().unwrap_or("").trim();
                    format!("line {}: {line}", text[..start].matches('\n').count() + 1)
                })
                .unwrap_or_default(),
            problem: format!("cannot be read: {}", e.message()),
            fix: "PARAMS.toml needs ct_on and ct_off; optional keys: ct_sigma, ct_sigma_temporal, refractory_s, cutoff_hz, leak_rate_hz, leak_rate_hz_per_dn, leak_spread_decades, shot_noise_rate_hz, shot_noise_bright_factor, hot_pixel_fraction, hot_pixel_rate_hz, timestamp_jitter_s, log_response (\"v2e\"|\"eps\"), log_eps, seed, [display]".into(),
        })?;
        params.validate(source_name)?;
        Ok(params)
    }

    /// Reads and validates a PARAMS.toml file.
    pub fn from_file(path: &Path) -> Result<Self, crate::sim::SimError> {
        let text = read_text_file(path)?;
        Ok(Self::from_toml(&text, &path.display().to_string())?)
    }

    /// The TOML text of these parameters.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("parameters serialise")
    }

    /// Checks every value's range.
    pub fn validate(&self, source_name: &str) -> Result<(), ParamsError> {
        let check = Check { source_name };
        check.thresholds(self.ct_on, self.ct_off)?;
        self.check_effects(&check)?;
        if let Some(eps) = self.log_eps {
            check.positive("log_eps", eps)?;
        }
        if let Some(d) = &self.display {
            check.display(d)?;
        }
        Ok(())
    }

    /// The effects' keys: none negative, no rate beyond one event a microsecond, the
    /// jitter and the hot-pixel share in their ranges.
    fn check_effects(&self, check: &Check) -> Result<(), ParamsError> {
        for (key, v) in [
            ("ct_sigma", self.ct_sigma),
            ("ct_sigma_temporal", self.ct_sigma_temporal),
            ("refractory_s", self.refractory_s),
            ("cutoff_hz", self.cutoff_hz),
            ("leak_rate_hz", self.leak_rate_hz),
            ("leak_rate_hz_per_dn", self.leak_rate_hz_per_dn),
            ("leak_spread_decades", self.leak_spread_decades),
            ("shot_noise_rate_hz", self.shot_noise_rate_hz),
            ("shot_noise_bright_factor", self.shot_noise_bright_factor),
            ("hot_pixel_rate_hz", self.hot_pixel_rate_hz),
            ("timestamp_jitter_s", self.timestamp_jitter_s),
        ] {
            check.non_negative(key, v)?;
        }
        // events are timed to the microsecond: no pixel fires more often than that
        for (key, v) in [
            ("leak_rate_hz", self.leak_rate_hz),
            ("shot_noise_rate_hz", self.shot_noise_rate_hz),
            ("hot_pixel_rate_hz", self.hot_pixel_rate_hz),
        ] {
            if let Some(v) = v
                && v > MAX_PIXEL_RATE_HZ
            {
                return Err(check.fail(
                    key,
                    format!(
                        "is {v:e} events per pixel per second; events are timed to the microsecond, so no pixel fires more than {MAX_PIXEL_RATE_HZ:e} times a second"
                    ),
                    "give a rate per pixel per second (real sensors: well below 1e3)",
                ));
            }
        }
        if let Some(g) = self.leak_rate_hz_per_dn
            && g * 255.0 > MAX_PIXEL_RATE_HZ
        {
            return Err(check.fail(
                "leak_rate_hz_per_dn",
                format!(
                    "is {g:e} events per pixel per second per DN, {:e} at full white (255 DN); events are timed to the microsecond, so no pixel fires more than {MAX_PIXEL_RATE_HZ:e} times a second",
                    g * 255.0
                ),
                "give the leak's growth per DN of the pixel's intensity (DVS-Voltmeter's DAVIS346 fit: 0.005)",
            ));
        }
        if let Some(j) = self.timestamp_jitter_s
            && j > MAX_JITTER_S
        {
            return Err(check.fail(
                "timestamp_jitter_s",
                format!(
                    "is {j} s; a jitter's standard deviation beyond {MAX_JITTER_S} s would reorder a recording's seconds, and the simulator keeps events within the frames' span, so it cannot be simulated as given"
                ),
                "give the standard deviation in seconds (real sensors: microseconds to a millisecond)",
            ));
        }
        if let Some(f) = self.hot_pixel_fraction
            && !(0.0..=1.0).contains(&f)
        {
            return Err(check.fail(
                "hot_pixel_fraction",
                format!("is {f}"),
                "give a fraction between 0 and 1",
            ));
        }
        Ok(())
    }

    pub fn seed(&self) -> u64 {
        self.seed.unwrap_or(0)
    }

    pub fn log_response(&self) -> LogResponse {
        self.log_response.unwrap_or_default()
    }

    pub fn log_eps(&self) -> f64 {
        self.log_eps.unwrap_or(0.001)
    }

    /// An effect is on when its key is present and non-zero.
    pub fn refractory_s(&self) -> f64 {
        self.refractory_s.unwrap_or(0.0)
    }

    pub fn cutoff_hz(&self) -> Option<f64> {
        self.cutoff_hz.filter(|&c| c > 0.0)
    }

    pub fn leak_rate_hz(&self) -> f64 {
        self.leak_rate_hz.unwrap_or(0.0)
    }

    pub fn leak_rate_hz_per_dn(&self) -> f64 {
        self.leak_rate_hz_per_dn.unwrap_or(0.0)
    }

    /// Whether the reference leaks, in the dark or with the light.
    pub fn has_leak(&self) -> bool {
        self.leak_rate_hz() > 0.0 || self.leak_rate_hz_per_dn() > 0.0
    }

    pub fn leak_spread_decades(&self) -> f64 {
        self.leak_spread_decades.unwrap_or(0.1)
    }

    pub fn shot_noise_rate_hz(&self) -> f64 {
        self.shot_noise_rate_hz.unwrap_or(0.0)
    }

    pub fn shot_noise_bright_factor(&self) -> f64 {
        self.shot_noise_bright_factor.unwrap_or(0.25)
    }

    /// Hot pixels are on when both their fraction and rate are positive.
    pub fn hot_pixels(&self) -> Option<(f64, f64)> {
        match (self.hot_pixel_fraction, self.hot_pixel_rate_hz) {
            (Some(f), Some(r)) if f > 0.0 && r > 0.0 => Some((f, r)),
            _ => None,
        }
    }
}

/// Reads a parameter or scene file (a regular file of at most 1 MB).
pub(crate) fn read_text_file(path: &Path) -> Result<String, crate::sim::SimError> {
    crate::files::read_small_text(path, 1 << 20)
        .map_err(|e| crate::sim::SimError::not_a_file(path, e))
}

/// The dotted key of the first NaN or infinite number in TOML `text` (TOML allows `nan` and
/// `inf`), or `None`; unreadable TOML is left to the typed parser's error.
pub(crate) fn first_non_finite(text: &str) -> Option<String> {
    fn walk(value: &toml::Value, key: String) -> Option<String> {
        match value {
            toml::Value::Float(f) if !f.is_finite() => Some(key),
            toml::Value::Table(t) => t.iter().find_map(|(k, v)| {
                walk(
                    v,
                    if key.is_empty() {
                        k.clone()
                    } else {
                        format!("{key}.{k}")
                    },
                )
            }),
            toml::Value::Array(a) => a
                .iter()
                .enumerate()
                .find_map(|(i, v)| walk(v, format!("{key}[{i}]"))),
            _ => None,
        }
    }
    let table: toml::Table = toml::from_str(text).ok()?;
    walk(&toml::Value::Table(table), String::new())
}

/// The range checks of [`PixelParams::validate`], naming the parameters' source in errors.
struct Check<'a> {
    source_name: &'a str,
}

impl Check<'_> {
    fn fail(&self, key: &str, problem: String, fix: &str) -> ParamsError {
        ParamsError {
            source_name: self.source_name.to_string(),
            key: key.to_string(),
            problem,
            fix: fix.to_string(),
        }
    }

    fn positive(&self, key: &str, v: f64) -> Result<(), ParamsError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.fail(
                key,
                format!("is {v}; it must be a positive number"),
                "give a value > 0",
            ))
        }
    }

    fn non_negative(&self, key: &str, v: Option<f64>) -> Result<(), ParamsError> {
        match v {
            Some(v) if !(v.is_finite() && v >= 0.0) => Err(self.fail(
                key,
                format!("is {v}; it must be zero or positive"),
                "give a value >= 0, or remove the key to switch the effect off",
            )),
            _ => Ok(()),
        }
    }

    /// Positive, and at least the floor every pixel's threshold is held to.
    fn thresholds(&self, ct_on: f64, ct_off: f64) -> Result<(), ParamsError> {
        let floor = super::effects::mismatch::MIN_THRESHOLD;
        for (key, v) in [("ct_on", ct_on), ("ct_off", ct_off)] {
            self.positive(key, v)?;
            if (v as f32) < floor {
                return Err(self.fail(
                    key,
                    format!(
                        "is {v:e}; the simulator floors every pixel's threshold at {floor} (as ESIM's minimum_contrast_threshold), so it would be simulated as {floor}"
                    ),
                    "give a threshold of 0.01 or more (real sensors: about 0.1 to 1)",
                ));
            }
        }
        Ok(())
    }

    fn display(&self, d: &DisplayParams) -> Result<(), ParamsError> {
        self.positive("display.refresh_hz", d.refresh_hz)?;
        self.positive("display.gamma", d.gamma)?;
        self.positive("display.white_dn", d.white_dn)?;
        if !(d.black_level.is_finite() && (0.0..1.0).contains(&d.black_level)) {
            return Err(self.fail(
                "display.black_level",
                format!("is {}", d.black_level),
                "give the luminance of black as a fraction of white, in [0, 1)",
            ));
        }
        self.non_negative("display.blur_px", d.blur_px)?;
        if let Some(blur) = d.blur_px
            && blur > MAX_BLUR_PX
        {
            return Err(self.fail(
                "display.blur_px",
                format!(
                    "is {blur:e} pixels; a blur wider than {MAX_BLUR_PX} pixels (the largest sensor) leaves one uniform grey"
                ),
                "give the optical blur's sigma in pixels (a few pixels at most for a focused camera)",
            ));
        }
        if d.time_offset_s.is_some_and(|t| !t.is_finite()) {
            return Err(self.fail(
                "display.time_offset_s",
                "is not finite".into(),
                "give seconds",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_and_inf_anywhere_name_their_key() {
        let e = PixelParams::from_toml("ct_on = 0.3\nct_off = nan\n", "p.toml").unwrap_err();
        assert!(e.to_string().contains("`ct_off`") && e.to_string().contains("finite"));
        let e = PixelParams::from_toml(
            "ct_on = 0.3\nct_off = 0.3\n[display]\nrefresh_hz = 60.0\ngamma = inf\nblack_level = 0.0\nwhite_dn = 200.0\n",
            "p.toml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("`display.gamma`"), "{e}");
        assert_eq!(first_non_finite("a = [1.0, -inf]"), Some("a[1]".into()));
    }

    /// A value TOML cannot read names its line (an empty value gave "`` cannot be read").
    #[test]
    fn an_unreadable_value_names_its_line() {
        let e = PixelParams::from_toml("ct_on = 0.3\nct_off = \n", "p.toml").unwrap_err();
        assert!(e.to_string().contains("`line 2: ct_off =`"), "{e}");
        let e =
            PixelParams::from_toml("ct_on = 0.3\nct_off = 0.3\nseed = -1\n", "p.toml").unwrap_err();
        assert!(e.to_string().contains("`line 3: seed = -1`"), "{e}");
    }

    /// A jitter of 1e9 s was accepted and the simulator clamped every event into the
    /// frames' span: a parameter no sensor has, simulated as something else.
    #[test]
    fn a_jitter_beyond_a_second_is_refused() {
        let e = PixelParams::from_toml(
            "ct_on = 0.3\nct_off = 0.3\ntimestamp_jitter_s = 1e9\n",
            "p.toml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("`timestamp_jitter_s`"), "{e}");
        assert!(
            PixelParams::from_toml(
                "ct_on = 0.3\nct_off = 0.3\ntimestamp_jitter_s = 0.001\n",
                "p"
            )
            .is_ok()
        );
    }

    /// A leak that grows with the light past a microsecond's events at full white, or
    /// below zero, is refused by name.
    #[test]
    fn a_leak_growth_no_pixel_could_fire_at_is_refused() {
        for bad in ["2e4", "-0.01"] {
            let e = PixelParams::from_toml(
                &format!("ct_on = 0.3\nct_off = 0.3\nleak_rate_hz_per_dn = {bad}\n"),
                "p.toml",
            )
            .unwrap_err();
            assert!(e.to_string().contains("`leak_rate_hz_per_dn`"), "{e}");
        }
        let p = PixelParams::from_toml(
            "ct_on = 0.3\nct_off = 0.3\nleak_rate_hz_per_dn = 0.005\n",
            "p",
        )
        .unwrap();
        assert!(p.has_leak() && p.leak_rate_hz() == 0.0);
    }

    #[test]
    fn thresholds_alone_make_an_ideal_pixel() {
        let p = PixelParams::from_toml("ct_on = 0.3\nct_off = 0.4\n", "t").unwrap();
        assert_eq!(p, PixelParams::ideal(0.3, 0.4));
        assert_eq!(p.refractory_s(), 0.0);
        assert_eq!(p.cutoff_hz(), None);
        assert_eq!(p.log_response(), LogResponse::V2e);
    }

    #[test]
    fn every_key_round_trips_through_toml() {
        let text = r#"
ct_on = 0.35
ct_off = 0.45
ct_sigma = 0.03
ct_sigma_temporal = 0.01
refractory_s = 0.0005
cutoff_hz = 300.0
leak_rate_hz = 0.1
leak_rate_hz_per_dn = 0.005
shot_noise_rate_hz = 1.0
shot_noise_bright_factor = 0.25
hot_pixel_fraction = 0.001
hot_pixel_rate_hz = 50.0
timestamp_jitter_s = 0.0001
log_response = "eps"
log_eps = 0.01
seed = 7

[display]
refresh_hz = 75.0
gamma = 2.0
black_level = 0.005
white_dn = 200.0
blur_px = 0.8
"#;
        let p = PixelParams::from_toml(text, "t").unwrap();
        assert_eq!(p.display.as_ref().unwrap().gamma, 2.0);
        let again = PixelParams::from_toml(&p.to_toml(), "t").unwrap();
        assert_eq!(p, again);
    }

    #[test]
    fn mistakes_name_the_key() {
        let e = PixelParams::from_toml("ct_on = 0.3\n", "p.toml").unwrap_err();
        assert!(e.to_string().contains("ct_off"), "{e}");
        let e = PixelParams::from_toml("ct_on = 0.3\nct_off = 0.3\ncutof_hz = 3\n", "p.toml")
            .unwrap_err();
        assert!(e.to_string().contains("cutof_hz"), "{e}");
        let e = PixelParams::from_toml("ct_on = -0.3\nct_off = 0.3\n", "p.toml").unwrap_err();
        assert!(e.to_string().contains("`ct_on`"), "{e}");
        // a hostile round's 1e-12 was simulated as 0.01 (5.2 M events) without a word
        let e = PixelParams::from_toml("ct_on = 0.3\nct_off = 1e-12\n", "p.toml").unwrap_err();
        assert!(
            e.to_string().contains("`ct_off`")
                && e.to_string().contains("is 1e-12")
                && e.to_string()
                    .contains("floors every pixel's threshold at 0.01"),
            "{e}"
        );
        assert!(PixelParams::from_toml("ct_on = 0.01\nct_off = 0.3\n", "p.toml").is_ok());
        let e = PixelParams::from_toml(
            "ct_on = 0.3\nct_off = 0.3\nhot_pixel_fraction = 2\n",
            "p.toml",
        )
        .unwrap_err();
        assert!(e.to_string().contains("hot_pixel_fraction"), "{e}");
    }
}
