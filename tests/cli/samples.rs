//! The committed samples are exactly what ctcal generates from the committed presets.

use crate::common::*;
use std::path::Path;

#[test]
fn committed_samples_are_what_ctcal_generates() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let committed = root.join("data_samples/texture_davis240c");
    let dir = tempfile::tempdir().unwrap();
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
    let mut files = vec![
        "events.txt".to_string(),
        "images.txt".to_string(),
        "simulation.json".to_string(),
    ];
    for entry in std::fs::read_dir(committed.join("images")).unwrap() {
        files.push(format!(
            "images/{}",
            entry.unwrap().file_name().to_string_lossy()
        ));
    }
    assert!(files.len() > 5);
    for file in files {
        let a = std::fs::read(committed.join(&file)).unwrap();
        let b = std::fs::read(fresh.join(&file)).unwrap_or_default();
        assert!(
            a == b,
            "data_samples/texture_davis240c/{file} differs from a fresh run"
        );
    }
}

#[test]
fn the_readme_main_job_runs_on_the_sample() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let s = json(&[
        "stats",
        root.join("data_samples/texture_davis240c")
            .to_str()
            .unwrap(),
    ]);
    assert_eq!(s["width"], 240);
    assert_eq!(s["frames"]["count"], 8);
    let rate = s["events_per_pixel_per_second"].as_f64().unwrap();
    assert!(rate > 1.0 && rate < 10.0, "{rate}");
}
