//! `ctcal estimate` against the v2e oracle cases (true thresholds in each params.json) and
//! on real recordings: values, intervals that contain the truth, per-pixel maps.

use crate::common::*;

/// The truth of an oracle case: (pos_thres, neg_thres).
fn true_thresholds(case: &str) -> (f64, f64) {
    let p = oracle_params(case);
    let args = &p["emulator_args"];
    (
        args["pos_thres"].as_f64().unwrap(),
        args["neg_thres"].as_f64().unwrap(),
    )
}

fn interval(v: &serde_json::Value) -> (f64, f64) {
    (v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

/// Runs `estimate aps` on an oracle case and checks both thresholds against the truth.
fn aps_recovers(case: &str, tolerance: f64, interval_contains_truth: bool) -> serde_json::Value {
    let e = json(&["estimate", "aps", oracle(case).to_str().unwrap()]);
    let (on, off) = true_thresholds(case);
    for (key, truth) in [("ct_on", on), ("ct_off", off)] {
        let value = e[key].as_f64().unwrap();
        assert!(
            (value / truth - 1.0).abs() < tolerance,
            "{case}: {key} {value} vs {truth}"
        );
        let (lo, hi) = interval(&e[format!("{key}_ci95")]);
        assert!(
            lo < value && value < hi,
            "{case}: {key} outside its own interval"
        );
        if interval_contains_truth {
            assert!(
                lo <= truth && truth <= hi,
                "{case}: {key} interval [{lo}, {hi}] misses {truth}"
            );
        }
    }
    assert_eq!(e["method"], "aps");
    assert!(!e["intervals_used"].as_array().unwrap().is_empty());
    assert!(!e["assumptions"].as_array().unwrap().is_empty());
    let names: Vec<&str> = e["estimators"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["event_timing", "resimulation"], "{case}");
    e
}

#[test]
fn aps_recovers_the_ideal_and_the_three_thresholds_within_5_percent() {
    for case in ["e_ct030_texture", "e_ct060_texture", "e_ct100_texture"] {
        aps_recovers(case, 0.05, true);
    }
}

#[test]
fn aps_on_the_ideal_case_finds_no_mismatch() {
    let e = aps_recovers("a_ideal_texture", 0.05, true);
    let sigma = e["ct_sigma"].as_f64().unwrap();
    assert!(
        sigma < 0.01,
        "ct_sigma {sigma} on a sensor without mismatch"
    );
}

#[test]
fn aps_recovers_asymmetric_thresholds_mismatch_and_per_pixel_maps() {
    let dir = tempfile::tempdir().unwrap();
    let maps = dir.path().join("maps");
    let case = oracle("b_asym_texture");
    let e = json(&[
        "estimate",
        "aps",
        case.to_str().unwrap(),
        "--maps",
        maps.to_str().unwrap(),
    ]);
    let (on, off) = true_thresholds("b_asym_texture");
    for (key, truth) in [("ct_on", on), ("ct_off", off)] {
        let value = e[key].as_f64().unwrap();
        assert!(
            (value / truth - 1.0).abs() < 0.05,
            "{key} {value} vs {truth}"
        );
        let (lo, hi) = interval(&e[format!("{key}_ci95")]);
        assert!(
            lo <= truth && truth <= hi,
            "{key} [{lo}, {hi}] misses {truth}"
        );
    }
    // the frozen mismatch, estimation noise removed: the truth is 0.03
    let sigma = e["ct_sigma"].as_f64().unwrap();
    assert!((sigma / 0.03 - 1.0).abs() < 0.3, "ct_sigma {sigma}");
    let (lo, hi) = interval(&e["ct_sigma_ci95"]);
    assert!(lo <= sigma && sigma <= hi);
    // the maps against the true per-pixel thresholds
    for (file, truth) in [
        ("ct_on.npy", "true_pos_thres.npy"),
        ("ct_off.npy", "true_neg_thres.npy"),
    ] {
        let ours: ndarray::Array2<f32> = ndarray_npy::read_npy(maps.join(file)).unwrap();
        let theirs: ndarray::Array2<f32> = ndarray_npy::read_npy(case.join(truth)).unwrap();
        assert_eq!(ours.dim(), (180, 240));
        let pairs: Vec<(f64, f64)> = ours
            .iter()
            .zip(theirs.iter())
            .filter(|(a, _)| a.is_finite())
            .map(|(a, b)| (*a as f64, *b as f64))
            .collect();
        assert!(
            pairs.len() > 30_000,
            "{file}: {} pixels with a value",
            pairs.len()
        );
        let r = ctcal::estimate::lsq::correlation(&pairs).unwrap();
        assert!(r >= 0.9, "{file}: correlation {r} with {truth}");
    }
    let counts: ndarray::Array2<u32> = ndarray_npy::read_npy(maps.join("ct_count.npy")).unwrap();
    assert!(counts.iter().map(|&c| c as u64).sum::<u64>() > 150_000);
    // the least-squares cross-check of Wang et al. is reported with the maps
    assert!(
        e["maps"]["least_squares_cross_check"]["ct_on"]
            .as_f64()
            .is_some()
    );
}

#[test]
fn aps_on_the_davis_like_case_is_within_10_percent() {
    aps_recovers("dev_davis_like", 0.10, false);
}

#[test]
fn aps_on_real_recordings_reports_estimates_with_intervals() {
    // IJRR slider_depth (DAVIS240C): published estimates put its thresholds at 0.2-0.5
    let e = json(&[
        "estimate",
        "aps",
        real("ijrr_slider_depth_50k").to_str().unwrap(),
    ]);
    for key in ["ct_on", "ct_off"] {
        let value = e[key].as_f64().unwrap();
        let (lo, hi) = interval(&e[format!("{key}_ci95")]);
        assert!(
            lo < value && value < hi && hi - lo < 0.5,
            "{key} {value} [{lo}, {hi}]"
        );
        assert!((0.15..0.6).contains(&value), "{key} {value}");
    }
    // frames black-level subtracted: the offset is found and said
    assert!(e["frame_offset_dn"]["value"].as_f64().unwrap() > 0.0);
    let e = json(&[
        "estimate",
        "aps",
        real("davis346_faery.aedat4").to_str().unwrap(),
    ]);
    for key in ["ct_on", "ct_off"] {
        let value = e[key].as_f64().unwrap();
        let (lo, hi) = interval(&e[format!("{key}_ci95")]);
        assert!(
            lo < value && value < hi && (0.05..1.5).contains(&value),
            "{key} {value}"
        );
    }
    assert!(
        e["assumptions"]
            .as_array()
            .unwrap()
            .iter()
            .any(|a| a.as_str().unwrap().contains("exposure 0.500 ms"))
    );
}

#[test]
fn aps_without_frames_says_which_method_to_use() {
    let e = bad_input(&[
        "estimate",
        "aps",
        real("evk4_faery_evt3.raw").to_str().unwrap(),
    ]);
    assert!(
        e.contains("evk4_faery_evt3.raw")
            && e.contains("needs grey frames")
            && e.contains("estimate eppps"),
        "{e}"
    );
}
