//! `ctcal report` and `ctcal config` on the committed data samples (recordings ctcal
//! simulated with known parameters): every part of the report is there, the estimates lie
//! beside the truth, the tables agree across formats and are snapshotted, the HTML page
//! renders in a real browser, and the configurations read back into the simulator.

use crate::common::{bad_input, ctcal, json};
use polars::prelude::*;
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn project() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The report of `data_samples`, made once for every test here (run from the project root
/// as a user would: `ctcal report data_samples --out DIR`). Under nextest every test is its
/// own process: the report is written to a folder of this process and renamed into place,
/// so that the first process to finish publishes it and the others read that one; the
/// folder is named after the binary's size and time, so a rebuilt binary makes a new one
/// (and the old ones are removed).
pub(crate) fn sample_report() -> &'static Path {
    static REPORT: OnceLock<PathBuf> = OnceLock::new();
    REPORT.get_or_init(|| {
        let tmp = Path::new(env!("CARGO_TARGET_TMPDIR"));
        let binary = std::fs::metadata(assert_cmd::cargo::cargo_bin("ctcal")).unwrap();
        let modified = binary
            .modified()
            .unwrap()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos();
        let name = format!("sample_report-{}-{modified}", binary.len());
        let out = tmp.join(&name);
        if out.join("results.json").exists() {
            return out;
        }
        remove_other_reports(tmp, &name);
        let mine = tmp.join(format!("{name}.{}", std::process::id()));
        if mine.exists() {
            std::fs::remove_dir_all(&mine).unwrap();
        }
        let output = ctcal()
            .current_dir(project())
            .args(["report", "data_samples", "--out"])
            .arg(&mine)
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "ctcal report failed: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        // another process may have published its copy first: then that one is read
        if std::fs::rename(&mine, &out).is_err() {
            std::fs::remove_dir_all(&mine).unwrap();
        }
        assert!(
            out.join("results.json").exists(),
            "{} published",
            out.display()
        );
        out
    })
}

