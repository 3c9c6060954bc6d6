//! The coverage study's machinery (`ctcal::coverage`, the runner in `benches/coverage/`) on
//! a seeded random subset: eight drawn cases with APS frames, written with their truth,
//! estimated by `ctcal estimate aps` and tabulated by the same library code as the study.

use ctcal::coverage::summary::Summary;
use ctcal::coverage::{CaseSpec, Method, Reported, RunRecord, write_case};
use std::path::Path;
use std::time::Duration;

/// The study's runner (it builds the binary's command line).
#[path = "../../benches/coverage/run.rs"]
mod run;
use run::{RunOptions, run_method};

/// Seeds from here on are drawn; the first [`CASES`] cases with APS frames are used.
const FIRST_SEED: u64 = 9000;
const CASES: usize = 8;

/// The coverage the aps threshold intervals must reach on these draws (95 % intervals, less
/// the binomial slack of a handful of determinable cases). Asserted since aps carries its
/// measured method systematic (`benches/coverage/aps-systematic-2026-11-29`); the spread
/// `ct_sigma` does not reach it yet and keeps its floor in [`APS_COVERED_TODAY`].
const APS_COVERAGE_BOUNDS: [(&str, f64); 2] = [("ct_on", 0.75), ("ct_off", 0.75)];

/// Covered intervals on these eight cases, asserted as a floor so that a fix can only raise
/// it. When this test was written: of 7 determinable each (one refused, too few events
/// between frames) Cp 3/7, Cn 2/7, ct_sigma 4/7. Since aps refuses thresholds resting on
/// fewer than 3 usable frame intervals, case-9000 (one usable interval, 0.07 for a true
/// 0.85) is refused too. Since aps withholds what its re-simulation cannot confirm (the
/// counts of ideal pixels on these frames match the recording's at no threshold), the
/// event timing's values of case-9006 (0.11 for 0.76, noise three quarters of the events)
/// and case-9007 (ON 0.24 for 0.47) are not determinable: of 4, Cp 2/4, Cn 2/4, ct_sigma
/// 1/4 (case-9007's spread, withheld with its thresholds, had been covered). The misses
/// left: case-9003 (dim, 10 DN: both methods agree on 0.58 for 0.78, a log response
/// question) and case-9008 (0.91 for 0.63). Since `ct_sigma` combines the polarities by
/// inverse variance and its interval carries the frame-rate systematic (2026-11-28), the
/// spread that was covered here is not resolved (`null` with an upper bound), and two are
/// determinable, both missed (case-9006 0.064 for 0.025, case-9003 0.031 for 0.046): 0/2
/// on these eight draws, against 21/34 -> 22/25 covered on the first 100 draws of the
/// study (`benches/coverage/aps-spread-2026-11-28`), so the spread's floor here is 0.
/// Since the thresholds' intervals carry the method systematic measured on 180 draws (13 %
/// of the value, 2026-11-29), five draws are determinable and all five are covered (Cp / Cn
/// 5/5); the spread: one determinable, missed.
const APS_COVERED_TODAY: [(&str, usize); 3] = [("ct_on", 5), ("ct_off", 5), ("ct_sigma", 0)];

fn cases() -> Vec<CaseSpec> {
    (FIRST_SEED..)
        .map(CaseSpec::draw)
        .filter(|c| Method::Aps.applies_to(c))
        .take(CASES)
        .collect()
}

fn run_aps(case: &CaseSpec, dir: &Path) -> RunRecord {
    let truth = write_case(case, dir).expect("the case is written");
    let written: CaseSpec =
        serde_json::from_slice(&std::fs::read(dir.join("case.json")).unwrap()).unwrap();
    assert_eq!(&written, case, "case.json reproduces the case");
    assert!(truth.events > 0 && truth.aps_frames >= 2, "{truth:?}");
    let (outcome, seconds) = run_method(&run_options(), Method::Aps, dir, case);
    RunRecord::new(case.clone(), Some(truth), Method::Aps, seconds, outcome)
}

/// How the tests run the binary: two threads, at most 5 minutes a command.
fn run_options() -> RunOptions {
    RunOptions {
        binary: env!("CARGO_BIN_EXE_ctcal").into(),
        threads: 2,
        timeout: Duration::from_secs(300),
    }
}

