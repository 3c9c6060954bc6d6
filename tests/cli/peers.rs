//! The peer-simulator emulators (`ctcal::sim::peers`): complete IJRR test cases from a
//! scene, and the side-by-side input on which their counts were compared with the real
//! DVS-Voltmeter and IEBCS Python code (numbers in the module docs).

use crate::common::*;
use ctcal::io::FrameList;
use ctcal::sim::peers::{Peer, esim, iebcs, voltmeter, write_case};
use ctcal::sim::pixel::Transition;
use ctcal::sim::scene::{ApsSpec, SceneSpec};
use ctcal::sim::source::MemoryFrames;
use ctcal::{EventChunk, Frame};
use std::path::Path;

/// The side-by-side input: 40 frames (1 kHz, 0..39 ms) of a 64x48 texture moving at
/// (300, 120) px/s, with APS frames at the render rate and no exposure, so that `images/`
/// holds exactly the 8-bit frames the peers were given.
fn side_by_side_scene() -> SceneSpec {
    let mut scene = SceneSpec::moving_texture(64, 48, 0.039, 1000.0);
    let texture = scene.texture.as_mut().unwrap();
    (texture.vx_px_s, texture.vy_px_s) = (300.0, 120.0);
    scene.aps = Some(ApsSpec {
        rate_hz: 1000.0,
        exposure_s: 0.0,
    });
    scene
}

fn peers() -> [Peer; 3] {
    [
        Peer::Esim(esim::Params {
            contrast_threshold_pos: 0.3,
            contrast_threshold_neg: 0.3,
            ..esim::Params::default()
        }),
        Peer::Voltmeter(voltmeter::Params::dvs346()),
        Peer::Iebcs(iebcs::Params::default()),
    ]
}

/// The frames of an IJRR folder's `images.txt`.
fn frames(dir: &Path) -> Vec<Frame> {
    let list = FrameList::read(&dir.join("images.txt")).unwrap();
    (0..list.len()).map(|i| list.load(i).unwrap()).collect()
}

fn run(peer: &Peer, frames: &[Frame], seed: u64) -> EventChunk {
    let mut source = MemoryFrames::new(frames, Transition::Linear).unwrap();
    peer.simulate(&mut source, seed).unwrap()
}

#[test]
fn write_case_makes_a_complete_ijrr_folder_with_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let scene = side_by_side_scene();
    for (k, peer) in peers().iter().enumerate() {
        let out = dir.path().join(format!("case{k}"));
        let truth = write_case(&out, &scene, peer, 5).unwrap();
        let events = read_events(&out);
        assert_eq!(events.len() as u64, truth.events);
        assert!(truth.events > 1000, "{peer:?}: {}", truth.events);
        assert!(events.is_time_sorted());
        assert_eq!(truth.aps_frames, 40);
        let images = frames(&out);
        assert_eq!(images.len(), 40);
        assert_eq!((images[0].t, images[39].t), (0, 39_000));
        let params: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("params.json")).unwrap())
                .unwrap();
        for key in ["ct_on", "ct_off", "ct_sigma", "log_offset_dn", "refractory"] {
            assert!(params.get(key).is_some(), "{key} missing");
        }
        for key in ["leak", "noise", "cutoff", "peer", "scene"] {
            assert!(params.get(key).is_some(), "{key} missing");
        }
        assert_eq!(params["events"], truth.events);
        // the same seed gives the same file; the events are those of the frames' source
        let again = dir.path().join(format!("again{k}"));
        write_case(&again, &scene, peer, 5).unwrap();
        assert_eq!(
            std::fs::read(out.join("events.txt")).unwrap(),
            std::fs::read(again.join("events.txt")).unwrap()
        );
    }
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("case1/params.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["simulator"], "DVS-Voltmeter");
    assert_eq!(json["log_offset_dn"], 20.0);
    assert_eq!(json["peer"]["params"]["k"][1], 20.0);
}

