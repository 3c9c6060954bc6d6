//! `ctcal convert` round trips: every shared input to an IJRR folder and to event_utils HDF5
//! and back, every event identical; frames survive too.

use crate::common::*;
use std::path::Path;

fn convert(input: &Path, out: &Path, to: &str) {
    ctcal()
        .args([
            "convert",
            input.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--to",
            to,
        ])
        .assert()
        .success();
}

#[test]
fn every_shared_input_round_trips_through_text_and_hdf5() {
    let data = shared_data();
    // every recording of the shared data: real/, h5/ and every oracle case
    let mut inputs = Vec::new();
    for folder in ["real", "h5", "oracle"] {
        for entry in std::fs::read_dir(data.join(folder)).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if name == "licences" || name.ends_with(".json") {
                continue;
            }
            inputs.push(path);
        }
    }
    inputs.sort();
    assert!(inputs.len() >= 26, "{} inputs", inputs.len());
    let dir = tempfile::tempdir().unwrap();
    for input in inputs {
        let original = read_events(&input);
        let text = dir.path().join("as_text");
        let h5 = dir.path().join("as.h5");
        let back_text = dir.path().join("back_text");
        let back_h5 = dir.path().join("back.h5");
        convert(&input, &text, "ijrr");
        convert(&input, &h5, "h5");
        convert(&h5, &back_text, "ijrr");
        convert(&text, &back_h5, "h5");
        for path in [&text, &h5, &back_text, &back_h5] {
            let events = read_events(path);
            assert!(
                events == original,
                "{} -> {}: events differ",
                input.display(),
                path.file_name().unwrap().to_string_lossy()
            );
        }
    }
}

#[test]
fn frames_and_sensor_survive_conversion() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("davis.h5");
    convert(&real("davis346_faery.aedat4"), &out, "h5");
    let s = json(&["stats", out.to_str().unwrap()]);
    assert_eq!(
        (s["width"].as_u64(), s["height"].as_u64()),
        (Some(346), Some(260))
    );
    assert_eq!(s["frames"]["count"].as_u64(), Some(59));
    let text = dir.path().join("davis_text");
    convert(&out, &text, "ijrr");
    let original = ctcal::Recording::open(&real("davis346_faery.aedat4"), &Default::default())
        .unwrap()
        .frames()
        .unwrap();
    let copied = ctcal::Recording::open(&text, &Default::default())
        .unwrap()
        .frames()
        .unwrap();
    assert_eq!(copied.len(), original.len());
    for (a, b) in original.iter().zip(&copied) {
        assert_eq!((a.t, &a.pixels), (b.t, &b.pixels));
    }
}

#[test]
fn a_failed_conversion_leaves_nothing_under_the_output_name() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("events.txt");
    std::fs::write(&bad, "0.1 1 1 1\n0.2 2 2 1\nnot an event\n").unwrap();
    let out = dir.path().join("out");
    let stderr = bad_input(&[
        "convert",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(stderr.contains("line 3"), "{stderr}");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "only the input remains: {leftovers:?}");
}

/// EVT3 counts time in loops of a 24-bit clock from 0: a recording that starts late (the
/// Gen3 sample at 913.7 s, 54 loops) is written with the loops up to its first event, and
/// reads back with every time as it was (it wrapped to 7.7 s before); a start decoders could
/// only reach through hundreds of millions of words (the DAVIS346 sample, timed from the
/// Unix epoch) is refused with the formats that keep it.
#[test]
fn evt3_keeps_a_late_start_and_refuses_one_it_cannot_count_to() {
    let dir = tempfile::tempdir().unwrap();
    let input = real("gen3_faery_evt2.raw");
    let out = dir.path().join("late.raw");
    convert(&input, &out, "evt3");
    let original = read_events(&input);
    assert!(original.t[0] > 1 << 24, "{}", original.t[0]);
    assert!(read_events(&out) == original, "times changed");
    let refused = dir.path().join("epoch.raw");
    let e = bad_input(&[
        "convert",
        real("davis346_faery.aedat4").to_str().unwrap(),
        "--out",
        refused.to_str().unwrap(),
    ]);
    assert!(
        e.contains("counts time from 0") && e.contains("write HDF5 or IJRR"),
        "{e}"
    );
    assert!(!refused.exists());
}
