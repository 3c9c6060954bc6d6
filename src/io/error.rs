//! Errors of reading and writing recordings. Every message names the file, the place in it
//! (line, byte offset, dataset index) and the fix, because the person reading it has a
//! recording in front of them, not the source code.

use std::path::{Path, PathBuf};

/// What went wrong while reading or writing a recording.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("{}: no such file or directory\n  fix: check the path (relative paths start from {})", path.display(), std::env::current_dir().map(|d| d.display().to_string()).unwrap_or_default())]
    NotFound { path: PathBuf },

    #[error("{}: cannot read: {source}\n  fix: check the file's permissions and that the disk is readable", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// (The I/O error is part of the message, not a separate cause, so that it is shown
    /// once.)
    #[error("{}: cannot write: {error}\n  fix: {}", path.display(), write_fix(error))]
    Write {
        path: PathBuf,
        error: std::io::Error,
    },

    #[error("{}: unknown format ({detail})\n  fix: {fix}", path.display())]
    UnknownFormat {
        path: PathBuf,
        detail: String,
        fix: String,
    },

    #[error("{}: {place}: {problem}\n  fix: {fix}", path.display())]
    Corrupt {
        path: PathBuf,
        place: String,
        problem: String,
        fix: String,
    },

    #[error("{}: {place}: event at x={x}, y={y} lies outside the {width}x{height} sensor{claimed}\n  fix: {fix}", path.display())]
    OutsideSensor {
        path: PathBuf,
        place: String,
        x: i64,
        y: i64,
        width: u16,
        height: u16,
        claimed: String,
        fix: String,
    },

    #[error("{}: {count} timestamps go backwards, the first at {place} ({previous_us} us, then {t_us} us)\n  fix: pass --sort to accept the file and sort its events by time", path.display())]
    Unsorted {
        path: PathBuf,
        count: u64,
        place: String,
        previous_us: i64,
        t_us: i64,
    },

    #[error("{}: contains no events\n  fix: check that this is the right file and that the recording was not cut short", path.display())]
    Empty { path: PathBuf },

    #[error("{}: no events lie in the selected time window ({detail})\n  fix: widen --start/--end (seconds from the first event)", path.display())]
    EmptyWindow { path: PathBuf, detail: String },

    #[error("{}: HDF5: {problem}\n  fix: {fix}", path.display())]
    Hdf5 {
        path: PathBuf,
        problem: String,
        fix: String,
    },

    #[error("{}: {problem}\n  fix: {fix}", path.display())]
    Invalid {
        path: PathBuf,
        problem: String,
        fix: String,
    },
}

/// The fix for a file whose format is not recognised.
pub const FIX_UNKNOWN_FORMAT: &str =
    "pass --format ijrr|h5|aedat4|evt2|evt3|dat|bag if the file is one of these";

impl InputError {
    /// A file that cannot be read as a regular file (missing, a folder, a FIFO, ...).
    pub fn not_a_file(path: &Path, problem: crate::files::NotAFile) -> Self {
        match problem {
            crate::files::NotAFile::Missing => InputError::NotFound {
                path: path.to_path_buf(),
            },
            other => InputError::invalid(path, other.problem(), other.fix()),
        }
    }

    pub(crate) fn unknown(path: &Path, detail: impl Into<String>, fix: impl Into<String>) -> Self {
        InputError::UnknownFormat {
            path: path.to_path_buf(),
            detail: detail.into(),
            fix: fix.into(),
        }
    }

    /// An I/O error while reading `path`, mapping "not found" to [`InputError::NotFound`].
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        if source.kind() == std::io::ErrorKind::NotFound {
            InputError::NotFound {
                path: path.to_path_buf(),
            }
        } else {
            InputError::Io {
                path: path.to_path_buf(),
                source,
            }
        }
    }

    pub fn write(path: &Path, error: std::io::Error) -> Self {
        InputError::Write {
            path: path.to_path_buf(),
            error,
        }
    }

    pub fn corrupt(
        path: &Path,
        place: impl Into<String>,
        problem: impl Into<String>,
        fix: impl Into<String>,
    ) -> Self {
        InputError::Corrupt {
            path: path.to_path_buf(),
            place: place.into(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    pub fn invalid(path: &Path, problem: impl Into<String>, fix: impl Into<String>) -> Self {
        InputError::Invalid {
            path: path.to_path_buf(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    pub fn hdf5(path: &Path, problem: impl Into<String>, fix: impl Into<String>) -> Self {
        InputError::Hdf5 {
            path: path.to_path_buf(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    /// Whether the user can fix this (exit code 2): every input problem, and output problems
    /// too (a full disk, a read-only folder, a refused path), which name the path and a fix.
    pub fn is_bad_input(&self) -> bool {
        true
    }
}

/// The fix for a failed write, by its cause.
fn write_fix(error: &std::io::Error) -> &'static str {
    use std::io::ErrorKind as K;
    match error.kind() {
        K::StorageFull | K::QuotaExceeded => {
            "free space on that disk, or write the output to another disk"
        }
        K::PermissionDenied | K::ReadOnlyFilesystem => {
            "write to a folder you may write in (check its permissions)"
        }
        K::NotFound => "check that the output's folder exists",
        K::BrokenPipe => "the program reading the output stopped early",
        _ => "check that the output's folder exists, is writable and has space",
    }
}

/// The usual fix for a binary file that ends early or holds garbage.
pub const FIX_TRUNCATED: &str =
    "the file is damaged or was cut short: copy it again from the source recording";
