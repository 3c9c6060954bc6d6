//! The recordings of a report: files and IJRR folders as given, or the recordings inside
//! folders of them, each with where its dataset name comes from (a given name, else its
//! folder, split by sensor once the sensors are known), named uniquely.

use crate::grouping::{Origin, file_stem};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A recording to report on.
#[derive(Clone, Debug, PartialEq)]
pub struct Input {
    pub path: PathBuf,
    /// Unique among the report's inputs, safe for paths.
    pub name: String,
    pub origin: Origin,
}

/// Why the inputs of a report cannot be listed.
#[derive(Debug, thiserror::Error)]
pub enum InputsError {
    #[error("{}: no such file or directory\n  fix: check the path", .0.display())]
    NotFound(PathBuf),
    #[error("{}: cannot list: {source}", path.display())]
    CannotList {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: holds no recording ctcal reads\n  fix: give recordings or folders of them (an IJRR folder has events.txt)", .0.display())]
    NoRecordings(PathBuf),
    #[error("{}: not a recording ctcal reads\n  fix: give recordings (IJRR folders, HDF5, AEDAT4, RAW, DAT, ROS bags) or folders of them", .0.display())]
    NotARecording(PathBuf),
    #[error("no recordings given\n  fix: give recordings or folders of them")]
    Nothing,
}

/// Whether `path` is a recording ctcal reads (an IJRR folder or a file of a known format).
fn is_recording(path: &Path) -> bool {
    if path.is_dir() {
        return path.join("events.txt").is_file();
    }
    path.file_name()
        .is_some_and(|n| !n.to_string_lossy().starts_with('.'))
        && ctcal_io::detect(path).is_ok()
}

fn folder_name(p: &Path) -> String {
    p.canonicalize()
        .ok()
        .and_then(|c| c.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "recordings".into())
}

/// The recordings in a folder of them, sorted.
fn listed(path: &Path) -> Result<Vec<PathBuf>, InputsError> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|source| InputsError::CannotList {
            path: path.to_path_buf(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_recording(p))
        .collect();
    entries.sort();
    if entries.is_empty() {
        return Err(InputsError::NoRecordings(path.to_path_buf()));
    }
    Ok(entries)
}

/// The recordings of an input: itself, or the recordings in a folder of them; `dataset`
/// names their dataset (else their folder does).
pub fn expand(path: &Path, dataset: Option<&str>) -> Result<Vec<Input>, InputsError> {
    if !path.exists() {
        return Err(InputsError::NotFound(path.to_path_buf()));
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
        return Err(InputsError::NotARecording(path.to_path_buf()));
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

/// Names the inputs uniquely (names made safe for paths; a repeated name gets `_2`, ...).
pub fn named(mut all: Vec<Input>) -> Result<Vec<Input>, InputsError> {
    if all.is_empty() {
        return Err(InputsError::Nothing);
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

/// The recordings of `paths` (each a recording or a folder of them) and of `datasets`
/// (name, path), named uniquely.
pub fn inputs(
    paths: &[PathBuf],
    datasets: &[(String, PathBuf)],
) -> Result<Vec<Input>, InputsError> {
    let mut all = Vec::new();
    for path in paths {
        all.extend(expand(path, None)?);
    }
    for (name, path) in datasets {
        all.extend(expand(path, Some(name.trim()))?);
    }
    named(all)
}
