//! The fits a simulator configuration is made from: `ctcal fit` results and report results
//! (their JSON), each value checked against what a camera can have before any reaches a
//! configuration, fits of one sensor only, with what the fits say they do not identify.

use super::Setup;
use crate::sim::PixelParams;

/// A fit set refused: the message names the file, the JSON path and the fix.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{0}")]
pub struct FitSetError(pub String);

type Result<T> = std::result::Result<T, FitSetError>;

/// The fits to configure from: parameters, frame exposures (µs) and the seed they were
/// made with.
#[derive(Default)]
pub struct FitSet {
    pub params: Vec<PixelParams>,
    pub exposures_us: Vec<Option<i64>>,
    pub seed: Option<u64>,
    /// The sensor (`WxH`) of each fit, where a report says it, with the sequence's name.
    pub sensors: Vec<(String, String)>,
    /// Parameters a fit does not identify, with why (its `why`).
    pub not_identified: std::collections::BTreeMap<String, String>,
    /// Per fit (named by its file or sequence), the parameters of effects its model lacks,
    /// with why (its `not_detected`).
    pub not_detected: Vec<(String, std::collections::BTreeMap<String, String>)>,
}

impl FitSet {
    /// Keeps what the fit `json` (named `fit`) says it does not identify (`why`) and which
    /// effects its model lacks undetected (`not_detected`, each fit's reason named).
    fn note_unidentified(&mut self, json: &serde_json::Value, fit: &str) {
        let reasons = |field: &str| {
            let object = json.get(field).and_then(|w| w.as_object());
            object
                .into_iter()
                .flatten()
                .filter_map(|(key, why)| Some((key.clone(), why.as_str()?.to_string())))
                .collect::<Vec<_>>()
        };
        self.not_identified.extend(reasons("why"));
        let not_detected = reasons("not_detected").into_iter().collect();
        self.not_detected.push((fit.to_string(), not_detected));
    }
}

impl FitSet {
    /// Adds the fits of one parsed file: a `ctcal fit` result, or a report's results (every
    /// fitted sequence). `file` names it in errors.
    pub fn add(&mut self, file: &str, json: &serde_json::Value) -> Result<()> {
        let Some(sequences) = json.get("sequences").and_then(|s| s.as_array()) else {
            let (p, exposure) = fit_params(json, file, "")?;
            self.note_unidentified(json, file);
            self.params.push(p);
            self.exposures_us.push(exposure);
            return Ok(());
        };
        self.seed = self.seed.or(json.get("seed").and_then(|s| s.as_u64()));
        let before = self.params.len();
        for (i, s) in sequences.iter().enumerate() {
            let Some(fit) = s.get("fit") else { continue };
            let name = s.get("name").and_then(|n| n.as_str()).unwrap_or("?");
            let (p, exposure) = fit_params(
                fit,
                &format!("{file} (sequence {name})"),
                &format!("sequences[{i}].fit."),
            )?;
            self.params.push(p);
            self.exposures_us.push(exposure);
            self.note_unidentified(fit, name);
            let (w, h) = (&s["stats"]["width"], &s["stats"]["height"]);
            if let (Some(w), Some(h)) = (w.as_u64(), h.as_u64()) {
                self.sensors.push((format!("{w}x{h}"), name.to_string()));
            }
        }
        if self.params.len() == before {
            return Err(FitSetError(format!(
                "{file}: the report has no fitted sequence\n  fix: report recordings with grey frames or events to fit, with the fit left in"
            )));
        }
        Ok(())
    }

    /// What a configuration needs besides the parameters: the one sensor of the fits
    /// (`files` names them in errors), the exposure where every fit agrees on it, the
    /// `seed` given, else the report's, else 2020.
    pub fn setup(&self, files: &str, seed: Option<u64>) -> Result<Setup> {
        if self.params.is_empty() {
            return Err(FitSetError(format!(
                "{files}: no fitted sequence\n  fix: give `ctcal fit` results or a report with fits"
            )));
        }
        let exposure_ms = match self.exposures_us.as_slice() {
            [first, rest @ ..] if rest.iter().all(|e| e == first) => first.map(|e| e as f64 / 1e3),
            _ => None,
        };
        Ok(Setup {
            exposure_ms,
            seed: seed.or(self.seed).unwrap_or(2020),
            sensor: one_sensor(self, files)?,
            not_identified: self.not_identified.clone(),
            not_detected: super::merged_reasons(&self.not_detected),
        })
    }
}

