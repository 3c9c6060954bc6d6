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

/// A report given to gather: its folder, its `results.json` and what that says.
struct GivenReport {
    dir: PathBuf,
    results: PathBuf,
    read: decode::Results,
}

impl GivenReport {
    /// The report `given` (a report folder, or its `results.json`), read and decoded.
    fn read(given: &Path) -> Result<Self, GatherError> {
        let (dir, results) = if given.is_dir() {
            (given.to_path_buf(), given.join("results.json"))
        } else {
            let parent = given.parent().unwrap_or(Path::new(".")).to_path_buf();
            (parent, given.to_path_buf())
        };
        if !results.is_file() {
            return Err(GatherError::NotAReport(given.to_path_buf()));
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
        Ok(GivenReport { dir, results, read })
    }
}

/// The reports gathered so far: the first one's seed (and where it is from) and presets,
/// the sequences, their files, and which report each sequence's name came from.
#[derive(Default)]
struct Gathering {
    seed: Option<(u64, PathBuf)>,
    presets: Vec<PresetLevel>,
    outcomes: Vec<(Input, Result<SequenceReport, String>)>,
    files: Vec<OutputFile>,
    seen: BTreeMap<String, PathBuf>,
}

impl Gathering {
    /// Adds one report's sequences (with their files) and failed recordings.
    fn add(&mut self, report: GivenReport) -> Result<(), GatherError> {
        let GivenReport { dir, results, read } = report;
        self.agree_on_seed(&results, read.seed, read.presets)?;
        for s in read.sequences {
            self.claim(&s.name, &results)?;
            self.add_sequence(&dir, s)?;
        }
        for (name, path, error) in read.failed {
            self.claim(&name, &results)?;
            let input = Input {
                path: PathBuf::from(path),
                name,
                origin: Origin::Named(String::new()),
            };
            self.outcomes.push((input, Err(error)));
        }
        Ok(())
    }

    /// Refuses a report (its `results`) made with another seed than the first; the first
    /// sets the seed and the presets.
    fn agree_on_seed(
        &mut self,
        results: &Path,
        seed: u64,
        presets: Vec<PresetLevel>,
    ) -> Result<(), GatherError> {
        match &self.seed {
            Some((ours, first)) if *ours != seed => Err(GatherError::Seeds {
                path: results.to_path_buf(),
                theirs: seed,
                first: first.clone(),
                ours: *ours,
            }),
            Some(_) => Ok(()),
            None => {
                self.seed = Some((seed, results.to_path_buf()));
                self.presets = presets;
                Ok(())
            }
        }
    }

    /// Refuses a sequence `name` an earlier report (or this one, `results`) already has.
    fn claim(&mut self, name: &str, results: &Path) -> Result<(), GatherError> {
        match self.seen.get(name) {
            Some(first) => Err(GatherError::Twice {
                name: name.to_string(),
                first: first.clone(),
                path: results.to_path_buf(),
            }),
            None => {
                self.seen.insert(name.to_string(), results.to_path_buf());
                Ok(())
            }
        }
    }

    /// Adds a sequence of the report folder `dir` with its files, its fit's model restored
    /// from its params.toml.
    fn add_sequence(&mut self, dir: &Path, mut s: SequenceReport) -> Result<(), GatherError> {
        let own = sequence_files(dir, &s)?;
        if let Some(path) = decode::params_toml_path(&s).map(str::to_string)
            && let Some(f) = own.iter().find(|f| f.path == path)
        {
            let text = String::from_utf8_lossy(&f.bytes).into_owned();
            decode::restore_fit_model(&mut s, &text).map_err(|source| GatherError::Decode {
                path: dir.join(&path),
                source,
            })?;
        }
        self.files.extend(own);
        let input = Input {
            path: s
                .inputs
                .first()
                .map_or_else(|| dir.to_path_buf(), |f| PathBuf::from(&f.path)),
            name: s.name.clone(),
            origin: Origin::Named(s.dataset.clone()),
        };
        self.outcomes.push((input, Ok(s)));
        Ok(())
    }
}

/// The reports in `dirs` (report folders, or their `results.json`), in order.
pub fn gather(dirs: &[PathBuf]) -> Result<Gathered, GatherError> {
    let mut gathering = Gathering::default();
    for given in dirs {
        gathering.add(GivenReport::read(given)?)?;
    }
    let Gathering {
        seed,
        presets,
        outcomes,
        files,
        ..
    } = gathering;
    let (seed, _) = seed.ok_or(GatherError::Nothing)?;
    Ok(Gathered {
        seed,
        presets,
        outcomes,
        files,
    })
}
