//! `ctcal fit` without grey frames: v2e oracle cases with their frames withheld against
//! their known parameters, and the shared events-only recordings end to end (fit, config).

use crate::common::{ctcal, json, oracle, oracle_params, pixel_positions, real, succeeded};

fn fit_without_frames(case: &str) -> serde_json::Value {
    json(&["fit", oracle(case).to_str().unwrap(), "--no-frames"])
}

#[test]
fn hot_pixels_are_named_exactly_without_frames() {
    let fit = fit_without_frames("dev_hot_pixels");
    let truth = &oracle_params("dev_hot_pixels")["post_processing"]["injection"]["hot_pixels"];
    assert_eq!(
        pixel_positions(&fit["hot_pixels_masked"]),
        pixel_positions(truth)
    );
    // the trains' rate beyond the scene's at their pixels: the median of the injected
    // rates (ON + OFF: 297, 62, 48 and 34 Hz, so 55.1 Hz), within the Poisson error of
    // the two middle trains' 50-odd events each (14 %)
    let mut rates: Vec<f64> = truth
        .as_array()
        .unwrap()
        .iter()
        .map(|h| h["on_rate_hz"].as_f64().unwrap() + h["off_rate_hz"].as_f64().unwrap())
        .collect();
    rates.sort_by(f64::total_cmp);
    let median = (rates[1] + rates[2]) / 2.0;
    let rate = fit["params"]["hot_pixel_rate_hz"].as_f64().unwrap();
    assert!((rate / median - 1.0).abs() < 0.14, "{rate} for {median}");
    // both with intervals that hold the truth: 4 hot pixels of 43,200, the injected median
    let holds = |key: &str, truth: f64| {
        let ci = fit["uncertainties"][key]["ci95"].as_array().unwrap();
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        assert!(lo < truth && truth < hi, "{key}: [{lo}, {hi}] for {truth}");
    };
    holds("hot_pixel_fraction", 4.0 / 43_200.0);
    holds("hot_pixel_rate_hz", median);
    // the uniform background activity (0.03 Hz a pixel): within a factor 2 or an upper bound
    let rate = fit["params"]["shot_noise_rate_hz"].as_f64();
    if let Some(rate) = rate {
        assert!((0.015..=0.06 * 1.2).contains(&rate), "{rate}");
    }
    // what the events cannot show is said so
    for key in ["ct_sigma", "cutoff_hz", "timestamp_jitter_s"] {
        assert!(fit["params"][key].is_null(), "{key}");
        assert_eq!(fit["identified"][key], false, "{key}");
        assert!(fit["why"][key].as_str().unwrap().contains("needs"), "{key}");
    }
    // eppps measured the fit run, not the whole recording (which `estimate eppps` alone
    // measures): which part is said
    let source = fit["events_only"]["thresholds_source"].as_str().unwrap();
    assert!(
        source.contains("prior") && source.contains("fit run only, the events' first"),
        "{source}"
    );
}

#[test]
fn refractory_period_is_found_from_the_intervals_within_30_percent() {
    let fit = fit_without_frames("dev_refractory");
    let truth = oracle_params("dev_refractory")["emulator_args"]["refractory_period_s"]
        .as_f64()
        .unwrap();
    let found = fit["params"]["refractory_s"].as_f64().expect("identified");
    assert!((found / truth - 1.0).abs() < 0.3, "{found} for {truth}");
    assert!(fit["error_after"].as_f64().unwrap() < 0.5 * fit["error_before"].as_f64().unwrap());
}