#[test]
fn the_written_frames_reproduce_the_scene_simulation() {
    // the peers run on the 8-bit frames of images/ give nearly the scene's own counts (the
    // scene is simulated from unrounded DN)
    let dir = tempfile::tempdir().unwrap();
    let peer = &peers()[0];
    let truth = write_case(dir.path(), &side_by_side_scene(), peer, 1).unwrap();
    let from_frames = run(peer, &frames(dir.path()), 1).len() as f64;
    assert!(
        (from_frames / truth.events as f64 - 1.0).abs() < 0.05,
        "{from_frames} vs {}",
        truth.events
    );
}

/// The side-by-side frames darkened to 15 % (`DN * 15 / 100`, integer), where
/// DVS-Voltmeter's diffusion and IEBCS's slower photoreceptor matter more.
fn dark(frames: &[Frame]) -> Vec<Frame> {
    frames
        .iter()
        .map(|f| Frame {
            pixels: f
                .pixels
                .iter()
                .map(|&p| ((p as u32 * 15) / 100) as u8)
                .collect(),
            ..f.clone()
        })
        .collect()
}

/// The mean event count of `peer` on `frames` over seeds 0..4.
fn mean_count(peer: &Peer, frames: &[Frame]) -> f64 {
    (0..4)
        .map(|seed| run(peer, frames, seed).len() as f64)
        .sum::<f64>()
        / 4.0
}

#[test]
fn counts_agree_with_the_real_dvs_voltmeter_and_iebcs() {
    // The real peers' mean counts over 20 seeds on these frames (their Python code at the
    // commits cited in the modules, run beside ctcal: DVS-Voltmeter with torch 2.15, IEBCS
    // with numpy, NOISE_FREQ noise, `update(E, 1000)` per frame), with their seed-to-seed
    // standard deviations. ctcal's means over 20 seeds were 6449.1, 1728.4, 2730.7, 3034.8
    // and 3500.9; here 4 seeds must land within the tolerance.
    let dir = tempfile::tempdir().unwrap();
    write_case(dir.path(), &side_by_side_scene(), &peers()[0], 1).unwrap();
    let bright = frames(dir.path());
    let dark = dark(&bright);
    let noisy = Peer::Iebcs(iebcs::Params {
        th_noise: 0.05,
        jit_us: 50.0,
        ref_us: 500,
        bgnp_hz: 5.0,
        bgnn_hz: 2.0,
        ..iebcs::Params::default()
    });
    let [_, volt, iebcs] = peers();
    let cases: [(&str, &Peer, &[Frame], f64, f64); 5] = [
        ("DVS-Voltmeter", &volt, &bright, 6450.0, 2.8),
        ("DVS-Voltmeter dark", &volt, &dark, 1728.5, 1.3),
        ("IEBCS", &iebcs, &bright, 2732.4, 7.9),
        ("IEBCS dark", &iebcs, &dark, 3029.0, 16.1),
        ("IEBCS noisy", &noisy, &bright, 3514.1, 23.9),
    ];
    for (name, peer, frames, real, sd) in cases {
        let ours = mean_count(peer, frames);
        // 4 standard errors of the difference of the two means, with ctcal's spread taken
        // as the real one's
        let tolerance = 4.0 * sd * (1.0 / 20.0 + 1.0 / 4.0f64).sqrt();
        assert!(
            (ours - real).abs() < tolerance,
            "{name}: ctcal {ours} vs real {real} (tolerance {tolerance:.1})"
        );
    }
}

