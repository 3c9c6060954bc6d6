//! `ctcal fit`: the closed loop on the v2e oracle cases (each made with known effects) and
//! on real recordings, and a recovery property test on recordings ctcal simulates itself.

use super::common::*;
use ctcal::fit::{EffectChoice, FitInput, FitOptions};
use ctcal::sim::scene::{SceneSource, SceneSpec, aps};
use ctcal::sim::{PixelMaps, PixelParams};
use proptest::prelude::*;

fn fit(path: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["fit", path.to_str().unwrap()];
    args.extend(extra);
    json(&args)
}

fn added(f: &serde_json::Value) -> Vec<String> {
    f["effects_added"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["effect"].as_str().unwrap().to_string())
        .collect()
}

fn param(f: &serde_json::Value, key: &str) -> Option<f64> {
    f["params"][key].as_f64()
}

fn emulator(case: &str, key: &str) -> f64 {
    oracle_params(case)["emulator_args"][key].as_f64().unwrap()
}

/// Every key of the contract, and errors that fell.
fn check_contract(f: &serde_json::Value) {
    for key in [
        "params",
        "effects_added",
        "error_metric",
        "error_before",
        "error_after",
        "ambiguities",
        "steps",
    ] {
        assert!(f.get(key).is_some(), "missing {key}");
    }
    let (before, after) = (
        f["error_before"].as_f64().unwrap(),
        f["error_after"].as_f64().unwrap(),
    );
    assert!(after <= before + 1e-12, "{after} > {before}");
    for e in f["effects_added"].as_array().unwrap() {
        assert!(e["evidence"].as_str().unwrap().len() > 10);
    }
    // every kept step beat chance on the selection blocks, but for an effect kept on its
    // signature (the error rising by no more than chance) and a look-alike the distance
    // did not separate (the lower error); the test blocks judged nothing
    for step in f["steps"].as_array().unwrap() {
        // hot pixels are measured directly (found on fit and selection blocks alike)
        if step["effect"] == "hot_pixels" {
            continue;
        }
        if let (Some(b), Some(a), true) = (
            step["error_before"].as_f64(),
            step["error_after"].as_f64(),
            step["kept"].as_bool().unwrap(),
        ) {
            let chance = step["chance"].as_f64().unwrap_or(0.0);
            let reason = step["reason"].as_str().unwrap();
            if reason.starts_with("kept on its signature") {
                assert!(a - b <= chance.max(0.02 * b), "{step}");
            } else if reason.contains("takes the place of") {
                assert!(a < b, "{step}");
            } else {
                assert!(b - a > chance && b - a >= 0.01 * b, "{step}");
            }
        }
    }
    // each effect's parameter is set, not identified (why), or off and said why (a
    // configuration writes it as zero, which is not a measurement)
    for key in [
        "ct_sigma",
        "refractory_s",
        "cutoff_hz",
        "leak_rate_hz",
        "shot_noise_rate_hz",
        "timestamp_jitter_s",
        "hot_pixel_fraction",
        "hot_pixel_rate_hz",
    ] {
        let set = !f["params"][key].is_null();
        let unidentified = f["why"][key].is_string();
        let off = f["not_detected"][key].is_string();
        assert_eq!(
            [set, unidentified, off].iter().filter(|&&b| b).count(),
            1,
            "{key}: set {set}, why {unidentified}, not_detected {off}"
        );
    }
    let h = &f["holdout"];
    let (fit, sel, test) = (
        h["fit_seconds"].as_f64().unwrap(),
        h["selection_seconds"].as_f64().unwrap(),
        h["test_seconds"].as_f64().unwrap(),
    );
    assert!(fit > 0.0 && sel > 0.0 && test > 0.0, "{h}");
    assert!(
        h["selection_blocks"]
            .as_array()
            .unwrap()
            .iter()
            .all(|s| !h["test_blocks"].as_array().unwrap().contains(s)),
        "{h}"
    );
}

