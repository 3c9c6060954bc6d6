//! The recordings of `ctcal report`'s command line: files and IJRR folders as given, or the
//! recordings inside folders of them, each with where its dataset name comes from (the
//! user's `--dataset NAME`, else its folder, split by sensor once the sensors are known).

use super::super::BadInput;
use super::ReportArgs;
use ctcal::report::grouping::{Origin, file_stem};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A recording to report on.
#[derive(Clone, Debug)]
pub(super) struct Input {
    pub path: PathBuf,
    pub name: String,
    pub origin: Origin,
}

/// Whether `path` is a recording ctcal reads (an IJRR folder or a file of a known format).
fn is_recording(path: &Path) -> bool {
    if path.is_dir() {
        return path.join("events.txt").is_file();
    }
    path.file_name()
        .is_some_and(|n| !n.to_string_lossy().starts_with('.'))
        && ctcal::io::detect(path).is_ok()
}

fn folder_name(p: &Path) -> String {
    p.canonicalize()
        .ok()
        .and_then(|c| c.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "recordings".into())
}

/// The recordings in a folder of them, sorted.
fn listed(path: &Path) -> Result<Vec<PathBuf>, BadInput> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| BadInput(format!("{}: cannot list: {e}", path.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_recording(p))
        .collect();
    entries.sort();
    if entries.is_empty() {
        return Err(BadInput(format!(
            "{}: holds no recording ctcal reads\n  fix: give recordings or folders of them (an IJRR folder has events.txt)",
            path.display()
        )));
    }
    Ok(entries)
}

/// The recordings of an input: itself, or the recordings in a folder of them.
fn expand(path: &Path, dataset: Option<&str>) -> Result<Vec<Input>, BadInput> {
    if !path.exists() {
        return Err(BadInput(format!(
            "{}: no such file or directory\n  fix: check the path",
            path.display()
        )));
    }
    let origin = |folder: &Path| match dataset {
        Some(name) => Origin::Named(name.to_string()),
        None => Origin::Folder(folder_name(folder)),
    };
    if is_recording(path) {
        let parent = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        return Ok(vec![Input {
            path: path.to_path_buf(),
            name: folder_name(path),
            origin: origin(parent),
        }]);
    }
    if !path.is_dir() {
        return Err(BadInput(format!(
            "{}: not a recording ctcal reads\n  fix: give recordings (IJRR folders, HDF5, AEDAT4, RAW, DAT, ROS bags) or folders of them",
            path.display()
        )));
    }
    Ok(listed(path)?
        .into_iter()
        .map(|p| Input {
            name: folder_name(&p),
            path: p,
            origin: origin(path),
        })
        .collect())
}

/// The inputs of the command line, named uniquely (names made safe for paths).
pub(super) fn inputs(args: &ReportArgs) -> Result<Vec<Input>, BadInput> {
    let mut all = Vec::new();
    for path in &args.inputs {
        all.extend(expand(path, None)?);
    }
    for spec in &args.datasets {
        let Some((name, path)) = spec.split_once('=') else {
            return Err(BadInput(format!(
                "--dataset `{spec}` is not NAME=INPUT\n  fix: e.g. --dataset ijrr=recordings/ijrr"
            )));
        };
        all.extend(expand(Path::new(path), Some(name.trim()))?);
    }
    if all.is_empty() {
        return Err(BadInput(
            "no recordings given\n  fix: ctcal report INPUT... --out DIR (or --dataset NAME=INPUT)"
                .into(),
        ));
    }
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for input in &mut all {
        let safe = file_stem(&input.name);
        let n = seen.entry(safe.clone()).or_insert(0);
        *n += 1;
        input.name = if *n == 1 { safe } else { format!("{safe}_{n}") };
    }
    Ok(all)
}
