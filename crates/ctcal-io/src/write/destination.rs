//! Where ctcal may write, and how, so that an output never costs a user a file.
//!
//! Rules (the CLI contract, `../shared/CLI.md`):
//! - an output is staged under a hidden sibling `.NAME.ctcal-partial-PID` and moved into
//!   place only when complete; a failure (or a panic) removes the partial copy, and partial
//!   copies left by a process that was killed are removed at the next run that writes beside
//!   them (their PID is no longer alive);
//! - an existing folder is written into only when it is empty, when ctcal made it (it holds
//!   ctcal's marker file listing what ctcal wrote), or with `--force`; then only the files
//!   ctcal writes are replaced, each by an atomic rename, and nothing else in the folder is
//!   touched;
//! - an existing file is replaced only when ctcal wrote it (its content carries ctcal's
//!   signature) or with `--force`;
//! - an output that equals or contains an input is refused; one inside an input folder needs
//!   `--force` (paths are compared canonically, symlinks resolved);
//! - a symlink is followed (the file it points at is written, the link stays); a character
//!   device or FIFO (`/dev/null`, a pipe) is written in place, never renamed over; sockets,
//!   block devices and folders where a file is expected are refused.

use crate::error::InputError;
use crate::hint::{Hint, Text};
use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};

/// The marker file ctcal leaves in every folder it writes: the list of files it wrote.
pub const MARKER: &str = ".ctcal-output.json";

/// Strings that only ctcal's own outputs carry near their start (see [`written_by_ctcal`]).
const SIGNATURES: [&[u8]; 3] = [
    b"\"ctcal_version\"",
    b"written by ctcal",
    b"% integrator_name ctcal",
];

/// The fix for an output that would replace what ctcal did not write.
fn force_fix(new: &str) -> Text {
    Text::from(format!("choose a new {new}, or "))
        .act(Hint::Force)
        .words(" to replace only the files ctcal writes")
}

/// The rules for one command's outputs: whether `--force` was given, and the inputs that no
/// output may overwrite.
#[derive(Clone, Debug, Default)]
pub struct OutputPolicy {
    pub force: bool,
    /// Inputs as given and canonical.
    inputs: Vec<(PathBuf, PathBuf)>,
}

/// How an output path relates to an input path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Relation {
    Equal,
    /// The input lies inside the output.
    Contains,
    /// The output lies inside the input (a folder).
    Inside,
}

impl OutputPolicy {
    pub fn new(force: bool) -> Self {
        Self {
            force,
            inputs: Vec::new(),
        }
    }

    /// Adds an input that outputs must not overwrite (ignored when it does not exist).
    pub fn protect(mut self, input: &Path) -> Self {
        if let Ok(canonical) = std::fs::canonicalize(input) {
            self.inputs.push((input.to_path_buf(), canonical));
        }
        self
    }

