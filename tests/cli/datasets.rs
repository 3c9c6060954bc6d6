//! The seed paper's datasets as they are published (ROS1 bags, MVSEC and DSEC HDF5): each
//! file in `../shared/data/datasets` holds the events and frames of the IJRR text recording
//! `real/ijrr_slider_depth_50k`, written by independent writers (rosbags, h5py), and must
//! decode to exactly those events, times shifted by the stated offsets.

use super::common::*;
use ctcal::{EventChunk, OpenOptions, Recording};
use sha2::{Digest, Sha256};
use std::path::PathBuf;

fn dataset(name: &str) -> PathBuf {
    shared_data().join("datasets").join(name)
}

fn dataset_truth() -> serde_json::Value {
    let text = std::fs::read_to_string(dataset("ijrr_slider_depth_50k.truth.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The dataset files and the shift of their clock against the IJRR text's.
const FILES: [(&str, i64); 4] = [
    ("ijrr_slider_depth_50k.bag", 0),
    ("ijrr_slider_depth_50k_bz2.bag", 0),
    (
        "ijrr_slider_depth_50k_mvsec_layout.h5",
        1_504_645_000_000_000,
    ),
    // DSEC: `t` counts from the first event, `t_offset` = 64e9 us
    (
        "ijrr_slider_depth_50k_dsec_layout.h5",
        64_000_000_000 - 3_811,
    ),
];

/// SHA-256 of the (t_us, x, y, p) table as little-endian int64 rows.
fn table_hash(events: &EventChunk, shift: i64) -> String {
    let mut hasher = Sha256::new();
    for e in events.iter() {
        for v in [e.t - shift, e.x as i64, e.y as i64, e.on as i64] {
            hasher.update(v.to_le_bytes());
        }
    }
    hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[test]
fn every_dataset_file_decodes_to_the_ijrr_events() {
    let truth = dataset_truth();
    let reference = read_events(&real("ijrr_slider_depth_50k"));
    assert_eq!(
        table_hash(&reference, 0),
        truth["sha256_of_txyp"].as_str().unwrap(),
        "the hash convention"
    );
    for (name, shift) in FILES {
        let events = read_events(&dataset(name));
        assert_eq!(
            events.len() as u64,
            truth["events"].as_u64().unwrap(),
            "{name}"
        );
        let on = events.on.iter().filter(|&&p| p).count() as u64;
        assert_eq!(on, truth["on_events"].as_u64().unwrap(), "{name}");
        assert_eq!(
            events.t[0] - shift,
            truth["t_first_us"].as_i64().unwrap(),
            "{name}"
        );
        assert_eq!(
            table_hash(&events, shift),
            truth["sha256_of_txyp"].as_str().unwrap(),
            "{name}"
        );
    }
    // the DSEC clock is t + t_offset
    let dsec = read_events(&dataset(FILES[3].0));
    assert_eq!(dsec.t[0], truth["dsec_t_offset_us"].as_i64().unwrap());
}

#[test]
fn bag_and_mvsec_frames_are_the_ijrr_frames() {
    let reference = Recording::open(&real("ijrr_slider_depth_50k"), &OpenOptions::default())
        .unwrap()
        .frames()
        .unwrap();
    assert_eq!(reference.len(), 5);
    for (name, shift) in &FILES[..3] {
        let recording = Recording::open(&dataset(name), &OpenOptions::default()).unwrap();
        let frames = recording.frames().unwrap();
        assert_eq!(frames.len(), reference.len(), "{name}");
        for (f, r) in frames.iter().zip(&reference) {
            assert_eq!(f.t - shift, r.t, "{name}");
            assert_eq!((f.width, f.height), (r.width, r.height), "{name}");
            assert!(f.pixels == r.pixels, "{name}: pixels differ at {} us", r.t);
        }
        let times = recording.frame_times().unwrap();
        assert_eq!(times, frames.iter().map(|f| f.t).collect::<Vec<_>>());
    }
}

#[test]
fn every_dataset_file_converts_and_reads_back_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    for (k, (name, _)) in FILES.iter().enumerate() {
        let original = read_events(&dataset(name));
        for to in ["ijrr", "h5", "bag"] {
            let out = dir.path().join(format!(
                "{k}_{to}{}",
                match to {
                    "h5" => ".h5",
                    "bag" => ".bag",
                    _ => "",
                }
            ));
            ctcal()
                .args(["convert", dataset(name).to_str().unwrap(), "--out"])
                .arg(&out)
                .args(["--to", to])
                .assert()
                .success();
            assert!(read_events(&out) == original, "{name} -> {to}");
        }
    }
}

#[test]
fn bags_of_every_chunk_compression_read_back_with_their_frames() {
    let dir = tempfile::tempdir().unwrap();
    let source = real("ijrr_slider_depth_50k");
    let original = read_events(&source);
    let frames = Recording::open(&source, &OpenOptions::default())
        .unwrap()
        .frames()
        .unwrap();
    for compression in ["none", "bz2", "lz4"] {
        let out = dir.path().join(format!("{compression}.bag"));
        ctcal()
            .args(["convert", source.to_str().unwrap(), "--out"])
            .arg(&out)
            .args(["--bag-compression", compression])
            .assert()
            .success();
        assert!(read_events(&out) == original, "{compression}");
        let read = Recording::open(&out, &OpenOptions::default())
            .unwrap()
            .frames()
            .unwrap();
        assert!(read == frames, "{compression}");
    }
}

#[test]
fn info_lists_the_topics_of_a_bag() {
    let info = json(&[
        "info",
        dataset("ijrr_slider_depth_50k_bz2.bag").to_str().unwrap(),
    ]);
    assert_eq!(info["format"], "bag");
    let topics = info["topics"].as_array().unwrap();
    let find = |name: &str| topics.iter().find(|t| t["name"] == name).unwrap();
    assert_eq!(find("/dvs/events")["message_type"], "dvs_msgs/EventArray");
    assert_eq!(find("/dvs/image_raw")["message_type"], "sensor_msgs/Image");
    assert_eq!(find("/dvs/image_raw")["messages"], 5);
    // 10 ms messages over 170 ms
    let messages = find("/dvs/events")["messages"].as_u64().unwrap();
    assert!((17..=19).contains(&messages), "{messages}");
    let mvsec = json(&["info", dataset(FILES[2].0).to_str().unwrap()]);
    assert_eq!(mvsec["layout"], "MVSEC");
    assert_eq!(mvsec["frames"], 5);
}

#[test]
fn a_bag_topic_of_another_type_or_missing_names_the_topics() {
    let bag = dataset("ijrr_slider_depth_50k.bag");
    let e = bad_input(&["stats", bag.to_str().unwrap(), "--topic", "/dvs/image_raw"]);
    assert!(
        e.contains("/dvs/image_raw carries sensor_msgs/Image")
            && e.contains("--topic")
            && e.contains("/dvs/events (dvs_msgs/EventArray"),
        "{e}"
    );
    let e = bad_input(&[
        "stats",
        bag.to_str().unwrap(),
        "--topic",
        "/davis/left/events",
    ]);
    assert!(
        e.contains("no topic /davis/left/events") && e.contains("fix:"),
        "{e}"
    );
}

#[test]
fn a_bag_without_event_topics_says_what_it_has() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frames_only.bag");
    let frames = Recording::open(&real("ijrr_slider_depth_50k"), &OpenOptions::default())
        .unwrap()
        .frames()
        .unwrap();
    let mut writer = ctcal::io::write::BagWriter::create(
        &path,
        ctcal::Sensor::new(240, 180),
        ctcal::io::write::BagCompression::None,
        &ctcal::io::write::OutputPolicy::default(),
    )
    .unwrap();
    writer.write_frame(&frames[0]).unwrap();
    writer.finish().unwrap();
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(
        e.contains("no dvs_msgs/EventArray topic")
            && e.contains("/dvs/image_raw (sensor_msgs/Image, 1 messages)")
            && e.contains("fix:"),
        "{e}"
    );
}

#[test]
fn damaged_bags_name_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(dataset("ijrr_slider_depth_50k_bz2.bag")).unwrap();
    // cut in the middle of its chunk: the index at the end is gone too
    let cut = dir.path().join("cut.bag");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = bad_input(&["stats", cut.to_str().unwrap()]);
    assert!(
        e.contains("cut short") && e.contains("index") && e.contains("fix:"),
        "{e}"
    );
    // a bag that was never closed (no index) and is cut inside its chunk: found by scanning
    let mut unclosed = bytes[..bytes.len() / 2].to_vec();
    let field = unclosed
        .windows(10)
        .position(|w| w == b"index_pos=")
        .expect("the bag header names index_pos")
        + 10;
    unclosed[field..field + 8].fill(0);
    let path = dir.path().join("unclosed.bag");
    std::fs::write(&path, &unclosed).unwrap();
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(
        e.contains("record at byte offset 4109")
            && e.contains("the file ends")
            && e.contains("fix:"),
        "{e}"
    );
    // garbage inside the bz2 data of the chunk
    let mut damaged = bytes.clone();
    let middle = bytes.len() / 2;
    damaged[middle..middle + 64].fill(0x55);
    let path = dir.path().join("garbage.bag");
    std::fs::write(&path, &damaged).unwrap();
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(
        e.contains("chunk at byte offset") && e.contains("bz2") && e.contains("fix:"),
        "{e}"
    );
}

/// The byte range of chunk `index` of a 1-D dataset.
fn chunk_location(path: &std::path::Path, dataset: &str, element: u64) -> (u64, u64) {
    let file = h5_open(path);
    let ds = file.dataset(dataset).unwrap();
    let (mut mask, mut address, mut size) = (0u32, 0u64, 0u64);
    let offset = [element];
    // SAFETY: a live dataset id, pointers to locals, under hdf5-metno's lock
    let status = hdf5::sync::sync(|| unsafe {
        hdf5_sys::h5d::H5Dget_chunk_info_by_coord(
            ds.id(),
            offset.as_ptr(),
            &mut mask,
            &mut address,
            &mut size,
        )
    });
    assert!(status >= 0);
    (address, size)
}

#[test]
fn a_blosc_chunk_that_does_not_decompress_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dsec.h5");
    std::fs::copy(dataset(FILES[3].0), &path).unwrap();
    let (address, size) = chunk_location(&path, "events/x", 5000);
    let mut bytes = std::fs::read(&path).unwrap();
    // keep the Blosc header, damage the compressed blocks
    let from = address as usize + 24;
    bytes[from..address as usize + size as usize].fill(0xa5);
    std::fs::write(&path, &bytes).unwrap();
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(
        e.contains("events/x") && e.contains("elements 4096..8192") && e.contains("fix:"),
        "{e}"
    );
}

