//! Bounded work for any input, and the small things users hit at once: every hostile or
//! mistaken input of the safety issue gets exit code 2 with the file, the place and a fix,
//! quickly, instead of a panic, a hang or a request for gigabytes. (Peak memory of the
//! cases that used to ask for gigabytes is asserted in-process by `tests/hostile.rs`.)

use crate::common::*;
use std::path::Path;
use std::time::{Duration, Instant};

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path.to_str().unwrap().to_string()
}

/// An event_utils HDF5 file from columns of any types.
fn h5_events<X: hdf5::H5Type, P: hdf5::H5Type>(
    path: &Path,
    ts: &[f64],
    xs: &[X],
    ys: &[X],
    ps: &[P],
) {
    let file = h5_create(path);
    let events = file.create_group("events").unwrap();
    events
        .new_dataset_builder()
        .with_data(ts)
        .create("ts")
        .unwrap();
    events
        .new_dataset_builder()
        .with_data(xs)
        .create("xs")
        .unwrap();
    events
        .new_dataset_builder()
        .with_data(ys)
        .create("ys")
        .unwrap();
    events
        .new_dataset_builder()
        .with_data(ps)
        .create("ps")
        .unwrap();
}

#[test]
fn a_sensor_over_4096_pixels_needs_sensor_given() {
    let dir = tempfile::tempdir().unwrap();
    // from an IJRR `width height` line
    let text = write(
        dir.path(),
        "big.txt",
        b"5000 100\n0.1 4500 10 1\n0.2 1 1 0\n",
    );
    let e = bad_input(&["stats", &text]);
    assert!(
        e.contains("big.txt")
            && e.contains("5000x100")
            && e.contains("width height")
            && e.contains("--sensor"),
        "{e}"
    );
    let s = json(&["stats", &text, "--sensor", "5000x100"]);
    assert_eq!(s["events"], 2);
    // a `width height` line of no sensor is refused unless the size is given
    let zero = write(dir.path(), "zero.txt", b"0 0\n0.1 1 1 1\n0.2 2 2 0\n");
    let e = bad_input(&["stats", &zero]);
    assert!(
        e.contains("zero.txt: line 1")
            && e.contains("`0 0` gives no sensor")
            && e.contains("--sensor WxH"),
        "{e}"
    );
    let s = json(&["stats", &zero, "--sensor", "4x4"]);
    assert_eq!(s["events"], 2);
    // from a Prophesee header
    let mut raw = b"% evt 3.0\n% geometry 8000x8000\n% end\n".to_vec();
    raw.extend_from_slice(&[0x00, 0x80, 0x00, 0x60, 0x05, 0x20]);
    let raw = write(dir.path(), "big.raw", &raw);
    let e = bad_input(&["stats", &raw]);
    assert!(e.contains("geometry") && e.contains("8000x8000"), "{e}");
    // from sensor_resolution
    let h5 = dir.path().join("big.h5");
    h5_events(&h5, &[0.1, 0.2], &[1i16, 2], &[1i16, 2], &[true, false]);
    h5_open_rw(&h5)
        .new_attr_builder()
        .with_data(&[100i64, 9000])
        .create("sensor_resolution")
        .unwrap();
    let e = bad_input(&["stats", h5.to_str().unwrap()]);
    assert!(
        e.contains("sensor_resolution") && e.contains("9000x100"),
        "{e}"
    );
    // from the largest coordinate when nothing states the size
    let far = write(dir.path(), "far.txt", b"0.1 1 1 1\n0.2 60000 3 0\n");
    let e = bad_input(&["stats", &far]);
    assert!(
        e.contains("line 2") && e.contains("60000") && e.contains("4096") && e.contains("--sensor"),
        "{e}"
    );
}

#[test]
fn time_options_beyond_any_recording_are_errors() {
    let input = real("ijrr_slider_depth_50k");
    let input = input.to_str().unwrap();
    for args in [
        ["--start", "1e300"],
        ["--end", "1e19"],
        ["--start", "-1"],
        ["--end", "nan"],
    ] {
        let flag = format!("{}={}", args[0], args[1]);
        let e = bad_input(&["stats", input, &flag]);
        assert!(
            e.contains(args[0]) && e.contains("seconds"),
            "{args:?}: {e}"
        );
    }
    let e = bad_input(&["stats", input, "--start", "5"]);
    assert!(e.contains("--start 5 s") && !e.contains("Some("), "{e}");
}

