//! `ctcal convert`: rewrites a recording as an IJRR folder, an event_utils HDF5 file,
//! Prophesee EVT3 or a ROS1 bag, every event unchanged (frames too, where the output holds
//! them).

use super::{BadInput, Global, InputArgs, progress_bar, warn};
use clap::{Args, ValueEnum};
use ctcal::Recording;
use ctcal::io::write::{BagCompression, BagWriter, Evt3Writer, H5Writer, IjrrWriter, OutputPolicy};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    Ijrr,
    H5,
    /// Prophesee RAW EVT 3.0 (events only).
    Evt3,
    /// ROS1 bag: dvs_msgs/EventArray on /dvs/events, mono8 frames on /dvs/image_raw.
    Bag,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output folder (IJRR) or file (HDF5).
    #[arg(long, value_name = "PATH")]
    pub out: PathBuf,
    /// Output layout (default from --out: .h5/.hdf5 -> h5, .raw/.evt3 -> evt3, .bag -> bag, no
    /// extension -> an ijrr folder).
    #[arg(long, value_enum)]
    pub to: Option<OutputFormat>,
    /// Accept timestamps that go backwards and write the events sorted by time.
    #[arg(long)]
    pub sort: bool,
    /// Bag output: how chunks are compressed.
    #[arg(long, value_enum, default_value = "none")]
    pub bag_compression: BagCompressionArg,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BagCompressionArg {
    None,
    Bz2,
    Lz4,
}

/// The writer of the output layout chosen.
enum Writer {
    Ijrr(IjrrWriter),
    H5(H5Writer),
    Evt3(Evt3Writer),
    Bag(BagWriter),
}

impl Writer {
    /// Creates `--out` in layout `to` (a bag compressed as `--bag-compression` asks) for
    /// a sensor of size `sensor`.
    fn create(
        to: OutputFormat,
        args: &ConvertArgs,
        sensor: ctcal::Sensor,
        policy: &OutputPolicy,
    ) -> anyhow::Result<Self> {
        Ok(match to {
            OutputFormat::Ijrr => Writer::Ijrr(IjrrWriter::create(&args.out, sensor, policy)?),
            OutputFormat::H5 => Writer::H5(H5Writer::create(&args.out, sensor, policy)?),
            OutputFormat::Evt3 => Writer::Evt3(Evt3Writer::create(&args.out, sensor, policy)?),
            OutputFormat::Bag => Writer::Bag(BagWriter::create(
                &args.out,
                sensor,
                match args.bag_compression {
                    BagCompressionArg::None => BagCompression::None,
                    BagCompressionArg::Bz2 => BagCompression::Bz2,
                    BagCompressionArg::Lz4 => BagCompression::Lz4,
                },
                policy,
            )?),
        })
    }

    /// Writes a chunk of events.
    fn write_events(&mut self, chunk: &ctcal::EventChunk) -> anyhow::Result<()> {
        match self {
            Writer::Ijrr(w) => w.write_events(chunk)?,
            Writer::H5(w) => w.write_events(chunk)?,
            Writer::Evt3(w) => w.write_events(chunk)?,
            Writer::Bag(w) => w.write_events(chunk)?,
        }
        Ok(())
    }

    /// Writes a frame (EVT3 holds none: nothing is written).
    fn write_frame(&mut self, frame: &ctcal::Frame) -> anyhow::Result<()> {
        match self {
            Writer::Ijrr(w) => w.write_frame(frame)?,
            Writer::H5(w) => w.write_frame(frame)?,
            Writer::Bag(w) => w.write_frame(frame)?,
            Writer::Evt3(_) => {}
        }
        Ok(())
    }

    /// Completes the output.
    fn finish(self) -> anyhow::Result<()> {
        match self {
            Writer::Ijrr(w) => w.finish()?,
            Writer::H5(w) => w.finish()?,
            Writer::Evt3(w) => w.finish()?,
            Writer::Bag(w) => w.finish()?,
        }
        Ok(())
    }
}

/// A writer fed events in time order, each frame written beside the events of its time
/// (a bag interleaves them).
struct Interleaved {
    writer: Writer,
    frames: Vec<ctcal::Frame>,
    next_frame: usize,
}