#[test]
fn bandwidth_is_added_where_pixels_are_slow_and_only_there() {
    let f = fit(&oracle("d_bw_middim_texture"), &[]);
    check_contract(&f);
    // the greedy loop tries a refractory period first (both drop events of fast changes);
    // once bandwidth is in, the refractory period is removed, and bandwidth beats it as
    // its look-alike beyond chance, so no ambiguity is named
    assert_eq!(added(&f), ["bandwidth"]);
    let steps = f["steps"].as_array().unwrap();
    let swap = steps
        .iter()
        .find(|s| s["effect"] == "refractory in place of bandwidth?")
        .expect("bandwidth compared with its look-alike");
    assert_eq!(swap["kept"], false, "{swap:#}");
    assert_eq!(f["ambiguities"], serde_json::json!([]));
    for key in ["ct_on", "ct_off"] {
        let v = param(&f, key).unwrap();
        assert!((v / 0.3 - 1.0).abs() < 0.10, "{key} {v}");
    }
    let (before, after) = (
        f["error_before"].as_f64().unwrap(),
        f["error_after"].as_f64().unwrap(),
    );
    assert!(after <= 0.7 * before, "held-out error {before} -> {after}");
    let control = fit(&oracle("d_ctrl_middim_texture"), &[]);
    check_contract(&control);
    assert!(
        !added(&control).contains(&"bandwidth".to_string()),
        "{:?}",
        added(&control)
    );
    assert!(param(&control, "cutoff_hz").is_none());
    // the control's detection limit: its scene with v2e's 30 Hz cutoff (the case above)
    // called for bandwidth and kept it, so a 30 Hz cutoff lies below the limit; a fit that
    // keeps a cutoff gives none
    let limit = control["bandwidth_detection"]["called_for_below_hz"]
        .as_f64()
        .unwrap();
    assert!(limit > 30.0 && limit < 2000.0, "{limit}");
    assert!(f.get("bandwidth_detection").is_none(), "{f:#}");
}

#[test]
fn shot_noise_is_added_to_noisy_recordings_at_its_rate() {
    for case in ["c_noisy_texture", "c_noisy_static"] {
        let f = fit(&oracle(case), &[]);
        check_contract(&f);
        assert!(
            added(&f).contains(&"shot_noise".to_string()),
            "{case}: {:?}",
            added(&f)
        );
        let rate = param(&f, "shot_noise_rate_hz").unwrap();
        let truth = emulator(case, "shot_noise_rate_hz");
        assert!(
            (rate / truth - 1.0).abs() < 0.5,
            "{case}: {rate} vs {truth}"
        );
        // the v2e leak of 0.1 Hz fires its first event a period after the start, so it
        // is not added here; the rate at which it would have been is above it (0.48-0.51
        // Hz today), and shot noise, in the model, has no limit
        let limits = &f["noise_detection"]["limits"];
        let leak = limits["leak_rate_hz"]["called_for_above_hz"]
            .as_f64()
            .unwrap();
        let leak_truth = emulator(case, "leak_rate_hz");
        assert!(
            !added(&f).contains(&"leak".to_string()) && leak > leak_truth && leak < 5.0,
            "{case}: leak called for above {leak} Hz, truth {leak_truth}"
        );
        assert!(limits.get("shot_noise_rate_hz").is_none(), "{limits:#}");
    }
}

#[test]
fn leak_is_added_to_a_static_scene_at_its_rate() {
    let f = fit(&oracle("c_leak_static"), &[]);
    check_contract(&f);
    assert_eq!(added(&f), vec!["leak".to_string()]);
    let rate = param(&f, "leak_rate_hz").unwrap();
    let truth = emulator("c_leak_static", "leak_rate_hz");
    assert!((rate / truth - 1.0).abs() < 0.3, "{rate} vs {truth}");
    // a static scene cannot show its thresholds: the step says so
    let thresholds = &f["steps"][0];
    assert_eq!(thresholds["effect"], "thresholds");
    assert_eq!(thresholds["kept"], false);
    assert!(
        thresholds["reason"]
            .as_str()
            .unwrap()
            .contains("static scene")
    );
}