#[test]
fn esim_without_threshold_noise_matches_ctcals_ideal_pixel_in_eps_mode() {
    // ESIM's equations (crossings interpolated linearly in ln(DN/255 + 1e-3) between
    // frames, every crossing fired) are those of ctcal's ideal pixel with the eps log
    // response, which is checked here; with its default threshold noise ESIM loses events
    let dir = tempfile::tempdir().unwrap();
    write_case(dir.path(), &side_by_side_scene(), &peers()[0], 1).unwrap();
    let frames = frames(dir.path());
    let esim = noiseless_esim(0.3, 0.3);
    let esim_events = run(&esim, &frames, 1);
    // peers()[0]: the same with ESIM's default threshold noise
    let stranded = run(&peers()[0], &frames, 1);
    let params = ctcal::sim::PixelParams::from_toml(
        "ct_on = 0.3\nct_off = 0.3\nlog_response = \"eps\"\nlog_eps = 0.001\n",
        "test",
    )
    .unwrap();
    let mut source = MemoryFrames::new(&frames, Transition::Linear).unwrap();
    let mut ideal = EventChunk::default();
    ctcal::sim::run::<ctcal::sim::SimError>(
        &mut source,
        &params,
        Default::default(),
        |chunk| {
            ideal.extend_from(chunk);
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    // per pixel the same event counts (times differ by ESIM's nanosecond truncation
    // against ctcal's rounding), except at ties: 8-bit frames return to the same DN, where
    // ESIM's accumulated f32 crossing can land exactly on the level (`cross <= L_b` fires)
    let counts = |e: &EventChunk| {
        let mut per = vec![0usize; 64 * 48];
        for v in e.iter() {
            per[v.x as usize + 64 * v.y as usize] += 1;
        }
        per
    };
    let (a, b) = (counts(&esim_events), counts(&ideal));
    let same = a.iter().zip(&b).filter(|(x, y)| x == y).count();
    assert!(esim_events.len() > 1000);
    assert!(
        same as f64 > 0.99 * 64.0 * 48.0,
        "{same} pixels of 3072 agree"
    );
    let relative = esim_events.len() as f64 / ideal.len() as f64 - 1.0;
    assert!(
        relative.abs() < 0.01,
        "ESIM {} vs ctcal {}",
        esim_events.len(),
        ideal.len()
    );
    // ESIM's default threshold noise (0.021 per interval) strands pixels: 32 % fewer
    // events on this input
    assert!(
        stranded.len() * 10 < esim_events.len() * 8,
        "{}",
        stranded.len()
    );
}

/// ESIM without its threshold noise (every crossing fired) at thresholds `on` and `off`.
fn noiseless_esim(on: f64, off: f64) -> Peer {
    Peer::Esim(esim::Params {
        contrast_threshold_pos: on,
        contrast_threshold_neg: off,
        contrast_threshold_sigma_pos: 0.0,
        contrast_threshold_sigma_neg: 0.0,
        ..esim::Params::default()
    })
}

/// A moving-texture case: a texture of `canvas_px` (mean `mean_dn`, log contrast
/// `log_std`, 1/f^`beta` spectrum, 1 px blur) moving at `velocity` px/s over a `size`
/// sensor for `duration_s`, rendered at `render_hz`, with APS frames at `aps_hz` exposed
/// `exposure_s`.
struct TextureCase {
    size: (usize, usize),
    duration_s: f64,
    render_hz: f64,
    seed: u64,
    canvas_px: usize,
    mean_dn: f64,
    log_std: f64,
    beta: f64,
    velocity: (f64, f64),
    aps_hz: f64,
    exposure_s: f64,
}

impl TextureCase {
    fn scene(&self) -> SceneSpec {
        let mut scene =
            SceneSpec::moving_texture(self.size.0, self.size.1, self.duration_s, self.render_hz);
        scene.seed = self.seed;
        let texture = scene.texture.as_mut().unwrap();
        texture.texture = ctcal::sim::scene::canvas::TextureParams {
            canvas_px: self.canvas_px,
            mean_dn: self.mean_dn,
            log_std: self.log_std,
            min_dn: 0.5,
            max_dn: 255.0,
            spectrum_beta: self.beta,
            blur_px: 1.0,
        };
        (texture.vx_px_s, texture.vy_px_s) = self.velocity;
        scene.aps = Some(ApsSpec {
            rate_hz: self.aps_hz,
            exposure_s: self.exposure_s,
        });
        scene
    }
}

/// `e`'s reading of `key`, after checking that its 95 % interval holds `truth` (an open
/// side only where `open_allowed`; otherwise both ends must be numbers).
fn reading_holding(e: &serde_json::Value, key: &str, truth: f64, open_allowed: bool) -> f64 {
    let value = e[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key}: {}", e["why"]));
    let ci = &e[format!("{key}_ci95")];
    let end = |i: usize, open: f64| match ci[i].as_f64() {
        Some(v) => v,
        None if open_allowed => open,
        None => panic!("{key}: a closed interval expected, got {ci}"),
    };
    let (lo, hi) = (end(0, 0.0), end(1, f64::INFINITY));
    assert!(
        lo <= truth && truth <= hi,
        "{key} [{lo}, {hi}] misses {truth}"
    );
    value
}

/// A dim texture (mean 12 DN, log contrast 0.6, 1/f^0.7 spectrum; none of the oracle
/// cases' texture), 96x72 for 0.5 s, rendered at 400 Hz with APS frames at 50 Hz.
fn dim_scene() -> SceneSpec {
    TextureCase {
        size: (96, 72),
        duration_s: 0.5,
        render_hz: 400.0,
        seed: 7,
        canvas_px: 256,
        mean_dn: 12.0,
        log_std: 0.6,
        beta: 0.7,
        velocity: (70.0, -30.0),
        aps_hz: 50.0,
        exposure_s: 0.0,
    }
    .scene()
}

#[test]
fn aps_reads_a_dim_esim_recording_through_the_response_the_timing_chose() {
    // ESIM reads ln(DN / 255 + 1e-3): at 12 DN a pure log, not v2e's lin-log (linear below
    // 20 DN). The event timing chooses the pure ln(DN + b); the re-simulation and the
    // self-calibration simulated the lin-log and matched the counts at no threshold
    // (draw 14015 without its threshold noise: not determinable, the timing's value
    // pushed from 0.109 / 0.245 to 0.162 / 0.362 for 0.114 / 0.237)
    let dir = tempfile::tempdir().unwrap();
    let (on, off) = (0.15, 0.25);
    write_case(dir.path(), &dim_scene(), &noiseless_esim(on, off), 3).unwrap();
    let e = json(&["estimate", "aps", dir.path().to_str().unwrap()]);
    let chosen = strings(&e["assumptions"])
        .iter()
        .any(|a| a.contains("a pure ln(DN + b) explains"));
    assert!(chosen, "{}", e["assumptions"]);
    for (key, truth) in [("ct_on", on), ("ct_off", off)] {
        let value = reading_holding(&e, key, truth, false);
        assert!(
            (value / truth - 1.0).abs() < 0.1,
            "{key} {value} vs {truth}"
        );
    }
    assert_eq!(estimator_names(&e), ["event_timing", "resimulation"]);
}

#[test]
fn eppps_reads_the_contrast_of_frames_whose_flow_the_motion_outruns() {
    // a texture (mean 60 DN, log contrast 0.5, 1/f^1.2) at 450 px/s with frames at 15 Hz:
    // 30 px between frames, beyond what the optical flow follows (12 px), so the travel
    // comes from the events; the frames' images still show the scene's contrast and stand
    // in for the natural-image prior (which read coverage draws 15004 and 15010, smooth
    // textures, 5-10 times high)
    let scene = TextureCase {
        size: (128, 96),
        duration_s: 0.6,
        render_hz: 2000.0,
        seed: 11,
        canvas_px: 512,
        mean_dn: 60.0,
        log_std: 0.5,
        beta: 1.2,
        velocity: (-440.0, 95.0),
        aps_hz: 15.0,
        exposure_s: 0.002,
    }
    .scene();
    let (on, off) = (0.25, 0.35);
    let dir = tempfile::tempdir().unwrap();
    write_case(dir.path(), &scene, &noiseless_esim(on, off), 5).unwrap();
    let e = json(&["estimate", "eppps", dir.path().to_str().unwrap()]);
    let assumptions = strings(&e["assumptions"]);
    let said = |words: &str| assumptions.iter().any(|a| a.contains(words));
    assert!(
        said("of the recording's own frames"),
        "{}",
        e["assumptions"]
    );
    assert!(!said("natural images (calib/priors/natural)"));
    for (key, truth) in [("ct_on", on), ("ct_off", off)] {
        let value = reading_holding(&e, key, truth, true);
        assert!(
            (value / truth).ln().abs() < 2f64.ln(),
            "{key} {value} vs {truth}"
        );
    }
}