#[test]
fn an_mvsec_file_without_the_left_camera_names_the_side_to_use() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("right_only.h5");
    let reference = read_events(&real("ijrr_slider_depth_50k"));
    {
        let file = h5_create(&path);
        let rows: Vec<f64> = reference
            .iter()
            .take(1000)
            .flat_map(|e| {
                [
                    e.x as f64,
                    e.y as f64,
                    1.5e9 + e.t as f64 * 1e-6,
                    if e.on { 1.0 } else { -1.0 },
                ]
            })
            .collect();
        let table = ndarray::Array2::from_shape_vec((1000, 4), rows).unwrap();
        file.create_group("davis").unwrap();
        file.create_group("davis/right").unwrap();
        file.new_dataset_builder()
            .with_data(&table)
            .create("davis/right/events")
            .unwrap();
    }
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(
        e.contains("without davis/left/events") && e.contains("--side right"),
        "{e}"
    );
    let s = json(&[
        "stats",
        path.to_str().unwrap(),
        "--side",
        "right",
        "--sensor",
        "240x180",
    ]);
    assert_eq!(s["events"], 1000);
    assert_eq!(s["t_first_us"], 1_500_000_000_000_000i64 + reference.t[0]);
}

#[test]
fn time_windows_read_the_same_events_and_seek_with_the_file_index() {
    let reference = json(&[
        "stats",
        real("ijrr_slider_depth_50k").to_str().unwrap(),
        "--start",
        "0.05",
        "--end",
        "0.1",
    ]);
    for (name, shift) in FILES {
        let s = json(&[
            "stats",
            dataset(name).to_str().unwrap(),
            "--start",
            "0.05",
            "--end",
            "0.1",
        ]);
        for key in ["events", "on_events", "active_pixel_fraction"] {
            assert_eq!(s[key], reference[key], "{name}: {key}");
        }
        assert_eq!(
            s["t_first_us"].as_i64().unwrap() - shift,
            reference["t_first_us"].as_i64().unwrap(),
            "{name}"
        );
    }
    // DSEC (ms_to_idx) and MVSEC (image_raw_event_inds) start reading near the window
    for (name, _) in &FILES[2..] {
        let recording = Recording::open(&dataset(name), &OpenOptions::default()).unwrap();
        let first = recording.first_event_time().unwrap();
        let (from, to) = (first + 100_000, first + 120_000);
        let mut stream = recording.events_between(from, to).unwrap();
        let mut read = EventChunk::default();
        while let Some(chunk) = stream.next_chunk().unwrap() {
            read.extend_from(chunk);
        }
        let inside = read_events(&dataset(name))
            .t
            .iter()
            .filter(|&&t| (from..=to).contains(&t))
            .count();
        let kept = read.t.iter().filter(|&&t| (from..=to).contains(&t)).count();
        assert_eq!(kept, inside, "{name}: every event of the window");
        assert!(
            read.len() < 25_000,
            "{name}: read {} of 50000 events",
            read.len()
        );
    }
}