/// Coverage draw 13010: DVS-Voltmeter pixels (thresholds 0.47, a leak that grows with the
/// light) under objects drifting at 10 px/s, so that 127,291 of its 127,304 events are ON,
/// nearly all of them the leak's. The fit kept a leak of 8.6 Hz [4.4, 17.0] and read ON
/// 0.98 [0.55, 1.77] from the counts with the leak held at 8.6 Hz: a miss. Profiled again
/// at the leak's interval ends, ON runs from about 0.07 to the end of the profile's range
/// (the leak alone outnumbers the events), so the threshold is not determinable, and says
/// why, instead of a confident miss.
#[test]
fn a_threshold_whose_events_a_kept_leak_makes_is_not_determinable() {
    let dir = coverage_case("case-13010");
    let f = fit(dir.path(), &[]);
    assert!(added(&f).contains(&"leak".to_string()), "{:?}", added(&f));
    assert!(f["params"]["ct_on"].is_null(), "{}", f["params"]["ct_on"]);
    let why = f["why"]["ct_on"].as_str().unwrap();
    assert!(
        why.starts_with("the events of this polarity are mostly the leak's"),
        "{why}"
    );
    let check = strings(&f["assumptions"])
        .into_iter()
        .find(|a| a.starts_with("leak-rate check:"))
        .expect("the leak-rate check");
    // the ON part of the note: "ON lo / fitted / hi: not determined"
    let on = check
        .split("; ")
        .find(|part| part.starts_with("ON "))
        .expect("the ON part");
    assert!(on.ends_with(": not determined"), "{check}");
}

/// Coverage draw 13008 (ctcal: a dim, low-contrast rotating texture whose events are
/// nearly all a leak's ON events, 2 of 2,480 OFF): its OFF threshold has no count cells to
/// fix it and is left at its search's start, where the ideal model makes 11,060 OFF events.
/// The read-noise note compares isolated events only of the polarities whose threshold is
/// measured, so it no longer blames those OFF events on the frames' noise (it had said
/// "572 % more isolated events than the recording").
#[test]
fn the_read_noise_note_leaves_out_a_polarity_whose_threshold_is_not_measured() {
    let dir = coverage_case("case-13008");
    let f = fit(dir.path(), &[]);
    assert!(f["params"]["ct_off"].is_null(), "{}", f["params"]["ct_off"]);
    let why = f["why"]["ct_off"].as_str().unwrap();
    assert!(
        why.starts_with("the fit blocks have too few events"),
        "{why}"
    );
    let off = &f["residuals_before"]["by_polarity"][0];
    assert_eq!(off["label"], "OFF");
    assert!(off["real"].as_u64().unwrap() < 10, "{off}");
    assert!(off["simulated"].as_u64().unwrap() > 1000, "{off}");
    let notes: Vec<&str> = strings(&f["assumptions"])
        .into_iter()
        .filter(|a| a.starts_with("the ideal model already makes"))
        .collect();
    assert!(notes.is_empty(), "{notes:?}");
}

/// Also the human table: a parameter the data leave undetermined shows its why, never its
/// interval as if it were a result (the JSON keeps the model's setting in `uncertainties`).
#[test]
fn exactly_the_injected_hot_pixels_are_masked() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("fit.json");
    let case = oracle("dev_hot_pixels");
    let output = succeeded(
        ctcal()
            .args(["fit", case.to_str().unwrap(), "--json"])
            .arg(&file)
            .output(),
    );
    let f: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&file).unwrap()).expect("the file is JSON");
    let table = String::from_utf8(output.stdout).unwrap();
    let why = f["why"].as_object().expect("why is an object");
    assert!(!why.is_empty(), "this fit leaves something undetermined");
    for key in why.keys().filter(|k| !k.starts_with("ct_o")) {
        let rows: Vec<&str> = table
            .lines()
            .filter(|l| l.split_whitespace().next() == Some(key.as_str()))
            .collect();
        assert!(
            rows.iter().all(|r| r.contains("not identified")) && !rows.is_empty(),
            "{key}: {rows:?}"
        );
    }
    check_contract(&f);
    assert!(added(&f).contains(&"hot_pixels".to_string()));
    let masked = pixel_positions(&f["hot_pixels_masked"]);
    let injected = pixel_positions(
        &oracle_params("dev_hot_pixels")["post_processing"]["injection"]["hot_pixels"],
    );
    assert_eq!(masked, injected);
    assert!(param(&f, "hot_pixel_fraction").unwrap() > 0.0);
}