/// Removes the sample reports of other binaries (best effort: another process may be
/// removing them too).
fn remove_other_reports(tmp: &Path, keep: &str) {
    let Ok(entries) = std::fs::read_dir(tmp) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with("sample_report") && !name.starts_with(keep) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

fn results() -> Value {
    let text = std::fs::read_to_string(sample_report().join("results.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn sequence<'a>(results: &'a Value, name: &str) -> &'a Value {
    results["sequences"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == name)
        .unwrap_or_else(|| panic!("sequence {name} in results.json"))
}

/// Every file under `dir`, relative, sorted.
fn files(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                out.push(path.strip_prefix(root).unwrap().display().to_string());
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn sha256(path: &Path) -> String {
    Sha256::digest(std::fs::read(path).unwrap())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

const TABLES: [&str; 5] = [
    "statistics",
    "thresholds",
    "fitted_parameters",
    "fit_steps",
    "datasets",
];

#[test]
fn the_sample_report_has_every_part() {
    let dir = sample_report();
    let all = files(dir);
    for part in [
        "index.html",
        "report.md",
        "results.json",
        ".ctcal-output.json",
    ] {
        assert!(all.contains(&part.to_string()), "{part} in {all:?}");
    }
    for table in TABLES {
        for ext in ["csv", "parquet", "tex", "md"] {
            let name = format!("tables/{table}.{ext}");
            assert!(all.contains(&name), "{name}");
        }
    }
    // a plot is a PNG, an SVG and the CSV of its data
    let stems = |ext: &str| -> Vec<String> {
        all.iter()
            .filter(|f| f.starts_with("plots/") && f.ends_with(ext))
            .map(|f| f.trim_end_matches(ext).to_string())
            .collect()
    };
    let pngs = stems(".png");
    assert_eq!(pngs, stems(".svg"));
    assert_eq!(pngs, stems(".csv"));
    for plot in [
        "plots/events_per_pixel_per_second",
        "plots/texture_davis240c/thresholds",
        "plots/texture_davis240c/threshold_maps",
        "plots/texture_davis240c/calibration_curve",
        "plots/texture_davis240c/fit_residuals",
        "plots/screen_checkerboard/thresholds",
    ] {
        assert!(pngs.contains(&plot.to_string()), "{plot} in {pngs:?}");
    }
    for png in &pngs {
        let bytes = std::fs::read(dir.join(format!("{png}.png"))).unwrap();
        assert_eq!(&bytes[1..4], b"PNG", "{png}");
    }
    // both recordings are fitted (the on-screen one has no frames: from its events alone):
    // every format of configuration for each, and one combined generator file per sensor
    for sequence in ["texture_davis240c", "screen_checkerboard"] {
        for name in [
            "esim.flagfile",
            "esim_config_generator.json",
            "v2e_args.sh",
            "v2e_args.json",
            "params.toml",
        ] {
            assert!(
                all.contains(&format!("configs/{sequence}/{name}")),
                "{sequence}/{name}"
            );
        }
    }
    for sensor in ["240x180", "120x90"] {
        assert!(all.contains(&format!(
            "configs/sensors/{sensor}/esim_config_generator.json"
        )));
    }

    // how it was made, and from what
    let r = results();
    assert_eq!(r["ctcal_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(r["seed"], 2020);
    let command = crate::common::strings(&r["command_line"]);
    assert_eq!(command[0], "ctcal");
    assert!(command.windows(2).any(|w| w == ["report", "data_samples"]));
    for s in r["sequences"].as_array().unwrap() {
        let inputs = s["inputs"].as_array().unwrap();
        assert!(!inputs.is_empty());
        for input in inputs {
            let path = project().join(input["path"].as_str().unwrap());
            assert_eq!(input["sha256"], sha256(&path), "{}", path.display());
            assert_eq!(
                input["bytes"].as_u64().unwrap(),
                std::fs::metadata(&path).unwrap().len()
            );
        }
    }
    // the on-screen recording has no frames: fitted from its events alone, and said so
    let screen = sequence(&r, "screen_checkerboard");
    assert!(screen["fit_not_applied"].is_null());
    let fit = &screen["fit"];
    assert!(fit["events_only"]["thresholds_source"].is_string());
    assert!(fit["params"]["ct_sigma"].is_null() && fit["why"]["ct_sigma"].is_string());

    // the Markdown report shows every PNG and every table
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for png in &pngs {
        let link = format!("]({png}.png)");
        assert!(md.contains(&link), "{link} in report.md");
    }
    // every table, headers in words with their units (the files keep machine names)
    for header in [
        "| dataset | sequences | event rate (events/px/s) |",
        "| sequence | dataset | sensor | events | duration (s) |",
        "| sequence | method | ct on (ln) | ct on lo (ln) | ct on hi (ln) |",
        "| sequence | parameter | value | standard error | 95 % low | 95 % high | truth |",
        "| sequence | effect | evidence | error before | error after | kept | reason |",
    ] {
        assert!(md.contains(header), "{header} in report.md");
    }
}

/// (ct_on, ct_off) of a method's estimate.
fn thresholds_of(s: &Value, method: &str) -> (f64, f64) {
    let e = s["methods"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["method"] == method)
        .unwrap_or_else(|| panic!("{method} in methods"));
    let e = &e["estimate"];
    assert!(e.is_object(), "{method} applied: {s:#}");
    (e["ct_on"].as_f64().unwrap(), e["ct_off"].as_f64().unwrap())
}

fn within(found: f64, truth: f64, relative: f64, what: &str) {
    assert!(
        (found - truth).abs() <= relative * truth,
        "{what}: {found:.4} vs true {truth} (allowed {:.0} %)",
        relative * 100.0
    );
}

#[test]
fn estimates_lie_beside_the_truth_the_samples_were_made_with() {
    let r = results();
    // the texture: simulated at ON 0.35, OFF 0.45 with mismatch, noise, leak, bandwidth
    let texture = sequence(&r, "texture_davis240c");
    assert_eq!(texture["truth"]["params"]["ct_on"], 0.35);
    assert_eq!(texture["truth"]["params"]["ct_off"], 0.45);
    let (on, off) = thresholds_of(texture, "aps");
    within(on, 0.35, 0.08, "aps ON");
    within(off, 0.45, 0.08, "aps OFF");
    let fit = &texture["fit"];
    let (on, off) = (
        fit["params"]["ct_on"].as_f64().unwrap(),
        fit["params"]["ct_off"].as_f64().unwrap(),
    );
    // each within its own 95 % interval, and the point within the aps estimate's 8 % (the
    // fit's standard errors are 10-12 % here)
    within(on, 0.35, 0.08, "fit ON");
    within(off, 0.45, 0.08, "fit OFF");
    for (key, truth) in [("ct_on", 0.35), ("ct_off", 0.45)] {
        let ci = fit["uncertainties"][key]["ci95"].as_array().unwrap();
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        assert!(
            lo <= truth && truth <= hi,
            "fit {key}: [{lo}, {hi}] for {truth}"
        );
    }
    // the closed loop lowers the sim-to-real error several times over
    let before = fit["error_before"].as_f64().unwrap();
    let after = fit["error_after"].as_f64().unwrap();
    assert!(after < before / 3.0, "error {before} -> {after}");
    // the on-screen checkerboard: 0.3 both ways, through a gamma-2 LCD
    let screen = sequence(&r, "screen_checkerboard");
    let (on, off) = thresholds_of(screen, "screen");
    within(on, 0.3, 0.10, "screen ON");
    within(off, 0.3, 0.10, "screen OFF");
    // the samples' folder holds two sensors: one dataset per sensor (never pooled
    // silently), each row the mean over its sequences
    let datasets = r["datasets"].as_array().unwrap();
    assert_eq!(datasets.len(), 2);
    for (dataset, name, sensor) in [
        (&datasets[0], "screen_checkerboard", "120x90"),
        (&datasets[1], "texture_davis240c", "240x180"),
    ] {
        assert_eq!(dataset["name"], format!("data_samples_{sensor}"));
        assert_eq!(dataset["sensors"], serde_json::json!([sensor]));
        assert_eq!(dataset["sequences"], serde_json::json!([name]));
        let rate = sequence(&r, name)["stats"]["events_per_pixel_per_second"]
            .as_f64()
            .unwrap();
        let mean = dataset["events_per_pixel_per_second"]["mean"]
            .as_f64()
            .unwrap();
        assert!((mean - rate).abs() < 1e-12, "{name}: {mean} vs {rate}");
    }
}

fn read_csv(path: &Path) -> DataFrame {
    CsvReadOptions::default()
        .with_has_header(true)
        .try_into_reader_with_file_path(Some(path.to_path_buf()))
        .unwrap()
        .finish()
        .unwrap()
}

fn read_parquet(path: &Path) -> DataFrame {
    ParquetReader::new(std::fs::File::open(path).unwrap())
        .finish()
        .unwrap()
}

/// `ctcal estimate aps` and `ctcal fit` read a recording as the report does (the events
/// between the first and last frame) and simulate with its seed: a researcher gets the
/// report's numbers from them. (Before, the report read every event of slider_depth and
/// its aps said 0.356/0.327 against `estimate aps`'s 0.365/0.329.)
#[test]
fn estimate_and_fit_give_the_report_numbers() {
    let results = results();
    let s = sequence(&results, "texture_davis240c");
    let input = project().join("data_samples/texture_davis240c");
    let input = input.to_str().unwrap();
    let aps = json(&["estimate", "aps", input]);
    assert_eq!(
        (
            aps["ct_on"].as_f64().unwrap(),
            aps["ct_off"].as_f64().unwrap()
        ),
        thresholds_of(s, "aps")
    );
    let fit = json(&["fit", input, "--seed", "2020"]);
    for key in ["ct_on", "ct_off"] {
        assert_eq!(fit["params"][key], s["fit"]["params"][key], "fit {key}");
    }
}

#[test]
fn tables_agree_across_formats_and_are_stable() {
    let dir = sample_report().join("tables");
    for table in TABLES {
        let csv = read_csv(&dir.join(format!("{table}.csv")));
        let parquet = read_parquet(&dir.join(format!("{table}.parquet")));
        assert_eq!(csv.shape(), parquet.shape(), "{table}");
        assert_eq!(
            csv.get_column_names(),
            parquet.get_column_names(),
            "{table}"
        );
        let md = std::fs::read_to_string(dir.join(format!("{table}.md"))).unwrap();
        assert_eq!(md.lines().count(), csv.height() + 2, "{table}.md rows");
        let tex = std::fs::read_to_string(dir.join(format!("{table}.tex"))).unwrap();
        assert_eq!(
            tex.lines().filter(|l| l.ends_with("\\\\")).count(),
            csv.height() + 1,
            "{table}.tex rows"
        );
    }
    // the same numbers: the parquet thresholds to full precision
    let parquet = read_parquet(&dir.join("thresholds.parquet"));
    let r = results();
    let texture = sequence(&r, "texture_davis240c");
    let (aps_on, _) = thresholds_of(texture, "aps");
    let sequences = parquet.column("sequence").unwrap().str().unwrap();
    let methods = parquet.column("method").unwrap().str().unwrap();
    let ct_on = parquet.column("ct_on").unwrap().f64().unwrap();
    let row = (0..parquet.height())
        .find(|&i| sequences.get(i) == Some("texture_davis240c") && methods.get(i) == Some("aps"))
        .unwrap();
    assert_eq!(ct_on.get(row), Some(aps_on));
    // per-sequence Parquet for datasets that outgrow one machine
    let one = read_parquet(&dir.join("texture_davis240c/thresholds.parquet"));
    assert_eq!(one.height(), 3);

    // tables and configurations as a reader sees them; the report is deterministic, so
    // any change of a number is a change of ctcal, to be reviewed
    for name in [
        "thresholds.md",
        "fitted_parameters.md",
        "fit_steps.md",
        "datasets.tex",
    ] {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        insta::assert_snapshot!(name, text);
    }
    let configs = sample_report().join("configs");
    for name in [
        "texture_davis240c/esim.flagfile",
        "texture_davis240c/v2e_args.sh",
        "texture_davis240c/v2e_args.json",
        "texture_davis240c/params.toml",
        "sensors/240x180/esim_config_generator.json",
        "screen_checkerboard/v2e_args.sh",
    ] {
        let text = std::fs::read_to_string(configs.join(name)).unwrap();
        insta::assert_snapshot!(name.replace('/', "__"), text);
    }
}

/// What a browser shows of the page: written by the page's script into `#result`.
const BROWSER_CHECK: &str = r#"<!doctype html><html><body>
<iframe id="report" src="REPORT_URL" width="1200" height="900"></iframe>
<pre id="result">pending</pre>
<script>
const frame = document.getElementById('report');
frame.addEventListener('load', () => {
  setTimeout(() => {
    const doc = frame.contentDocument;
    const lines = [];
    for (const img of doc.images) {
      let inked = -1;
      if (img.complete && img.naturalWidth > 0) {
        const canvas = document.createElement('canvas');
        canvas.width = img.naturalWidth; canvas.height = img.naturalHeight;
        const ctx = canvas.getContext('2d');
        ctx.drawImage(img, 0, 0);
        const data = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
        let n = 0;
        for (let i = 0; i < data.length; i += 4) {
          if (data[i] < 200 || data[i + 1] < 200 || data[i + 2] < 200) n++;
        }
        inked = n / (data.length / 4);
      }
      lines.push('img ' + img.getAttribute('src') + ' ' + img.naturalWidth + ' ' + inked.toFixed(4));
    }
    for (const table of doc.querySelectorAll('table')) {
      lines.push('table ' + table.rows.length + ' ' + table.rows[0].cells.length);
    }
    lines.push('h2 ' + doc.querySelectorAll('h2').length);
    document.getElementById('result').textContent = lines.join('\n');
  }, 500);
});
</script></body></html>"#;

#[test]
fn the_html_report_renders_in_a_browser() {
    let chromium = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .expect("chromium is needed to check the HTML report: run `bash .ci/install-deps`");
    let report = sample_report().canonicalize().unwrap();
    let check = tempfile::tempdir().unwrap();
    let page = check.path().join("check.html");
    let url = format!("file://{}", report.join("index.html").display());
    std::fs::write(&page, BROWSER_CHECK.replace("REPORT_URL", &url)).unwrap();
    let output = std::process::Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--allow-file-access-from-files",
            "--virtual-time-budget=20000",
            "--dump-dom",
        ])
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&output.stdout);
    let result = dom
        .split("<pre id=\"result\">")
        .nth(1)
        .and_then(|r| r.split("</pre>").next())
        .unwrap_or_else(|| panic!("no result from chromium: {dom}"));
    assert_ne!(result, "pending", "the page did not load");
    let images: Vec<&str> = result.lines().filter(|l| l.starts_with("img ")).collect();
    let pngs = files(&report)
        .into_iter()
        .filter(|f| f.starts_with("plots/") && f.ends_with(".png"))
        .count();
    assert_eq!(images.len(), pngs, "every plot on the page:\n{result}");
    for line in &images {
        let fields: Vec<&str> = line.split(' ').collect();
        let width: u32 = fields[2].parse().unwrap();
        let inked: f64 = fields[3].parse().unwrap();
        assert!(width >= 400, "{line}: loaded at a readable size");
        // drawn, not blank, not a solid block
        assert!((0.01..0.95).contains(&inked), "{line}: inked fraction");
    }
    // the page itself rendered to PNG, as a person would see its top: drawn, with colour
    let shot = check.path().join("page.png");
    let status = std::process::Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            "--window-size=1200,2400",
            "--virtual-time-budget=10000",
        ])
        .arg(format!("--screenshot={}", shot.display()))
        .arg(&url)
        .output()
        .unwrap();
    assert!(status.status.success(), "chromium screenshot failed");
    let page = image::open(&shot).unwrap().to_rgb8();
    assert_eq!(page.dimensions(), (1200, 2400));
    let inked = page
        .pixels()
        .filter(|p| p.0.iter().any(|&c| c < 200))
        .count() as f64
        / (1200.0 * 2400.0);
    assert!(inked > 0.01, "the page is nearly blank: {inked}");
    let coloured = page
        .pixels()
        .filter(|p| {
            let [r, g, b] = p.0;
            r.max(g).max(b) - r.min(g).min(b) > 60
        })
        .count();
    assert!(
        coloured > 5_000,
        "no plot colours on the page: {coloured} pixels"
    );
    let tables: Vec<&str> = result.lines().filter(|l| l.starts_with("table ")).collect();
    // datasets, statistics and thresholds once; the fitted model and the loop per fit
    let fitted = results()["sequences"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| !s["fit"].is_null())
        .count();
    assert_eq!(
        fitted, 2,
        "both samples are fitted (the screen one from events alone)"
    );
    assert_eq!(tables.len(), TABLES.len() - 2 + 2 * fitted, "{result}");
    for line in tables {
        let rows: usize = line.split(' ').nth(1).unwrap().parse().unwrap();
        assert!(rows >= 2, "{line}: a header and rows");
    }
}

#[test]
fn config_reads_a_report_or_a_fit_and_round_trips_through_the_simulator() {
    let report = sample_report();
    let run = |args: &[&str]| -> String {
        let output = ctcal().args(args).output().unwrap();
        assert!(
            output.status.success(),
            "ctcal {args:?}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        String::from_utf8(output.stdout).unwrap()
    };
    // one sensor's fit: the texture alone (the sample's two sequences are two sensors, which
    // a configuration does not combine)
    let texture_only = tempfile::tempdir().unwrap();
    let mut r = results();
    r["sequences"]
        .as_array_mut()
        .unwrap()
        .retain(|s| s["name"] == "texture_davis240c");
    std::fs::write(texture_only.path().join("results.json"), r.to_string()).unwrap();
    let report_arg = texture_only.path().to_str().unwrap();
    // one sequence fitted: the report's own files, whichever way asked
    let v2e = run(&["config", report_arg, "--format", "v2e"]);
    assert_eq!(
        v2e,
        std::fs::read_to_string(report.join("configs/texture_davis240c/v2e_args.sh")).unwrap()
    );
    // every parameter in the tool's own names (the report issue's lists), and nothing else
    let esim = [
        "--contrast_threshold_pos",
        "--contrast_threshold_neg",
        "--contrast_threshold_sigma_pos",
        "--contrast_threshold_sigma_neg",
        "--refractory_period_ns",
        "--log_eps",
        "--use_log_image",
        "--exposure_time_ms",
        "--random_seed",
    ];
    let v2e_names = [
        "--pos_thres",
        "--neg_thres",
        "--sigma_thres",
        "--cutoff_hz",
        "--leak_rate_hz",
        "--shot_noise_rate_hz",
        "--refractory_period",
        "--leak_jitter_fraction",
        "--noise_rate_cov_decades",
        "--dvs_emulator_seed",
        "--output_width",
        "--output_height",
    ];
    let flags = |text: &str, separator: char| -> Vec<String> {
        text.lines()
            .map(str::trim_start)
            .filter(|l| l.starts_with("--"))
            .map(|l| l.split(separator).next().unwrap().to_string())
            .collect()
    };
    let esim_text = run(&["config", report_arg, "--format", "esim"]);
    assert_eq!(flags(&esim_text, '='), esim, "{esim_text}");
    // nanoseconds, an integer
    let refractory = esim_text
        .lines()
        .find_map(|l| l.strip_prefix("--refractory_period_ns="))
        .unwrap();
    refractory.parse::<u64>().unwrap();
    assert_eq!(flags(&v2e, ' '), v2e_names, "{v2e}");
    let generator: Value =
        serde_json::from_str(&run(&["config", report_arg, "--format", "esim-generator"])).unwrap();
    let mut keys: Vec<&str> = generator["camera_params"]
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    keys.sort();
    assert_eq!(
        keys,
        [
            "contrast_threshold_mean",
            "ct_diff_sigma",
            "hard_c_t_sigmas",
            "max_C",
            "min_C",
            "refractory_period_ns",
            "sim_framerate"
        ]
    );
    // the range covers the fitted thresholds with margin for training
    let r = results();
    let fit_params = &sequence(&r, "texture_davis240c")["fit"]["params"];
    let (on, off) = (
        fit_params["ct_on"].as_f64().unwrap(),
        fit_params["ct_off"].as_f64().unwrap(),
    );
    let camera = &generator["camera_params"];
    assert!(camera["min_C"].as_f64().unwrap() < on.min(off));
    assert!(camera["max_C"].as_f64().unwrap() > on.max(off));

    // a fit's JSON (as `ctcal fit --json` writes it) gives the same parameters
    let work = tempfile::tempdir().unwrap();
    let fit = sequence(&r, "texture_davis240c")["fit"].clone();
    let fit_json = work.path().join("fit.json");
    std::fs::write(&fit_json, serde_json::to_string(&fit).unwrap()).unwrap();
    // (a fit alone does not say the sensor size: the script says to add it)
    let from_fit = run(&["config", fit_json.to_str().unwrap(), "--format", "v2e"]);
    assert_eq!(flags(&from_fit, ' '), v2e_names[..v2e_names.len() - 2]);
    assert!(from_fit.contains("# the sensor size is not known: add --output_width"));
    let values = |text: &str| -> Vec<String> {
        text.lines()
            .map(str::trim_start)
            .filter(|l| l.starts_with("--pos") || l.starts_with("--neg"))
            .map(String::from)
            .collect()
    };
    assert_eq!(values(&from_fit), values(&v2e));

    // ctcal's own PARAMS.toml drives `ctcal simulate` with exactly the fitted parameters
    let params = work.path().join("params.toml");
    run(&[
        "config",
        fit_json.to_str().unwrap(),
        "--format",
        "ctcal",
        "--seed",
        "5",
        "--out",
        params.to_str().unwrap(),
    ]);
    let scene = project().join("calib/scenes/sample_texture_davis240c.toml");
    let sim = json(&[
        "simulate",
        "--scene",
        scene.to_str().unwrap(),
        "--params",
        params.to_str().unwrap(),
        "--out",
        work.path().join("sim").to_str().unwrap(),
    ]);
    // every parameter the fit identified (thresholds always here), as simulated
    for key in ["ct_on", "ct_off", "ct_sigma", "shot_noise_rate_hz"] {
        let Some(fitted) = fit["params"][key].as_f64() else {
            assert!(
                !key.starts_with("ct_on") && !key.starts_with("ct_off"),
                "{key}"
            );
            continue;
        };
        let simulated = sim["params"][key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key} in {sim:#}"));
        assert_eq!(fitted, simulated, "{key}");
    }
    assert_eq!(sim["params"]["seed"], 5);
    assert!(sim["events"].as_u64().unwrap() > 10_000);
}

#[test]
fn config_and_report_refuse_bad_input_with_a_fix() {
    let work = tempfile::tempdir().unwrap();
    let w = |name: &str| work.path().join(name).display().to_string();
    // config
    let e = bad_input(&["config", &w("missing.json"), "--format", "v2e"]);
    assert!(e.contains("missing.json"), "{e}");
    std::fs::create_dir(work.path().join("empty")).unwrap();
    let e = bad_input(&["config", &w("empty"), "--format", "v2e"]);
    assert!(e.contains("results.json") && e.contains("fix:"), "{e}");
    std::fs::write(work.path().join("stats.json"), r#"{"events": 3}"#).unwrap();
    let e = bad_input(&["config", &w("stats.json"), "--format", "v2e"]);
    assert!(e.contains("stats.json") && e.contains("params"), "{e}");
    std::fs::write(work.path().join("broken.json"), "{\"params\": ").unwrap();
    let e = bad_input(&["config", &w("broken.json"), "--format", "v2e"]);
    assert!(e.contains("broken.json"), "{e}");
    let report = sample_report().to_str().unwrap().to_string();
    let e = bad_input(&["config", &report, "--format", "carla"]);
    assert!(
        e.contains("carla") && e.contains("esim") && e.contains("v2e"),
        "{e}"
    );

    // report
    let samples = project().join("data_samples");
    let samples = samples.to_str().unwrap();
    let e = bad_input(&["report", &w("nowhere"), "--out", &w("r1")]);
    assert!(e.contains("nowhere") && e.contains("fix:"), "{e}");
    let e = bad_input(&["report", &w("empty"), "--out", &w("r2")]);
    assert!(
        e.contains("holds no recording") && e.contains("fix:"),
        "{e}"
    );
    let e = bad_input(&["report", "--dataset", samples, "--out", &w("r3")]);
    assert!(e.contains("NAME=INPUT"), "{e}");
    let e = bad_input(&["report", "--out", &w("r4")]);
    assert!(e.contains("no recordings given"), "{e}");
    // a user's folder is refused before any work, and left as it was
    let users = work.path().join("thesis");
    std::fs::create_dir(&users).unwrap();
    std::fs::write(users.join("chapter1.tex"), "precious").unwrap();
    let e = bad_input(&["report", samples, "--out", users.to_str().unwrap()]);
    assert!(e.contains("--force") || e.contains("new folder"), "{e}");
    assert_eq!(files(&users), vec!["chapter1.tex".to_string()]);
    assert_eq!(
        std::fs::read_to_string(users.join("chapter1.tex")).unwrap(),
        "precious"
    );
    // an output inside an input
    let inside = project().join("data_samples/report");
    let e = bad_input(&["report", samples, "--out", inside.to_str().unwrap()]);
    assert!(e.contains("input"), "{e}");
    assert!(!inside.exists(), "nothing written inside the input");
    let e = bad_input(&[
        "report",
        "--dataset",
        &format!("samples={samples}"),
        "--out",
        inside.to_str().unwrap(),
    ]);
    assert!(e.contains("input"), "{e}");
    for r in ["r1", "r2", "r3", "r4"] {
        assert!(!work.path().join(r).exists(), "{r} left behind");
    }
}

#[test]
fn named_datasets_are_summarised_one_row_each() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("report");
    let samples = project().join("data_samples");
    ctcal()
        .args(["report", "--no-fit", "--dataset"])
        .arg(format!(
            "texture={}",
            samples.join("texture_davis240c").display()
        ))
        .arg("--dataset")
        .arg(format!(
            "on screen={}",
            samples.join("screen_checkerboard").display()
        ))
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let r: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let names: Vec<&str> = r["datasets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["texture", "on_screen"]);
    for s in r["sequences"].as_array().unwrap() {
        assert!(s["fit"].is_null());
        assert_eq!(s["fit_not_applied"], "left out (--no-fit)");
    }
    let table = read_csv(&out.join("tables/datasets.csv"));
    assert_eq!(table.height(), 2);
    // no fit, no configuration
    assert!(!out.join("configs").exists());
}

#[test]
fn the_committed_sample_report_is_what_ctcal_makes_today() {
    let committed = project().join("reports/sample");
    let fresh = sample_report();
    let mut compared = 0;
    for file in files(fresh) {
        let text = file.starts_with("tables/") && !file.ends_with(".parquet")
            || file.starts_with("configs/");
        if !text {
            continue;
        }
        let path = committed.join(&file);
        let got = std::fs::read_to_string(&path).unwrap_or_else(|_| {
            panic!(
                "{} missing: run `cargo run --release -- report data_samples --out reports/sample`",
                path.display()
            )
        });
        assert_eq!(
            got,
            std::fs::read_to_string(fresh.join(&file)).unwrap(),
            "{file} differs: run `cargo run --release -- report data_samples --out reports/sample`"
        );
        compared += 1;
    }
    assert!(compared >= 19, "{compared} files compared");
    // the Markdown report, but for the --out path on its command line
    let body = |path: &Path| -> String {
        std::fs::read_to_string(path.join("report.md"))
            .unwrap()
            .lines()
            .filter(|l| !l.contains("--out"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(body(&committed), body(fresh));
    // every number and reason of the results, but for the command line and the timings
    assert!(
        crate::from_results::comparable(&committed) == crate::from_results::comparable(fresh),
        "reports/sample/results.json differs: run `cargo run --release -- report data_samples --out reports/sample`"
    );
    // the PNG plots are all there (rendering is checked in the browser test)
    for file in files(fresh).iter().filter(|f| f.ends_with(".png")) {
        assert!(committed.join(file).is_file(), "{file} in reports/sample");
    }
}
