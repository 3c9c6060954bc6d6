//! Errors of reading and writing recordings. Every message names the file, the place in it
//! (line, byte offset, dataset index) and the fix, because the person reading it has a
//! recording in front of them, not the source code. A fix that sets an option names it as a
//! [`Hint`], which the library words neutrally and the `ctcal` binary as its flag.

use crate::hint::{Hint, Text};
use std::fmt;
use std::path::{Path, PathBuf};

/// What went wrong while reading or writing a recording. Its message ([`InputError::message`])
/// names the options that fix it as [`Hint`]s.
#[derive(Debug)]
pub enum InputError {
    NotFound {
        path: PathBuf,
    },
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// (The I/O error is part of the message, not a separate cause, so that it is shown
    /// once.)
    Write {
        path: PathBuf,
        error: std::io::Error,
    },
    UnknownFormat {
        path: PathBuf,
        detail: String,
        fix: Text,
    },
    Corrupt {
        path: PathBuf,
        place: String,
        problem: String,
        fix: Text,
    },
    OutsideSensor {
        path: PathBuf,
        place: String,
        x: i64,
        y: i64,
        width: u16,
        height: u16,
        claimed: String,
        fix: Text,
    },
    Unsorted {
        path: PathBuf,
        count: u64,
        place: String,
        previous_us: i64,
        t_us: i64,
    },
    Empty {
        path: PathBuf,
    },
    EmptyWindow {
        path: PathBuf,
        detail: String,
    },
    Hdf5 {
        path: PathBuf,
        problem: String,
        fix: Text,
    },
    Invalid {
        path: PathBuf,
        problem: Text,
        fix: Text,
    },
}

/// The fix for a file whose format is not recognised.
pub fn fix_unknown_format() -> Text {
    Text::default()
        .act(Hint::Format(None))
        .words(" ijrr|h5|aedat4|evt2|evt3|dat|bag if the file is one of these")
}

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

    pub(crate) fn unknown(path: &Path, detail: impl Into<String>, fix: impl Into<Text>) -> Self {
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
        fix: impl Into<Text>,
    ) -> Self {
        InputError::Corrupt {
            path: path.to_path_buf(),
            place: place.into(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    pub fn invalid(path: &Path, problem: impl Into<Text>, fix: impl Into<Text>) -> Self {
        InputError::Invalid {
            path: path.to_path_buf(),
            problem: problem.into(),
            fix: fix.into(),
        }
    }

    pub fn hdf5(path: &Path, problem: impl Into<String>, fix: impl Into<Text>) -> Self {
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

    /// The message: the file, the place in it, the problem and the fix.
    pub fn message(&self) -> Text {
        Text::from(format!("{}: ", self.path().display()))
            .and(&self.problem())
            .fixed_by(&self.fix())
    }

    /// The file read or written.
    pub fn path(&self) -> &Path {
        match self {
            InputError::NotFound { path }
            | InputError::Io { path, .. }
            | InputError::Write { path, .. }
            | InputError::UnknownFormat { path, .. }
            | InputError::Corrupt { path, .. }
            | InputError::OutsideSensor { path, .. }
            | InputError::Unsorted { path, .. }
            | InputError::Empty { path }
            | InputError::EmptyWindow { path, .. }
            | InputError::Hdf5 { path, .. }
            | InputError::Invalid { path, .. } => path,
        }
    }

    /// What is wrong, and where in the file.
    fn problem(&self) -> Text {
        match self {
            InputError::NotFound { .. } => "no such file or directory".into(),
            InputError::Io { source, .. } => format!("cannot read: {source}").into(),
            InputError::Write { error, .. } => format!("cannot write: {error}").into(),
            InputError::UnknownFormat { detail, .. } => format!("unknown format ({detail})").into(),
            InputError::Corrupt { place, problem, .. } => format!("{place}: {problem}").into(),
            InputError::OutsideSensor {
                place,
                x,
                y,
                width,
                height,
                claimed,
                ..
            } => format!(
                "{place}: event at x={x}, y={y} lies outside the {width}x{height} sensor{claimed}"
            )
            .into(),
            InputError::Unsorted {
                count,
                place,
                previous_us,
                t_us,
                ..
            } => format!(
                "{count} timestamps go backwards, the first at {place} ({previous_us} us, then {t_us} us)"
            )
            .into(),
            InputError::Empty { .. } => "contains no events".into(),
            InputError::EmptyWindow { detail, .. } => {
                format!("no events lie in the selected time window ({detail})").into()
            }
            InputError::Hdf5 { problem, .. } => format!("HDF5: {problem}").into(),
            InputError::Invalid { problem, .. } => problem.clone(),
        }
    }

    /// What to do about it.
    fn fix(&self) -> Text {
        match self {
            InputError::NotFound { .. } => format!(
                "check the path (relative paths start from {})",
                std::env::current_dir()
                    .map(|d| d.display().to_string())
                    .unwrap_or_default()
            )
            .into(),
            InputError::Io { .. } => {
                "check the file's permissions and that the disk is readable".into()
            }
            InputError::Write { error, .. } => write_fix(error).into(),
            InputError::Unsorted { .. } => {
                Text::from("accept the file by sorting its events by time").aside(Hint::Sort)
            }
            InputError::Empty { .. } => {
                "check that this is the right file and that the recording was not cut short".into()
            }
            InputError::EmptyWindow { .. } => Text::from("widen ")
                .name(Hint::TimeWindow)
                .words(" (seconds from the first event)"),
            InputError::UnknownFormat { fix, .. }
            | InputError::Corrupt { fix, .. }
            | InputError::OutsideSensor { fix, .. }
            | InputError::Hdf5 { fix, .. }
            | InputError::Invalid { fix, .. } => fix.clone(),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.message().fmt(f)
    }
}

impl std::error::Error for InputError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            InputError::Io { source, .. } => Some(source),
            _ => None,
        }
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