/// A record of a bag: where it starts, its header fields and where its data lie.
struct BagRecord {
    start: usize,
    fields: Vec<(String, std::ops::Range<usize>)>,
    data: std::ops::Range<usize>,
}

impl BagRecord {
    fn field(&self, name: &str) -> Option<std::ops::Range<usize>> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, r)| r.clone())
    }

    fn op(&self, bytes: &[u8]) -> u8 {
        bytes[self.field("op").unwrap().start]
    }

    fn end(&self) -> usize {
        self.data.end
    }
}

/// The records of `bytes[from..to]`.
fn bag_records(bytes: &[u8], from: usize, to: usize) -> Vec<BagRecord> {
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
    let mut records = Vec::new();
    let mut at = from;
    while at < to {
        let header_len = u32_at(at);
        let mut fields = Vec::new();
        let mut i = at + 4;
        while i < at + 4 + header_len {
            let n = u32_at(i);
            let field = &bytes[i + 4..i + 4 + n];
            let eq = field.iter().position(|&b| b == b'=').unwrap();
            fields.push((
                String::from_utf8_lossy(&field[..eq]).into_owned(),
                i + 4 + eq + 1..i + 4 + n,
            ));
            i += 4 + n;
        }
        let data_start = at + 4 + header_len + 4;
        let data_len = u32_at(at + 4 + header_len);
        records.push(BagRecord {
            start: at,
            fields,
            data: data_start..data_start + data_len,
        });
        at = data_start + data_len;
    }
    records
}