#[test]
fn shot_noise_of_a_static_scene_within_a_factor_2_and_no_refractory_from_a_timestamp_grid() {
    let fit = fit_without_frames("c_noisy_static");
    let truth = oracle_params("c_noisy_static")["emulator_args"]["shot_noise_rate_hz"]
        .as_f64()
        .unwrap();
    let rate = fit["params"]["shot_noise_rate_hz"]
        .as_f64()
        .expect("identified");
    assert!(
        (truth / 2.0..=truth * 2.0).contains(&rate),
        "{rate} for {truth}"
    );
    // v2e stamps this case's events on a 4 ms grid: a gap of one step is not a refractory period
    assert_eq!(fit["events_only"]["timestamp_step_us"], 4000);
    assert!(fit["params"]["refractory_s"].is_null());
    assert!(
        fit["why"]["refractory_s"]
            .as_str()
            .unwrap()
            .contains("grid")
    );
    // the fitted noise simulated back onto the test blocks measures what they measure
    // (0.02 here; twice the rate would give ln 2 = 0.69), the ideal pixel far from it
    assert!(fit["events_only"]["simulated_back_why"].is_null());
    let background = |key: &str| fit[key]["background"].as_f64().unwrap();
    assert!(
        background("components_after") < 0.1,
        "{}",
        background("components_after")
    );
    assert!(
        background("components_before") > 3.0,
        "{}",
        background("components_before")
    );
    // a static scene: no absolute thresholds, and why
    assert!(fit["params"]["ct_on"].is_null());
    assert!(fit["why"]["ct_on"].as_str().unwrap().contains("eppps"));
}

#[test]
fn leak_fires_on_only_and_is_told_from_shot_noise() {
    let fit = fit_without_frames("c_leak_static");
    let steps = fit["steps"].as_array().unwrap();
    let kept = |name: &str| {
        steps
            .iter()
            .any(|s| s["effect"] == name && s["kept"] == true)
    };
    assert!(kept("leak") && !kept("shot_noise"), "{steps:?}");
    let on = fit["events_only"]["noise_on_test_hz"].as_f64().unwrap();
    assert!((0.5..=2.0).contains(&on), "{on}");
    assert_eq!(fit["events_only"]["noise_off_test_hz"], 0.0);
}

#[test]
fn events_only_recordings_fit_and_configure_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    for (name, sensor) in [
        ("evk4_faery_evt3.raw", (1280, 720)),
        ("dvxplorer_tonic.aedat4", (320, 240)),
        ("gen3_faery_evt2.raw", (640, 480)),
    ] {
        let fit_path = dir.path().join(format!("{name}.json"));
        succeeded(
            ctcal()
                .args(["fit", real(name).to_str().unwrap(), "--json"])
                .arg(&fit_path)
                .output(),
        );
        let fit: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&fit_path).unwrap()).unwrap();
        let kept: Vec<&str> = fit["effects_added"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["effect"].as_str().unwrap())
            .collect();
        assert!(
            kept.contains(&"hot_pixels") && kept.contains(&"shot_noise"),
            "{name}: {kept:?}"
        );
        assert!(fit["error_after"].as_f64().unwrap() < fit["error_before"].as_f64().unwrap());
        assert!(fit["params"]["ct_on"].as_f64().unwrap() > 0.0);
        assert!(fit["params"]["ct_sigma"].is_null());
        let output = succeeded(
            ctcal()
                .args(["config"])
                .arg(&fit_path)
                .args(["--format", "v2e"])
                .output(),
        );
        let config = String::from_utf8(output.stdout).unwrap();
        assert!(config.contains("--shot_noise_rate_hz"), "{config}");
        assert!(
            config.contains("not identified") || config.contains("ct_sigma"),
            "{config}"
        );
        let _ = sensor;
    }
}

/// A Gen3 recording (no frames) reported end to end: the per-sequence page gives the fitted
/// noise, what is not identified and why, the loop's table and the simulated-back test
/// errors, and its v2e configuration marks what the events do not identify.
#[test]
fn an_events_only_recording_is_reported_with_its_noise_model() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    succeeded(
        ctcal()
            .arg("report")
            .arg(real("gen3_faery_evt2.raw"))
            .arg("--out")
            .arg(&out)
            .output(),
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("Effects added: **hot_pixels, shot_noise**"),
        "{md}"
    );
    assert!(md.contains("ct_sigma not identified"), "{md}");
    assert!(md.contains("#### The loop"), "{md}");
    assert!(md.contains("simulated back onto the test blocks"), "{md}");
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let fit = &results["sequences"][0]["fit"];
    assert!(fit["events_only"]["simulated_back_why"].is_null());
    assert!(fit["error_after"].as_f64().unwrap() < 0.5 * fit["error_before"].as_f64().unwrap());
    let v2e = std::fs::read_to_string(out.join("configs/gen3_faery_evt2_raw/v2e_args.sh")).unwrap();
    assert!(v2e.contains("NOT IDENTIFIED"), "{v2e}");
}
