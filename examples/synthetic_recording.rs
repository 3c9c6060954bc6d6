//! Writes a large deterministic synthetic recording for benchmarks (streaming memory,
//! decoder throughput): edges sweeping across the sensor plus uniform background events.
//!
//! cargo run --release --example synthetic_recording -- OUT.raw|OUT.h5|OUT_DIR EVENTS [WxH] [RATE_PER_S]

use ctcal::io::write::{Evt3Writer, H5Writer, IjrrWriter};
use ctcal::{CHUNK_EVENTS, EventChunk, Sensor};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

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
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2020);
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    enum W {
        Evt3(Evt3Writer),
        H5(H5Writer),
        Ijrr(IjrrWriter),
    }
    let mut writer = match ext {
        "raw" => W::Evt3(Evt3Writer::create(&out, sensor)?),
        "h5" => W::H5(H5Writer::create(&out, sensor)?),
        _ => W::Ijrr(IjrrWriter::create(&out, sensor)?),
    };
    let (w, h) = (sensor.width as f64, sensor.height as f64);
    let mut chunk = EventChunk::with_capacity(CHUNK_EVENTS);
    let mut t_s = 0.0f64;
    let mut written = 0u64;
    while written < total {
        chunk.clear();
        let n = (total - written).min(CHUNK_EVENTS as u64);
        for _ in 0..n {
            t_s += -rng.random::<f64>().max(1e-300).ln() / rate;
            let (x, y, on) = if rng.random::<f64>() < 0.9 {
                // one of four edges sweeping at 200 px/s, with 2 px of jitter
                let edge = rng.random_range(0..4u32) as f64;
                let x =
                    ((t_s * 200.0 + edge * w / 4.0) % w + rng.random::<f64>() * 2.0).min(w - 1.0);
                (x, rng.random::<f64>() * h, edge < 2.0)
            } else {
                (
                    rng.random::<f64>() * w,
                    rng.random::<f64>() * h,
                    rng.random::<bool>(),
                )
            };
            chunk.push((t_s * 1e6) as i64, x as u16, y as u16, on);
        }
        match &mut writer {
            W::Evt3(wr) => wr.write_events(&chunk)?,
            W::H5(wr) => wr.write_events(&chunk)?,
            W::Ijrr(wr) => wr.write_events(&chunk)?,
        }
        written += n;
    }
    match writer {
        W::Evt3(wr) => wr.finish()?,
        W::H5(wr) => wr.finish()?,
        W::Ijrr(wr) => wr.finish()?,
    }
    eprintln!(
        "wrote {written} events over {t_s:.1} s to {}",
        out.display()
    );
    Ok(())
}
