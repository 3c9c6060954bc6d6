//! A report a researcher can hand on (issue 17): it survives a bad recording, shows every
//! caveat of results.json on the page and in report.md, groups by dataset name or sensor
//! and never combines sensors, writes configurations a shell runs as they are, and exports
//! the hot-pixel masks in the form `--mask` reads.

use crate::common::{bad_input, ctcal, json, oracle, succeeded};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn samples(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data_samples")
        .join(name)
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn text(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// An IJRR folder whose events.txt breaks on its second line.
fn corrupted(dir: &Path) -> PathBuf {
    let broken = dir.join("broken_ijrr");
    std::fs::create_dir_all(&broken).unwrap();
    std::fs::write(
        broken.join("events.txt"),
        "0.000100 5 5 1\nthis is not an event\n0.000300 6 6 0\n",
    )
    .unwrap();
    broken
}

/// The texture and the on-screen samples (no fit, for speed) beside a corrupted recording:
/// (work folder, report folder, exit code, stderr).
fn with_a_corrupted_recording() -> &'static (tempfile::TempDir, PathBuf, Option<i32>, String) {
    static RUN: OnceLock<(tempfile::TempDir, PathBuf, Option<i32>, String)> = OnceLock::new();
    RUN.get_or_init(|| {
        let work = tempfile::tempdir().unwrap();
        let broken = corrupted(work.path());
        let out = work.path().join("report");
        let output = ctcal()
            .arg("report")
            .arg(samples("texture_davis240c"))
            .arg(&broken)
            .arg(samples("screen_checkerboard"))
            .args(["--no-fit", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        (work, out, output.status.code(), stderr)
    })
}

#[test]
fn a_corrupted_recording_is_listed_and_the_others_are_written() {
    let (_work, out, code, stderr) = with_a_corrupted_recording();
    // the recording failed on its input: exit 2, its error (with the fix) repeated
    assert_eq!(
        *code,
        Some(2),
        "exit 2 when some recordings failed on their input: {stderr}"
    );
    assert!(
        stderr.contains("1 of 3 recordings could not be reported")
            && stderr.contains("broken_ijrr: ")
            && stderr.contains("fix:"),
        "{stderr}"
    );
    let r = read_json(&out.join("results.json"));
    let names: Vec<&str> = r["sequences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["texture_davis240c", "screen_checkerboard"]);
    let failed = r["failed"].as_array().unwrap();
    assert_eq!(failed.len(), 1);
    assert_eq!(failed[0]["name"], "broken_ijrr");
    let error = failed[0]["error"].as_str().unwrap();
    assert!(
        error.contains("events.txt"),
        "the error names the file: {error}"
    );
    // the good sequences are whole: their plots, masks and tables are written
    for file in [
        "plots/texture_davis240c/thresholds.png",
        "plots/screen_checkerboard/thresholds.png",
        "masks/texture_davis240c/hot_pixels.npy",
        "tables/texture_davis240c/statistics.parquet",
        "tables/statistics.csv",
    ] {
        assert!(out.join(file).is_file(), "{file}");
    }
    assert!(!out.join("plots/broken_ijrr").exists());
    // the failure is on the page and in report.md, with its error
    let first_line = error.lines().next().unwrap();
    let one_line: String = first_line.split_whitespace().collect::<Vec<_>>().join(" ");
    let html = text(&out.join("index.html"));
    assert!(html.contains("id=\"failed\"") && html.contains("broken_ijrr"));
    assert!(html.contains(&escape(&one_line)), "{one_line} on the page");
    let md = text(&out.join("report.md"));
    assert!(md.contains("## Recordings that failed") && md.contains(&one_line));
}

#[test]
fn a_report_of_nothing_but_a_bad_recording_is_bad_input_and_writes_nothing() {
    let work = tempfile::tempdir().unwrap();
    let broken = corrupted(work.path());
    let out = work.path().join("report");
    let e = bad_input(&[
        "report",
        broken.to_str().unwrap(),
        "--no-fit",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(e.contains("events.txt"), "{e}");
    assert!(!out.exists(), "nothing written");
}

/// Text as the page escapes it.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Every assumption, "why" and warning of results.json.
fn caveats(r: &Value) -> Vec<String> {
    let mut out = Vec::new();
    let mut strings = |v: &Value| match v {
        Value::Array(a) => out.extend(a.iter().filter_map(|s| s.as_str().map(String::from))),
        Value::Object(o) => out.extend(o.values().filter_map(|s| s.as_str().map(String::from))),
        _ => {}
    };
    for s in r["sequences"].as_array().unwrap() {
        strings(&s["warnings"]);
        for m in s["methods"].as_array().unwrap() {
            strings(&m["estimate"]["assumptions"]);
            strings(&m["estimate"]["why"]);
        }
        strings(&s["fit"]["assumptions"]);
        strings(&s["fit"]["why"]);
    }
    for d in r["datasets"].as_array().unwrap() {
        strings(&d["warnings"]);
    }
    out.into_iter()
        .map(|c| c.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect()
}

#[test]
fn every_caveat_of_results_json_is_on_the_page_and_in_report_md() {
    let report = crate::report::sample_report();
    let r = read_json(&report.join("results.json"));
    let all = caveats(&r);
    // the sample's estimates carry many assumptions (noise, travel, prior, extrapolations)
    assert!(all.len() >= 10, "{} caveats: {all:#?}", all.len());
    let html = text(&report.join("index.html"));
    let md = text(&report.join("report.md"));
    for c in &all {
        assert!(html.contains(&escape(c)), "on the page: {c}");
        assert!(md.contains(c.as_str()), "in report.md: {c}");
    }
    // an extrapolated or undeterminable value is flagged beside its number
    let (_, out, _, _) = with_a_corrupted_recording();
    let r = read_json(&out.join("results.json"));
    let html = text(&out.join("index.html"));
    for c in caveats(&r) {
        assert!(html.contains(&escape(&c)), "on the page: {c}");
    }
}

#[test]
fn the_page_has_contents_a_glossary_and_tables_with_units() {
    let (_, out, _, _) = with_a_corrupted_recording();
    let html = text(&out.join("index.html"));
    for part in [
        "id=\"contents\"",
        "href=\"#seq-texture_davis240c\"",
        "id=\"seq-texture_davis240c\"",
        "id=\"glossary\"",
        "<dt>evidence</dt>",
        "<dt>held-out error</dt>",
        "<dt>distance components</dt>",
        "<th>duration (s)</th>",
        "<th>background rate (Hz)</th>",
    ] {
        assert!(html.contains(part), "{part} on the page");
    }
    // no fit: the CSV keeps its fit columns, the page hides them (they are empty)
    let csv = text(&out.join("tables/datasets.csv"));
    assert!(csv.lines().next().unwrap().contains("ct_fit"));
    assert!(!html.contains("ct fit (ln)"), "an empty column is hidden");
    // PNGs for print
    let png = std::fs::read(out.join("plots/texture_davis240c/threshold_maps.png")).unwrap();
    let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
    assert!(width >= 1800, "{width} px wide");
}

#[test]
fn datasets_group_by_name_or_sensor_and_say_when_they_mix_sensors() {
    let work = tempfile::tempdir().unwrap();
    // loose recordings of two sensors in one folder: one dataset per sensor
    let loose = work.path().join("loose");
    ctcal()
        .arg("report")
        .arg(samples("texture_davis240c"))
        .arg(samples("screen_checkerboard"))
        .args(["--no-fit", "--out"])
        .arg(&loose)
        .assert()
        .success();
    let r = read_json(&loose.join("results.json"));
    let datasets: Vec<(&str, &Value)> = r["datasets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| (d["name"].as_str().unwrap(), &d["sensors"]))
        .collect();
    assert_eq!(
        datasets,
        [
            ("data_samples_240x180", &serde_json::json!(["240x180"])),
            ("data_samples_120x90", &serde_json::json!(["120x90"]))
        ]
    );
    // a dataset the user names stays whole, with a warning on the page
    let named = work.path().join("named");
    let output = ctcal()
        .arg("report")
        .arg("--dataset")
        .arg(format!("mine={}", samples("texture_davis240c").display()))
        .arg("--dataset")
        .arg(format!("mine={}", samples("screen_checkerboard").display()))
        .args(["--no-fit", "--out"])
        .arg(&named)
        .output()
        .unwrap();
    assert!(output.status.success());
    let r = read_json(&named.join("results.json"));
    let d = &r["datasets"][0];
    assert_eq!(r["datasets"].as_array().unwrap().len(), 1);
    assert_eq!(d["name"], "mine");
    assert_eq!(d["sensors"], serde_json::json!(["240x180", "120x90"]));
    let warning = d["warnings"][0].as_str().unwrap();
    assert!(warning.contains("mixes sensors") && warning.contains("240x180: 1 sequence"));
    assert!(text(&named.join("index.html")).contains(&escape(warning)));
}

#[test]
fn config_refuses_to_combine_sensors() {
    let work = tempfile::tempdir().unwrap();
    let mut r = read_json(&crate::report::sample_report().join("results.json"));
    // the fitted texture twice, once as if from a DAVIS346
    let sequences = r["sequences"].as_array_mut().unwrap();
    let mut other = sequences
        .iter()
        .find(|s| s["name"] == "texture_davis240c")
        .unwrap()
        .clone();
    other["name"] = "texture_davis346".into();
    other["stats"]["width"] = 346.into();
    other["stats"]["height"] = 260.into();
    sequences.push(other);
    let dir = work.path().join("mixed_report");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(dir.join("results.json"), r.to_string()).unwrap();
    let e = bad_input(&["config", dir.to_str().unwrap(), "--format", "v2e"]);
    assert!(
        e.contains("3 sensors")
            && e.contains("120x90: screen_checkerboard")
            && e.contains("240x180: texture_davis240c")
            && e.contains("346x260: texture_davis346")
            && e.contains("fix:"),
        "{e}"
    );
}

#[test]
fn config_refuses_a_fit_whose_thresholds_are_not_identified() {
    let work = tempfile::tempdir().unwrap();
    let r = read_json(&crate::report::sample_report().join("results.json"));
    let mut fit = r["sequences"][1]["fit"].clone();
    assert!(fit["params"]["ct_on"].is_f64(), "{fit:#}");
    fit["params"]["ct_on"] = Value::Null;
    fit["why"] = serde_json::json!({"ct_on": "a static scene"});
    let path = work.path().join("fit.json");
    std::fs::write(&path, fit.to_string()).unwrap();
    let e = bad_input(&["config", path.to_str().unwrap(), "--format", "v2e"]);
    assert!(
        e.contains("ct_on") && e.contains("a static scene") && e.contains("does not identify"),
        "{e}"
    );
}

/// A stand-in for v2e that prints its arguments, one a line.
fn stub(dir: &Path) -> PathBuf {
    let path = dir.join("v2e_stub.sh");
    std::fs::write(
        &path,
        "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\n' \"$a\"; done\n",
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    path
}

#[test]
fn the_v2e_script_runs_as_it_is_and_matches_its_json() {
    let report = crate::report::sample_report();
    let dir = report.join("configs/texture_davis240c");
    let script = dir.join("v2e_args.sh");
    let syntax = std::process::Command::new("bash")
        .arg("-n")
        .arg(&script)
        .status()
        .unwrap();
    assert!(syntax.success(), "bash -n {}", script.display());
    let work = tempfile::tempdir().unwrap();
    let output = succeeded(
        std::process::Command::new("sh")
            .arg(&script)
            .args(["-i", "my video.mp4"])
            .env("V2E", stub(work.path()))
            .output(),
    );
    let argv: Vec<String> = String::from_utf8(output.stdout)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    // the caller's arguments last, whole
    assert_eq!(argv[argv.len() - 2..], ["-i", "my video.mp4"]);
    let v2e = read_json(&dir.join("v2e_args.json"));
    let listed: Vec<String> = v2e["argv"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap().to_string())
        .collect();
    assert_eq!(argv[..argv.len() - 2], listed[..]);
    let value = |flag: &str| -> f64 {
        let i = argv
            .iter()
            .position(|a| a == flag)
            .unwrap_or_else(|| panic!("{flag}"));
        argv[i + 1].parse().unwrap()
    };
    let r = read_json(&report.join("results.json"));
    let fit = &r["sequences"][1]["fit"]["params"];
    assert!((value("--pos_thres") - fit["ct_on"].as_f64().unwrap()).abs() < 1e-6);
    assert!((value("--neg_thres") - fit["ct_off"].as_f64().unwrap()).abs() < 1e-6);
    assert_eq!(value("--output_width"), 240.0);
    assert_eq!(value("--output_height"), 180.0);
    assert_eq!(v2e["arguments"]["output_width"], 240);
    assert_eq!(v2e["arguments"]["dvs_emulator_seed"], 2020);
    // a whole esim_config_generator file, with the sensor
    let generator = read_json(&dir.join("esim_config_generator.json"));
    for key in [
        "foreground_params",
        "background_params",
        "foreground_images",
        "background_images",
        "camera_params",
    ] {
        assert!(generator[key].is_object(), "{key}");
    }
    assert_eq!(generator["ctcal_sensor"]["width"], 240);
}

#[test]
fn the_hot_pixel_mask_reads_back_with_mask() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("report");
    let case = oracle("dev_hot_pixels");
    ctcal()
        .arg("report")
        .arg(&case)
        .args(["--no-fit", "--out"])
        .arg(&out)
        .assert()
        .success();
    let r = read_json(&out.join("results.json"));
    let s = &r["sequences"][0];
    let hot = s["stats"]["hot_pixels"].as_array().unwrap();
    assert!(!hot.is_empty(), "the case has hot pixels");
    let name = s["name"].as_str().unwrap();
    let npy = out.join(format!("masks/{name}/hot_pixels.npy"));
    let png = out.join(format!("masks/{name}/hot_pixels.png"));
    let array: ndarray::Array2<u8> = ndarray_npy::read_npy(&npy).unwrap();
    assert_eq!(array.dim(), (180, 240));
    assert_eq!(array.iter().filter(|&&v| v == 0).count(), hot.len());
    for p in hot {
        let (x, y) = (
            p["x"].as_u64().unwrap() as usize,
            p["y"].as_u64().unwrap() as usize,
        );
        assert_eq!(array[[y, x]], 0, "hot pixel ({x}, {y}) masked");
    }
    let image = image::open(&png).unwrap().to_luma8();
    assert_eq!(image.dimensions(), (240, 180));
    assert_eq!(image.pixels().filter(|p| p.0[0] == 0).count(), hot.len());
    // both read back by --mask: the hot pixels are left out
    let whole = json(&["stats", case.to_str().unwrap()]);
    for mask in [&npy, &png] {
        let masked = json(&[
            "stats",
            case.to_str().unwrap(),
            "--mask",
            mask.to_str().unwrap(),
        ]);
        assert_eq!(
            masked["pixels_kept"].as_u64().unwrap(),
            240 * 180 - hot.len() as u64,
            "{}",
            mask.display()
        );
        assert!(masked["events"].as_u64().unwrap() < whole["events"].as_u64().unwrap());
        assert_eq!(masked["hot_pixels"].as_array().unwrap().len(), 0);
    }
}

/// Two recordings of one sensor at different bias settings (a Prophesee `.bias` file beside
/// each): the report carries each recording's biases in `results.json` and tabulates the
/// thresholds and noise beside the bias that differs (measured pairs, issue 16).
#[test]
fn recordings_of_one_sensor_at_different_biases_are_tabulated_beside_them() {
    let work = tempfile::tempdir().unwrap();
    let source = crate::common::real("gen3_faery_evt2.raw");
    for (name, diff_on) in [("low", 370), ("high", 400)] {
        std::fs::copy(&source, work.path().join(format!("{name}.raw"))).unwrap();
        std::fs::write(
            work.path().join(format!("{name}.bias")),
            format!("299 % bias_diff\n228 % bias_diff_off\n{diff_on} % bias_diff_on\n"),
        )
        .unwrap();
    }
    let out = work.path().join("report");
    succeeded(
        ctcal()
            .arg("report")
            .arg(work.path().join("low.raw"))
            .arg(work.path().join("high.raw"))
            .args(["--no-fit", "--out"])
            .arg(&out)
            .output(),
    );
    let r = read_json(&out.join("results.json"));
    let diff_on: Vec<i64> = r["sequences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            s["stats"]["biases"]["values"]["bias_diff_on"]
                .as_i64()
                .unwrap()
        })
        .collect();
    assert_eq!(diff_on, [370, 400]);
    let csv = std::fs::read_to_string(out.join("tables/bias_sweep.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(
        header.starts_with("sequence,sensor,bias_diff_on,ct_on,ct_off,"),
        "{header}"
    );
    // only the bias that differs is a column
    assert!(!header.contains("bias_diff_off"), "{header}");
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 2, "{csv}");
    assert!(
        rows[0].starts_with("low_raw,640x480,370") && rows[1].starts_with("high_raw,640x480,400"),
        "{csv}"
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        md.contains("beside the biases that differ") && md.contains("| bias diff on |"),
        "{md}"
    );
    // and plotted against the bias: one point per recording, the same file twice gives the
    // same background rate at both settings
    assert!(md.contains("](plots/bias_sweep_bias_diff_on.png)"), "{md}");
    assert!(out.join("plots/bias_sweep_bias_diff_on.svg").is_file());
    let plot = std::fs::read_to_string(out.join("plots/bias_sweep_bias_diff_on.csv")).unwrap();
    let background: Vec<(f64, f64)> = plot
        .lines()
        .filter_map(|l| l.strip_prefix("background rate,background,"))
        .map(|l| {
            let (x, y) = l.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect();
    assert_eq!(background.len(), 2, "{plot}");
    assert_eq!((background[0].0, background[1].0), (370.0, 400.0), "{plot}");
    assert!(
        background[0].1 > 0.0 && background[0].1 == background[1].1,
        "{plot}"
    );
}