/// A sensor larger than `--max-pixels` is fitted on its busiest region (`dev_hot_pixels`,
/// 240x180, at most 12,000 pixels: a 126x94 rectangle): the region is named, the hot pixels
/// inside it are found at their sensor coordinates and none outside it, and the thresholds'
/// intervals still hold the truth (0.35 / 0.35).
#[test]
fn a_sensor_larger_than_the_pixel_limit_is_fitted_on_its_busiest_region() {
    let f = fit(&oracle("dev_hot_pixels"), &["--max-pixels", "12000"]);
    check_contract(&f);
    let (note, [x0, x1, y0, y1]) = region_of(&f, "fitted");
    assert!(
        (x1 - x0) * (y1 - y0) <= 12_000 && x1 - x0 == 126 && y1 - y0 == 94,
        "{note}"
    );
    let inside = |x: u64, y: u64| (x0..x1).contains(&x) && (y0..y1).contains(&y);
    let masked = pixel_positions(&f["hot_pixels_masked"]);
    let injected_inside: Vec<(u64, u64)> = pixel_positions(
        &oracle_params("dev_hot_pixels")["post_processing"]["injection"]["hot_pixels"],
    )
    .into_iter()
    .filter(|&(x, y)| inside(x, y))
    .collect();
    assert!(!injected_inside.is_empty(), "{note}");
    assert_eq!(masked, injected_inside);
    for key in ["ct_on", "ct_off"] {
        let ci = f["uncertainties"][key]["ci95"].as_array().unwrap();
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        assert!(lo < 0.35 && 0.35 < hi, "{key} [{lo}, {hi}]");
    }
}

/// A window with more events than `--max-events` is fitted on its busiest region holding
/// about that many (`e_ct060_texture`, 109,375 events on 240x180, at most 30,000: about
/// 11,850 pixels of the sensor's aspect): the events the note counts are those of the
/// oracle's own file inside the region, within a tenth of the budget, and the thresholds'
/// intervals hold v2e's 0.6.
#[test]
fn a_window_denser_than_the_event_budget_is_fitted_on_a_region_of_that_many_events() {
    let case = oracle("e_ct060_texture");
    let f = fit(&case, &["--max-events", "30000"]);
    check_contract(&f);
    let (note, [x0, x1, y0, y1]) = region_of(&f, "fitted");
    assert!(
        note.contains("the window's 109375 events are more than the 30000"),
        "{note}"
    );
    let pixels = (x1 - x0) * (y1 - y0);
    assert!((10_000..=11_850).contains(&pixels), "{note}");
    let inside = events_inside(&case, [x0, x1, y0, y1]);
    assert!(
        note.contains(&format!(": {inside} events here")),
        "{inside}: {note}"
    );
    assert!(inside <= 33_000, "{inside}");
    for key in ["ct_on", "ct_off"] {
        let ci = f["uncertainties"][key]["ci95"].as_array().unwrap();
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        assert!(lo < 0.6 && 0.6 < hi, "{key} [{lo}, {hi}]");
    }
}

