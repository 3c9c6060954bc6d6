//! Bad input: each case gets exit code 2 and a message naming the file, the place and a fix.

use crate::common::*;
use assert_cmd::Command;
use ctcal::{OpenOptions, Recording};
use std::path::Path;

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path.to_str().unwrap().to_string()
}

fn truncated_copy(dir: &Path, source: &Path, name: &str, keep: usize) -> String {
    let bytes = std::fs::read(source).unwrap();
    write(dir, name, &bytes[..keep])
}

#[test]
fn missing_file() {
    let e = bad_input(&["stats", "/no/such/recording.raw"]);
    assert!(
        e.contains("/no/such/recording.raw") && e.contains("no such file"),
        "{e}"
    );
    assert!(e.contains("fix:"), "{e}");
}

#[test]
fn unknown_format() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "mystery.bin",
        &[0xde, 0xad, 0xbe, 0xef, 0, 1, 2, 3],
    );
    let e = bad_input(&["info", &path]);
    assert!(
        e.contains("mystery.bin") && e.contains("unknown format") && e.contains("--format"),
        "{e}"
    );
}

#[test]
fn truncated_evt3_aedat4_and_dat() {
    let dir = tempfile::tempdir().unwrap();
    let evt3 = truncated_copy(
        dir.path(),
        &real("evk4_faery_evt3.raw"),
        "cut.raw",
        225 + 500_000 + 1,
    );
    let e = bad_input(&["stats", &evt3]);
    assert!(
        e.contains("cut.raw") && e.contains("byte offset 500225") && e.contains("ends inside"),
        "{e}"
    );

    let aedat = truncated_copy(
        dir.path(),
        &real("davis346_faery.aedat4"),
        "cut.aedat4",
        3_000_000,
    );
    let e = bad_input(&["stats", &aedat]);
    assert!(
        e.contains("cut.aedat4") && e.contains("byte offset") && e.contains("cut short"),
        "{e}"
    );

    let dat = truncated_copy(
        dir.path(),
        &real("evk4_faery_gen4.dat"),
        "cut.dat",
        65 + 2 + 8 * 1000 + 3,
    );
    let e = bad_input(&["stats", &dat]);
    assert!(
        e.contains("cut.dat") && e.contains("ends inside an event"),
        "{e}"
    );

    let evt2 = truncated_copy(
        dir.path(),
        &real("gen3_faery_evt2.raw"),
        "cut2.raw",
        166 + 4 * 1000 + 2,
    );
    let e = bad_input(&["stats", &evt2]);
    assert!(
        e.contains("cut2.raw") && e.contains("4-byte EVT2 word"),
        "{e}"
    );
}

#[test]
fn garbage_and_nan_lines_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let garbage = write(
        dir.path(),
        "garbage.txt",
        b"0.1 1 2 1\n0.2 3 4 0\n0.3 hello 4 1\n",
    );
    let e = bad_input(&["stats", &garbage]);
    assert!(
        e.contains("garbage.txt") && e.contains("line 3") && e.contains("hello"),
        "{e}"
    );
    let nan = write(dir.path(), "nan.txt", b"# comment\n0.1 1 2 1\nnan 3 4 0\n");
    let e = bad_input(&["stats", &nan]);
    assert!(e.contains("line 3") && e.contains("finite"), "{e}");
    let polarity = write(dir.path(), "pol.txt", b"0.1 1 2 7\n");
    let e = bad_input(&["stats", &polarity]);
    assert!(e.contains("line 1") && e.contains("polarity"), "{e}");
}

#[test]
fn coordinates_outside_the_sensor() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "events.txt",
        b"240 180\n0.1 10 10 1\n0.2 300 10 1\n",
    );
    let e = bad_input(&["stats", &path]);
    assert!(
        e.contains("line 3")
            && e.contains("x=300")
            && e.contains("240x180")
            && e.contains("--sensor"),
        "{e}"
    );
    // the user's --sensor is enforced too
    let e = bad_input(&[
        "stats",
        real("davis346_faery.aedat4").to_str().unwrap(),
        "--sensor",
        "240x180",
    ]);
    assert!(e.contains("outside the 240x180 sensor"), "{e}");
}