/// Draw `seed`'s case written under `work` and run through `method`.
fn run_draw(method: Method, seed: u64, work: &Path) -> RunRecord {
    let case = CaseSpec::draw(seed);
    let dir = work.join(&case.id);
    let truth = write_case(&case, &dir).expect("the case is written");
    let (outcome, seconds) = run_method(&run_options(), method, &dir, &case);
    RunRecord::new(case, Some(truth), method, seconds, outcome)
}

/// Draw `seed` of the peers' study (made by one of ctcal, ESIM, DVS-Voltmeter and IEBCS,
/// as `coverage --generators ctcal,esim,voltmeter,iebcs` draws it) written under `work`
/// and run through `method`.
fn run_peer_draw(method: Method, seed: u64, work: &Path) -> RunRecord {
    use ctcal::coverage::Generator::{Ctcal, Esim, Iebcs, Voltmeter};
    let case = CaseSpec::draw_from(seed, &[Ctcal, Esim, Voltmeter, Iebcs]);
    let dir = work.join(&case.id);
    let truth = write_case(&case, &dir).expect("the case is written");
    let (outcome, seconds) = run_method(&run_options(), method, &dir, &case);
    RunRecord::new(case, Some(truth), method, seconds, outcome)
}

/// The value `record` reports for `key` with its true value, after asserting that it
/// is an interval (open sides reach 0 and infinity) holding the truth.
fn covered_value(record: &RunRecord, key: &str) -> (f64, f64) {
    let id = &record.case.id;
    let true_value = record.truth.as_ref().expect("the case was written").values[key];
    let Reported::Interval { value, lo, hi } = record.reported[key].clone() else {
        panic!(
            "{id} {key}: {:?} ({:?})",
            record.reported[key], record.outcome
        );
    };
    assert!(
        lo.unwrap_or(0.0) <= true_value && true_value <= hi.unwrap_or(f64::INFINITY),
        "{id} {key}: {value} [{lo:?}, {hi:?}] for {true_value}"
    );
    (value, true_value)
}

/// The JSON a run printed, after asserting that it succeeded with output.
fn json_output(record: &RunRecord) -> &serde_json::Value {
    let ctcal::coverage::Outcome::Ok {
        output: Some(output),
    } = &record.outcome
    else {
        panic!("{}: {:?}", record.case.id, record.outcome);
    };
    output
}

/// A number, or `null` with a reason; a refusal (exit 2) must say why.
fn assert_answered(record: &RunRecord) {
    let id = &record.case.id;
    if let ctcal::coverage::Outcome::Failed {
        exit_code, message, ..
    } = &record.outcome
    {
        assert_eq!(*exit_code, Some(2), "{id}: not a refusal: {message}");
        assert!(
            !message.trim().is_empty(),
            "{id}: refused without a message"
        );
        return;
    }
    for key in ["ct_on", "ct_off"] {
        match &record.reported[key] {
            Reported::Interval { .. } | Reported::NoInterval { .. } => {}
            Reported::NotDeterminable { why } => assert!(!why.is_empty(), "{id} {key}"),
            Reported::NotReported => panic!("{id}: aps did not report {key}"),
        }
    }
}

#[test]
fn aps_intervals_on_a_random_subset_are_scored() {
    let work = tempfile::tempdir().unwrap();
    let records: Vec<RunRecord> = cases()
        .iter()
        .map(|case| run_aps(case, &work.path().join(&case.id)))
        .collect();
    records.iter().for_each(assert_answered);
    let summary = Summary::tabulate(&records);
    assert_eq!((summary.cases, summary.runs), (CASES, CASES));
    for (parameter, covered_today) in APS_COVERED_TODAY {
        let row = summary.row(Method::Aps, parameter).expect("a row");
        assert_eq!(row.cases, CASES, "{parameter}");
        assert_eq!(
            row.failed + row.not_reported + row.not_determinable + row.determinable,
            row.cases
        );
        assert!(row.covered >= covered_today, "{parameter}: {row:?}");
    }
    for (parameter, bound) in APS_COVERAGE_BOUNDS {
        let row = summary.row(Method::Aps, parameter).expect("a row");
        assert!(
            row.determinable >= 4 && row.covered as f64 >= bound * row.determinable as f64,
            "{parameter}: {row:?}"
        );
    }
    let breakdown = &summary.breakdowns[0];
    assert_eq!(breakdown.parameters, ["ct_on", "ct_off", "ct_sigma"]);
    assert!(
        breakdown
            .rows
            .iter()
            .any(|r| r.group.starts_with("family "))
    );
    let markdown = summary.to_markdown();
    for line in [
        "| aps | Cp |",
        "| aps | Cn |",
        "| aps | ct_sigma |",
        "## Worst misses",
    ] {
        assert!(markdown.contains(line), "{line} missing:\n{markdown}");
    }
    eprintln!("{markdown}");
}

