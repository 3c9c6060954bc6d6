//! Part of a recording: `--roi`, `--mask` and `--exclude-hot-pixels`, checked against hand
//! computed values on a small recording whose every event is known.

use super::common::*;

/// An 8x8 sensor: every pixel but (5, 5) fires at `0.001 * (8y + x)` s (ON) and 0.5 s later
/// (OFF); (0, 0) fires once more at 1.0 s; (5, 5) is hot: 100 events, 0.0005 s + 10 ms apart.
fn recording() -> tempfile::TempDir {
    let mut events = Vec::new();
    for y in 0..8u32 {
        for x in 0..8u32 {
            if (x, y) != (5, 5) {
                let t = 0.001 * (8 * y + x) as f64;
                events.push((t, x, y, 1));
                events.push((0.5 + t, x, y, 0));
            }
        }
    }
    events.push((1.0, 0, 0, 1));
    for i in 0..100 {
        events.push((0.0005 + 0.01 * i as f64, 5, 5, 1));
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("8 8\n");
    for (t, x, y, p) in events {
        text.push_str(&format!("{t:.6} {x} {y} {p}\n"));
    }
    std::fs::write(dir.path().join("events.txt"), text).unwrap();
    dir
}

fn stats(dir: &tempfile::TempDir, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["stats", dir.path().to_str().unwrap()];
    args.extend(extra);
    json(&args)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9 * b.abs().max(1.0)
}

#[test]
fn rates_divide_by_the_kept_pixels() {
    let dir = recording();
    let whole = stats(&dir, &[]);
    assert_eq!(whole["events"], 227);
    assert!(close(
        whole["events_per_pixel_per_second"].as_f64().unwrap(),
        227.0 / 64.0
    ));
    assert_eq!(whole["pixels_kept"], 64);
    assert_eq!(whole["hot_pixels"][0]["x"], 5);

    // the top-left 4x4: 16 pixels x 2 events + (0, 0)'s third, over 0 .. 1.0 s
    let roi = stats(&dir, &["--roi", "0,0,4,4"]);
    assert_eq!(
        (roi["events"].as_u64(), roi["pixels_kept"].as_u64()),
        (Some(33), Some(16))
    );
    assert!(close(
        roi["events_per_pixel_per_second"].as_f64().unwrap(),
        33.0 / 16.0
    ));
    assert!(close(
        roi["on_per_pixel_per_second"].as_f64().unwrap(),
        17.0 / 16.0
    ));
    assert_eq!(roi["active_pixel_fraction"], 1.0);
    assert_eq!(roi["hot_pixels"].as_array().unwrap().len(), 0);

    // hot pixels left out: 127 events over 63 pixels and 1 s
    let cold = stats(&dir, &["--exclude-hot-pixels"]);
    assert_eq!(cold["pixels_kept"], 63);
    assert!(close(
        cold["events_per_pixel_per_second"].as_f64().unwrap(),
        127.0 / 63.0
    ));
    assert_eq!(cold["excluded_hot_pixels"][0]["y"], 5);

    // both: the bottom-right 4x4 without (5, 5): 15 pixels x 2 events, from (4, 4) at
    // 0.036 s to (7, 7) at 0.563 s
    let both = stats(&dir, &["--roi", "4,4,8,8", "--exclude-hot-pixels"]);
    assert_eq!(
        (both["events"].as_u64(), both["pixels_kept"].as_u64()),
        (Some(30), Some(15))
    );
    assert!(close(both["duration_s"].as_f64().unwrap(), 0.527));
    assert!(close(
        both["events_per_pixel_per_second"].as_f64().unwrap(),
        30.0 / (15.0 * 0.527)
    ));
    assert!(
        both["selection"]
            .as_str()
            .unwrap()
            .contains("1 hot pixels left out")
    );
}

#[test]
fn masks_from_png_and_npy_keep_their_non_zero_pixels() {
    let dir = recording();
    // keep row 0: 8 pixels, 16 events + (0, 0)'s third
    let png = dir.path().join("row0.png");
    image::GrayImage::from_fn(8, 8, |_, y| image::Luma([if y == 0 { 1 } else { 0 }]))
        .save(&png)
        .unwrap();
    let s = stats(&dir, &["--mask", png.to_str().unwrap()]);
    assert_eq!(
        (s["events"].as_u64(), s["pixels_kept"].as_u64()),
        (Some(17), Some(8))
    );
    assert!(close(
        s["events_per_pixel_per_second"].as_f64().unwrap(),
        17.0 / 8.0
    ));
    // the same rows as a .npy of another type, intersected with a region: (0..2, 0)
    let npy = dir.path().join("row0.npy");
    let mask = ndarray::Array2::from_shape_fn((8, 8), |(y, _)| if y == 0 { 1u8 } else { 0 });
    ndarray_npy::WriteNpyExt::write_npy(&mask, std::fs::File::create(&npy).unwrap()).unwrap();
    let s = stats(&dir, &["--mask", npy.to_str().unwrap(), "--roi", "0,0,2,8"]);
    assert_eq!(
        (s["events"].as_u64(), s["pixels_kept"].as_u64()),
        (Some(5), Some(2))
    );
}

#[test]
fn a_region_or_mask_that_does_not_fit_the_sensor_names_the_fix() {
    let dir = recording();
    let path = dir.path().to_str().unwrap();
    let e = bad_input(&["stats", path, "--roi", "0,0,9,8"]);
    assert!(
        e.contains(path) && e.contains("beyond the 8x8 sensor") && e.contains("X1 <= 8"),
        "{e}"
    );
    let png = dir.path().join("small.png");
    image::GrayImage::new(4, 4).save(&png).unwrap();
    let e = bad_input(&["stats", path, "--mask", png.to_str().unwrap()]);
    assert!(
        e.contains("small.png") && e.contains("4x4") && e.contains("8x8"),
        "{e}"
    );
    let e = bad_input(&["stats", path, "--roi", "3,3,3,5"]);
    assert!(e.contains("empty"), "{e}");
}