#[test]
fn unsorted_timestamps_are_counted_and_accepted_with_sort() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "events.txt",
        b"0.3 1 1 1\n0.1 2 2 0\n0.2 3 3 1\n0.15 4 4 1\n",
    );
    let e = bad_input(&["stats", &path]);
    assert!(
        e.contains("2 timestamps go backwards") && e.contains("line 2") && e.contains("--sort"),
        "{e}"
    );
    let s = json(&["stats", &path, "--sort", "--sensor", "8x8"]);
    assert_eq!(s["events"], 4);
    assert_eq!(s["t_first_us"], 100_000);
    assert_eq!(s["t_last_us"], 300_000);
}

#[test]
fn empty_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let empty = write(dir.path(), "empty.raw", b"");
    let e = bad_input(&["stats", &empty]);
    assert!(e.contains("empty.raw") && e.contains("no events"), "{e}");
    let comments_only = write(dir.path(), "events.txt", b"# nothing recorded\n");
    let e = bad_input(&["stats", &comments_only, "--format", "ijrr"]);
    assert!(e.contains("no events"), "{e}");
    let header_only = write(dir.path(), "header.raw", b"% evt 3.0\n% geometry 640x480\n");
    let e = bad_input(&["stats", &header_only]);
    assert!(e.contains("no events"), "{e}");
}

#[test]
fn hdf5_with_missing_datasets() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("partial.h5");
    {
        let file = h5_create(&path);
        let events = file.create_group("events").unwrap();
        events
            .new_dataset_builder()
            .with_data(&[0.1f64, 0.2])
            .create("ts")
            .unwrap();
        events
            .new_dataset_builder()
            .with_data(&[1i16, 2])
            .create("xs")
            .unwrap();
    }
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(e.contains("partial.h5") && e.contains("events/ys"), "{e}");
}

#[test]
fn bad_options_are_usage_errors() {
    let input = real("ijrr_slider_depth_50k");
    let e = bad_input(&["stats", input.to_str().unwrap(), "--window", "0"]);
    assert!(e.contains("--window"), "{e}");
    let e = bad_input(&["stats", input.to_str().unwrap(), "--sensor", "big"]);
    assert!(e.contains("WxH"), "{e}");
    let e = bad_input(&["stats", input.to_str().unwrap(), "--start", "5"]);
    assert!(
        e.contains("no events lie in the selected time window"),
        "{e}"
    );
    // a region without events, no time window asked for: the region is named, not a
    // window ("no events lie in the selected time window ()", "widen --start/--end")
    let e = bad_input(&["stats", input.to_str().unwrap(), "--roi", "0,0,1,1"]);
    assert!(
        e.contains("no event lies in the selected pixels (--roi 0,0,1,1)")
            && !e.contains("--start"),
        "{e}"
    );
    // the estimates and the fit said "no motion to measure" or "too few events between
    // frames ... (--start/--end)" of the same empty region
    for command in [&["estimate", "eppps"][..], &["estimate", "aps"], &["fit"]] {
        let mut args = command.to_vec();
        args.extend([input.to_str().unwrap(), "--roi", "0,0,1,1"]);
        let e = bad_input(&args);
        assert!(
            e.contains("no event lies in the selected pixels (region x 0..1, y 0..1")
                && !e.contains("--start")
                && !e.contains("motion"),
            "{command:?}: {e}"
        );
    }
}