#[test]
fn absurd_timestamps_are_refused_where_they_are() {
    let dir = tempfile::tempdir().unwrap();
    // 1e300 s cannot be microseconds at all
    let text = write(dir.path(), "huge.txt", b"0.1 1 1 1\n1e300 2 2 1\n");
    let e = bad_input(&["stats", &text]);
    assert!(e.contains("line 2"), "{e}");
    // 3e12 s fits in 64 bits of microseconds, but lies beyond 2^61 us
    let text = write(dir.path(), "far.txt", b"0.1 1 1 1\n3e12 2 2 1\n");
    let e = bad_input(&["stats", &text]);
    assert!(e.contains("line 2") && e.contains("beyond"), "{e}");
}

#[test]
fn a_gap_of_ten_million_seconds_gives_a_bounded_timeline() {
    let dir = tempfile::tempdir().unwrap();
    let text = write(
        dir.path(),
        "gap.txt",
        b"240 180\n0.000001 1 1 1\n0.000002 2 2 0\n10000000.0 3 3 1\n",
    );
    let started = Instant::now();
    let s = json(&["stats", &text]);
    assert!(started.elapsed() < Duration::from_secs(20));
    let timeline = s["rate_timeline"].as_array().unwrap();
    assert!(timeline.len() <= 100_000, "{}", timeline.len());
    let total: u64 = timeline.iter().map(|w| w["events"].as_u64().unwrap()).sum();
    assert_eq!(total, 3);
}

#[test]
fn hdf5_coordinates_and_polarities_are_checked_by_dataset_and_index() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan_x.h5");
    h5_events(
        &path,
        &[0.1, 0.2, 0.3],
        &[1.0f64, f64::NAN, 3.0],
        &[1.0f64, 2.0, 3.0],
        &[1u8, 0, 1],
    );
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(e.contains("events/xs[1]") && e.contains("NaN"), "{e}");
    let path = dir.path().join("negative_x.h5");
    h5_events(&path, &[0.1, 0.2], &[1i32, -5], &[1i32, 2], &[1u8, 0]);
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(e.contains("x=-5") && e.contains("event index 1"), "{e}");
    let path = dir.path().join("nan_p.h5");
    h5_events(
        &path,
        &[0.1, 0.2],
        &[1i16, 2],
        &[1i16, 2],
        &[1.0f64, f64::NAN],
    );
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(e.contains("events/ps[1]") && e.contains("polarity"), "{e}");
    let path = dir.path().join("two.h5");
    h5_events(&path, &[0.1, 0.2], &[1i16, 2], &[1i16, 2], &[1u8, 2]);
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(e.contains("events/ps[1]") && e.contains("is 2"), "{e}");
}

#[test]
fn hdf5_frames_are_checked_before_they_are_read() {
    let dir = tempfile::tempdir().unwrap();
    // a scalar `frame` (v2e layout) used to panic
    let path = dir.path().join("scalar_frame.h5");
    {
        let file = h5_create(&path);
        file.new_dataset_builder()
            .with_data(&ndarray::arr2(&[[1000u32, 1, 1, 1], [2000, 2, 2, 0]]))
            .create("events")
            .unwrap();
        file.new_dataset::<u8>().create("frame").unwrap();
    }
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(e.contains("frame is a scalar"), "{e}");
    // a frame stack claiming terabytes it does not store
    let path = dir.path().join("huge_frames.h5");
    {
        let file = h5_create(&path);
        file.new_dataset_builder()
            .with_data(&ndarray::arr2(&[[1000u32, 1, 1, 1], [2000, 2, 2, 0]]))
            .create("events")
            .unwrap();
        file.new_dataset::<u8>()
            .chunk((1, 64, 64))
            .deflate(1)
            .shape((1_000_000, 4000, 4000))
            .create("frame")
            .unwrap();
        file.new_dataset_builder()
            .with_data(&[0u32; 2])
            .create("frame_ts")
            .unwrap();
    }
    let started = Instant::now();
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(started.elapsed() < Duration::from_secs(20));
    assert!(
        e.contains("claims shape") && e.contains("stores only"),
        "{e}"
    );
    // a colour frame among grey ones (a hostile round: the fix said "check that the file
    // is an event_utils or v2e HDF5 file")
    let path = dir.path().join("rgb.h5");
    h5_events(&path, &[0.1, 0.2], &[1i16, 2], &[1i16, 2], &[true, false]);
    {
        let file = h5_open_rw(&path);
        let images = file.create_group("images").unwrap();
        let ds = images
            .new_dataset_builder()
            .with_data(&ndarray::Array3::<u8>::zeros((4, 4, 3)))
            .create("image000000000")
            .unwrap();
        ds.new_attr::<f64>()
            .create("timestamp")
            .unwrap()
            .write_scalar(&0.1)
            .unwrap();
    }
    let e = bad_input(&["stats", path.to_str().unwrap(), "--sensor", "8x8"]);
    assert!(
        e.contains("images/image000000000 has shape [4, 4, 3]")
            && e.contains("colour image (3 channels)")
            && e.contains("grey"),
        "{e}"
    );
    // frames of two sizes, and frames out of order, as for IJRR folders
    for (name, sizes, times) in [
        ("sizes.h5", [(4usize, 4usize), (4, 5)], [0.1, 0.2]),
        ("order.h5", [(4, 4), (4, 4)], [0.2, 0.1]),
    ] {
        let path = dir.path().join(name);
        h5_events(&path, &[0.1, 0.2], &[1i16, 2], &[1i16, 2], &[true, false]);
        {
            // every handle closed before ctcal reads the file
            let file = h5_open_rw(&path);
            let images = file.create_group("images").unwrap();
            for (i, ((h, w), t)) in sizes.iter().zip(times).enumerate() {
                let ds = images
                    .new_dataset_builder()
                    .with_data(&ndarray::Array2::<u8>::zeros((*h, *w)))
                    .create(format!("image{i:09}").as_str())
                    .unwrap();
                ds.new_attr::<f64>()
                    .create("timestamp")
                    .unwrap()
                    .write_scalar(&t)
                    .unwrap();
            }
        }
        let e = bad_input(&["stats", path.to_str().unwrap(), "--sensor", "8x8"]);
        assert!(e.contains("images/image000000001"), "{name}: {e}");
        assert!(
            e.contains("first frame") || e.contains("earlier"),
            "{name}: {e}"
        );
    }
}

