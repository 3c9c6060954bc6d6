//! Input files are checked before they are opened: a FIFO, socket or device where a file is
//! expected would make a reader wait forever (or read forever), and a folder where a file is
//! expected gives a confusing error deep inside a decoder. Shared by the readers (the IO crate)
//! and the simulator's own inputs (parameter and scene files, textures).

use std::path::Path;

/// Why a path cannot be read as a regular file.
#[derive(Debug)]
pub enum NotAFile {
    Missing,
    Folder,
    /// A FIFO, socket or device (named).
    Special(&'static str),
    Unreadable(std::io::Error),
}

impl NotAFile {
    /// What is wrong, for a message that names the path first.
    pub fn problem(&self) -> String {
        match self {
            NotAFile::Missing => "no such file".into(),
            NotAFile::Folder => "is a folder, but a file is expected here".into(),
            NotAFile::Special(what) => format!("is {what}, not a regular file"),
            NotAFile::Unreadable(e) => format!("cannot be read: {e}"),
        }
    }

    pub fn fix(&self) -> &'static str {
        match self {
            NotAFile::Missing => "check the path",
            NotAFile::Folder => "give the path of a file inside the folder",
            NotAFile::Special(_) => {
                "copy the data to a regular file first (ctcal reads files more than once and needs their size)"
            }
            NotAFile::Unreadable(_) => "check the file's permissions",
        }
    }
}

/// Checks that `path` is a regular file (symlinks followed).
pub fn check_regular(path: &Path) -> Result<std::fs::Metadata, NotAFile> {
    let meta = std::fs::metadata(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            NotAFile::Missing
        } else {
            NotAFile::Unreadable(e)
        }
    })?;
    let kind = meta.file_type();
    if kind.is_file() {
        return Ok(meta);
    }
    if kind.is_dir() {
        return Err(NotAFile::Folder);
    }
    Err(NotAFile::Special(special_kind(&meta)))
}

fn special_kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let kind = meta.file_type();
        if kind.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if kind.is_socket() {
            return "a socket";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
    }
    let _ = meta;
    "a special file"
}

/// Reads a small text file (parameters, scenes, configs), refusing special files and files
/// over `max_bytes`.
pub fn read_small_text(path: &Path, max_bytes: u64) -> Result<String, NotAFile> {
    let meta = check_regular(path)?;
    if meta.len() > max_bytes {
        return Err(NotAFile::Unreadable(std::io::Error::other(format!(
            "{} bytes, more than the {max_bytes} a text file of this kind can have",
            meta.len()
        ))));
    }
    std::fs::read_to_string(path).map_err(NotAFile::Unreadable)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_missing_files_and_fifos_are_named() {
        let dir = tempfile::tempdir().unwrap();
        assert!(matches!(check_regular(dir.path()), Err(NotAFile::Folder)));
        assert!(matches!(
            check_regular(&dir.path().join("nope")),
            Err(NotAFile::Missing)
        ));
        let file = dir.path().join("f.txt");
        std::fs::write(&file, "x").unwrap();
        assert!(check_regular(&file).is_ok());
        #[cfg(unix)]
        {
            let fifo = dir.path().join("pipe");
            let status = std::process::Command::new("mkfifo").arg(&fifo).status();
            if status.is_ok_and(|s| s.success()) {
                let e = check_regular(&fifo).unwrap_err();
                assert!(e.problem().contains("FIFO"), "{}", e.problem());
            }
        }
    }
}