/// `estimate eppps` with frames on two draws of the study's first 100 whose line scans miss
/// the truth by about 40 % (draw 23: a natural image at 15 px/s with a 9.7 Hz photoreceptor,
/// both read 1.4x high; draw 46: multi-object at 18 px/s with bandwidth, refractory period
/// and leak, both read 0.72x low). With the 10 % method systematic of six clean cases their
/// intervals missed by 1.5-1.9 half-widths; the systematic measured on 262 polarity-cases
/// of random draws (37 %) holds them. On draw 23 the events now show the photoreceptor (10
/// Hz at white): the scans through it read 0.562 / 0.567 for 0.636 / 0.634, and the ideal
/// scans' 0.907 / 0.891 stay inside the interval.
#[test]
fn eppps_intervals_hold_the_truth_on_draws_its_scans_miss() {
    let work = tempfile::tempdir().unwrap();
    for (seed, read_high) in [(23, true), (46, false)] {
        let record = run_draw(Method::Eppps, seed, work.path());
        let slow = &json_output(&record)["photoreceptor_slow"];
        assert_eq!(slow.is_null(), !read_high, "{slow}");
        for (key, side) in [("ct_on", "on"), ("ct_off", "off")] {
            let (value, true_value) = covered_value(&record, key);
            // the ideal scans' reading, where the low-passed one replaced it
            let ideal = slow["ideal"][side]["value"].as_f64().unwrap_or(value);
            let error = (ideal / true_value).ln();
            assert!(
                error.abs() > 0.25 && (error > 0.0) == read_high,
                "draw {seed} {key}: {ideal} for {true_value}, the scans' miss this test is about"
            );
            if read_high {
                assert!((value / true_value).ln().abs() < 0.25, "{key}: {value}");
            }
        }
    }
}

/// Draw 3016 (a rotating texture at 402 deg/s, 96 x 72, shot noise at 2.9 Hz and a small
/// mismatch of 0.021): `fit` panicked in the mismatch search. A model whose pixels in a
/// tile all fired equally often has a count dispersion of 0, the ratio of the recording's
/// to it was infinite, and Brent's line search stepped from the infinite distance to a NaN
/// spread (`Normal::new` refused it). The dispersion ratio now has a floor (a tenth of
/// Poisson's index) and a search refuses a distance that is not finite. Measured after
/// the fix: ON 0.860 [0.581, 1.274] for 0.883, OFF 0.599 [0.284, 1.262] for 0.567, shot
/// noise 2.46 Hz [1.84, 3.28] for 2.89.
#[test]
fn fit_of_a_regular_rotation_completes_and_holds_the_truth() {
    let work = tempfile::tempdir().unwrap();
    let record = run_draw(Method::Fit, 3016, work.path());
    for key in ["ct_on", "ct_off", "shot_noise_rate_hz"] {
        covered_value(&record, key);
    }
}

/// Draw 7035: a texture moving at 521 px/s, its frames 7.5 px apart on average and the
/// optical flow following 5 of its 69 intervals. `estimate aps` refuses such frames; the
/// fit re-simulated them while its fit run kept three followed intervals, and both
/// intervals missed (ON 0.186 [0.089, 0.391] for 0.695, OFF 0.150 [0.069, 0.324] for
/// 0.408). Where the motion outruns the fit run's frames the fit now reads the events
/// alone, and says so (measured: ON 0.458 [0.052, 4.07], OFF 0.320 [0.087, 1.18]).
#[test]
fn fit_reads_the_events_alone_where_the_motion_outruns_the_frames() {
    let work = tempfile::tempdir().unwrap();
    let record = run_draw(Method::Fit, 7035, work.path());
    for key in ["ct_on", "ct_off"] {
        covered_value(&record, key);
    }
    let output = json_output(&record);
    let said = output["assumptions"].as_array().unwrap().iter().any(|a| {
        a.as_str()
            .unwrap()
            .contains("the motion outruns the fit run's frames")
    });
    assert!(said, "{}", output["assumptions"]);
}