/// The uncompressed bag of the slider, its records in its (one) chunk, and the connection
/// id of `/dvs/events`.
fn slider_bag() -> (Vec<u8>, Vec<BagRecord>, u32) {
    let bytes = std::fs::read(dataset("ijrr_slider_depth_50k.bag")).unwrap();
    let top = bag_records(&bytes, 13, bytes.len());
    let chunk = top.iter().find(|r| r.op(&bytes) == 0x05).unwrap();
    let inner = bag_records(&bytes, chunk.data.start, chunk.data.end);
    let events = inner
        .iter()
        .find(|r| r.op(&bytes) == 0x07 && &bytes[r.field("topic").unwrap()] == b"/dvs/events")
        .unwrap();
    let id = u32::from_le_bytes(bytes[events.field("conn").unwrap()].try_into().unwrap());
    (bytes, inner, id)
}

/// The message records of connection `id`.
fn messages_of<'a>(bytes: &[u8], records: &'a [BagRecord], id: u32) -> Vec<&'a BagRecord> {
    records
        .iter()
        .filter(|r| r.op(bytes) == 0x02 && bytes[r.field("conn").unwrap()] == id.to_le_bytes())
        .collect()
}

/// Where event `k` of a `dvs_msgs/EventArray` message's data starts.
fn event_offset(bytes: &[u8], data: &std::ops::Range<usize>, k: usize) -> usize {
    // header: seq, stamp (secs, nsecs), frame_id (length + bytes); height, width, count
    let frame_id = u32::from_le_bytes(bytes[data.start + 12..data.start + 16].try_into().unwrap());
    data.start + 16 + frame_id as usize + 12 + 13 * k
}