/// v2e's refractory period of 5 ms on a two-level checkerboard (the events held back, not
/// dropped). The distance barely moves with it on the short selection run; its signature
/// (no same-pixel interval under the period, replicated on the selection blocks and gone
/// with the effect) keeps it. A slow photoreceptor explains the counts almost as well:
/// the refractory period stays as the lower selection error, the pair named.
#[test]
fn refractory_is_added_with_its_period() {
    let f = fit(&oracle("dev_refractory"), &[]);
    check_contract(&f);
    assert!(
        added(&f).contains(&"refractory".to_string()),
        "{:?}",
        added(&f)
    );
    let period = param(&f, "refractory_s").unwrap();
    assert!((period / 0.005 - 1.0).abs() < 0.3, "{period}");
    let ci = f["uncertainties"]["refractory_s"]["ci95"]
        .as_array()
        .unwrap();
    assert!(
        ci[0].as_f64().unwrap() < 0.005 && ci[1].as_f64().unwrap() > 0.005,
        "{ci:?}"
    );
    // a slow photoreceptor explains the thinned fast changes in the period's place, but
    // the recording's shortest intervals still call for the period beside it: the
    // look-alike is tried beside the period, and the recording (which has no cutoff) does
    // not measure it: named as the period's look-alike, or its cutoff not identified
    let ambiguities = f["ambiguities"].as_array().unwrap();
    let named = ambiguities
        .iter()
        .any(|a| a["kept"] == "refractory" && a["alternative"] == "bandwidth");
    let beside_unmeasured = f["steps"]
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s["effect"] == "bandwidth beside refractory?")
        && f["params"]["cutoff_hz"].is_null()
        && f["why"]["cutoff_hz"].is_string();
    assert!(named || beside_unmeasured, "{ambiguities:?} {:#}", f["why"]);
}

#[test]
fn ideal_recordings_get_no_effect_and_their_thresholds() {
    for (case, truth) in [("a_ideal_texture", 0.3), ("e_ct060_texture", 0.6)] {
        let f = fit(&oracle(case), &[]);
        check_contract(&f);
        assert!(added(&f).is_empty(), "{case}: {:?}", added(&f));
        for key in ["ct_on", "ct_off"] {
            let v = param(&f, key).unwrap();
            assert!((v / truth - 1.0).abs() < 0.03, "{case} {key} {v}");
        }
        // shot noise at the 1 Hz that c_noisy_texture's fit finds would show on these
        // textures (0.06-0.12 Hz would, today), and a simulation at the rate given does
        // add isolated events of both polarities
        let shot = &f["noise_detection"]["limits"]["shot_noise_rate_hz"];
        let rate = shot["called_for_above_hz"].as_f64().unwrap();
        assert!(rate > 0.01 && rate < 1.0, "{case}: {shot}");
        let [off, on] = [0, 1].map(|k| shot["isolated_hz_per_hz"][k].as_f64().unwrap());
        assert!(off > 0.05 && on > 0.05, "{case}: {shot}");
        // and the configuration's zero says so
        let off_why = f["not_detected"]["shot_noise_rate_hz"].as_str().unwrap();
        assert!(
            off_why.contains("its detection limit on this recording is")
                && off_why.contains("a rate above that is unlikely"),
            "{case}: {off_why}"
        );
        assert_eq!(f["error_before"], f["error_after"]);
    }
}

#[test]
fn real_recordings_fit_end_to_end() {
    for input in [real("davis346_faery.aedat4"), real("ijrr_slider_depth_50k")] {
        let f = fit(&input, &[]);
        check_contract(&f);
        if input.ends_with("davis346_faery.aedat4") {
            davis346_spread_is_bounded_and_questioned(&f);
        }
        for key in ["ct_on", "ct_off"] {
            let v = param(&f, key).unwrap();
            assert!((0.05..2.0).contains(&v), "{}: {key} {v}", input.display());
            let se = f["uncertainties"][key]["standard_error"].as_f64().unwrap();
            assert!(se > 0.0 && se < v, "{}: {key} +- {se}", input.display());
        }
        // every step names its effect and why it was or was not kept
        for step in f["steps"].as_array().unwrap() {
            assert!(!step["reason"].as_str().unwrap().is_empty());
        }
        assert!(
            f["residuals_after"]["by_intensity"]
                .as_array()
                .unwrap()
                .len()
                == 6
        );
    }
}

