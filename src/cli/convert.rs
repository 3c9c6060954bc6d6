//! `ctcal convert`: rewrites a recording as an IJRR folder or an event_utils HDF5 file,
//! every event unchanged (frames too, where present).

use super::{BadInput, Global, InputArgs, progress_bar, warn};
use clap::{Args, ValueEnum};
use ctcal::Recording;
use ctcal::io::write::{Evt3Writer, H5Writer, IjrrWriter};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputFormat {
    Ijrr,
    H5,
    /// Prophesee RAW EVT 3.0 (events only).
    Evt3,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Output folder (IJRR) or file (HDF5).
    #[arg(long, value_name = "PATH")]
    pub out: PathBuf,
    /// Output layout (default: h5 when --out ends in .h5/.hdf5, evt3 for .raw, else ijrr).
    #[arg(long, value_enum)]
    pub to: Option<OutputFormat>,
    /// Accept timestamps that go backwards and write the events sorted by time.
    #[arg(long)]
    pub sort: bool,
}

enum Writer {
    Ijrr(IjrrWriter),
    H5(H5Writer),
    Evt3(Evt3Writer),
}

pub fn run(args: &ConvertArgs, global: &Global) -> anyhow::Result<()> {
    let to = args.to.unwrap_or_else(|| {
        let ext = args
            .out
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        if ext == "h5" || ext == "hdf5" {
            OutputFormat::H5
        } else {
            OutputFormat::Ijrr
        }
    });
    let recording = Recording::open(&args.input.input, &args.input.open_options())?;
    if recording.path.canonicalize().ok() == args.out.canonicalize().ok() {
        return Err(
            BadInput("--out names the input itself; choose another output path".into()).into(),
        );
    }
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
        warn(global, w);
    }
    let mut writer = match to {
        OutputFormat::Ijrr => Writer::Ijrr(IjrrWriter::create(&args.out, resolved.sensor)?),
        OutputFormat::H5 => Writer::H5(H5Writer::create(&args.out, resolved.sensor)?),
        OutputFormat::Evt3 => Writer::Evt3(Evt3Writer::create(&args.out, resolved.sensor)?),
    };
    let mut write = |chunk: &ctcal::EventChunk| -> anyhow::Result<()> {
        match &mut writer {
            Writer::Ijrr(w) => w.write_events(chunk)?,
            Writer::H5(w) => w.write_events(chunk)?,
            Writer::Evt3(w) => w.write_events(chunk)?,
        }
        Ok(())
    };
    match &sorted {
        Some(all) => write(all)?,
        None => {
            let mut stream = recording.events()?;
            let bar = progress_bar(global, stream.progress().total, "converting");
            while let Some(chunk) = stream.next_chunk()? {
                write(chunk)?;
                bar.set_position(stream.progress().done);
            }
            bar.finish_and_clear();
        }
    }
    for frame in recording.frames()? {
        match &mut writer {
            Writer::Ijrr(w) => w.write_frame(&frame)?,
            Writer::H5(w) => w.write_frame(&frame)?,
            Writer::Evt3(_) => {
                warn(
                    global,
                    "EVT3 holds events only; the frames were not written",
                );
                break;
            }
        }
    }
    match writer {
        Writer::Ijrr(w) => w.finish()?,
        Writer::H5(w) => w.finish()?,
        Writer::Evt3(w) => w.finish()?,
    }
    Ok(())
}