/// slider_depth's events rewritten in microseconds, its frames left in seconds: no event
/// lies between its frames. The error named a window the user never chose ("0 s .. -3810.8
/// s", widen --start/--end); it now gives both clocks and the fix.
#[test]
fn frames_and_events_on_different_clocks_are_named_as_such() {
    let source = real("ijrr_slider_depth_50k");
    let dir = tempfile::tempdir().unwrap();
    for name in ["images.txt", "images"] {
        let from = source.join(name);
        if from.is_dir() {
            std::fs::create_dir(dir.path().join(name)).unwrap();
            for entry in std::fs::read_dir(&from).unwrap() {
                let entry = entry.unwrap();
                std::fs::copy(entry.path(), dir.path().join(name).join(entry.file_name())).unwrap();
            }
        } else {
            std::fs::copy(&from, dir.path().join(name)).unwrap();
        }
    }
    let micro: String = std::fs::read_to_string(source.join("events.txt"))
        .unwrap()
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            match f.as_slice() {
                [t, x, y, p] => {
                    let us = (t.parse::<f64>().unwrap() * 1e6).round() as i64;
                    format!("{us} {x} {y} {p}\n")
                }
                _ => format!("{l}\n"),
            }
        })
        .collect();
    std::fs::write(dir.path().join("events.txt"), micro).unwrap();
    let e = bad_input(&["fit", dir.path().to_str().unwrap()]);
    assert!(
        e.contains("no event lies between the first and the last frame")
            && e.contains("not on one clock")
            && !e.contains("--start"),
        "{e}"
    );
}

#[test]
fn hdf5_with_integer_microsecond_times_and_signed_polarity() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("int_times.h5");
    {
        let file = h5_create(&path);
        let events = file.create_group("events").unwrap();
        events
            .new_dataset_builder()
            .with_data(&[1_000i64, 2_500, 7_000])
            .create("ts")
            .unwrap();
        events
            .new_dataset_builder()
            .with_data(&[1u16, 2, 3])
            .create("xs")
            .unwrap();
        events
            .new_dataset_builder()
            .with_data(&[4u16, 5, 6])
            .create("ys")
            .unwrap();
        events
            .new_dataset_builder()
            .with_data(&[1i8, -1, 1])
            .create("ps")
            .unwrap();
    }
    let s = json(&["stats", path.to_str().unwrap(), "--sensor", "8x8"]);
    assert_eq!(
        (s["t_first_us"].as_i64(), s["t_last_us"].as_i64()),
        (Some(1_000), Some(7_000))
    );
    assert_eq!(
        (s["events"].as_u64(), s["on_events"].as_u64()),
        (Some(3), Some(2))
    );
}