/// Registers a stand-in for h5py's LZF filter (id 32000) in this process, so that a file
/// using it can be written; a fresh ctcal process has no such filter, as a user's machine
/// has none.
fn register_fake_lzf() {
    use hdf5_sys::h5z::{H5Z_CLASS_T_VERS, H5Z_class2_t, H5Zregister};
    extern "C" fn identity(
        _flags: std::ffi::c_uint,
        _cd_nelmts: usize,
        _cd_values: *const std::ffi::c_uint,
        nbytes: usize,
        _buf_size: *mut usize,
        _buf: *mut *mut std::ffi::c_void,
    ) -> usize {
        nbytes
    }
    static NAME: &[u8] = b"lzf stand-in\0";
    let class = H5Z_class2_t {
        version: H5Z_CLASS_T_VERS as i32,
        id: 32000,
        encoder_present: 1,
        decoder_present: 1,
        name: NAME.as_ptr().cast(),
        can_apply: None,
        set_local: None,
        filter: Some(identity),
    };
    // SAFETY: `class` is a valid filter class whose name is a static C string;
    // libhdf5 copies the struct; called under hdf5-metno's lock.
    let status =
        hdf5::sync::sync(|| unsafe { H5Zregister((&class as *const H5Z_class2_t).cast()) });
    assert!(status >= 0);
}

#[test]
fn an_lzf_compressed_hdf5_names_the_filter_and_the_fix() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lzf.h5");
    register_fake_lzf();
    {
        let file = h5_create(&path);
        let events = file.create_group("events").unwrap();
        let lzf = hdf5::filters::Filter::user(32000, &[]);
        events
            .new_dataset_builder()
            .with_data(&[0.1f64, 0.2])
            .chunk(2)
            .set_filters(std::slice::from_ref(&lzf))
            .create("ts")
            .unwrap();
        for name in ["xs", "ys"] {
            events
                .new_dataset_builder()
                .with_data(&[1i16, 2])
                .create(name)
                .unwrap();
        }
        events
            .new_dataset_builder()
            .with_data(&[true, false])
            .create("ps")
            .unwrap();
    }
    let e = bad_input(&["stats", path.to_str().unwrap()]);
    assert!(
        e.contains("lzf.h5")
            && e.contains("events/ts")
            && e.contains("LZF")
            && e.contains("h5repack"),
        "{e}"
    );
}

#[cfg(unix)]
#[test]
fn fifos_and_folders_where_a_file_is_expected_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.raw");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let fifo = fifo.to_str().unwrap();
    let started = Instant::now();
    for args in [
        vec!["stats", fifo],
        vec!["info", fifo, "--format", "evt3"],
        vec![
            "simulate", "--params", fifo, "--scene", "x.toml", "--out", "o",
        ],
    ] {
        let e = bad_input(&args);
        assert!(
            e.contains("pipe.raw") && e.contains("FIFO"),
            "{args:?}: {e}"
        );
    }
    let folder = dir.path().to_str().unwrap();
    let e = bad_input(&[
        "simulate", "--params", folder, "--scene", "x.toml", "--out", "o",
    ]);
    assert!(e.contains("is a folder"), "{e}");
    assert!(started.elapsed() < Duration::from_secs(20), "no hang");
}