/// Draws 3065 and 3073: bright rotations whose frames are 53 % and 47 % clipped at white.
/// `estimate aps` refused them ("no usable frame interval") while a frame could have at
/// most 30 % of its pixels clipped, although clipped pixels are left out one by one. With
/// frames refused only beyond 80 % clipped, both answer and hold the truth (measured: ON
/// 0.336 [0.246, 0.427] for 0.351, OFF 0.462 [0.333, 0.591] for 0.466; ON 0.589
/// [0.403, 0.774] for 0.633, OFF 0.180 [0.100, 0.260] for 0.164).
#[test]
fn aps_on_frames_half_clipped_at_white_holds_the_truth() {
    let work = tempfile::tempdir().unwrap();
    for seed in [3065, 3073] {
        let case = CaseSpec::draw(seed);
        let record = run_aps(&case, &work.path().join(&case.id));
        for key in ["ct_on", "ct_off"] {
            covered_value(&record, key);
        }
    }
}

/// Draw 4046: a slow rotation (15 px/s) with shot noise at 1.7 Hz a pixel and thresholds
/// of 0.14 (ON) and 0.77 (OFF). Simulated without its noise the scene makes no OFF event at
/// all: every OFF event is noise. The support window (100 ms) is longer than the noise's
/// spacing among 8 neighbours, so 93 % of noise events find support by chance, and eppps
/// read OFF 0.08 [0.03, 0.20] for 0.77 counting them as signal. The unsupported events,
/// divided by the chance a noise event goes unsupported, now bound the noise: OFF is not
/// determinable (the noise may be every OFF event) and ON still holds the truth.
#[test]
fn eppps_says_when_the_noise_may_be_every_event_of_a_polarity() {
    let work = tempfile::tempdir().unwrap();
    let record = run_draw(Method::Eppps, 4046, work.path());
    covered_value(&record, "ct_on");
    let Reported::NotDeterminable { why } = &record.reported["ct_off"] else {
        panic!("OFF: {:?}", record.reported["ct_off"]);
    };
    assert!(why.contains("the noise may be every OFF event"), "{why}");
}

/// Draw 11002 of the peers' study: DVS-Voltmeter, thresholds 0.79, a natural-image
/// multi-object scene at 21 px/s whose pixels all start from a reset, so that its leak
/// makes nearly every pixel fire one ON event whatever the scene does (97 % of the 44,470
/// events are ON; 0.81 ON events per pixel-second where the frames do not change, 0.84
/// where they change most). Every leak event finds a neighbour's within the support window,
/// and eppps with frames read ON 0.106 [0.051, 0.219] for 0.79. The pixels whose frames
/// show a still scene now measure the background and it sets ON's noise bracket (measured:
/// ON 0.380 [0.134, 1.080], OFF 1.19 [0.50, 2.88], both holding the truth).
#[test]
fn eppps_measures_the_background_where_the_frames_are_still() {
    let work = tempfile::tempdir().unwrap();
    let record = run_peer_draw(Method::Eppps, 11002, work.path());
    assert_eq!(record.case.generator, ctcal::coverage::Generator::Voltmeter);
    covered_value(&record, "ct_on");
    covered_value(&record, "ct_off");
    let output = json_output(&record);
    let still = &output["estimators"][0]["details"]["still_pixels"];
    assert_eq!(still["decides_noise"]["on"], true, "{still}");
    assert!(
        still["events"]["on"].as_f64().unwrap() > 10_000.0,
        "{still}"
    );
}

