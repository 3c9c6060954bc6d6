//! `ctcal report --from-results`: reports made elsewhere merged into one, by the same merge
//! as a report of recordings: a report rebuilt from its own results is the same report, and
//! a dataset reported in two parts is the report of the whole.

use crate::common::{bad_input, ctcal, shared_data};
use crate::report::sample_report;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn results(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).unwrap()).unwrap()
}

/// The results without what differs between runs (the command line, the stage timings).
pub(crate) fn comparable(dir: &Path) -> Value {
    let mut r = results(dir);
    r.as_object_mut().unwrap().remove("command_line");
    for s in r["sequences"].as_array_mut().unwrap() {
        s.as_object_mut().unwrap().remove("seconds");
    }
    r
}

/// Every file of a report but its pages and results (which carry the command line), with
/// its bytes.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if path.is_dir() {
                walk(root, &path, out);
            } else if ![
                "index.html",
                "report.md",
                "results.json",
                ".ctcal-output.json",
            ]
            .contains(&name.as_str())
            {
                let bytes = std::fs::read(&path).unwrap();
                out.push((path.strip_prefix(root).unwrap().to_path_buf(), bytes));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

#[test]
fn a_report_rebuilt_from_its_results_is_the_same_report() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("again");
    ctcal()
        .args(["report", "--from-results"])
        .arg(sample_report())
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    assert_eq!(comparable(&out), comparable(sample_report()));
    assert_eq!(files(&out), files(sample_report()));
    let command = results(&out)["command_line"].clone();
    let command = crate::common::strings(&command);
    assert!(
        command
            .windows(2)
            .any(|w| w == ["report", "--from-results"])
    );
}

#[test]
fn a_dataset_reported_in_two_parts_is_the_report_of_the_whole() {
    let real = shared_data().join("real");
    let (a, b) = (
        real.join("ijrr_slider_depth_50k"),
        real.join("ijrr_shapes_rotation_chunk"),
    );
    let work = tempfile::tempdir().unwrap();
    let report = |out: &str, parts: &[&Path]| {
        let mut cmd = ctcal();
        cmd.arg("report");
        for p in parts {
            cmd.arg("--dataset").arg(format!("ijrr={}", p.display()));
        }
        cmd.arg("--out")
            .arg(work.path().join(out))
            .assert()
            .success();
        work.path().join(out)
    };
    let whole = report("whole", &[&a, &b]);
    let first = report("first", &[&a]);
    let second = report("second", &[&b]);
    let merged = work.path().join("merged");
    ctcal()
        .args(["report", "--from-results"])
        .arg(&first)
        .arg(second.join("results.json"))
        .arg("--out")
        .arg(&merged)
        .assert()
        .success();
    assert_eq!(comparable(&merged), comparable(&whole));
    assert_eq!(files(&merged), files(&whole));
    // a sequence in two of the reports is refused, as is a folder that is no report
    let twice = bad_input(&[
        "report",
        "--from-results",
        first.to_str().unwrap(),
        whole.to_str().unwrap(),
        "--out",
        work.path().join("twice").to_str().unwrap(),
    ]);
    assert!(twice.contains("ijrr_slider_depth_50k") && twice.contains("is in both"));
    let not_a_report = bad_input(&[
        "report",
        "--from-results",
        real.to_str().unwrap(),
        "--out",
        work.path().join("none").to_str().unwrap(),
    ]);
    assert!(not_a_report.contains("not a ctcal report"));
    assert!(!work.path().join("twice").exists() && !work.path().join("none").exists());
}