impl Interleaved {
    /// Writes a chunk of events, then the frames up to its last event's time (every frame
    /// left, if it is the `last`).
    fn write(&mut self, chunk: &ctcal::EventChunk, last: bool) -> anyhow::Result<()> {
        self.writer.write_events(chunk)?;
        let until = if last {
            ctcal::TimeUs::MAX
        } else {
            chunk.t.last().copied().unwrap_or(ctcal::TimeUs::MIN)
        };
        while self.next_frame < self.frames.len() && self.frames[self.next_frame].t <= until {
            self.writer.write_frame(&self.frames[self.next_frame])?;
            self.next_frame += 1;
        }
        Ok(())
    }
}

/// The output layout `--out`'s extension asks for, when `--to` is not given.
pub fn layout_from_extension(out: &std::path::Path) -> Result<OutputFormat, BadInput> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "" => Ok(OutputFormat::Ijrr),
        "h5" | "hdf5" => Ok(OutputFormat::H5),
        "raw" | "evt3" => Ok(OutputFormat::Evt3),
        "bag" => Ok(OutputFormat::Bag),
        other => Err(BadInput(format!(
            "{}: ctcal cannot write .{other} files\n  fix: pass --to ijrr (a folder), --to h5 (event_utils HDF5), --to evt3 (Prophesee RAW) or --to bag (ROS1), or end --out in .h5, .raw, .bag or no extension",
            out.display()
        ))),
    }
}

/// `ctcal convert`: the sensor resolved, the output created, every event (and frame)
/// written, the output completed.
pub fn run(args: &ConvertArgs, global: &Global) -> anyhow::Result<()> {
    let to = match args.to {
        Some(to) => to,
        None => layout_from_extension(&args.out)?,
    };
    let recording = Recording::open(&args.input.input, &args.input.open_options())?;
    let policy = global.outputs([args.input.input.as_path(), recording.event_file()]);
    for note in &recording.notes {
        warn(global, note);
    }
    // the writer needs the sensor first: infer it in a first pass when the file is silent
    let sorted = if args.sort {
        Some(recording.read_all(true)?)
    } else {
        None
    };
    let max_coordinates = max_coordinates(&recording, sorted.as_ref())?;
    let resolved = recording.resolve_sensor(max_coordinates);
    if let Some(w) = &resolved.warning {
        warn(global, &super::flags::render(w));
    }
    let writer = Writer::create(to, args, resolved.sensor, &policy)?;
    let frames = recording.frames()?;
    if matches!(writer, Writer::Evt3(_)) && !frames.is_empty() {
        warn(
            global,
            "EVT3 holds events only; the frames were not written",
        );
    }
    let mut output = Interleaved {
        writer,
        frames,
        next_frame: 0,
    };
    match &sorted {
        Some(all) => output.write(all, true)?,
        None => write_streamed(&recording, &mut output, global)?,
    }
    output.writer.finish()
}

/// The largest x and y of the events, where the file does not give the sensor: of the
/// sorted events if read, else from a first pass over the file.
fn max_coordinates(
    recording: &Recording,
    sorted: Option<&ctcal::EventChunk>,
) -> anyhow::Result<Option<(u16, u16)>> {
    Ok(match (sorted, recording.sensor) {
        (Some(all), _) => all.max_coordinates(),
        (None, Some(_)) => None,
        (None, None) => {
            let mut stream = recording.events()?;
            while stream.next_chunk()?.is_some() {}
            stream.max_coordinates()
        }
    })
}

/// Streams the recording's events chunk by chunk into `output`, with a progress bar, then
/// the frames after the last event.
fn write_streamed(
    recording: &Recording,
    output: &mut Interleaved,
    global: &Global,
) -> anyhow::Result<()> {
    let mut stream = recording.events()?;
    let bar = progress_bar(global, stream.progress().total, "converting");
    while let Some(chunk) = stream.next_chunk()? {
        output.write(chunk, false)?;
        bar.set_position(stream.progress().done);
    }
    output.write(&ctcal::EventChunk::default(), true)?;
    bar.finish_and_clear();
    Ok(())
}
