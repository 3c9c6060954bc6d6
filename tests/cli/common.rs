//! Helpers shared by the integration tests.

use assert_cmd::Command;
use ctcal::{EventChunk, OpenOptions, Recording};
use std::path::{Path, PathBuf};

/// `../shared/data` beside the project root.
pub fn shared_data() -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    assert!(
        path.is_dir(),
        "shared test data missing at {}",
        path.display()
    );
    path
}

pub fn real(name: &str) -> PathBuf {
    shared_data().join("real").join(name)
}

pub fn oracle(name: &str) -> PathBuf {
    shared_data().join("oracle").join(name)
}

/// The `ctcal` binary.
pub fn ctcal() -> Command {
    let mut cmd = Command::cargo_bin("ctcal").expect("ctcal binary built");
    cmd.arg("--quiet");
    // Tests run in parallel threads of one process that also writes HDF5 files: a child
    // spawned while such a file is open inherits its descriptor, and with it libhdf5's
    // flock, for its whole run. Locking guards against concurrent writers, which the
    // tests do not have, so the children skip it.
    cmd.env("HDF5_USE_FILE_LOCKING", "FALSE");
    cmd
}

/// Creates an HDF5 file for a test without libhdf5's file lock. A child `ctcal` that
/// another test thread spawns while the file is open inherits its descriptor, and with it
/// the lock, for the child's whole run: reopening the file here would then fail with
/// EAGAIN. The tests have no concurrent writers, the lock's only purpose.
pub fn h5_create(path: &Path) -> hdf5::File {
    hdf5::File::with_options()
        .with_fapl(|fapl| fapl.file_locking(false))
        .create(path)
        .unwrap_or_else(|e| panic!("creating {}: {e}", path.display()))
}

/// Opens an HDF5 file for writing without libhdf5's file lock (see [`h5_create`]).
pub fn h5_open_rw(path: &Path) -> hdf5::File {
    hdf5::File::with_options()
        .with_fapl(|fapl| fapl.file_locking(false))
        .open_rw(path)
        .unwrap_or_else(|e| panic!("opening {}: {e}", path.display()))
}

/// Opens an HDF5 file for reading without libhdf5's file lock (see [`h5_create`]).
pub fn h5_open(path: &Path) -> hdf5::File {
    hdf5::File::with_options()
        .with_fapl(|fapl| fapl.file_locking(false))
        .open(path)
        .unwrap_or_else(|e| panic!("opening {}: {e}", path.display()))
}

/// Runs `ctcal <args> --json -` and parses stdout.
pub fn json(args: &[&str]) -> serde_json::Value {
    let output = ctcal()
        .args(args)
        .args(["--json", "-"])
        .output()
        .expect("runs");
    assert!(
        output.status.success(),
        "ctcal {args:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("stdout is JSON")
}

/// The output of a command that must have succeeded (its stderr in the failure message).
pub fn succeeded(output: std::io::Result<std::process::Output>) -> std::process::Output {
    let output = output.expect("runs");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// Runs ctcal expecting exit code 2; returns stderr.
pub fn bad_input(args: &[&str]) -> String {
    let output = ctcal().args(args).output().expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(
        output.status.code(),
        Some(2),
        "ctcal {args:?}: expected exit 2, stderr: {stderr}"
    );
    assert!(output.stdout.is_empty(), "nothing on stdout for an error");
    stderr
}

/// Every event of a recording, via the library.
pub fn read_events(path: &Path) -> EventChunk {
    Recording::open(path, &OpenOptions::default())
        .and_then(|r| r.read_all(false))
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// FNV-1a over (t, x, y, on) of every event: a fingerprint of an exact decode.
pub fn fingerprint(events: &EventChunk) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            hash ^= b as u64;
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for e in events.iter() {
        eat(&e.t.to_le_bytes());
        eat(&e.x.to_le_bytes());
        eat(&e.y.to_le_bytes());
        eat(&[e.on as u8]);
    }
    hash
}

/// `real/truth.json`.
pub fn truth() -> serde_json::Value {
    let text = std::fs::read_to_string(shared_data().join("real/truth.json")).expect("truth.json");
    serde_json::from_str(&text).expect("valid JSON")
}

/// An oracle case's `params.json`.
pub fn oracle_params(case: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(oracle(case).join("params.json")).expect("params.json");
    serde_json::from_str(&text).expect("valid JSON")
}

/// The (x, y) of each pixel of a JSON array of them (a fit's `hot_pixels_masked`, an
/// oracle's injected hot pixels), sorted.
pub fn pixel_positions(value: &serde_json::Value) -> Vec<(u64, u64)> {
    let mut pixels: Vec<(u64, u64)> = value
        .as_array()
        .expect("an array of pixels")
        .iter()
        .map(|p| (p["x"].as_u64().unwrap(), p["y"].as_u64().unwrap()))
        .collect();
    pixels.sort_unstable();
    pixels
}

/// The strings of a JSON array (panics where it is not one of strings).
pub fn strings(value: &serde_json::Value) -> Vec<&str> {
    value
        .as_array()
        .expect("a JSON array")
        .iter()
        .map(|a| a.as_str().expect("a string"))
        .collect()
}

/// The names of an estimate's `estimators`, in order.
pub fn estimator_names(e: &serde_json::Value) -> Vec<&str> {
    e["estimators"]
        .as_array()
        .expect("estimators")
        .iter()
        .map(|x| x["name"].as_str().expect("a name"))
        .collect()
}

/// The region note in `output`'s `assumptions` that starts with `verb` ("fitted on the
/// region x X0..X1, y Y0..Y1 of ..."), and its bounds `[x0, x1, y0, y1]`.
pub fn region_of(output: &serde_json::Value, verb: &str) -> (String, [u64; 4]) {
    let note = output["assumptions"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|a| a.as_str())
        .find(|a| a.starts_with(verb) && a.contains(" on the region x "))
        .expect("the region is named in the assumptions")
        .to_string();
    let bounds = &note[note.find(" on the region x ").unwrap()..];
    let numbers: Vec<u64> = bounds
        .split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .take(4)
        .map(|s| s.parse().unwrap())
        .collect();
    let [x0, x1, y0, y1] = numbers[..] else {
        panic!("{note}")
    };
    (note, [x0, x1, y0, y1])
}

/// The events of an oracle case's `events.txt` inside `[x0, x1, y0, y1]` (ends exclusive).
pub fn events_inside(case: &Path, [x0, x1, y0, y1]: [u64; 4]) -> usize {
    let text = std::fs::read_to_string(case.join("events.txt")).unwrap();
    text.lines()
        .filter_map(|line| {
            let mut fields = line.split_whitespace().skip(1);
            let x: u64 = fields.next()?.parse().ok()?;
            let y: u64 = fields.next()?.parse().ok()?;
            Some((x0..x1).contains(&x) && (y0..y1).contains(&y))
        })
        .filter(|&inside| inside)
        .count()
}

/// A coverage study's case (its `case.json`, [`ctcal::coverage::CaseSpec`], kept as
/// `tests/cli/cases/{id}.json`) written into a temporary folder with its truth.
pub fn coverage_case(id: &str) -> tempfile::TempDir {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/cli/cases/{id}.json"));
    let text = std::fs::read_to_string(&path).unwrap();
    let case: ctcal::coverage::CaseSpec = serde_json::from_str(&text).unwrap();
    let dir = tempfile::tempdir().unwrap();
    ctcal::coverage::write_case(&case, dir.path()).unwrap();
    dir
}