    /// Adds several inputs.
    pub fn protect_all<'a>(self, inputs: impl IntoIterator<Item = &'a Path>) -> Self {
        inputs.into_iter().fold(self, |policy, p| policy.protect(p))
    }

    fn check_inputs(&self, shown: &Path, canonical: &Path) -> Result<(), InputError> {
        for (given, input) in &self.inputs {
            let relation = if canonical == input {
                Relation::Equal
            } else if input.starts_with(canonical) {
                Relation::Contains
            } else if canonical.starts_with(input) {
                Relation::Inside
            } else {
                continue;
            };
            let problem = match relation {
                Relation::Equal => format!("is the input {}", given.display()),
                Relation::Contains => format!("contains the input {}", given.display()),
                Relation::Inside => format!("lies inside the input folder {}", given.display()),
            };
            if relation == Relation::Inside && self.force {
                continue;
            }
            let fix = match relation {
                Relation::Inside => Text::from("write the output outside the input folder, or ")
                    .act(Hint::Force)
                    .words(" to write there anyway"),
                _ => {
                    "choose an output path that is neither the input nor a folder holding it".into()
                }
            };
            return Err(InputError::invalid(
                shown,
                format!("the output {problem}"),
                fix,
            ));
        }
        Ok(())
    }

    /// Checks that a file output may be written at `path`, without creating anything (to
    /// refuse early, before a long computation).
    pub fn check_file(&self, path: &Path) -> Result<(), InputError> {
        self.plan_file(path).map(|_| ())
    }

    /// Checks that a folder output may be written at `path`, without creating anything.
    pub fn check_folder(&self, path: &Path) -> Result<(), InputError> {
        self.plan_folder(path).map(|_| ())
    }

    /// Prepares a file output at `path`.
    pub fn file(&self, path: &Path) -> Result<Staged, InputError> {
        let (target, in_place) = self.plan_file(path)?;
        if in_place {
            return Ok(Staged {
                shown: path.to_path_buf(),
                target: target.clone(),
                partial: target,
                in_place: true,
                committed: false,
            });
        }
        let parent = parent_of(&target);
        create_parent(path, &parent)?;
        clean_stale_partials(&parent);
        let partial = partial_path(&target);
        remove_any(&partial).map_err(|e| InputError::write(&partial, e))?;
        Ok(Staged {
            shown: path.to_path_buf(),
            target,
            partial,
            in_place: false,
            committed: false,
        })
    }

    /// The file a file output at `path` writes, and whether it is written in place.
    fn plan_file(&self, path: &Path) -> Result<(PathBuf, bool), InputError> {
        if path.as_os_str().to_string_lossy().ends_with('/') {
            return Err(InputError::invalid(
                path,
                "names a folder, but this output is a file",
                "give a file path (e.g. results.json)",
            ));
        }
        let target = follow_link(path)?;
        let canonical = canonical_future(&target);
        self.check_inputs(path, &canonical)?;
        match std::fs::metadata(&target) {
            Ok(meta) => {
                let kind = FileKind::of(&meta);
                match kind {
                    FileKind::Regular => {
                        if !self.force && !written_by_ctcal(&target) {
                            return Err(InputError::invalid(
                                path,
                                "exists and was not written by ctcal",
                                force_fix("path"),
                            ));
                        }
                    }
                    FileKind::Stream => return Ok((target, true)),
                    other => {
                        return Err(InputError::invalid(
                            path,
                            format!("is {}, not a file ctcal can write", other.describe()),
                            "give the path of a regular file",
                        ));
                    }
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(InputError::write(path, e)),
        }
        Ok((target, false))
    }

    /// Prepares a folder output at `path`.
    pub fn folder(&self, path: &Path) -> Result<StagedFolder, InputError> {
        let (target, existing) = self.plan_folder(path)?;
        let parent = parent_of(&target);
        create_parent(path, &parent)?;
        clean_stale_partials(&parent);
        let partial = partial_path(&target);
        remove_any(&partial).map_err(|e| InputError::write(&partial, e))?;
        std::fs::create_dir(&partial).map_err(|e| InputError::write(path, e))?;
        Ok(StagedFolder {
            shown: path.to_path_buf(),
            target,
            partial,
            existing,
            committed: false,
        })
    }

    /// The folder a folder output at `path` writes, and what it holds already.
    fn plan_folder(&self, path: &Path) -> Result<(PathBuf, Option<ExistingFolder>), InputError> {
        let target = follow_link(path)?;
        let canonical = canonical_future(&target);
        self.check_inputs(path, &canonical)?;
        let existing = match std::fs::metadata(&target) {
            Ok(meta) if meta.is_dir() => Some(self.existing_folder(path, &target)?),
            Ok(meta) => {
                return Err(InputError::invalid(
                    path,
                    format!(
                        "is {}, but this output is a folder",
                        FileKind::of(&meta).describe()
                    ),
                    "give the path of a new folder",
                ));
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => return Err(InputError::write(path, e)),
        };
        Ok((target, existing))
    }

    /// What may be replaced in an existing folder, or why it may not be written at all.
    fn existing_folder(&self, shown: &Path, target: &Path) -> Result<ExistingFolder, InputError> {
        let entries: Vec<String> = std::fs::read_dir(target)
            .map_err(|e| InputError::write(shown, e))?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        let previous = read_marker(target);
        if entries.is_empty() || self.force || previous.is_some() {
            return Ok(ExistingFolder {
                previous: previous.unwrap_or_default(),
                force: self.force,
            });
        }
        let mut shown_entries: Vec<&str> = entries.iter().map(String::as_str).collect();
        shown_entries.sort_unstable();
        let more = shown_entries.len().saturating_sub(3);
        let mut list = shown_entries
            .iter()
            .take(3)
            .copied()
            .collect::<Vec<_>>()
            .join(", ");
        if more > 0 {
            list.push_str(&format!(" and {more} more"));
        }
        Err(InputError::invalid(
            shown,
            format!("is an existing folder that ctcal did not create (it holds {list})"),
            force_fix("folder"),
        ))
    }
}

/// What kind of thing a path is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FileKind {
    Regular,
    Folder,
    /// A character device or FIFO: written in place.
    Stream,
    Other(&'static str),
}

impl FileKind {
    fn of(meta: &std::fs::Metadata) -> Self {
        let kind = meta.file_type();
        if kind.is_file() {
            return FileKind::Regular;
        }
        if kind.is_dir() {
            return FileKind::Folder;
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if kind.is_char_device() || kind.is_fifo() {
                return FileKind::Stream;
            }
            if kind.is_socket() {
                return FileKind::Other("a socket");
            }
            if kind.is_block_device() {
                return FileKind::Other("a block device");
            }
        }
        FileKind::Other("a special file")
    }

    fn describe(self) -> &'static str {
        match self {
            FileKind::Regular => "a file",
            FileKind::Folder => "a folder",
            FileKind::Stream => "a device or pipe",
            FileKind::Other(what) => what,
        }
    }
}

/// The file a symlink at `path` points at (following chains), or `path` itself when it is
/// no link; a link whose target does not exist (dangling, or a loop) is refused: writing
/// through it would create the target's folders wherever the link points.
fn follow_link(path: &Path) -> Result<PathBuf, InputError> {
    let is_link = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
    if !is_link {
        return Ok(path.to_path_buf());
    }
    match std::fs::metadata(path) {
        Ok(_) => Ok(follow_symlink(path)),
        Err(e) => {
            let target = std::fs::read_link(path)
                .map(|t| t.display().to_string())
                .unwrap_or_else(|_| "?".into());
            let problem = if e.kind() == std::io::ErrorKind::NotFound {
                format!("is a symbolic link to {target}, which does not exist")
            } else {
                format!("is a symbolic link to {target}, which cannot be followed ({e})")
            };
            Err(InputError::invalid(
                path,
                problem,
                "create the link's target first, remove the link, or give another path",
            ))
        }
    }
}

/// The file a symlink points at (following chains), or `path` itself.
fn follow_symlink(path: &Path) -> PathBuf {
    let mut current = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => match std::fs::read_link(&current) {
                Ok(target) if target.is_absolute() => current = target,
                Ok(target) => current = parent_of(&current).join(target),
                Err(_) => return current,
            },
            _ => return current,
        }
    }
    current
}