#[test]
fn a_bag_event_far_ahead_of_its_neighbours_is_disorder_as_in_every_reader() {
    let dir = tempfile::tempdir().unwrap();
    let (bytes, records, id) = slider_bag();
    let messages = messages_of(&bytes, &records, id);
    // an event stamped 2^32 - 1 s (136 years later) inside message 3, and at its end
    let last = u32::from_le_bytes(
        bytes[event_offset(&bytes, &messages[2].data, 0) - 4..][..4]
            .try_into()
            .unwrap(),
    ) as usize;
    for (name, k, expected) in [
        ("inside.bag", 5, "message 3 ("),
        ("at_end.bag", last - 1, "message 4 ("),
    ] {
        let mut damaged = bytes.clone();
        let at = event_offset(&bytes, &messages[2].data, k) + 4;
        damaged[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let path = dir.path().join(name);
        std::fs::write(&path, &damaged).unwrap();
        let e = bad_input(&["stats", path.to_str().unwrap()]);
        // one bad stamp is one step back, as a text reader counts it
        assert!(
            e.contains(name)
                && e.contains("1 timestamps go backwards")
                && e.contains("topic /dvs/events")
                && e.contains(expected)
                && e.contains("--sort"),
            "{name}: {e}"
        );
    }
    // the same damage in a text file says the same
    let text = dir.path().join("events.txt");
    std::fs::write(&text, "0.1 1 1 1\n4294967295.0 2 2 1\n0.2 3 3 0\n").unwrap();
    let e = bad_input(&["stats", text.to_str().unwrap()]);
    assert!(e.contains("timestamps go backwards"), "{e}");
}

#[test]
fn a_bag_chunk_with_its_records_reversed_is_unsorted() {
    let dir = tempfile::tempdir().unwrap();
    let (bytes, records, id) = slider_bag();
    let messages = messages_of(&bytes, &records, id);
    // the event messages in reverse order, every other record in place
    let mut reversed = bytes[..records[0].start].to_vec();
    let mut next = messages.iter().rev();
    for r in &records {
        let source = if messages.iter().any(|m| m.start == r.start) {
            next.next().unwrap()
        } else {
            r
        };
        reversed.extend_from_slice(&bytes[source.start..source.end()]);
    }
    reversed.extend_from_slice(&bytes[records.last().unwrap().end()..]);
    assert_eq!(reversed.len(), bytes.len());
    let path = dir.path().join("reversed.bag");
    std::fs::write(&path, &reversed).unwrap();
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    // a step back at every message after the first, as a text reader would count
    assert!(
        e.contains("reversed.bag")
            && e.contains(&format!("{} timestamps go backwards", messages.len() - 1))
            && e.contains("ends before a message before it started")
            && e.contains("--sort"),
        "{e}"
    );
    // with --sort every event is there, as in the original
    let sorted = json(&["stats", path.to_str().unwrap(), "--sort"]);
    let original = json(&[
        "stats",
        dataset("ijrr_slider_depth_50k.bag").to_str().unwrap(),
    ]);
    for key in ["events", "on_events", "t_first_us", "t_last_us"] {
        assert_eq!(sorted[key], original[key], "{key}");
    }
}

#[test]
fn a_bag_message_of_an_unknown_connection_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (bytes, records, id) = slider_bag();
    let message = messages_of(&bytes, &records, id)[4];
    let mut damaged = bytes.clone();
    let conn = message.field("conn").unwrap();
    damaged[conn].copy_from_slice(&77u32.to_le_bytes());
    let path = dir.path().join("unknown.bag");
    std::fs::write(&path, &damaged).unwrap();
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(
        e.contains("unknown.bag")
            && e.contains(&format!(
                "record at byte {}",
                message.start - records[0].start
            ))
            && e.contains("connection id 77")
            && e.contains("0 (/dvs/events)")
            && e.contains("fix:"),
        "{e}"
    );
}