#[test]
fn simulation_work_and_values_are_validated_with_limits() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.toml", b"ct_on = 0.3\nct_off = 0.3\n");
    let out = dir.path().join("o");
    let out = out.to_str().unwrap();
    let scene = |text: &str| write(dir.path(), "s.toml", text.as_bytes());
    let texture = "kind = \"texture\"\nheight = 48\n[texture]\nvx_px_s = 30.0\n";
    let cases = [
        (format!("width = 100000\nduration_s = 1.0\n{texture}"), "width"),
        (format!("width = 64\nduration_s = 1.0\nrender_hz = 1e9\n{texture}"), "render_hz"),
        (format!("width = 64\nduration_s = 1e9\n{texture}"), "duration_s"),
        (format!("width = 64\nduration_s = nan\n{texture}"), "duration_s"),
        (format!("width = 64\nduration_s = 1.0\n{texture}canvas_px = 100000\n"), "canvas_px"),
        (
            "kind = \"multi_object\"\nwidth = 64\nheight = 48\nduration_s = 0.1\n[multi_object]\nobjects = [10, 5]\nbackground_velocity_px_s = [5.0, 10.0]\nbackground_angular_velocity_deg_s = [0.0, 5.0]\nbackground_scale = [1.0, 1.2]\nobject_velocity_px_s = [40.0, 80.0]\nobject_angular_velocity_deg_s = [0.0, 20.0]\nobject_scale = [0.5, 1.0]\n".to_string(),
            "objects",
        ),
        (
            "kind = \"checkerboard\"\nwidth = 64\nheight = 48\nduration_s = 0.1\n[checkerboard]\nsquare_px = 8.0\nlo_dn = 60.0\nhi_dn = inf\n".to_string(),
            "hi_dn",
        ),
    ];
    for (text, key) in cases {
        let path = scene(&text);
        let started = Instant::now();
        let e = bad_input(&[
            "simulate", "--params", &params, "--scene", &path, "--out", out,
        ]);
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "{key}: slow refusal"
        );
        assert!(e.contains(key) && e.contains("fix:"), "{key}: {e}");
    }
    // the work budget: a 2000x2000 scene at 10 kHz for 10 s, refused with the estimate
    let path = scene(
        "width = 2000\nheight = 2000\nduration_s = 10.0\nrender_hz = 10000.0\nkind = \"texture\"\n[texture]\nvx_px_s = 30.0\n",
    );
    let e = bad_input(&[
        "simulate", "--params", &params, "--scene", &path, "--out", out,
    ]);
    assert!(e.contains("pixel updates") && e.contains("--force"), "{e}");
    // NaN in PARAMS names the key
    let nan = write(
        dir.path(),
        "nan.toml",
        b"ct_on = 0.3\nct_off = 0.3\nleak_rate_hz = nan\n",
    );
    let e = bad_input(&[
        "simulate",
        "--params",
        &nan,
        "--frames",
        oracle("a_ideal_texture").to_str().unwrap(),
        "--out",
        out,
    ]);
    assert!(e.contains("leak_rate_hz") && e.contains("finite"), "{e}");
    // thread counts
    for n in ["0", "100000"] {
        let e = bad_input(&[
            "--threads",
            n,
            "info",
            real("ijrr_slider_depth_50k").to_str().unwrap(),
        ]);
        assert!(e.contains("--threads"), "{e}");
    }
    // the calibration stimulus
    let e = bad_input(&["calib", "checkerboard", "--out", out, "--refresh-hz", "1e9"]);
    assert!(e.contains("--refresh-hz"), "{e}");
    let e = bad_input(&["calib", "checkerboard", "--out", out, "--width", "100000"]);
    assert!(e.contains("--width"), "{e}");
    assert!(!Path::new(out).exists());
}