/// The folder holding `path` (`.` for a bare name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The canonical form `path` will have: its deepest existing ancestor canonicalised, the
/// rest appended with `..` resolved lexically.
pub(crate) fn canonical_future(path: &Path) -> PathBuf {
    if let Ok(c) = std::fs::canonicalize(path) {
        return c;
    }
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .unwrap_or_else(|_| PathBuf::from("/"))
            .join(path)
    };
    let mut existing = absolute.clone();
    let mut rest: Vec<std::ffi::OsString> = Vec::new();
    while std::fs::symlink_metadata(&existing).is_err() {
        let Some(name) = existing.file_name() else {
            break;
        };
        rest.push(name.to_os_string());
        if !existing.pop() {
            break;
        }
    }
    let mut out = std::fs::canonicalize(&existing).unwrap_or(existing);
    for part in rest.iter().rev() {
        match Path::new(part).components().next() {
            Some(Component::ParentDir) => {
                out.pop();
            }
            Some(Component::CurDir) | None => {}
            _ => out.push(part),
        }
    }
    out
}

fn create_parent(shown: &Path, parent: &Path) -> Result<(), InputError> {
    if parent.is_dir() {
        return Ok(());
    }
    std::fs::create_dir_all(parent).map_err(|e| InputError::write(shown, e))
}