#[test]
fn config_refuses_fit_values_no_camera_has_naming_their_json_path() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.cfg");
    let out = out.to_str().unwrap();
    let valid = r#""ct_on": 0.3, "ct_off": 0.3"#;
    let cases = [
        (
            "huge.json",
            r#"{"params": {"ct_on": 1e308, "ct_off": 0.3}}"#.to_string(),
            "`params.ct_on` is 1e308",
        ),
        (
            "list.json",
            r#"{"params": [0.3, 0.3]}"#.to_string(),
            "`params` is a list",
        ),
        (
            "exposure.json",
            format!(r#"{{"params": {{{valid}}}, "frame_exposure_us": -5}}"#),
            "`frame_exposure_us` is -5",
        ),
        (
            "text.json",
            r#"{"params": {"ct_on": "0.3", "ct_off": 0.3}}"#.to_string(),
            "`params.ct_on` is the string \"0.3\"",
        ),
        (
            "display.json",
            format!(
                r#"{{"params": {{{valid}, "display": {{"refresh_hz": 1e9, "gamma": 2.0, "black_level": 0.0, "white_dn": 200.0}}}}}}"#
            ),
            "`params.display.refresh_hz` is 1e9",
        ),
        (
            "negative.json",
            format!(r#"{{"params": {{{valid}, "leak_rate_hz": -1.0}}}}"#),
            "`params.leak_rate_hz` is -1",
        ),
    ];
    for (name, text, expected) in cases {
        let fit = write(dir.path(), name, text.as_bytes());
        for format in ["esim", "esim-generator", "v2e", "ctcal"] {
            let e = bad_input(&["config", &fit, "--format", format, "--out", out]);
            assert!(
                e.contains(name) && e.contains(expected) && e.contains("fix:"),
                "{name} {format}: {e}"
            );
            assert!(
                !Path::new(out).exists(),
                "{name} {format}: a config written"
            );
        }
    }
    // in a report folder, the path goes through the sequence
    let report = dir.path().join("report");
    std::fs::create_dir(&report).unwrap();
    std::fs::write(
        report.join("results.json"),
        format!(
            r#"{{"ctcal_version": "0.1.0", "sequences": [{{"name": "a", "fit": {{"params": {{{valid}}}}}}}, {{"name": "b", "fit": {{"params": {{"ct_on": 0.3, "ct_off": 1e308}}}}}}]}}"#
        ),
    )
    .unwrap();
    let e = bad_input(&[
        "config",
        report.to_str().unwrap(),
        "--format",
        "esim",
        "--out",
        out,
    ]);
    assert!(
        e.contains("results.json") && e.contains("`sequences[1].fit.params.ct_off` is 1e308"),
        "{e}"
    );
    assert!(!Path::new(out).exists());
    // an ordinary fit still configures
    let fit = write(
        dir.path(),
        "ok.json",
        format!(r#"{{"params": {{{valid}}}, "frame_exposure_us": 2000}}"#).as_bytes(),
    );
    ctcal()
        .args(["config", &fit, "--format", "esim", "--out", out])
        .assert()
        .success();
    assert!(
        std::fs::read_to_string(out)
            .unwrap()
            .contains("--exposure_time_ms=2")
    );
}

/// `real/evk4_faery_evt3.raw` cut after its header and `keep` bytes of events (a whole
/// number of EVT3 words), with its `% geometry 1280x720` rewritten to `geometry`.
fn evt3_with_geometry(dir: &Path, geometry: &str, keep: usize) -> String {
    let bytes = std::fs::read(real("evk4_faery_evt3.raw")).unwrap();
    let at = bytes
        .windows(8)
        .position(|w| w == b"1280x720")
        .expect("the header's geometry");
    let mut mutated = bytes[..at].to_vec();
    mutated.extend_from_slice(geometry.as_bytes());
    let header_end = 225;
    mutated.extend_from_slice(&bytes[at + 8..header_end + keep]);
    write(dir, &format!("geometry_{geometry}.raw"), &mutated)
}

/// A `% geometry` that is no sensor fell back silently to the camera plugin's size (only
/// sides over 4096 were refused); every stated size now is used, or refused naming its
/// header line, the line's fix and the plugin's size, and `--sensor` overrides it aloud.
#[test]
fn a_prophesee_geometry_that_is_no_sensor_names_its_header_line() {
    let dir = tempfile::tempdir().unwrap();
    for (geometry, why) in [
        ("0x0", "a side of 0 pixels"),
        ("axb", "`a` is not a whole number of pixels"),
        ("-5x-5", "`-5` is not a whole number of pixels"),
        ("65536x65536", "a side of 65536 pixels"),
        ("100000x1", "a side of 100000 pixels"),
    ] {
        let raw = evt3_with_geometry(dir.path(), geometry, 20_000);
        let e = bad_input(&["stats", &raw]);
        assert!(
            e.contains(&format!("geometry_{geometry}.raw: header line 5: `% geometry {geometry}` states no usable sensor size ({why}"))
                && e.contains("(e.g. `% geometry 1280x720`), or pass --sensor WxH")
                && e.contains("is 1280x720: pass --sensor 1280x720 if that is the camera"),
            "{geometry}: {e}"
        );
        let output = Command::cargo_bin("ctcal")
            .unwrap()
            .args(["info", &raw, "--sensor", "1280x720"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{geometry}: {stderr}");
        assert!(
            stderr.contains("warning: header line 5: `% geometry")
                && stderr.contains("the sensor size given (1280x720) is used"),
            "{geometry}: {stderr}"
        );
    }
    // a size over 4096 names the line too
    let raw = evt3_with_geometry(dir.path(), "8192x8192", 20_000);
    let e = bad_input(&["stats", &raw]);
    assert!(
        e.contains("% geometry on header line 5 says the sensor is 8192x8192"),
        "{e}"
    );
}

/// `real/davis346_faery.aedat4` with its streams' `sizeX`/`sizeY` text replaced by `value`
/// (the XML attribute's type `int` shortened to `type_name` to keep the header's length).
fn aedat4_with_size(dir: &Path, value: &str, type_name: &str) -> String {
    let mut bytes = std::fs::read(real("davis346_faery.aedat4")).unwrap();
    for (key, size) in [("sizeX", "346"), ("sizeY", "260")] {
        let from = format!(r#"key="{key}" type="int">{size}<"#);
        let to = format!(r#"key="{key}" type="{type_name}">{value}<"#);
        assert_eq!(from.len(), to.len());
        let at = bytes
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .unwrap();
        bytes[at..at + to.len()].copy_from_slice(to.as_bytes());
    }
    write(dir, &format!("size_{}.aedat4", value.trim()), &bytes)
}

/// An AEDAT4 event stream whose `sizeX`/`sizeY` give no sensor was said to "not state the
/// sensor size"; the warning now gives what they state and why it is not used.
#[test]
fn an_aedat4_size_that_is_no_sensor_is_named_in_the_warning() {
    let dir = tempfile::tempdir().unwrap();
    for (value, type_name, states) in [("99999", "i", "99999x99999"), ("  0", "int", "0x0")] {
        let file = aedat4_with_size(dir.path(), value, type_name);
        let output = Command::cargo_bin("ctcal")
            .unwrap()
            .args(["info", &file])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{value}: {stderr}");
        assert!(
            stderr.contains(&format!(
                "sizeX/sizeY of the event stream in the AEDAT4 header state {states}, which is no sensor size"
            )) && stderr.contains("so it is not used; using DAVIS346 (346x260)")
                && !stderr.contains("does not state"),
            "{value}: {stderr}"
        );
    }
}

/// A copy of `h5/e_ct060_event_utils.h5` in `dir` whose frame 3 (`images/image000000003`)
/// is replaced by `pixels`, keeping its timestamp.
fn event_utils_with_frame_3<T: hdf5::H5Type, D: ndarray::Dimension>(
    dir: &Path,
    name: &str,
    pixels: &ndarray::Array<T, D>,
) -> String {
    let path = dir.join(name);
    // written, not copied: the shared file's read-only mode would come along
    let original = std::fs::read(shared_data().join("h5/e_ct060_event_utils.h5")).unwrap();
    std::fs::write(&path, original).unwrap();
    {
        let file = h5_open_rw(&path);
        let images = file.group("images").unwrap();
        let t: f64 = images
            .dataset("image000000003")
            .unwrap()
            .attr("timestamp")
            .unwrap()
            .read_scalar()
            .unwrap();
        images.unlink("image000000003").unwrap();
        let ds = images
            .new_dataset_builder()
            .with_data(pixels)
            .create("image000000003")
            .unwrap();
        ds.new_attr::<f64>()
            .create("timestamp")
            .unwrap()
            .write_scalar(&t)
            .unwrap();
    }
    path.to_str().unwrap().to_string()
}

/// A float frame of NaN was read as a black frame (libhdf5 converts NaN to 0) and
/// `estimate aps` dropped its intervals without a word; a NaN or infinite pixel now names
/// the frame, how many there are and the first.
#[test]
fn a_non_finite_hdf5_frame_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let nan = ndarray::Array2::<f32>::from_elem((180, 240), f32::NAN);
    let path = event_utils_with_frame_3(dir.path(), "nan.h5", &nan);
    let e = bad_input(&["estimate", "aps", &path]);
    assert!(
        e.contains("nan.h5: images/image000000003 (frame 3): 43200 of the frame's 43200 pixels are NaN or infinite (the first at x = 0, y = 0: NaN)")
            && e.contains("fix: the frame is damaged"),
        "{e}"
    );
    // one infinite pixel in a v2e frame stack
    let path = dir.path().join("inf_v2e.h5");
    {
        let file = h5_create(&path);
        file.new_dataset_builder()
            .with_data(&ndarray::arr2(&[[1000u32, 1, 1, 1], [2000, 2, 2, 0]]))
            .create("events")
            .unwrap();
        let mut frames = ndarray::Array3::<f32>::zeros((2, 4, 4));
        frames[[1, 2, 3]] = f32::INFINITY;
        file.new_dataset_builder()
            .with_data(&frames)
            .create("frame")
            .unwrap();
        file.new_dataset_builder()
            .with_data(&[0u32, 1500])
            .create("frame_ts")
            .unwrap();
    }
    let e = bad_input(&["estimate", "aps", path.to_str().unwrap(), "--sensor", "4x4"]);
    assert!(
        e.contains("frame[1]: 1 of the frame's 16 pixels is NaN or infinite (the first at x = 3, y = 2: inf)"),
        "{e}"
    );
}

/// `real/davis346_faery.aedat4` with `damage` applied to the bytes of its first packet (its
/// header at 8 bytes before the returned slice start), written to `dir/name`.
fn aedat4_with_first_packet(dir: &Path, name: &str, damage: impl Fn(&mut [u8])) -> String {
    let mut bytes = std::fs::read(real("davis346_faery.aedat4")).unwrap();
    let header = u32::from_le_bytes(bytes[14..18].try_into().unwrap()) as usize;
    damage(&mut bytes[18 + header..]);
    write(dir, name, &bytes)
}

/// A damaged AEDAT4 packet gave the FlatBuffer verifier's own text and trace ("invalid
/// FlatBuffer: Range [4278190100, 4278190104) is out of bounds." and blank lines); it now
/// names the packet's index, byte offset and stream, what is wrong in one line, and the fix.
#[test]
fn a_damaged_aedat4_packet_is_named_in_one_message() {
    let dir = tempfile::tempdir().unwrap();
    let empty = aedat4_with_first_packet(dir.path(), "size0.aedat4", |p| {
        p[4..8].copy_from_slice(&0i32.to_le_bytes())
    });
    let garbled = aedat4_with_first_packet(dir.path(), "lz4.aedat4", |p| {
        p[28..68].iter_mut().for_each(|b| *b ^= 0xff)
    });
    for (path, bytes) in [(&empty, "0 bytes"), (&garbled, "6464 bytes")] {
        let e = bad_input(&["stats", path]);
        assert!(
            e.contains("packet 0 at byte offset 3126 (event stream 0): the packet (")
                && e.contains(&format!(
                    "{bytes} after decompression) is no valid event packet ("
                ))
                && e.contains("fix: the file is damaged at this packet")
                && !e.contains("invalid FlatBuffer")
                && !e.contains("\n\n"),
            "{e}"
        );
        assert_eq!(e.lines().count(), 2, "{e}");
    }
}

/// libhdf5's conversion to grey levels turned a frame normalised to [0, 1] into black and
/// white and saturated a 12-bit readout at 255, both read as scenes without a word; they are
/// refused naming the frame, while a float frame of whole grey levels reads exactly as the
/// 8-bit one it came from.
#[test]
fn hdf5_frames_that_are_not_grey_levels_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let original = shared_data().join("h5/e_ct060_event_utils.h5");
    let frames = Recording::open(&original, &OpenOptions::default())
        .unwrap()
        .frames()
        .unwrap();
    let (w, h) = (frames[3].width as usize, frames[3].height as usize);
    let levels = ndarray::Array2::from_shape_vec((h, w), frames[3].pixels.clone()).unwrap();

    let whole = levels.mapv(|v| v as f32);
    let path = event_utils_with_frame_3(dir.path(), "whole.h5", &whole);
    let read = Recording::open(Path::new(&path), &OpenOptions::default())
        .unwrap()
        .frames()
        .unwrap();
    assert!(read[3].pixels == frames[3].pixels && read.len() == frames.len());

    let normalised = levels.mapv(|v| v as f64 / 255.0);
    let path = event_utils_with_frame_3(dir.path(), "normalised.h5", &normalised);
    let e = bad_input(&["estimate", "aps", &path]);
    assert!(
        e.contains("normalised.h5: images/image000000003 (frame 3): the frame's values all lie in [0, 1] with fractions")
            && e.contains("fix: write the frames as 8-bit grey levels: round(255 x value)"),
        "{e}"
    );

    let twelve_bit = levels.mapv(|v| v as u16 * 16);
    let path = event_utils_with_frame_3(dir.path(), "twelve.h5", &twelve_bit);
    let e = bad_input(&["estimate", "aps", &path]);
    let over = twelve_bit.iter().filter(|&&v| v > 255).count();
    assert!(
        over > 1000
            && e.contains(&format!("twelve.h5: images/image000000003 (frame 3): {over} of the frame's {} pixels are outside the grey levels 0-255", w * h))
            && e.contains("scale a 10- or 12-bit readout to 0-255"),
        "{e}"
    );
}