#[test]
fn stats_into_a_closed_pipe_exits_quietly() {
    use std::io::Read;
    use std::process::Stdio;
    // a timeline of 17,000 windows: far more JSON than a pipe buffer holds
    for _ in 0..5 {
        let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("ctcal"))
            .args(["stats", real("ijrr_slider_depth_50k").to_str().unwrap()])
            .args(["--window", "0.00001", "--json", "-"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = [0u8; 100];
        child.stdout.take().unwrap().read_exact(&mut first).unwrap();
        // the reader (`head`) is gone now
        let output = child.wait_with_output().unwrap();
        assert_eq!(
            output.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        assert!(
            output.stderr.is_empty(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
    }
}

#[test]
fn convert_writes_what_the_extension_says_or_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let input = real("ijrr_slider_depth_50k");
    let input = input.to_str().unwrap();
    let raw = dir.path().join("x.raw");
    ctcal()
        .args(["convert", input, "--out"])
        .arg(&raw)
        .assert()
        .success();
    assert!(raw.is_file(), "a .raw output is an EVT3 file, not a folder");
    assert_eq!(json(&["info", raw.to_str().unwrap()])["format"], "evt3");
    for ext in ["aedat4", "dat", "csv"] {
        let out = dir.path().join(format!("x.{ext}"));
        let e = bad_input(&["convert", input, "--out", out.to_str().unwrap()]);
        assert!(
            e.contains(&format!(".{ext}")) && e.contains("--to ijrr") && e.contains("--to evt3"),
            "{e}"
        );
        assert!(!out.exists());
    }
}

#[test]
fn jittered_events_stay_sorted_inside_the_simulated_span() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(
        dir.path(),
        "p.toml",
        b"ct_on = 0.3\nct_off = 0.3\ntimestamp_jitter_s = 0.0005\nseed = 3\n",
    );
    let out = dir.path().join("o");
    ctcal()
        .args([
            "simulate",
            "--params",
            &params,
            "--frames",
            oracle("a_ideal_texture").to_str().unwrap(),
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let events = read_events(&out);
    let frames = ctcal::io::FrameList::read(&oracle("a_ideal_texture").join("images.txt")).unwrap();
    let (first, last) = (frames.entries[0].t, frames.entries.last().unwrap().t);
    assert!(events.is_time_sorted());
    assert!(
        events.t[0] >= first && *events.t.last().unwrap() <= last,
        "{} .. {}",
        events.t[0],
        events.t.last().unwrap()
    );
}

#[test]
fn messages_give_the_right_advice() {
    let dir = tempfile::tempdir().unwrap();
    // a PNG is not an event recording
    let png = real("ijrr_slider_depth_50k").join("images/frame_00000000.png");
    let e = bad_input(&["stats", png.to_str().unwrap()]);
    assert!(
        e.contains("PNG image, not an event recording") && !e.contains("--format"),
        "{e}"
    );
    // a forced format that does not fit says so
    let e = bad_input(&[
        "stats",
        real("evk4_faery_evt3.raw").to_str().unwrap(),
        "--format",
        "evt2",
    ]);
    assert!(
        e.contains("--format evt2 does not fit") && e.contains("evt3"),
        "{e}"
    );
    let text = write(dir.path(), "e.txt", b"0.1 1 1 1\n");
    let e = bad_input(&["stats", &text, "--format", "aedat4"]);
    assert!(e.contains("--format aedat4 does not fit"), "{e}");
    assert!(!e.contains("Some("), "{e}");
}

/// An `.npy` file whose header claims `shape` of `descr` values, followed by `data` bytes.
fn npy_claiming(path: &Path, descr: &str, shape: &str, data: usize) {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while !(10 + header.len() + 1).is_multiple_of(64) {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.resize(bytes.len() + data, 0);
    std::fs::write(path, bytes).unwrap();
}

/// CRC-32 of PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A grey PNG of `width` x `height` zeros, written row by row: a few hundred KB that decode
/// to `width * height` bytes.
fn png_of_zeros(path: &Path, width: u32, height: u32) {
    use std::io::Write;
    let mut deflate = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    let row = vec![0u8; width as usize + 1];
    for _ in 0..height {
        deflate.write_all(&row).unwrap();
    }
    let data = deflate.finish().unwrap();
    let chunk = |out: &mut Vec<u8>, kind: &[u8], body: &[u8]| {
        out.extend_from_slice(&(body.len() as u32).to_be_bytes());
        let mut typed = kind.to_vec();
        typed.extend_from_slice(body);
        out.extend_from_slice(&typed);
        out.extend_from_slice(&crc32(&typed).to_be_bytes());
    };
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    chunk(&mut png, b"IDAT", &data);
    chunk(&mut png, b"IEND", &[]);
    std::fs::write(path, png).unwrap();
}

/// Every command that takes `--mask`, on the slider recording (it has frames, for `fit` and
/// `report`); `out` is the report folder.
fn mask_commands<'a>(input: &'a str, mask: &'a str, out: &'a str) -> Vec<Vec<&'a str>> {
    vec![
        vec!["stats", input, "--mask", mask],
        vec!["estimate", "eppps", input, "--mask", mask],
        vec!["fit", input, "--mask", mask],
        vec!["report", input, "--no-fit", "--mask", mask, "--out", out],
    ]
}

#[test]
fn masks_are_checked_against_the_sensor_before_they_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let input = real("ijrr_slider_depth_50k");
    let input = input.to_str().unwrap();
    let out = dir.path().join("report");
    let out = out.to_str().unwrap();
    // a 1 KB .npy claiming 100000 x 100000 bytes (10 GB): used to be allocated
    let huge = dir.path().join("huge.npy");
    npy_claiming(&huge, "|u1", "(100000, 100000)", 1000);
    // the sensor's shape, but the data cut short
    let short = dir.path().join("short.npy");
    npy_claiming(&short, "<f8", "(180, 240)", 1000);
    // a 400 KB PNG that decodes to 20000 x 20000 (400 MB grey, 1.6 GB as RGBA)
    let bomb = dir.path().join("bomb.png");
    png_of_zeros(&bomb, 20_000, 20_000);
    assert!(std::fs::metadata(&bomb).unwrap().len() < 1 << 20);
    for (mask, expected) in [
        (&huge, "shape (100000, 100000)"),
        (&short, "holds 1000 bytes"),
        (&bomb, "20000x20000"),
    ] {
        let mask = mask.to_str().unwrap();
        for args in mask_commands(input, mask, out) {
            let started = Instant::now();
            let e = bad_input(&args);
            assert!(
                started.elapsed() < Duration::from_secs(20),
                "{args:?}: {:?}",
                started.elapsed()
            );
            assert!(
                e.contains(mask) && e.contains(expected) && e.contains("fix:"),
                "{args:?}: {e}"
            );
        }
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        3,
        "no report folder or partial copy left"
    );
}

#[test]
fn a_mask_that_keeps_no_pixel_is_an_error_naming_it_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    let input = real("ijrr_slider_depth_50k");
    let input = input.to_str().unwrap();
    let out = dir.path().join("report");
    let out = out.to_str().unwrap();
    let png = dir.path().join("nothing.png");
    image::GrayImage::new(240, 180).save(&png).unwrap();
    let npy = dir.path().join("nothing.npy");
    ndarray_npy::write_npy(&npy, &ndarray::Array2::<f32>::zeros((180, 240))).unwrap();
    for mask in [&png, &npy] {
        let mask = mask.to_str().unwrap();
        for args in mask_commands(input, mask, out) {
            let e = bad_input(&args);
            assert!(
                e.contains(&format!("the mask {mask} keeps no pixel"))
                    && e.contains("fix:")
                    && !e.contains("time window"),
                "{args:?}: {e}"
            );
        }
    }
    // inside a region: the message says so
    let mut corner = ndarray::Array2::<u8>::zeros((180, 240));
    corner[[0, 0]] = 1;
    ndarray_npy::write_npy(&npy, &corner).unwrap();
    let e = bad_input(&[
        "fit",
        input,
        "--roi",
        "100,100,200,150",
        "--mask",
        npy.to_str().unwrap(),
    ]);
    assert!(
        e.contains("keeps no pixel inside the region x 100..200, y 100..150"),
        "{e}"
    );
    assert!(!Path::new(out).exists());
}

#[test]
fn a_huge_sensor_keeps_state_only_for_the_area_its_events_reach() {
    let dir = tempfile::tempdir().unwrap();
    // a Prophesee header claiming 65535 x 65535: the error used to suggest --sensor
    // 65535x65535, which then asked for a 68.7 GB grid and aborted
    let mut raw = b"% evt 3.0\n% geometry 65535x65535\n% end\n".to_vec();
    raw.extend_from_slice(&[0x00, 0x80, 0x00, 0x60, 0x05, 0x20]);
    let raw = write(dir.path(), "huge.raw", &raw);
    let e = bad_input(&["stats", &raw]);
    assert!(
        e.contains("huge.raw")
            && e.contains("geometry")
            && e.contains("65535x65535")
            && e.contains("--sensor WxH with the camera's real size")
            && e.contains("--sensor 65535x65535"),
        "{e}"
    );
    // both fixes it suggests work (the memory is asserted in tests/hostile.rs)
    for sensor in ["65535x65535", "640x480"] {
        let s = json(&["stats", &raw, "--sensor", sensor]);
        assert_eq!(s["events"], 1, "{sensor}");
    }
    // events that do spread over such a sensor: refused with the area and the fixes, and
    // nothing written
    let far = write(dir.path(), "far.txt", b"0.1 1 1 1\n0.2 60000 60000 0\n");
    let out = dir.path().join("s.json");
    let e = bad_input(&[
        "stats",
        &far,
        "--sensor",
        "65535x65535",
        "--json",
        out.to_str().unwrap(),
    ]);
    assert!(
        e.contains("far.txt")
            && e.contains("x = 60000, y = 60000")
            && e.contains("--sensor WxH")
            && e.contains("--force"),
        "{e}"
    );
    assert!(!out.exists());
    // the estimators (and a selection) hold maps of the whole sensor: refused, naming the
    // area the events reach
    let e = bad_input(&["estimate", "eppps", &raw, "--sensor", "65535x65535"]);
    assert!(
        e.contains("huge.raw")
            && e.contains("65535x65535 sensor")
            && e.contains("the events reach x = 5, y = 0")
            && e.contains("--force"),
        "{e}"
    );
    let e = bad_input(&[
        "stats",
        &raw,
        "--sensor",
        "65535x65535",
        "--roi",
        "0,0,10,10",
    ]);
    assert!(
        e.contains("--roi") && e.contains("budget") && e.contains("--sensor WxH"),
        "{e}"
    );
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, vec!["far.txt", "huge.raw"]);
}