/// `.NAME.ctcal-partial-PID` beside `target`.
fn partial_path(target: &Path) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    parent_of(target).join(format!(".{name}.ctcal-partial-{}", std::process::id()))
}

/// The PID of a partial copy's name, if the name is one ctcal gives.
fn partial_pid(name: &str) -> Option<u32> {
    if !name.starts_with('.') {
        return None;
    }
    let (_, pid) = name.rsplit_once(".ctcal-partial-")?;
    if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    pid.parse().ok()
}

/// Whether process `pid` is running (always true where that cannot be told).
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Removes partial copies in `folder` left by ctcal processes that no longer run (killed,
/// out of memory). Best effort: a copy that cannot be removed is left.
pub fn clean_stale_partials(folder: &Path) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(pid) = partial_pid(&name)
            && pid != std::process::id()
            && !process_alive(pid)
        {
            let _ = remove_any(&entry.path());
        }
    }
}

fn remove_any(path: &Path) -> std::io::Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path),
        Ok(_) => std::fs::remove_file(path),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
    }
}

/// Whether ctcal wrote the file at `path`: an HDF5 file with a root `ctcal_version`
/// attribute, or any other file whose first 4 KB carry one of ctcal's signatures
/// (`"ctcal_version"` in JSON, `written by ctcal` in text configs, `% integrator_name
/// ctcal` in EVT3 headers).
pub fn written_by_ctcal(path: &Path) -> bool {
    use std::io::Read;
    let mut head = Vec::new();
    if std::fs::File::open(path)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .is_err()
    {
        return false;
    }
    if head.starts_with(crate::h5::SIGNATURE) {
        // without libhdf5 the attribute cannot be read: not known to be ctcal's, so kept
        #[cfg(not(feature = "hdf5"))]
        return false;
        #[cfg(feature = "hdf5")]
        return hdf5::File::open(path)
            .map(|f| f.attr("ctcal_version").is_ok())
            .unwrap_or(false);
    }
    SIGNATURES
        .iter()
        .any(|s| head.windows(s.len()).any(|w| w == *s))
}

/// A file output being written: to a partial sibling moved into place by
/// [`Staged::commit`] (deleted if dropped uncommitted), or in place for a device or FIFO.
#[derive(Debug)]
pub struct Staged {
    /// The path as the user gave it (for messages).
    pub shown: PathBuf,
    /// The file that will hold the output (a symlink's target).
    pub target: PathBuf,
    /// Where to write now.
    pub partial: PathBuf,
    /// Written in place (a device or FIFO): nothing to move, nothing to remove.
    pub in_place: bool,
    committed: bool,
}

impl Staged {
    /// Moves the finished output into place.
    pub fn commit(mut self) -> Result<(), InputError> {
        if !self.in_place {
            std::fs::rename(&self.partial, &self.target)
                .map_err(|e| InputError::write(&self.shown, e))?;
        }
        self.committed = true;
        Ok(())
    }

