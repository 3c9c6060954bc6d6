//! Outputs never delete what ctcal did not write (issue: "the trust issue"): every way an
//! output could replace, delete or half-write a user's files, each with exit code 2, the
//! path and a fix, and the user's files intact afterwards.

use crate::common::*;
use std::path::{Path, PathBuf};

/// A user's folder with a file of their own in it.
fn users_folder(parent: &Path, name: &str) -> PathBuf {
    let folder = parent.join(name);
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("notes.md"), "my notes").unwrap();
    folder
}

fn notes_survive(folder: &Path) {
    assert_eq!(
        std::fs::read_to_string(folder.join("notes.md")).unwrap(),
        "my notes",
        "the user's file in {} was touched",
        folder.display()
    );
}

/// Names in `dir` (hidden ones too).
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A small IJRR recording the test may damage: events.txt and calib.txt.
fn small_recording(parent: &Path) -> PathBuf {
    let rec = parent.join("rec");
    std::fs::create_dir_all(&rec).unwrap();
    std::fs::write(
        rec.join("events.txt"),
        "0.001 1 1 1\n0.002 2 2 0\n0.003 3 3 1\n",
    )
    .unwrap();
    std::fs::write(rec.join("calib.txt"), "199.0 199.0 120.0 90.0\n").unwrap();
    rec
}

#[test]
fn an_existing_users_folder_is_refused_by_every_writing_command() {
    let dir = tempfile::tempdir().unwrap();
    let rec = small_recording(dir.path());
    let params = dir.path().join("p.toml");
    std::fs::write(&params, "ct_on = 0.3\nct_off = 0.3\n").unwrap();
    let out = users_folder(dir.path(), "out");
    let out_s = out.to_str().unwrap();
    for args in [
        vec!["convert", rec.to_str().unwrap(), "--out", out_s],
        vec![
            "simulate",
            "--params",
            params.to_str().unwrap(),
            "--frames",
            oracle("a_ideal_texture").to_str().unwrap(),
            "--out",
            out_s,
        ],
        vec![
            "calib",
            "checkerboard",
            "--out",
            out_s,
            "--duration-s",
            "0.1",
        ],
    ] {
        let e = bad_input(&args);
        assert!(
            e.contains("did not create") && e.contains("--force") && e.contains(out_s),
            "{args:?}: {e}"
        );
        notes_survive(&out);
        assert_eq!(names(&out), vec!["notes.md"]);
    }
    assert_eq!(
        names(dir.path()),
        vec!["out", "p.toml", "rec"],
        "nothing left beside"
    );
}

#[test]
fn force_replaces_only_the_files_ctcal_writes_and_a_rerun_needs_no_force() {
    let dir = tempfile::tempdir().unwrap();
    let out = users_folder(dir.path(), "stimulus");
    let out_s = out.to_str().unwrap();
    ctcal()
        .args([
            "--force",
            "calib",
            "checkerboard",
            "--out",
            out_s,
            "--duration-s",
            "0.1",
        ])
        .assert()
        .success();
    notes_survive(&out);
    assert!(out.join("stimulus.txt").is_file());
    assert_eq!(std::fs::read_dir(out.join("stimulus")).unwrap().count(), 8);
    // ctcal's own folder (it has the marker): a shorter stimulus replaces the longer one,
    // and the frames it no longer writes go; the user's file stays
    ctcal()
        .args([
            "calib",
            "checkerboard",
            "--out",
            out_s,
            "--duration-s",
            "0.04",
        ])
        .assert()
        .success();
    notes_survive(&out);
    assert_eq!(std::fs::read_dir(out.join("stimulus")).unwrap().count(), 3);
}

#[test]
fn an_output_that_holds_or_is_an_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let rec = small_recording(dir.path());
    // convert rec/events.txt --out rec: would have deleted rec/calib.txt
    let e = bad_input(&[
        "convert",
        rec.join("events.txt").to_str().unwrap(),
        "--out",
        rec.to_str().unwrap(),
    ]);
    assert!(e.contains("contains the input"), "{e}");
    assert!(rec.join("calib.txt").is_file());
    // convert box/rec.h5 --out box: would have deleted the input
    let boxed = dir.path().join("box");
    std::fs::create_dir(&boxed).unwrap();
    std::fs::copy(
        shared_data().join("h5/e_ct060_event_utils.h5"),
        boxed.join("rec.h5"),
    )
    .unwrap();
    let e = bad_input(&[
        "convert",
        boxed.join("rec.h5").to_str().unwrap(),
        "--out",
        boxed.to_str().unwrap(),
    ]);
    assert!(e.contains("contains the input"), "{e}");
    assert_eq!(
        std::fs::metadata(boxed.join("rec.h5")).unwrap().len(),
        std::fs::metadata(shared_data().join("h5/e_ct060_event_utils.h5"))
            .unwrap()
            .len()
    );
    // the input itself, through another spelling of its path
    let e = bad_input(&[
        "convert",
        rec.join("events.txt").to_str().unwrap(),
        "--to",
        "h5",
        "--out",
        rec.join("../rec/events.txt").to_str().unwrap(),
    ]);
    assert!(e.contains("is the input"), "{e}");
    // inside the input folder: refused, unless --force
    let inside = rec.join("converted.h5");
    let e = bad_input(&[
        "stats",
        rec.to_str().unwrap(),
        "--json",
        rec.join("stats.json").to_str().unwrap(),
    ]);
    assert!(
        e.contains("inside the input folder") && e.contains("--force"),
        "{e}"
    );
    ctcal()
        .args(["--force", "convert", rec.to_str().unwrap(), "--out"])
        .arg(&inside)
        .assert()
        .success();
    assert!(rec.join("calib.txt").is_file() && inside.is_file());
}