/// Events of the real slider recording (no frames) under a first line stating `size`.
fn slider_events_stating(dir: &Path, name: &str, size: &str) -> String {
    let events = std::fs::read_to_string(real("ijrr_slider_depth_50k").join("events.txt")).unwrap();
    let body: String = events
        .lines()
        .skip(1)
        .take(20_000)
        .map(|l| format!("{l}\n"))
        .collect();
    let folder = dir.join(name);
    std::fs::create_dir(&folder).unwrap();
    write(&folder, "events.txt", format!("{size}\n{body}").as_bytes());
    folder.to_string_lossy().into_owned()
}

#[test]
fn a_stated_sensor_far_beyond_the_events_gives_way_to_their_reach() {
    // a hostile round's header claimed 4096x4096 over a 1280x720 camera: the estimators'
    // maps (682 MB for fit) and the hot-pixel share followed the claim
    let dir = tempfile::tempdir().unwrap();
    let honest = json(&[
        "estimate",
        "eppps",
        &slider_events_stating(dir.path(), "honest", "240 180"),
    ]);
    let claimed = slider_events_stating(dir.path(), "claimed", "4096 4096");
    let lying = json(&["estimate", "eppps", &claimed]);
    assert_eq!(lying["ct_on"], honest["ct_on"]);
    assert_eq!(lying["ct_off_ci95"], honest["ct_off_ci95"]);
    assert!(
        strings(&lying["assumptions"])
            .iter()
            .any(|a| a.contains("cover those 43200 pixels, not the 16777216 stated")),
        "{}",
        lying["assumptions"]
    );
    // a size given stands as given
    let given = json(&["estimate", "eppps", &claimed, "--sensor", "240x180"]);
    assert_eq!(given["ct_on"], honest["ct_on"]);
    assert!(
        !strings(&given["assumptions"])
            .iter()
            .any(|a| a.contains("4096x4096 stated"))
    );
}

