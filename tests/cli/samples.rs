//! The committed samples are exactly what ctcal generates from the committed presets.

use crate::common::*;
use std::path::Path;

/// Every file of `committed` is byte for byte the same in `fresh`.
fn same_files(committed: &Path, fresh: &Path) {
    let mut files = Vec::new();
    let mut folders = vec![committed.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path.file_name().is_some_and(|n| n != ".ctcal-output.json") {
                files.push(path.strip_prefix(committed).unwrap().to_path_buf());
            }
        }
    }
    assert!(files.len() > 5, "{}", committed.display());
    for file in files {
        let a = std::fs::read(committed.join(&file)).unwrap();
        let b = std::fs::read(fresh.join(&file)).unwrap_or_default();
        assert!(
            a == b,
            "{} differs from a fresh run",
            committed.join(&file).display()
        );
    }
}

#[test]
fn committed_samples_are_what_ctcal_generates() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    // the textured scene through a DAVIS240C-like pixel
    let fresh = dir.path().join("texture_davis240c");
    ctcal()
        .current_dir(root)
        .args(["simulate", "--params", "calib/params/davis240c_like.toml"])
        .args([
            "--scene",
            "calib/scenes/sample_texture_davis240c.toml",
            "--out",
        ])
        .arg(&fresh)
        .assert()
        .success();
    same_files(&root.join("data_samples/texture_davis240c"), &fresh);
    // the checkerboard stimulus recorded from a screen (the stimulus at the same relative
    // path as in data_samples/README.md, which simulation.json records)
    ctcal()
        .current_dir(dir.path())
        .args(["calib", "checkerboard", "--out", "target/sample_stimulus"])
        .args(["--width", "120", "--height", "90", "--square-px", "10"])
        .args(["--duration-s", "0.5", "--speed-px-s", "20"])
        .assert()
        .success();
    ctcal()
        .current_dir(dir.path())
        .arg("simulate")
        .arg("--params")
        .arg(root.join("calib/params/screen_sample.toml"))
        .args([
            "--frames",
            "target/sample_stimulus",
            "--out",
            "screen_checkerboard",
        ])
        .assert()
        .success();
    same_files(
        &root.join("data_samples/screen_checkerboard"),
        &dir.path().join("screen_checkerboard"),
    );
}

#[test]
fn the_samples_are_small_and_complete() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("data_samples");
    let s = json(&["stats", root.join("texture_davis240c").to_str().unwrap()]);
    assert_eq!(s["width"], 240);
    assert_eq!(s["frames"]["count"], 15);
    let rate = s["events_per_pixel_per_second"].as_f64().unwrap();
    assert!(rate > 1.0 && rate < 10.0, "{rate}");
    let screen = json(&["info", root.join("screen_checkerboard").to_str().unwrap()]);
    assert_eq!(
        (screen["width"].as_u64(), screen["height"].as_u64()),
        (Some(120), Some(90))
    );
    let mut bytes = 0;
    let mut folders = vec![root];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let entry = entry.unwrap();
            if entry.path().is_dir() {
                folders.push(entry.path());
            } else {
                bytes += entry.metadata().unwrap().len();
            }
        }
    }
    assert!(bytes < 5_000_000, "data_samples holds {bytes} bytes");
}