/// A user's file named by `--json` is refused before the recording is read, not after
/// the work: the recording here is not a recording at all, and the error is the JSON's
/// (fit used to read, fit for 11 s and only then refuse).
#[test]
fn json_a_command_may_not_write_is_refused_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let mine = dir.path().join("mine.json");
    std::fs::write(&mine, "{\"mine\": true}").unwrap();
    let not_a_recording = dir.path().join("notes.txt");
    std::fs::write(&not_a_recording, "not events").unwrap();
    let (input, json) = (not_a_recording.to_str().unwrap(), mine.to_str().unwrap());
    for command in [
        &["fit", input][..],
        &["estimate", "aps", input],
        &["estimate", "eppps", input],
        &["stats", input],
    ] {
        let mut args = command.to_vec();
        args.extend(["--json", json]);
        let e = bad_input(&args);
        assert!(
            e.contains("mine.json") && e.contains("not written by ctcal"),
            "{command:?}: {e}"
        );
    }
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "{\"mine\": true}");
}

#[test]
fn json_never_replaces_a_folder_a_users_file_or_a_link() {
    let dir = tempfile::tempdir().unwrap();
    let input = real("ijrr_slider_depth_50k");
    let input = input.to_str().unwrap();
    let folder = users_folder(dir.path(), "results");
    let e = bad_input(&["stats", input, "--json", folder.to_str().unwrap()]);
    assert!(e.contains("is a folder"), "{e}");
    notes_survive(&folder);
    // DIR/ used to fail midway and leave the folder renamed to a hidden name
    let e = bad_input(&["stats", input, "--json", &format!("{}/", folder.display())]);
    assert!(e.contains("names a folder"), "{e}");
    notes_survive(&folder);
    assert_eq!(names(dir.path()), vec!["results"]);
    // a user's file is not replaced; ctcal's own JSON is
    let mine = dir.path().join("mine.json");
    std::fs::write(&mine, "{\"mine\": true}").unwrap();
    let e = bad_input(&["stats", input, "--json", mine.to_str().unwrap()]);
    assert!(
        e.contains("not written by ctcal") && e.contains("--force"),
        "{e}"
    );
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "{\"mine\": true}");
    let ours = dir.path().join("stats.json");
    for _ in 0..2 {
        ctcal()
            .args(["stats", input, "--json", ours.to_str().unwrap()])
            .assert()
            .success();
    }
    // a symlink is followed: the link stays a link, the file it points at is written
    #[cfg(unix)]
    {
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink(&ours, &link).unwrap();
        std::fs::write(&ours, "{\"ctcal_version\": \"old\"}").unwrap();
        ctcal()
            .args(["stats", input, "--json", link.to_str().unwrap()])
            .assert()
            .success();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        let written: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&ours).unwrap()).unwrap();
        assert_eq!(written["events"], 50_000);
    }
}

#[cfg(unix)]
#[test]
fn devices_are_written_in_place_and_write_errors_are_reported() {
    use std::os::unix::fs::FileTypeExt;
    let input = real("ijrr_slider_depth_50k");
    let input = input.to_str().unwrap();
    ctcal()
        .args(["convert", input, "--to", "evt3", "--out", "/dev/null"])
        .assert()
        .success();
    ctcal()
        .args(["stats", input, "--json", "/dev/null"])
        .assert()
        .success();
    let null = std::fs::metadata("/dev/null").unwrap();
    assert!(null.file_type().is_char_device(), "/dev/null was replaced");
    // a folder output cannot be a device
    let e = bad_input(&["convert", input, "--out", "/dev/null"]);
    assert!(e.contains("/dev/null") && e.contains("device"), "{e}");
    // a full disk is an output error: exit 2, the path and a fix
    if Path::new("/dev/full").exists() {
        let e = bad_input(&["stats", input, "--json", "/dev/full"]);
        assert!(
            e.contains("/dev/full") && e.contains("No space") && e.contains("fix:"),
            "{e}"
        );
    }
}