    /// Writes `bytes` and commits.
    pub fn write_all(self, bytes: &[u8]) -> Result<(), InputError> {
        use std::io::Write;
        let result = std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(!self.in_place)
            .open(&self.partial)
            .and_then(|mut f| {
                f.write_all(bytes)?;
                f.flush()?;
                if !self.in_place {
                    f.sync_all()?;
                }
                Ok(())
            });
        result.map_err(|e| InputError::write(&self.shown, e))?;
        self.commit()
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed && !self.in_place {
            // best effort: the error that stopped the writer is the one to report
            let _ = remove_any(&self.partial);
        }
    }
}

/// An existing folder being written into: the files ctcal wrote there last time, and
/// whether `--force` allows replacing files ctcal did not write.
#[derive(Debug)]
struct ExistingFolder {
    previous: BTreeSet<PathBuf>,
    force: bool,
}

/// A folder output being written in a partial sibling; [`StagedFolder::commit`] moves it
/// into place (or its files into an existing folder, one by one). Dropped uncommitted, the
/// partial folder is deleted.
#[derive(Debug)]
pub struct StagedFolder {
    pub shown: PathBuf,
    pub target: PathBuf,
    partial: PathBuf,
    existing: Option<ExistingFolder>,
    committed: bool,
}

impl StagedFolder {
    /// The folder to write into now.
    pub fn dir(&self) -> &Path {
        &self.partial
    }

