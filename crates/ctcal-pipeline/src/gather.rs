//! Reports made elsewhere gathered for one merge: each folder's `results.json` read back
//! ([`super::decode`]) with the files of each of its sequences (tables, plots,
//! configurations, masks), so that a dataset reported in parts, on several machines,
//! becomes one report.

use super::decode::{self, DecodeError};
use super::inputs::Input;
use crate::OutputFile;
use crate::grouping::Origin;
use crate::model::{PresetLevel, SequenceReport};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Why reports cannot be gathered.
#[derive(Debug, thiserror::Error)]
pub enum GatherError {
    #[error("{}: a folder without results.json (not a ctcal report)\n  fix: give folders a ctcal report wrote", .0.display())]
    NotAReport(PathBuf),
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not JSON: {source}\n  fix: give the results.json a ctcal report wrote, unedited", path.display())]
    NotJson {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error("{}: {source}\n  fix: give the results.json a ctcal report wrote, unedited", path.display())]
    Decode { path: PathBuf, source: DecodeError },
    #[error("{}: seed {theirs}, but {} has seed {ours}: their simulations differ\n  fix: merge reports made with the same seed", path.display(), first.display())]
    Seeds {
        path: PathBuf,
        theirs: u64,
        first: PathBuf,
        ours: u64,
    },
    #[error("sequence `{name}` is in both {} and {}\n  fix: merge reports of different recordings", first.display(), path.display())]
    Twice {
        name: String,
        first: PathBuf,
        path: PathBuf,
    },
    #[error("no reports given\n  fix: give folders a ctcal report wrote")]
    Nothing,
}

/// The reports of several folders, ready to merge.
pub struct Gathered {
    pub seed: u64,
    pub presets: Vec<PresetLevel>,
    /// Each sequence, or the error it failed with, and the input it stands for (its dataset
    /// kept as the report named it).
    pub outcomes: Vec<(Input, Result<SequenceReport, String>)>,
    /// Every file of the sequences, at its path inside a report folder.
    pub files: Vec<OutputFile>,
}

fn read(path: &Path) -> Result<Vec<u8>, GatherError> {
    std::fs::read(path).map_err(|source| GatherError::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// The files of one sequence inside the report folder `dir`.
fn sequence_files(dir: &Path, s: &SequenceReport) -> Result<Vec<OutputFile>, GatherError> {
    let mut paths: Vec<String> = Vec::new();
    let tables = dir.join("tables").join(&s.name);
    if tables.is_dir() {
        let mut names: Vec<String> = std::fs::read_dir(&tables)
            .map_err(|source| GatherError::Read {
                path: tables.clone(),
                source,
            })?
            .filter_map(|e| e.ok())
            .filter(|e| e.path().is_file())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        paths.extend(names.iter().map(|n| format!("tables/{}/{n}", s.name)));
    }
    for plot in &s.outputs.plots {
        for ext in ["png", "svg", "csv"] {
            paths.push(format!("plots/{}.{ext}", plot.name));
        }
    }
    paths.extend(s.outputs.configs.iter().cloned());
    paths.extend(s.outputs.masks.iter().cloned());
    paths
        .into_iter()
        .map(|path| {
            Ok(OutputFile {
                bytes: read(&dir.join(&path))?,
                path,
            })
        })
        .collect()
}

/// The reports in `dirs` (report folders, or their `results.json`), in order.
pub fn gather(dirs: &[PathBuf]) -> Result<Gathered, GatherError> {
    let mut seed: Option<(u64, PathBuf)> = None;
    let mut presets = Vec::new();
    let mut outcomes = Vec::new();
    let mut files = Vec::new();
    let mut seen: BTreeMap<String, PathBuf> = BTreeMap::new();
    for given in dirs {
        let (dir, results) = if given.is_dir() {
            (given.clone(), given.join("results.json"))
        } else {
            let parent = given.parent().unwrap_or(Path::new(".")).to_path_buf();
            (parent, given.clone())
        };
        if !results.is_file() {
            return Err(GatherError::NotAReport(given.clone()));
        }
        let bytes = read(&results)?;
        let json: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|source| GatherError::NotJson {
                path: results.clone(),
                source,
            })?;
        let read = decode::results(&json).map_err(|source| GatherError::Decode {
            path: results.clone(),
            source,
        })?;
        match &seed {
            Some((ours, first)) if *ours != read.seed => {
                return Err(GatherError::Seeds {
                    path: results,
                    theirs: read.seed,
                    first: first.clone(),
                    ours: *ours,
                });
            }
            Some(_) => {}
            None => {
                seed = Some((read.seed, results.clone()));
                presets = read.presets;
            }
        }
        let mut claim = |name: &str| match seen.get(name) {
            Some(first) => Err(GatherError::Twice {
                name: name.to_string(),
                first: first.clone(),
                path: results.clone(),
            }),
            None => {
                seen.insert(name.to_string(), results.clone());
                Ok(())
            }
        };
        for mut s in read.sequences {
            claim(&s.name)?;
            let own = sequence_files(&dir, &s)?;
            if let Some(path) = decode::params_toml_path(&s).map(str::to_string)
                && let Some(f) = own.iter().find(|f| f.path == path)
            {
                let text = String::from_utf8_lossy(&f.bytes).into_owned();
                decode::restore_fit_model(&mut s, &text).map_err(|source| GatherError::Decode {
                    path: dir.join(&path),
                    source,
                })?;
            }
            files.extend(own);
            let input = Input {
                path: s
                    .inputs
                    .first()
                    .map_or_else(|| dir.clone(), |f| PathBuf::from(&f.path)),
                name: s.name.clone(),
                origin: Origin::Named(s.dataset.clone()),
            };
            outcomes.push((input, Ok(s)));
        }
        for (name, path, error) in read.failed {
            claim(&name)?;
            let input = Input {
                path: PathBuf::from(path),
                name,
                origin: Origin::Named(String::new()),
            };
            outcomes.push((input, Err(error)));
        }
    }
    let (seed, _) = seed.ok_or(GatherError::Nothing)?;
    Ok(Gathered {
        seed,
        presets,
        outcomes,
        files,
    })
}