#[test]
fn duplicated_events_are_named_in_the_estimates_assumptions() {
    // a hostile round doubled every event of the slider recording: eppps moved from 0.378
    // to 0.248 without a word
    let dir = tempfile::tempdir().unwrap();
    let slider = real("ijrr_slider_depth_50k");
    let doubled: String = std::fs::read_to_string(slider.join("events.txt"))
        .unwrap()
        .lines()
        .flat_map(|l| [l, l])
        .map(|l| format!("{l}\n"))
        .collect();
    write(dir.path(), "events.txt", doubled.as_bytes());
    for name in ["images.txt", "images"] {
        let to = dir.path().join(name);
        if name == "images" {
            std::fs::create_dir(&to).unwrap();
            for f in std::fs::read_dir(slider.join(name)).unwrap() {
                let f = f.unwrap().path();
                std::fs::copy(&f, to.join(f.file_name().unwrap())).unwrap();
            }
        } else {
            std::fs::copy(slider.join(name), &to).unwrap();
        }
    }
    let repeats = |output: &serde_json::Value| -> Vec<String> {
        strings(&output["assumptions"])
            .into_iter()
            .filter(|a| a.contains("same microsecond"))
            .map(String::from)
            .collect()
    };
    let out = json(&["estimate", "eppps", dir.path().to_str().unwrap()]);
    assert_eq!(
        repeats(&out),
        vec![
            "events: 50000 of 100000 (50.0 %) repeat their pixel's previous event in the same microsecond, and every estimate counts them as events; a camera's pixel fires at most once in its refractory period, so they come from a simulator that gives all crossings of a step one time, or from a file whose events were duplicated (then remove the copies: each is counted twice)"
        ]
    );
    let original = json(&["estimate", "eppps", slider.to_str().unwrap()]);
    assert!(repeats(&original).is_empty());
}