/// Draw 13010 of the peers' third fresh study: DVS-Voltmeter, thresholds 0.469, a
/// multi-object scene at 10 px/s whose background grows with the light (2.7 ON events per
/// pixel-second at 40-80 DN, 11.1 at 200-255 DN, still pixels and moving ones alike; 127,291
/// of its 127,304 events are ON). Its still pixels, pooled to one rate (5.5), left a fifth of
/// the ON events to the scene, and eppps read ON 0.102 [0.038, 0.274]. Read at each counted
/// pixel's brightness, the background may be every ON event: ON is not determinable.
#[test]
fn eppps_reads_the_background_at_each_pixels_brightness() {
    let work = tempfile::tempdir().unwrap();
    let record = run_peer_draw(Method::Eppps, 13010, work.path());
    assert_eq!(record.case.generator, ctcal::coverage::Generator::Voltmeter);
    let Reported::NotDeterminable { why } = &record.reported["ct_on"] else {
        panic!("ON: {:?}", record.reported["ct_on"]);
    };
    assert!(why.contains("background may be every ON event"), "{why}");
    let output = json_output(&record);
    let ranges = output["estimators"][0]["details"]["still_pixels"]["by_brightness"]
        .as_array()
        .expect("still pixels per brightness")
        .clone();
    let rate = |r: &serde_json::Value| {
        r["events"][0].as_f64().unwrap() / r["exposure_s"].as_f64().unwrap()
    };
    let (dimmest, brightest) = (rate(&ranges[0]), rate(&ranges[ranges.len() - 1]));
    assert!(
        brightest > 2.0 * dimmest,
        "{dimmest} {brightest}: {ranges:?}"
    );
}

/// Draw 12035 of the peers' second fresh study: DVS-Voltmeter, a rotation whose leak makes
/// 97 % of the events ON (thresholds 0.561 both). eppps without frames read OFF 2.40
/// [0.88, 6.56]: the few OFF events were taken for a high Cn. Without frames an imbalance
/// may be a leak's or the scene's, so each polarity's interval also holds the threshold
/// both would share (`estimate::eppps::balance`), and the assumptions say so.
#[test]
fn eppps_without_frames_carries_an_imbalance_it_cannot_attribute() {
    let work = tempfile::tempdir().unwrap();
    let record = run_peer_draw(Method::EpppsEvents, 12035, work.path());
    assert_eq!(record.case.generator, ctcal::coverage::Generator::Voltmeter);
    let truth = record.truth.as_ref().unwrap();
    assert!(truth.on_events as f64 > 0.95 * truth.events as f64);
    covered_value(&record, "ct_off");
    let output = json_output(&record);
    assert!(
        crate::common::strings(&output["assumptions"])
            .iter()
            .any(|a| a.starts_with("ON/OFF balance") && a.contains("OFF [")),
        "{}",
        output["assumptions"]
    );
}

/// Draw 4078: a natural image at 11 DN mean, 723 events, v2e's lin-log response. The pure
/// `ln(DN + b)` (b = 37.5 DN) scattered 0.97 times as much and was taken, reading ON 0.067
/// [0.034, 0.100] for the true 0.442 (OFF 0.132 for 0.818); lin-log gives 0.46 and 1.02.
/// The pixels leave the score ratio at 0.87 .. 1.08, so the other response's thresholds are
/// carried into the intervals (`estimate::timing::response`).
#[test]
fn aps_carries_a_log_response_the_events_cannot_rule_out() {
    let work = tempfile::tempdir().unwrap();
    let record = run_draw(Method::Aps, 4078, work.path());
    let (on, _) = covered_value(&record, "ct_on");
    covered_value(&record, "ct_off");
    let output = json_output(&record);
    let other = &output["log_response_other"];
    assert_eq!(other["response"], "v2e", "{other}");
    let ratio = other["ct_on"].as_f64().unwrap() / other["chosen_ct_on"].as_f64().unwrap();
    assert!(ratio > 3.0 && on < 0.2, "{other}");
    // lin-log over the pure log chosen: the pure log had to scatter 0.98 times lin-log
    let [lo, hi] = [0, 1].map(|k| other["score_ratio_ci95"][k].as_f64().unwrap());
    assert!(lo < 1.0 / 0.98 && hi > 1.0 / 0.98, "{other}");
    assert!(
        crate::common::strings(&output["assumptions"])
            .iter()
            .any(|a| a.starts_with("log response not determined: v2e's lin-log")),
        "{}",
        output["assumptions"]
    );
}

