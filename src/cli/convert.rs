//! `ctcal convert`: rewrites a recording as an IJRR folder, an event_utils HDF5 file,
//! Prophesee EVT3 or a ROS1 bag, every event unchanged (frames too, where the output holds
//! them).

use super::{BadInput, Global, InputArgs, progress_bar, warn};
use clap::{Args, ValueEnum};
use ctcal::Recording;
use ctcal::io::write::{BagCompression, BagWriter, Evt3Writer, H5Writer, IjrrWriter};
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

enum Writer {
    Ijrr(IjrrWriter),
    H5(H5Writer),
    Evt3(Evt3Writer),
    Bag(BagWriter),
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
    let max_coordinates = match (&sorted, recording.sensor) {
        (Some(all), _) => all.max_coordinates(),
        (None, Some(_)) => None,
        (None, None) => {
            let mut stream = recording.events()?;
            while stream.next_chunk()?.is_some() {}
            stream.max_coordinates()
        }
    };
    let resolved = recording.resolve_sensor(max_coordinates);
    if let Some(w) = &resolved.warning {
        warn(global, &super::flags::render(w));
    }
    let mut writer = match to {
        OutputFormat::Ijrr => {
            Writer::Ijrr(IjrrWriter::create(&args.out, resolved.sensor, &policy)?)
        }
        OutputFormat::H5 => Writer::H5(H5Writer::create(&args.out, resolved.sensor, &policy)?),
        OutputFormat::Evt3 => {
            Writer::Evt3(Evt3Writer::create(&args.out, resolved.sensor, &policy)?)
        }
        OutputFormat::Bag => Writer::Bag(BagWriter::create(
            &args.out,
            resolved.sensor,
            match args.bag_compression {
                BagCompressionArg::None => BagCompression::None,
                BagCompressionArg::Bz2 => BagCompression::Bz2,
                BagCompressionArg::Lz4 => BagCompression::Lz4,
            },
            &policy,
        )?),
    };
    // frames go out beside the events of their time (a bag interleaves them)
    let frames = recording.frames()?;
    let mut next_frame = 0;
    if matches!(writer, Writer::Evt3(_)) && !frames.is_empty() {
        warn(
            global,
            "EVT3 holds events only; the frames were not written",
        );
    }
    let mut write = |chunk: &ctcal::EventChunk, last: bool| -> anyhow::Result<()> {
        match &mut writer {
            Writer::Ijrr(w) => w.write_events(chunk)?,
            Writer::H5(w) => w.write_events(chunk)?,
            Writer::Evt3(w) => w.write_events(chunk)?,
            Writer::Bag(w) => w.write_events(chunk)?,
        }
        let until = if last {
            ctcal::TimeUs::MAX
        } else {
            chunk.t.last().copied().unwrap_or(ctcal::TimeUs::MIN)
        };
        while next_frame < frames.len() && frames[next_frame].t <= until {
            let frame = &frames[next_frame];
            match &mut writer {
                Writer::Ijrr(w) => w.write_frame(frame)?,
                Writer::H5(w) => w.write_frame(frame)?,
                Writer::Bag(w) => w.write_frame(frame)?,
                Writer::Evt3(_) => {}
            }
            next_frame += 1;
        }
        Ok(())
    };
    match &sorted {
        Some(all) => write(all, true)?,
        None => {
            let mut stream = recording.events()?;
            let bar = progress_bar(global, stream.progress().total, "converting");
            while let Some(chunk) = stream.next_chunk()? {
                write(chunk, false)?;
                bar.set_position(stream.progress().done);
            }
            write(&ctcal::EventChunk::default(), true)?;
            bar.finish_and_clear();
        }
    }
    match writer {
        Writer::Ijrr(w) => w.finish()?,
        Writer::H5(w) => w.finish()?,
        Writer::Evt3(w) => w.finish()?,
        Writer::Bag(w) => w.finish()?,
    }
    Ok(())
}