#[test]
fn noise_and_blur_beyond_the_budget_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let run = |params: &str, frames: &str| {
        let path = write(dir.path(), "p.toml", params.as_bytes());
        let mut cmd = ctcal();
        cmd.args(["simulate", "--params", &path, "--frames"])
            .arg(oracle(frames))
            .arg("--out")
            .arg(&out);
        cmd.output().unwrap()
    };
    // an earlier output, which a refused run must leave as it is
    assert!(
        run("ct_on = 0.3\nct_off = 0.3\n", "a_ideal_texture")
            .status
            .success()
    );
    let before = std::fs::read(out.join("events.txt")).unwrap();
    let display =
        "[display]\nrefresh_hz = 75.0\ngamma = 2.0\nblack_level = 0.005\nwhite_dn = 200.0\n";
    for (extra, frames, expected) in [
        // used to abort after 21 s and 4.6 GB, leaving a partial output
        (
            "leak_rate_hz = 1e9",
            "a_ideal_texture",
            "`leak_rate_hz` is 1e9",
        ),
        // used to abort after 42 s and 6 GB
        (
            "shot_noise_rate_hz = 1e7",
            "a_ideal_texture",
            "`shot_noise_rate_hz` is 1e7",
        ),
        // within one event a microsecond, but 4e9 events
        (
            "leak_rate_hz = 1e5",
            "a_ideal_texture",
            "lower leak_rate_hz",
        ),
        (
            "shot_noise_rate_hz = 2e4",
            "a_ideal_texture",
            "lower shot_noise_rate_hz",
        ),
        // used to run 110 s and write 7.3 GB
        (
            "hot_pixel_fraction = 0.01\nhot_pixel_rate_hz = 1e6",
            "a_ideal_texture",
            "lower hot_pixel_rate_hz",
        ),
        // used to run for minutes (a kernel of 6 million taps)
        (
            &format!("{display}blur_px = 1e6\n"),
            "dev_screen_checker",
            "`display.blur_px` is 1e6",
        ),
        (
            &format!("{display}blur_px = 1000.0\n"),
            "dev_screen_checker",
            "the display blur (display.blur_px)",
        ),
    ] {
        let started = Instant::now();
        let output = run(&format!("ct_on = 0.3\nct_off = 0.3\n{extra}\n"), frames);
        let e = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{extra}: {e}");
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "{extra}: {:?}",
            started.elapsed()
        );
        assert!(
            e.contains("p.toml") && e.contains(expected) && e.contains("fix:"),
            "{extra}: {e}"
        );
        assert_eq!(std::fs::read(out.join("events.txt")).unwrap(), before);
        let mut left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(
            left,
            vec!["p.toml", "sim"],
            "{extra}: a partial output left"
        );
    }
}

#[test]
fn frame_times_are_finite_and_in_order_in_every_reader() {
    let dir = tempfile::tempdir().unwrap();
    // v2e frame_ts stored as floats: NaN used to become i64::MIN, a median frame interval
    // of -9.2e12 s
    for (name, times, place, problem) in [
        ("nan.h5", [f64::NAN, 1000.0, 2000.0], "frame_ts[0]", "NaN"),
        (
            "inf.h5",
            [1000.0, f64::INFINITY, 3000.0],
            "frame_ts[1]",
            "inf",
        ),
        (
            "order.h5",
            [2000.0, 1000.0, 3000.0],
            "frame_ts[1]",
            "earlier",
        ),
    ] {
        let path = dir.path().join(name);
        {
            let file = h5_create(&path);
            file.new_dataset_builder()
                .with_data(&ndarray::arr2(&[[1000u32, 1, 1, 1], [2000, 2, 2, 0]]))
                .create("events")
                .unwrap();
            file.new_dataset_builder()
                .with_data(&ndarray::Array3::<u8>::zeros((3, 4, 4)))
                .create("frame")
                .unwrap();
            file.new_dataset_builder()
                .with_data(&times)
                .create("frame_ts")
                .unwrap();
        }
        for command in ["stats", "info"] {
            let e = bad_input(&[command, path.to_str().unwrap(), "--sensor", "8x8"]);
            assert!(
                e.contains(name) && e.contains(place) && e.contains(problem) && e.contains("fix:"),
                "{name} {command}: {e}"
            );
        }
    }
    // an IJRR frame list with a time beyond any clock
    let rec = dir.path().join("rec");
    std::fs::create_dir_all(rec.join("images")).unwrap();
    std::fs::write(rec.join("events.txt"), "0.1 1 1 1\n0.2 2 2 0\n").unwrap();
    for name in ["a.png", "b.png"] {
        image::GrayImage::new(4, 4)
            .save(rec.join("images").join(name))
            .unwrap();
    }
    std::fs::write(
        rec.join("images.txt"),
        "0.1 images/a.png\n3e12 images/b.png\n",
    )
    .unwrap();
    let e = bad_input(&["stats", rec.to_str().unwrap()]);
    assert!(
        e.contains("images.txt") && e.contains("line 2") && e.contains("beyond"),
        "{e}"
    );
}