#[test]
fn partial_outputs_of_killed_runs_are_cleaned_at_the_next_start() {
    let dir = tempfile::tempdir().unwrap();
    // what a killed or out-of-memory run leaves: a partial copy named for its (dead) PID
    let stale = dir.path().join(".out.ctcal-partial-99999999");
    std::fs::create_dir(&stale).unwrap();
    std::fs::write(stale.join("events.txt"), "half").unwrap();
    let stale_file = dir.path().join(".s.json.ctcal-partial-99999998");
    std::fs::write(&stale_file, "{").unwrap();
    ctcal()
        .args(["calib", "checkerboard", "--duration-s", "0.05", "--out"])
        .arg(dir.path().join("out"))
        .assert()
        .success();
    assert_eq!(names(dir.path()), vec!["out"]);
}

#[test]
fn a_failed_simulation_leaves_nothing_and_keeps_an_existing_output() {
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("p.toml");
    std::fs::write(&params, "ct_on = 0.3\nct_off = 0.3\n").unwrap();
    let out = dir.path().join("sim");
    let frames = oracle("a_ideal_texture");
    let run = |extra: &[&str]| {
        let mut cmd = ctcal();
        cmd.args(["simulate", "--params", params.to_str().unwrap()])
            .args(["--frames", frames.to_str().unwrap(), "--out"])
            .arg(&out)
            .args(extra);
        cmd.output().unwrap()
    };
    assert!(run(&[]).status.success());
    let before = std::fs::read(out.join("events.txt")).unwrap();
    // a map of the wrong size fails after the output was checked: the old output stays
    let wrong = oracle("b_asym_texture").join("true_pos_thres.npy");
    let scene_map = dir.path().join("small.npy");
    let small: ndarray::Array2<f32> = ndarray::Array2::from_elem((4, 4), 0.3);
    ndarray_npy::write_npy(&scene_map, &small).unwrap();
    let failed = run(&["--ct-on-map", scene_map.to_str().unwrap()]);
    assert_eq!(failed.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&failed.stderr).contains("small.npy"));
    assert_eq!(std::fs::read(out.join("events.txt")).unwrap(), before);
    assert!(wrong.is_file());
    assert_eq!(names(dir.path()), vec!["p.toml", "sim", "small.npy"]);
}

#[cfg(unix)]
#[test]
fn a_dangling_symlink_output_is_refused_and_creates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = real("ijrr_slider_depth_50k");
    let input = input.to_str().unwrap();
    // every link points into folders that do not exist: writing through one used to create
    // them
    let elsewhere = dir.path().join("elsewhere");
    let link = |name: &str, target: &str| {
        let path = dir.path().join(name);
        std::os::unix::fs::symlink(elsewhere.join(target), &path).unwrap();
        path.to_str().unwrap().to_string()
    };
    let json_link = link("stats.json", "deep/stats.json");
    let folder_link = link("out", "a/b");
    let file_link = link("converted.h5", "c/converted.h5");
    let config_link = link("esim.flagfile", "d/esim.flagfile");
    let params = dir.path().join("p.toml");
    std::fs::write(&params, "ct_on = 0.3\nct_off = 0.3\n").unwrap();
    let fit = dir.path().join("fit.json");
    std::fs::write(&fit, r#"{"params": {"ct_on": 0.3, "ct_off": 0.3}}"#).unwrap();
    let frames = oracle("a_ideal_texture");
    for (args, shown, target) in [
        (
            vec!["stats", input, "--json", &json_link],
            "stats.json",
            "elsewhere/deep/stats.json",
        ),
        (
            vec!["convert", input, "--out", &folder_link],
            "out",
            "elsewhere/a/b",
        ),
        (
            vec!["convert", input, "--to", "h5", "--out", &file_link],
            "converted.h5",
            "elsewhere/c/converted.h5",
        ),
        (
            vec![
                "simulate",
                "--params",
                params.to_str().unwrap(),
                "--frames",
                frames.to_str().unwrap(),
                "--out",
                &folder_link,
            ],
            "out",
            "elsewhere/a/b",
        ),
        (
            vec![
                "config",
                fit.to_str().unwrap(),
                "--format",
                "esim",
                "--out",
                &config_link,
            ],
            "esim.flagfile",
            "elsewhere/d/esim.flagfile",
        ),
    ] {
        let e = bad_input(&args);
        assert!(
            e.contains(shown)
                && e.contains(target)
                && e.contains("symbolic link")
                && e.contains("does not exist")
                && e.contains("fix:"),
            "{args:?}: {e}"
        );
        assert!(!elsewhere.exists(), "{args:?} created the link's target");
    }
    assert_eq!(
        names(dir.path()),
        vec![
            "converted.h5",
            "esim.flagfile",
            "fit.json",
            "out",
            "p.toml",
            "stats.json"
        ],
        "nothing half-written beside the links"
    );
}