    /// Writes `bytes` to `relative` inside the folder (creating sub-folders).
    pub fn write(&self, relative: &str, bytes: &[u8]) -> Result<(), InputError> {
        let path = self.partial.join(relative);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).map_err(|e| InputError::write(&self.shown, e))?;
        }
        std::fs::write(&path, bytes).map_err(|e| InputError::write(&self.shown, e))
    }

    /// Moves the finished folder into place and records what ctcal wrote in its marker.
    pub fn commit(mut self) -> Result<(), InputError> {
        let written = list_files(&self.partial).map_err(|e| InputError::write(&self.shown, e))?;
        let marker = marker_text(&written);
        match &self.existing {
            None => {
                std::fs::write(self.partial.join(MARKER), &marker)
                    .map_err(|e| InputError::write(&self.shown, e))?;
                std::fs::rename(&self.partial, &self.target)
                    .map_err(|e| InputError::write(&self.shown, e))?;
            }
            Some(existing) => {
                // refuse before moving anything: a file ctcal did not write is replaced only
                // with --force
                if !existing.force
                    && let Some(clash) = written.iter().find(|f| {
                        !existing.previous.contains(*f)
                            && std::fs::symlink_metadata(self.target.join(f)).is_ok()
                    })
                {
                    return Err(InputError::invalid(
                        &self.shown,
                        format!("holds {}, which ctcal did not write there", clash.display()),
                        force_fix("path"),
                    ));
                }
                for file in &written {
                    let to = self.target.join(file);
                    if let Some(parent) = to.parent() {
                        std::fs::create_dir_all(parent)
                            .map_err(|e| InputError::write(&self.shown, e))?;
                    }
                    std::fs::rename(self.partial.join(file), &to)
                        .map_err(|e| InputError::write(&self.shown, e))?;
                }
                // files of ctcal's previous run that this run did not write again
                for stale in existing.previous.difference(&written) {
                    if is_plain_relative(stale) {
                        let _ = std::fs::remove_file(self.target.join(stale));
                    }
                }
                std::fs::write(self.target.join(MARKER), &marker)
                    .map_err(|e| InputError::write(&self.shown, e))?;
                let _ = remove_any(&self.partial);
            }
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for StagedFolder {
    fn drop(&mut self) {
        if !self.committed {
            let _ = remove_any(&self.partial);
        }
    }
}

/// A relative path without `..` or a root (a marker is data from disk: never follow it out
/// of its folder).
fn is_plain_relative(path: &Path) -> bool {
    path.components().all(|c| matches!(c, Component::Normal(_)))
}

/// Every file under `root`, relative to it (the marker excluded).
fn list_files(root: &Path) -> std::io::Result<BTreeSet<PathBuf>> {
    let mut out = BTreeSet::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(relative) = stack.pop() {
        for entry in std::fs::read_dir(root.join(&relative))? {
            let entry = entry?;
            let path = relative.join(entry.file_name());
            if entry.file_type()?.is_dir() {
                stack.push(path);
            } else if path != Path::new(MARKER) {
                out.insert(path);
            }
        }
    }
    Ok(out)
}

#[derive(serde::Serialize, serde::Deserialize)]
struct Marker {
    ctcal_version: String,
    note: String,
    files: Vec<PathBuf>,
}

fn marker_text(files: &BTreeSet<PathBuf>) -> String {
    let marker = Marker {
        ctcal_version: env!("CARGO_PKG_VERSION").to_string(),
        note: "ctcal wrote this folder; it replaces only the files listed here".into(),
        files: files.iter().cloned().collect(),
    };
    serde_json::to_string_pretty(&marker).expect("marker serialises") + "\n"
}

/// The files ctcal wrote in `folder`, from its marker (`None` without a readable marker).
fn read_marker(folder: &Path) -> Option<BTreeSet<PathBuf>> {
    let path = folder.join(MARKER);
    let meta = std::fs::symlink_metadata(&path).ok()?;
    if !meta.is_file() || meta.len() > 64 << 20 {
        return None;
    }
    let text = std::fs::read_to_string(&path).ok()?;
    let marker: Marker = serde_json::from_str(&text).ok()?;
    Some(marker.files.into_iter().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder_output(policy: &OutputPolicy, path: &Path, files: &[(&str, &str)]) {
        let staged = policy.folder(path).unwrap();
        for (name, text) in files {
            staged.write(name, text.as_bytes()).unwrap();
        }
        staged.commit().unwrap();
    }

    #[test]
    fn a_new_folder_gets_the_files_and_a_marker() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a/b/out");
        folder_output(
            &OutputPolicy::default(),
            &out,
            &[("x.txt", "1"), ("sub/y.txt", "2")],
        );
        assert_eq!(std::fs::read_to_string(out.join("sub/y.txt")).unwrap(), "2");
        let marker = read_marker(&out).unwrap();
        assert!(marker.contains(Path::new("x.txt")) && marker.len() == 2);
        // nothing left beside it
        let names: Vec<_> = std::fs::read_dir(out.parent().unwrap())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("out")]);
    }

    #[test]
    fn a_users_folder_is_refused_and_force_replaces_only_ctcal_files() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("notes.md"), "mine").unwrap();
        let e = OutputPolicy::default().folder(&out).unwrap_err();
        let InputError::Invalid { fix, .. } = &e else {
            panic!("{e}")
        };
        assert_eq!(fix.hints().collect::<Vec<_>>(), [&Hint::Force]);
        let e = e.to_string();
        assert!(e.contains("did not create") && e.contains("notes.md"));
        folder_output(&OutputPolicy::new(true), &out, &[("x.txt", "1")]);
        assert_eq!(
            std::fs::read_to_string(out.join("notes.md")).unwrap(),
            "mine"
        );
        assert_eq!(std::fs::read_to_string(out.join("x.txt")).unwrap(), "1");
    }

    #[test]
    fn ctcals_own_folder_is_rewritten_without_force_and_stale_files_go() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let policy = OutputPolicy::default();
        folder_output(&policy, &out, &[("a.txt", "1"), ("old.txt", "2")]);
        std::fs::write(out.join("notes.md"), "mine").unwrap();
        folder_output(&policy, &out, &[("a.txt", "3")]);
        assert_eq!(std::fs::read_to_string(out.join("a.txt")).unwrap(), "3");
        assert!(!out.join("old.txt").exists(), "ctcal's stale file removed");
        assert_eq!(
            std::fs::read_to_string(out.join("notes.md")).unwrap(),
            "mine"
        );
        // a user file where ctcal now wants to write is not replaced without --force
        std::fs::write(out.join("b.txt"), "mine too").unwrap();
        let staged = policy.folder(&out).unwrap();
        staged.write("b.txt", b"ctcal").unwrap();
        assert!(staged.commit().is_err());
        assert_eq!(
            std::fs::read_to_string(out.join("b.txt")).unwrap(),
            "mine too"
        );
    }

    #[test]
    fn outputs_that_hold_or_are_inputs_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let rec = dir.path().join("rec");
        std::fs::create_dir(&rec).unwrap();
        std::fs::write(rec.join("events.txt"), "0 1 1 1\n").unwrap();
        let policy = OutputPolicy::default().protect(&rec.join("events.txt"));
        let e = policy.folder(&rec).unwrap_err().to_string();
        assert!(e.contains("contains the input"), "{e}");
        let e = policy
            .file(&rec.join("events.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("is the input"), "{e}");
        let policy = OutputPolicy::default().protect(&rec);
        let e = policy
            .file(&rec.join("stats.json"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("inside the input folder"), "{e}");
        assert!(
            OutputPolicy::new(true)
                .protect(&rec)
                .file(&rec.join("s.json"))
                .is_ok()
        );
        assert_eq!(
            std::fs::read_to_string(rec.join("events.txt")).unwrap(),
            "0 1 1 1\n"
        );
    }

    #[test]
    fn files_symlinks_and_devices() {
        let dir = tempfile::tempdir().unwrap();
        let mine = dir.path().join("mine.json");
        std::fs::write(&mine, "{\"a\": 1}").unwrap();
        assert!(OutputPolicy::default().file(&mine).is_err());
        let ours = dir.path().join("ours.json");
        std::fs::write(&ours, "{\n  \"ctcal_version\": \"0.1.0\"\n}").unwrap();
        OutputPolicy::default()
            .file(&ours)
            .unwrap()
            .write_all(b"new")
            .unwrap();
        assert_eq!(std::fs::read_to_string(&ours).unwrap(), "new");
        #[cfg(unix)]
        {
            let link = dir.path().join("link.json");
            std::os::unix::fs::symlink(&ours, &link).unwrap();
            std::fs::write(&ours, "\"ctcal_version\"").unwrap();
            OutputPolicy::default()
                .file(&link)
                .unwrap()
                .write_all(b"via link")
                .unwrap();
            assert!(
                std::fs::symlink_metadata(&link)
                    .unwrap()
                    .file_type()
                    .is_symlink()
            );
            assert_eq!(std::fs::read_to_string(&ours).unwrap(), "via link");
            let null = OutputPolicy::default()
                .file(Path::new("/dev/null"))
                .unwrap();
            assert!(null.in_place);
            null.write_all(b"gone").unwrap();
            assert!(Path::new("/dev/null").exists());
            let full = OutputPolicy::default()
                .file(Path::new("/dev/full"))
                .unwrap();
            let e = full.write_all(b"x").unwrap_err().to_string();
            assert!(e.contains("/dev/full") && e.contains("fix:"), "{e}");
        }
        let e = OutputPolicy::default()
            .file(dir.path())
            .unwrap_err()
            .to_string();
        assert!(e.contains("a folder"), "{e}");
    }

    #[test]
    fn stale_partials_of_dead_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // PIDs above the kernel's pid_max (4194304 at most) cannot be alive
        let stale = dir.path().join(".out.ctcal-partial-99999999");
        std::fs::create_dir(&stale).unwrap();
        std::fs::write(stale.join("events.txt"), "x").unwrap();
        let not_ours = dir.path().join(".out.ctcal-partial-abc");
        std::fs::write(&not_ours, "x").unwrap();
        let alive = dir
            .path()
            .join(format!(".x.ctcal-partial-{}", std::process::id()));
        std::fs::write(&alive, "x").unwrap();
        clean_stale_partials(dir.path());
        if cfg!(target_os = "linux") {
            assert!(!stale.exists());
        }
        assert!(not_ours.exists() && alive.exists());
    }
}