#[test]
fn a_dsec_index_that_contradicts_the_times_is_checked_against_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dsec.h5");
    std::fs::copy(dataset(FILES[3].0), &path).unwrap();
    // millisecond 50 said to start where millisecond 53 does: a window from 50 ms used to
    // start 3 ms late and lose the events between
    {
        let file = h5_open_rw(&path);
        let mut index: Vec<u64> = file.dataset("ms_to_idx").unwrap().read_raw().unwrap();
        let (right, wrong) = (index[50], index[53]);
        assert!(wrong > right + 100, "{right} {wrong}");
        index[50] = wrong;
        file.unlink("ms_to_idx").unwrap();
        file.new_dataset_builder()
            .with_data(&index)
            .create("ms_to_idx")
            .unwrap();
    }
    let window = ["--start", "0.05", "--end", "0.1", "--json", "-"];
    let reference = json(&[
        "stats",
        dataset(FILES[3].0).to_str().unwrap(),
        "--start",
        "0.05",
        "--end",
        "0.1",
    ]);
    // not quiet: the warning is the message
    let output = std::process::Command::new(assert_cmd::cargo::cargo_bin("ctcal"))
        .env("HDF5_USE_FILE_LOCKING", "FALSE")
        .arg("stats")
        .arg(&path)
        .args(window)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let s: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    for key in ["events", "on_events", "t_first_us", "t_last_us"] {
        assert_eq!(s[key], reference[key], "{key}");
    }
    assert!(
        stderr.contains("dsec.h5")
            && stderr.contains("ms_to_idx[50]")
            && stderr.contains("contradicts events/t")
            && stderr.contains("found on the event times"),
        "{stderr}"
    );
}

#[test]
fn float32_times_that_lost_their_precision_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let reference = read_events(&real("ijrr_slider_depth_50k"));
    // MVSEC's layout with float32 rows: at 1.5e9 s float32 values lie 128 s apart, and
    // the whole recording used to collapse to one time (duration 0)
    let path = dir.path().join("mvsec_f32.h5");
    {
        let file = h5_create(&path);
        let rows: Vec<f32> = reference
            .iter()
            .take(1000)
            .flat_map(|e| {
                [
                    e.x as f32,
                    e.y as f32,
                    (1_504_645_000.0 + e.t as f64 * 1e-6) as f32,
                    if e.on { 1.0 } else { -1.0 },
                ]
            })
            .collect();
        let table = ndarray::Array2::from_shape_vec((1000, 4), rows).unwrap();
        file.create_group("davis").unwrap();
        file.create_group("davis/left").unwrap();
        file.new_dataset_builder()
            .with_data(&table)
            .create("davis/left/events")
            .unwrap();
    }
    for command in ["stats", "info"] {
        let e = bad_input(&[command, path.to_str().unwrap(), "--sensor", "240x180"]);
        assert!(
            e.contains("mvsec_f32.h5")
                && e.contains("davis/left/events[:, 2]")
                && e.contains("float32")
                && e.contains("1.280e2 s apart")
                && e.contains("float64")
                && e.contains("fix:"),
            "{command}: {e}"
        );
    }
    // float32 seconds from zero keep their microseconds over a short recording
    let path = dir.path().join("event_utils_f32.h5");
    {
        let file = h5_create(&path);
        let events = file.create_group("events").unwrap();
        let n = 1000;
        let ts: Vec<f32> = reference.t[..n].iter().map(|&t| t as f32 * 1e-6).collect();
        let xs: Vec<i16> = reference.x[..n].iter().map(|&x| x as i16).collect();
        let ys: Vec<i16> = reference.y[..n].iter().map(|&y| y as i16).collect();
        let ps: Vec<u8> = reference.on[..n].iter().map(|&p| p as u8).collect();
        events
            .new_dataset_builder()
            .with_data(&ts)
            .create("ts")
            .unwrap();
        events
            .new_dataset_builder()
            .with_data(&xs)
            .create("xs")
            .unwrap();
        events
            .new_dataset_builder()
            .with_data(&ys)
            .create("ys")
            .unwrap();
        events
            .new_dataset_builder()
            .with_data(&ps)
            .create("ps")
            .unwrap();
    }
    let s = json(&["stats", path.to_str().unwrap(), "--sensor", "240x180"]);
    assert_eq!(s["events"], 1000);
    assert_eq!(s["t_first_us"], reference.t[0]);
}
