//! Decoder and statistics throughput: IJRR text (bytes/s), EVT3, HDF5 (event_utils, DSEC
//! Blosc) and ROS bags (events/s), and
//! the statistics kernel on events already in memory (events/s), on deterministic
//! synthetic recordings (`ctcal::synthetic`).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ctcal::io::write::{
    BagCompression, BagWriter, Evt3Writer, H5Writer, IjrrWriter, OutputPolicy, dsec,
};
use ctcal::stats::{StatsAccumulator, StatsOptions};
use ctcal::synthetic::SyntheticEvents;
use ctcal::{CHUNK_EVENTS, OpenOptions, Recording, Sensor};
use std::path::Path;

const SENSOR: Sensor = Sensor {
    width: 1280,
    height: 720,
};

/// Reads every event once; returns the count.
fn decode(path: &Path) -> u64 {
    let recording = Recording::open(path, &OpenOptions::default()).expect("opens");
    let mut stream = recording.events().expect("stream");
    while stream.next_chunk().expect("decodes").is_some() {}
    stream.events_read()
}

fn readers(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let events = SyntheticEvents::new(SENSOR, 2e6, 1).take(4_000_000);
    let text = dir.path().join("text");
    let mut w = IjrrWriter::create(&text, SENSOR, &OutputPolicy::default()).unwrap();
    w.write_events(&events).unwrap();
    w.finish().unwrap();
    let evt3 = dir.path().join("events.raw");
    let mut w = Evt3Writer::create(&evt3, SENSOR, &OutputPolicy::default()).unwrap();
    w.write_events(&events).unwrap();
    w.finish().unwrap();
    let h5 = dir.path().join("events.h5");
    let mut w = H5Writer::create(&h5, SENSOR, &OutputPolicy::default()).unwrap();
    w.write_events(&events).unwrap();
    w.finish().unwrap();

    let bag = dir.path().join("events.bag");
    let mut w =
        BagWriter::create(&bag, SENSOR, BagCompression::None, &OutputPolicy::default()).unwrap();
    w.write_events(&events).unwrap();
    w.finish().unwrap();
    let dsec_file = dir.path().join("dsec.h5");
    dsec::write_dsec(&dsec_file, &events, &OutputPolicy::default()).unwrap();

    let mut group = c.benchmark_group("decode");
    group.sample_size(10);
    let text_bytes = std::fs::metadata(text.join("events.txt")).unwrap().len();
    group.throughput(Throughput::Bytes(text_bytes));
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    group.bench_function("ijrr_text", |b| b.iter(|| one.install(|| decode(&text))));
    // lines split between two threads (`crates/ctcal-io/src/ijrr/split.rs`)
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    group.bench_function("ijrr_text_two_threads", |b| {
        b.iter(|| two.install(|| decode(&text)))
    });
    group.throughput(Throughput::Elements(events.len() as u64));
    group.bench_function("evt3", |b| b.iter(|| decode(&evt3)));
    group.bench_function("hdf5_event_utils", |b| b.iter(|| decode(&h5)));
    group.bench_function("ros_bag", |b| b.iter(|| decode(&bag)));
    group.bench_function("hdf5_dsec_blosc", |b| b.iter(|| decode(&dsec_file)));
    group.finish();

    let mut group = c.benchmark_group("stats");
    group.sample_size(10);
    group.throughput(Throughput::Elements(events.len() as u64));
    group.bench_function("kernel_in_memory", |b| {
        b.iter(|| {
            let mut acc = StatsAccumulator::new(StatsOptions::default(), Some(SENSOR));
            for start in (0..events.len()).step_by(CHUNK_EVENTS) {
                let end = (start + CHUNK_EVENTS).min(events.len());
                let chunk = ctcal::EventChunk {
                    t: events.t[start..end].to_vec(),
                    x: events.x[start..end].to_vec(),
                    y: events.y[start..end].to_vec(),
                    on: events.on[start..end].to_vec(),
                };
                acc.add(&chunk);
            }
            acc.events()
        })
    });
    group.bench_function("decode_evt3_and_stats", |b| {
        b.iter(|| {
            let recording = Recording::open(&evt3, &OpenOptions::default()).unwrap();
            let mut acc = StatsAccumulator::new(StatsOptions::default(), recording.sensor);
            let mut stream = recording.events().unwrap();
            while let Some(chunk) = stream.next_chunk().unwrap() {
                acc.add(chunk);
            }
            let resolved = recording.resolve_sensor(stream.max_coordinates());
            acc.finish(resolved.sensor, &resolved.source, &[])
                .map(|s| s.events)
        })
    });
    group.finish();
}

criterion_group!(benches, readers);
criterion_main!(benches);