/// Draw 12036 of the peers' second fresh study: ctcal's simulator, Cp 0.116 against Cn 0.656
/// and a leak of 0.041 Hz. Without frames the isolated events' ON excess read as a leak of
/// 1.02 [0.87, 1.20] Hz: the scene's own unsupported events fire ON 7.6 times as often as OFF
/// here, and may be the excess as well as leak. The interval now reaches down to the least
/// leak the counts allow (`fit::events_only::candidates::SceneShare`).
#[test]
fn fit_without_frames_holds_a_leak_the_scene_s_balance_may_explain() {
    let work = tempfile::tempdir().unwrap();
    let record = run_peer_draw(Method::FitEvents, 12036, work.path());
    assert_eq!(record.case.generator, ctcal::coverage::Generator::Ctcal);
    covered_value(&record, "leak_rate_hz");
    let output = json_output(&record);
    let why = output["why"]["leak_rate_hz"].as_str().unwrap_or_default();
    assert!(
        why.starts_with("the scene fires OFF/ON = "),
        "{}",
        output["why"]
    );
}

/// Draw 11005 of the peers' first fresh study: ctcal's simulator, a checkerboard at 31 DN
/// whose photoreceptor cuts off at 6.8 Hz at white, 1.2 Hz at its brightness, with edges
/// every 80 ms. The pixels average the scene and fire a tenth of what the frames' change
/// asks for, and the events come frames late: aps read ON 1.95 [0.57, 3.33] for the true
/// 0.315, its interval missing. The events now show the low-pass
/// (`estimate::photoreceptor`), the re-simulation with it finds the lower thresholds,
/// and the intervals reach them.
#[test]
fn aps_reaches_the_thresholds_of_a_photoreceptor_slower_than_the_scene() {
    let work = tempfile::tempdir().unwrap();
    let record = run_peer_draw(Method::Aps, 11005, work.path());
    assert_eq!(record.case.generator, ctcal::coverage::Generator::Ctcal);
    covered_value(&record, "ct_on");
    covered_value(&record, "ct_off");
    let slow = &json_output(&record)["photoreceptor_slow"];
    let cutoff = slow["check"]["cutoff_hz"].as_f64().unwrap();
    // the truth 6.77 Hz at white, on a grid of 1, 2, 3, 5, 7, 10, 20 ... Hz
    assert!((3.0..=10.0).contains(&cutoff), "{slow}");
    assert!(
        slow["check"]["significance"].as_f64().unwrap() > 10.0,
        "{slow}"
    );
    let on = slow["resimulated_thresholds"][0].as_f64().unwrap();
    assert!(on < 0.6, "{slow}");
}

/// The same draw through `estimate eppps`: its ideal scans along the frames read ON = OFF
/// 1.53 for the true 0.315 / 0.220 (the pixels fire a tenth of the frames' change), and
/// both intervals, [0.738, 3.18], missed. The scans through the low-pass the events show
/// (7 Hz at white) read 0.386 [0.186, 0.798] and 0.186 [0.090, 0.386]; those are now the
/// values, in intervals that hold the ideal scans' too: [0.186, 3.18] and [0.090, 3.18].
#[test]
fn eppps_reads_the_thresholds_of_a_photoreceptor_slower_than_the_scene() {
    let work = tempfile::tempdir().unwrap();
    let record = run_peer_draw(Method::Eppps, 11005, work.path());
    let slow = &json_output(&record)["photoreceptor_slow"];
    let cutoff = slow["check"]["cutoff_hz"].as_f64().unwrap();
    assert!((3.0..=10.0).contains(&cutoff), "{slow}");
    for (key, side) in [("ct_on", "on"), ("ct_off", "off")] {
        let (value, truth) = covered_value(&record, key);
        assert!(
            (value / truth).ln().abs() < 0.3,
            "{key} {value} for {truth}"
        );
        assert_eq!(value, slow["scanned"][side]["value"].as_f64().unwrap());
        let ideal = slow["ideal"][side]["value"].as_f64().unwrap();
        assert!(ideal > 3.0 * truth, "{key}: the ideal scans read {ideal}");
    }
}