/// The DAVIS346's three frames: the model keeps no spread; event timing on the fit run
/// resolves none and allows at most 0.029, while the counts, 44 % more dispersed than the
/// model's, still call for one (the fit blocks chose 0.054, within chance).
fn davis346_spread_is_bounded_and_questioned(f: &serde_json::Value) {
    let d = &f["mismatch_detection"];
    let at_most = d["at_most"].as_f64().unwrap();
    assert!((0.01..0.06).contains(&at_most), "{d}");
    assert_eq!(d["timing_ci95"][1].as_f64(), Some(at_most));
    assert_eq!(d["counts_call_for_it"], true, "{d}");
    let said = f["not_detected"]["ct_sigma"].as_str().unwrap();
    assert!(said.contains("allows at most"), "{said}");
    assert!(said.contains("a spread may be present"), "{said}");
}

#[test]
fn effect_choices_and_bad_input() {
    // none: the ideal pixel with fitted thresholds
    let f = fit(&oracle("c_noisy_texture"), &["--effects", "none"]);
    assert!(added(&f).is_empty());
    assert_eq!(f["steps"].as_array().unwrap().len(), 1);
    // a list is tried in its order, whatever the evidence
    let f = fit(&oracle("c_leak_static"), &["--effects", "shot_noise,leak"]);
    let tried: Vec<&str> = f["steps"]
        .as_array()
        .unwrap()
        .iter()
        .skip(1)
        .map(|s| s["effect"].as_str().unwrap())
        .collect();
    // the list in its order, then each kept effect refitted once with the others in place
    assert_eq!(tried[..2], ["shot_noise", "leak"]);
    let kept = added(&f);
    assert!(kept.contains(&"leak".to_string()));
    let refits: Vec<String> = tried[2..]
        .iter()
        .filter(|s| s.ends_with("(refit)"))
        .map(|s| s.to_string())
        .collect();
    let removals = tried[2..]
        .iter()
        .filter(|s| s.ends_with("(still needed?)"))
        .count();
    // with two effects or more added, each is refitted and then tested for whether it is
    // still needed (removed when not: then it is no longer in effects_added)
    assert_eq!(refits.len(), removals, "{tried:?}");
    assert!(refits.is_empty() || refits.len() >= 2, "{tried:?}");
    if refits.is_empty() {
        assert!(kept.len() <= 1, "{kept:?}");
    }
    // a region of about 200 events holds too few for a count cell: refused, not fitted
    // from the search's start (a one-pixel region of 14 events wrote error_before =
    // error_after = 0 and two start values as thresholds)
    let e = bad_input(&[
        "fit",
        real("ijrr_slider_depth_50k").to_str().unwrap(),
        "--roi",
        "80,140,100,160",
    ]);
    assert!(
        e.contains("too few to fit") && e.contains("a fit needs 1000"),
        "{e}"
    );
    let e = bad_input(&[
        "fit",
        oracle("a_ideal_texture").to_str().unwrap(),
        "--effects",
        "glare",
    ]);
    assert!(
        e.contains("`glare` is not an effect") && e.contains("shot_noise"),
        "{e}"
    );
    let e = bad_input(&[
        "fit",
        oracle("a_ideal_texture").to_str().unwrap(),
        "--holdout",
        "0.9",
    ]);
    assert!(e.contains("--holdout"), "{e}");
    // 0.1 of 10 blocks leaves one held-out block, a test block and no selection block
    let e = bad_input(&[
        "fit",
        oracle("a_ideal_texture").to_str().unwrap(),
        "--holdout",
        "0.1",
    ]);
    assert!(
        e.contains("leaves 9 fit, 0 selection and 1 test blocks of 10")
            && e.contains("hold out a fraction between 0.16 and 0.75"),
        "{e}"
    );
}