/// Refuses fits of different sensors: a configuration describes one camera.
fn one_sensor(fits: &FitSet, file: &str) -> Result<Option<(u32, u32)>> {
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
        return Err(FitSetError(format!(
            "{file}: the fitted sequences come from {} sensors ({}); a configuration describes one camera, so none is combined across sensors\n  fix: use the per-sequence configurations in the report's configs/SEQUENCE/, or report each sensor as its own dataset and give `ctcal fit` results of one sensor",
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
fn identified(fit: &serde_json::Value, file: &str, prefix: &str) -> Result<()> {
    for key in ["ct_on", "ct_off"] {
        if fit["params"].get(key).is_some_and(|v| v.is_null()) {
            let why = fit["why"][key].as_str().unwrap_or("no reason given");
            return Err(FitSetError(format!(
                "{file}: `{prefix}params.{key}` is null: the recording does not identify it ({why})\n  fix: configure from a fit of a recording that shows the thresholds (motion, frames that explain its events)"
            )));
        }
    }
    Ok(())
}

/// The largest magnitude each numeric fit parameter may have (the PARAMS.toml keys; the
/// `display` table's as `display.KEY`): what a camera can have, far beyond what a fit finds,
/// so that a damaged or hand-edited fit never reaches a simulator's configuration.
const PLAUSIBLE: [(&str, f64); 21] = [
    // contrast thresholds and their spreads, natural-log units
    ("ct_on", 10.0),
    ("ct_off", 10.0),
    ("ct_sigma", 10.0),
    ("ct_sigma_temporal", 10.0),
    ("refractory_s", 10.0),
    ("cutoff_hz", 1e6),
    ("leak_rate_hz", 1e6),
    ("leak_rate_hz_per_dn", 1e4),
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
fn validate_fit_json(fit: &serde_json::Value, file: &str, prefix: &str) -> Result<()> {
    let place = Place { file, prefix };
    let Some(params) = fit.get("params") else {
        return Err(FitSetError(format!(
            "{file}: {}has no `params` (not a `ctcal fit` result)\n  fix: give a `ctcal fit` result (its JSON) or a report folder",
            if prefix.is_empty() {
                String::new()
            } else {
                format!("`{}` ", prefix.trim_end_matches('.'))
            }
        )));
    };
    for (key, value) in param_values(params, &place)? {
        plausible_param(fit, &key, value, &place)?;
    }
    plausible_exposure(fit, &place)
}

/// Where a fit lies: its `file` and the JSON path (`prefix`) inside it.
struct Place<'a> {
    file: &'a str,
    prefix: &'a str,
}

/// What to do about a value that is not what a fit writes.
const UNEDITED: &str = "give an unedited `ctcal fit` result (or correct this value)";

impl Place<'_> {
    /// The value at `path` (below the fit) refused: its `problem` and the `fix`.
    fn bad(&self, path: &str, problem: String, fix: &str) -> FitSetError {
        FitSetError(format!(
            "{}: `{}{path}` {problem}\n  fix: {fix}",
            self.file, self.prefix
        ))
    }
}

/// A JSON value as an error message names it.
fn describe(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Array(_) => "a list".to_string(),
        serde_json::Value::Object(_) => "an object".to_string(),
        serde_json::Value::String(s) => format!("the string {s:?}"),
        other => other.to_string(),
    }
}

/// Every value of a fit's `params`, by key (the `display` table's as `display.KEY`);
/// refused where `params` or its display is no object.
fn param_values<'a>(
    params: &'a serde_json::Value,
    place: &Place,
) -> Result<Vec<(String, &'a serde_json::Value)>> {
    let Some(object) = params.as_object() else {
        return Err(place.bad(
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
                return Err(place.bad(
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
    Ok(values)
}

/// Refuses a numeric parameter `key` of the fit that is no number or beyond
/// [`PLAUSIBLE`]; keys it does not list pass, as does a null the fit gives its reason for.
fn plausible_param(
    fit: &serde_json::Value,
    key: &str,
    value: &serde_json::Value,
    place: &Place,
) -> Result<()> {
    let Some(&(_, max)) = PLAUSIBLE.iter().find(|(k, _)| *k == key) else {
        return Ok(());
    };
    let path = format!("params.{key}");
    // a parameter the fit says it does not identify is null, with its reason
    if value.is_null() && fit["why"][key].is_string() {
        return Ok(());
    }
    let Some(v) = value.as_f64() else {
        return Err(place.bad(
            &path,
            format!("is {}, not a number", describe(value)),
            UNEDITED,
        ));
    };
    if !(v.is_finite() && v.abs() <= max) {
        return Err(place.bad(
            &path,
            format!("is {v:e}, beyond any camera (at most {max:e} in magnitude)"),
            UNEDITED,
        ));
    }
    Ok(())
}

/// Refuses a `frame_exposure_us` that is not a whole number of microseconds in
/// 1..=[`MAX_EXPOSURE_US`] (none, or null, passes).
fn plausible_exposure(fit: &serde_json::Value, place: &Place) -> Result<()> {
    match fit.get("frame_exposure_us") {
        None | Some(serde_json::Value::Null) => Ok(()),
        Some(value) => match value.as_i64() {
            Some(us) if us > 0 && us <= MAX_EXPOSURE_US => Ok(()),
            _ => Err(place.bad(
                "frame_exposure_us",
                format!(
                    "is {}; an exposure is a whole number of microseconds, 1..={MAX_EXPOSURE_US}",
                    describe(value)
                ),
                UNEDITED,
            )),
        },
    }
}

/// The parameters of one fit result in `file`, at JSON path `prefix` (`place` names it in
/// errors).
fn fit_params(
    fit: &serde_json::Value,
    file: &str,
    prefix: &str,
) -> Result<(PixelParams, Option<i64>)> {
    identified(fit, file, prefix)?;
    validate_fit_json(fit, file, prefix)?;
    let params: PixelParams = serde_json::from_value(fit["params"].clone()).map_err(|e| {
        FitSetError(format!(
            "{file}: `{prefix}params`: {e}\n  fix: give an unedited `ctcal fit` result"
        ))
    })?;
    params.validate(file).map_err(|e| {
        FitSetError(format!(
            "{file}: `{prefix}params.{}` {}\n  fix: {}",
            e.key, e.problem, e.fix
        ))
    })?;
    Ok((
        params,
        fit.get("frame_exposure_us").and_then(|v| v.as_i64()),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn fit(ct_on: f64) -> serde_json::Value {
        json!({"params": {"ct_on": ct_on, "ct_off": 0.3}, "frame_exposure_us": 2000})
    }

    #[test]
    fn a_report_gives_its_fits_seed_sensor_and_common_exposure() {
        let report = json!({"seed": 7, "sequences": [
            {"name": "a", "fit": fit(0.25), "stats": {"width": 240, "height": 180}},
            {"name": "b", "stats": {"width": 240, "height": 180}},
            {"name": "c", "fit": fit(0.35), "stats": {"width": 240, "height": 180}},
        ]});
        let mut fits = FitSet::default();
        fits.add("results.json", &report).unwrap();
        assert_eq!(fits.params.len(), 2);
        let setup = fits.setup("results.json", None).unwrap();
        assert_eq!(
            (setup.seed, setup.sensor, setup.exposure_ms),
            (7, Some((240, 180)), Some(2.0))
        );
        assert_eq!(fits.setup("results.json", Some(3)).unwrap().seed, 3);
    }

    #[test]
    fn refusals_name_the_file_the_json_path_and_the_fix() {
        let mut fits = FitSet::default();
        let e = fits.add("f.json", &fit(1e9)).unwrap_err().0;
        assert!(
            e.contains("f.json") && e.contains("`params.ct_on`") && e.contains("fix:"),
            "{e}"
        );
        let unidentified =
            json!({"params": {"ct_on": null, "ct_off": 0.3}, "why": {"ct_on": "a static scene"}});
        let e = fits.add("g.json", &unidentified).unwrap_err().0;
        assert!(
            e.contains("a static scene") && e.contains("does not identify"),
            "{e}"
        );
        let mixed = json!({"sequences": [
            {"name": "a", "fit": fit(0.25), "stats": {"width": 240, "height": 180}},
            {"name": "b", "fit": fit(0.25), "stats": {"width": 346, "height": 260}},
        ]});
        fits.add("r.json", &mixed).unwrap();
        let e = fits.setup("r.json", None).unwrap_err().0;
        assert!(e.contains("2 sensors") && e.contains("346x260: b"), "{e}");
        let e = FitSet::default().setup("none", None).unwrap_err().0;
        assert!(e.contains("no fitted sequence"), "{e}");
    }
}
