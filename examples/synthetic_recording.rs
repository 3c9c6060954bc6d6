//! Writes a large deterministic synthetic recording for benchmarks (streaming memory,
//! decoder throughput); see `ctcal::synthetic`.
//!
//! cargo run --release --example synthetic_recording -- OUT.raw|OUT.h5|OUT.bag|OUT_dsec.h5|OUT_DIR EVENTS [WxH] [RATE_PER_S]
//!
//! `.bag`: a ROS1 bag (uncompressed chunks, 4096 events a message); `_dsec.h5`: the DSEC
//! layout with Blosc/zstd columns in 4096-event chunks, as the DSEC files are written.

use ctcal::io::write::{BagCompression, BagWriter, Evt3Writer, H5Writer, IjrrWriter, OutputPolicy};
use ctcal::synthetic::SyntheticEvents;
use ctcal::{CHUNK_EVENTS, EventChunk, Sensor};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        anyhow::bail!("usage: synthetic_recording OUT EVENTS [WxH] [RATE_PER_S]");
    }
    let out = std::path::PathBuf::from(&args[1]);
    let total: u64 = args[2].replace('_', "").parse()?;
    let sensor = args
        .get(3)
        .and_then(|s| Sensor::parse(s))
        .unwrap_or(Sensor::new(1280, 720));
    let rate: f64 = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(2e6);
    let mut source = SyntheticEvents::new(sensor, rate, 2020);
    if out.to_string_lossy().ends_with("_dsec.h5") {
        return write_dsec(&out, &mut source, total);
    }
    enum Writer {
        Evt3(Evt3Writer),
        H5(H5Writer),
        Ijrr(IjrrWriter),
        Bag(BagWriter),
    }
    let policy = OutputPolicy::default();
    let mut writer = match out.extension().and_then(|e| e.to_str()) {
        Some("raw") => Writer::Evt3(Evt3Writer::create(&out, sensor, &policy)?),
        Some("h5") => Writer::H5(H5Writer::create(&out, sensor, &policy)?),
        Some("bag") => Writer::Bag(BagWriter::create(
            &out,
            sensor,
            BagCompression::None,
            &policy,
        )?),
        _ => Writer::Ijrr(IjrrWriter::create(&out, sensor, &policy)?),
    };
    let mut chunk = EventChunk::with_capacity(CHUNK_EVENTS);
    let mut written = 0u64;
    while written < total {
        chunk.clear();
        let n = (total - written).min(CHUNK_EVENTS as u64) as usize;
        source.fill(&mut chunk, n);
        match &mut writer {
            Writer::Evt3(w) => w.write_events(&chunk)?,
            Writer::H5(w) => w.write_events(&chunk)?,
            Writer::Ijrr(w) => w.write_events(&chunk)?,
            Writer::Bag(w) => w.write_events(&chunk)?,
        }
        written += n as u64;
    }
    match writer {
        Writer::Evt3(w) => w.finish()?,
        Writer::H5(w) => w.finish()?,
        Writer::Ijrr(w) => w.finish()?,
        Writer::Bag(w) => w.finish()?,
    }
    eprintln!("wrote {written} events to {}", out.display());
    Ok(())
}

/// The DSEC layout ([`ctcal::io::write::dsec`]).
fn write_dsec(
    out: &std::path::Path,
    source: &mut SyntheticEvents,
    total: u64,
) -> anyhow::Result<()> {
    let events = source.take(total as usize);
    ctcal::io::write::dsec::write_dsec(out, &events, &OutputPolicy::default())?;
    eprintln!("wrote {} events to {}", events.len(), out.display());
    Ok(())
}