/// A recording ctcal simulates itself: a translating 1/f texture of 160 x 120 pixels seen
/// for 0.8 s, 40 Hz APS frames, events from the scene rendered at 1 kHz through `params`.
fn simulated_recording(params: &PixelParams, seed: u64) -> (ctcal::EventChunk, Vec<ctcal::Frame>) {
    let mut spec = SceneSpec::moving_texture(160, 120, 0.8, 1000.0);
    spec.seed = seed;
    spec.aps = Some(ctcal::sim::scene::ApsSpec {
        rate_hz: 40.0,
        exposure_s: 0.0,
    });
    let scene = spec.realise().unwrap();
    let frames = aps::render(
        &scene,
        spec.width,
        spec.height,
        spec.duration_s,
        1000.0,
        spec.aps.as_ref().unwrap(),
    );
    let mut source = SceneSource::new(&spec, scene);
    let mut events = ctcal::EventChunk::default();
    ctcal::sim::run::<ctcal::sim::SimError>(
        &mut source,
        params,
        PixelMaps::default(),
        |chunk| {
            events.extend_from(chunk);
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    events.sort_by_time();
    (events, frames)
}

/// The fit of a recording made with known parameters recovers them: the thresholds within
/// 10 %, shot noise (when made) added at its rate within 50 %, and no effect the recording
/// was not made with.
fn fit_recovers(ct_on: f64, asymmetry: f64, noise: f64, seed: u64) -> Result<(), TestCaseError> {
    let mut params = PixelParams::ideal(ct_on, ct_on * asymmetry);
    if noise > 0.0 {
        params.shot_noise_rate_hz = Some(noise);
    }
    params.seed = Some(seed);
    let (events, frames) = simulated_recording(&params, seed);
    let sensor = ctcal::Sensor::new(160, 120);
    let excluded = vec![false; sensor.pixels()];
    let result = ctcal::fit::fit(
        &FitInput {
            sensor,
            events: &events,
            frames: &frames,
            excluded: &excluded,
            unread: &[],
        },
        &FitOptions {
            effects: EffectChoice::Auto,
            ..FitOptions::default()
        },
        &|_, _| {},
    )
    .unwrap();
    let added: Vec<&str> = result
        .effects_added
        .iter()
        .map(|e| e.effect.name())
        .collect();
    prop_assert!(
        (result.params.ct_on / params.ct_on - 1.0).abs() < 0.1,
        "ON {} vs {}",
        result.params.ct_on,
        params.ct_on
    );
    prop_assert!(
        (result.params.ct_off / params.ct_off - 1.0).abs() < 0.1,
        "OFF {} vs {}",
        result.params.ct_off,
        params.ct_off
    );
    if noise > 0.0 {
        prop_assert!(added.contains(&"shot_noise"), "{added:?}");
        let rate = result.params.shot_noise_rate_hz.unwrap();
        prop_assert!(
            (rate / noise - 1.0).abs() < 0.5,
            "shot noise {rate} vs {noise}"
        );
    }
    prop_assert!(
        added.iter().all(|e| *e == "shot_noise" || *e == "leak"),
        "{added:?}"
    );
    Ok(())
}

proptest! {
    // a fixed generator seed: CI runs the same cases every time (change it here to explore
    // others); case (0.218, 0.997, 0.78, 331) once stopped the threshold profile
    // on an overshoot and gave shot noise 0.29 Hz
    #![proptest_config(ProptestConfig {
        cases: 3,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(331),
        ..ProptestConfig::default()
    })]

    /// [`fit_recovers`] on random parameters.
    #[test]
    fn a_fit_recovers_the_parameters_of_a_simulated_recording(
        ct_on in 0.2f64..0.5,
        asymmetry in 0.8f64..1.25,
        noise in prop_oneof![Just(0.0f64), 0.5f64..2.0],
        seed in 1u64..1000,
    ) {
        fit_recovers(ct_on, asymmetry, noise, seed)?;
    }
}

/// The case that once stopped the threshold profile on an overshoot (shot noise 0.29 Hz
/// for a true 0.78 Hz): low thresholds, strong noise.
#[test]
fn a_fit_recovers_strong_shot_noise_at_low_thresholds() {
    fit_recovers(
        0.21787868029451585,
        0.9972102660351376,
        0.7815150007348058,
        331,
    )
    .unwrap();
}
