//! IJRR folders: `events.txt` with a `width height` first line (as rpg_e2vid writes), then
//! `t x y p` with t in seconds to the microsecond and p 0/1; frames as `images.txt` +
//! `images/frame_XXXXXXXX.png`, and for a recording of an on-screen stimulus the stimulus
//! as `stimulus.txt` + `stimulus/frame_XXXXXXXX.png`.

use super::{OutputPolicy, StagedFolder, format_seconds, save_png};
use crate::error::InputError;
use crate::events::{EventChunk, Frame, Sensor};
use std::io::Write;
use std::path::Path;

/// Writes an IJRR folder.
pub struct IjrrWriter {
    staged: StagedFolder,
    events: std::io::BufWriter<std::fs::File>,
    line: Vec<u8>,
    /// The index lines and counts of `images/` and `stimulus/`.
    frames: [Vec<u8>; 2],
    frame_count: [usize; 2],
}

/// The two kinds of frame lists an IJRR folder holds.
const FRAME_LISTS: [(&str, &str); 2] = [("images", "images.txt"), ("stimulus", "stimulus.txt")];

impl IjrrWriter {
    /// Starts a folder at `target` (where `policy` allows); `sensor` becomes the
    /// `width height` first line.
    pub fn create(
        target: &Path,
        sensor: Sensor,
        policy: &OutputPolicy,
    ) -> Result<Self, InputError> {
        let staged = policy.folder(target)?;
        let file = std::fs::File::create(staged.dir().join("events.txt"))
            .map_err(|e| InputError::write(target, e))?;
        let mut events = std::io::BufWriter::with_capacity(1 << 20, file);
        writeln!(events, "{} {}", sensor.width, sensor.height)
            .map_err(|e| InputError::write(target, e))?;
        Ok(Self {
            staged,
            events,
            line: Vec::with_capacity(64),
            frames: [Vec::new(), Vec::new()],
            frame_count: [0, 0],
        })
    }

    pub fn write_events(&mut self, chunk: &EventChunk) -> Result<(), InputError> {
        let mut buffer = itoa::Buffer::new();
        for i in 0..chunk.len() {
            self.line.clear();
            format_seconds(chunk.t[i], &mut self.line);
            self.line.push(b' ');
            self.line
                .extend_from_slice(buffer.format(chunk.x[i]).as_bytes());
            self.line.push(b' ');
            self.line
                .extend_from_slice(buffer.format(chunk.y[i]).as_bytes());
            self.line
                .extend_from_slice(if chunk.on[i] { b" 1\n" } else { b" 0\n" });
            self.events
                .write_all(&self.line)
                .map_err(|e| InputError::write(&self.staged.shown, e))?;
        }
        Ok(())
    }

    /// Adds a frame (PNG in `images/`, a line in `images.txt`).
    pub fn write_frame(&mut self, frame: &Frame) -> Result<(), InputError> {
        self.add_to_list(0, frame)
    }

    /// Adds a frame of the on-screen stimulus (PNG in `stimulus/`, a line in
    /// `stimulus.txt`).
    pub fn write_stimulus_frame(&mut self, frame: &Frame) -> Result<(), InputError> {
        self.add_to_list(1, frame)
    }

    fn add_to_list(&mut self, list: usize, frame: &Frame) -> Result<(), InputError> {
        let (folder, _) = FRAME_LISTS[list];
        if self.frame_count[list] == 0 {
            std::fs::create_dir_all(self.staged.dir().join(folder))
                .map_err(|e| InputError::write(&self.staged.shown, e))?;
        }
        let name = format!("{folder}/frame_{:08}.png", self.frame_count[list]);
        save_png(&self.staged.dir().join(&name), frame)
            .map_err(|e| InputError::write(&self.staged.shown, e))?;
        format_seconds(frame.t, &mut self.frames[list]);
        self.frames[list].extend_from_slice(format!(" {name}\n").as_bytes());
        self.frame_count[list] += 1;
        Ok(())
    }

    /// Adds another file to the folder (e.g. provenance), written with it.
    pub fn add_file(&mut self, name: &str, bytes: &[u8]) -> Result<(), InputError> {
        self.staged.write(name, bytes)
    }

    /// Flushes and moves the folder into place.
    pub fn finish(mut self) -> Result<(), InputError> {
        self.events
            .flush()
            .map_err(|e| InputError::write(&self.staged.shown, e))?;
        for (list, (_, index)) in FRAME_LISTS.iter().enumerate() {
            if self.frame_count[list] > 0 {
                self.staged.write(index, &self.frames[list])?;
            }
        }
        drop(self.events);
        self.staged.commit()
    }
}
