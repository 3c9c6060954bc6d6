//! Hostile files: every decoder must end in `Ok` or an `InputError` on damaged input, never
//! panic, hang or allocate from what a header or a timestamp claims.
//!
//! - A property test (proptest) mutates every real recording of `../shared/data/real`, and
//!   ROS bags of its events (plain and bz2 chunks),
//!   (truncations, byte flips, zeroed and duplicated blocks, huge header values) and runs the
//!   whole read path on each: format detection, the event stream with the statistics pass,
//!   frame times and frames. 2,000 cases by default (`CTCAL_MUTATION_CASES` changes it).
//! - Named cases that used to ask for gigabytes (a 1e7 s gap, a bit flip in an AEDAT4
//!   timestamp, 20,000 EVT3 clock wraps in a 100 KB file) run through the same path.
//!
//! Memory is measured in-process by a counting global allocator; this is its own test
//! binary so that the count holds only its own work, and its tests run one at a time.

use ctcal::stats::{StatsAccumulator, StatsOptions};
use ctcal::{InputError, OpenOptions, Recording};
use proptest::prelude::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting live bytes and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; the counters are plain atomics.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        unsafe { System.dealloc(p, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, p: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, layout, new_size) };
        if !q.is_null() {
            if new_size > layout.size() {
                let grown = new_size - layout.size();
                let live = LIVE.fetch_add(grown, Ordering::Relaxed) + grown;
                PEAK.fetch_max(live, Ordering::Relaxed);
            } else {
                LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
        }
        q
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The bound every read must stay under (the issue asks for < 500 MB).
const MEMORY_BOUND: usize = 500 << 20;

/// Tests of this binary run one at a time, so the allocation count is each test's own.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Runs `f` and returns its result with the peak of memory allocated during it (beyond what
/// was live before).
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let out = f();
    (out, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

/// Everything `ctcal stats` and the estimators read: detection, the event stream into the
/// statistics pass, the sensor, frame times and frames. Returns the events read.
fn read_everything(path: &Path) -> Result<u64, InputError> {
    let recording = Recording::open(path, &OpenOptions::default())?;
    let mut accumulator = StatsAccumulator::new(StatsOptions::default(), recording.sensor);
    let mut stream = recording.events()?;
    while let Some(chunk) = stream.next_chunk()? {
        let mut sorted = chunk.clone();
        sorted.sort_by_time();
        accumulator.add(&sorted);
    }
    let resolved = recording.resolve_sensor(stream.max_coordinates());
    let times = recording.frame_times()?;
    let _ = recording.frames()?;
    let stats = accumulator.finish(resolved.sensor, &resolved.source, &times);
    Ok(stats.map_or(0, |s| s.events))
}

fn shared_real(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/real")
        .join(name)
}

/// A real recording cut to a valid prefix of at most ~`budget` bytes (at a line, word or
/// packet boundary), so that each case is quick and the unmutated seed decodes cleanly.
struct Seed {
    name: &'static str,
    /// File name the mutated copy gets (the extension is a hint to detection).
    file_name: &'static str,
    bytes: Vec<u8>,
    /// Where the binary data start (after a text header), for header mutations.
    header_end: usize,
}

fn prophesee_header_end(bytes: &[u8]) -> usize {
    let mut at = 0;
    while at < bytes.len() && bytes[at] == b'%' {
        match bytes[at..].iter().position(|&b| b == b'\n') {
            Some(n) => at += n + 1,
            None => break,
        }
    }
    at
}

fn seeds() -> Vec<Seed> {
    const BUDGET: usize = 96 << 10;
    let mut seeds = Vec::new();
    for (name, dir) in [
        ("slider", "ijrr_slider_depth_50k"),
        ("shapes", "ijrr_shapes_rotation_chunk"),
        ("boxes", "ijrr_boxes_rotation_chunk"),
    ] {
        let bytes = std::fs::read(shared_real(dir).join("events.txt")).unwrap();
        let cut = bytes[..BUDGET].iter().rposition(|&b| b == b'\n').unwrap() + 1;
        seeds.push(Seed {
            name,
            file_name: "events.txt",
            bytes: bytes[..cut].to_vec(),
            header_end: 0,
        });
    }
    for (name, file, file_name, word) in [
        ("evk4_evt3", "evk4_faery_evt3.raw", "rec.raw", 2),
        ("gen3_evt2", "gen3_faery_evt2.raw", "rec.raw", 4),
        ("gen3b_evt2", "gen3_expelliarmus_evt2.raw", "rec.raw", 4),
        ("evk4_dat", "evk4_faery_gen4.dat", "rec.dat", 8),
    ] {
        let bytes = std::fs::read(shared_real(file)).unwrap();
        let header_end = prophesee_header_end(&bytes);
        // DAT: two bytes of event type and size follow the header
        let data = header_end + if word == 8 { 2 } else { 0 };
        let cut = data + (BUDGET - data) / word * word;
        seeds.push(Seed {
            name,
            file_name,
            bytes: bytes[..cut].to_vec(),
            header_end,
        });
    }
    for (name, file) in [
        ("davis346", "davis346_faery.aedat4"),
        ("dvxplorer", "dvxplorer_tonic.aedat4"),
    ] {
        let bytes = std::fs::read(shared_real(file)).unwrap();
        let header = u32::from_le_bytes(bytes[14..18].try_into().unwrap()) as usize;
        let mut at = 18 + header;
        // whole packets up to the budget (frames are ~90 KB: allow a few)
        while at + 8 <= bytes.len() {
            let size = i32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap()) as usize;
            if at + 8 + size > (BUDGET * 4).max(18 + header + 8) {
                break;
            }
            at += 8 + size;
        }
        seeds.push(Seed {
            name,
            file_name: "rec.aedat4",
            bytes: bytes[..at].to_vec(),
            header_end: 18 + header,
        });
    }
    // ROS bags, plain and bz2: the real slider events and one frame, written in small
    // chunks so that a seed holds several
    let recording = Recording::open(
        &shared_real("ijrr_slider_depth_50k"),
        &OpenOptions::default(),
    )
    .unwrap();
    let mut events = recording.read_all(false).unwrap();
    events.t.truncate(5000);
    events.x.truncate(5000);
    events.y.truncate(5000);
    events.on.truncate(5000);
    let frame = recording.frames().unwrap().remove(1);
    for (name, compression) in [
        ("bag", ctcal::io::write::BagCompression::None),
        ("bag_bz2", ctcal::io::write::BagCompression::Bz2),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("seed.bag");
        let mut writer = ctcal::io::write::BagWriter::create(
            &path,
            ctcal::Sensor::new(240, 180),
            compression,
            &ctcal::io::write::OutputPolicy::default(),
        )
        .unwrap()
        .events_per_message(500)
        .chunk_bytes(16 << 10);
        writer.write_events(&events).unwrap();
        writer.write_frame(&frame).unwrap();
        writer.finish().unwrap();
        seeds.push(Seed {
            name,
            file_name: "rec.bag",
            bytes: std::fs::read(&path).unwrap(),
            header_end: 13 + 4096,
        });
    }
    seeds
}

/// One way to damage a file.
#[derive(Clone, Debug)]
enum Mutation {
    /// Keep this fraction of the file.
    Truncate(f64),
    /// XOR `count` bytes from `at` (a fraction of the length) with `mask`.
    Flip { at: f64, count: usize, mask: u8 },
    /// Zero `len` bytes from `at`.
    Zero { at: f64, len: usize },
    /// Copy `len` bytes from `from` over `to`, or insert them there.
    Duplicate {
        from: f64,
        to: f64,
        len: usize,
        insert: bool,
    },
    /// Overwrite 1-8 bytes in the header region with a huge value (all ones, or the
    /// largest positive 32-bit integer), or put huge numbers in a text header.
    HugeHeader { at: f64, width: usize, kind: u8 },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0.0..1.0f64).prop_map(Mutation::Truncate),
        (0.0..1.0f64, 1..16usize, 1..=255u8).prop_map(|(at, count, mask)| Mutation::Flip {
            at,
            count,
            mask
        }),
        (0.0..1.0f64, 1..4096usize).prop_map(|(at, len)| Mutation::Zero { at, len }),
        (0.0..1.0f64, 0.0..1.0f64, 1..8192usize, any::<bool>()).prop_map(
            |(from, to, len, insert)| Mutation::Duplicate {
                from,
                to,
                len,
                insert
            }
        ),
        (0.0..1.0f64, 1..=8usize, 0..4u8).prop_map(|(at, width, kind)| Mutation::HugeHeader {
            at,
            width,
            kind
        }),
    ]
}

fn apply(seed: &Seed, mutations: &[Mutation]) -> Vec<u8> {
    let mut bytes = seed.bytes.clone();
    for m in mutations {
        let n = bytes.len();
        if n == 0 {
            break;
        }
        let pos = |f: f64| ((f * n as f64) as usize).min(n - 1);
        match *m {
            Mutation::Truncate(f) => bytes.truncate((f * n as f64) as usize),
            Mutation::Flip { at, count, mask } => {
                let start = pos(at);
                for b in bytes[start..(start + count).min(n)].iter_mut() {
                    *b ^= mask;
                }
            }
            Mutation::Zero { at, len } => {
                let start = pos(at);
                bytes[start..(start + len).min(n)].fill(0);
            }
            Mutation::Duplicate {
                from,
                to,
                len,
                insert,
            } => {
                let start = pos(from);
                let block = bytes[start..(start + len).min(n)].to_vec();
                let to = pos(to);
                if insert {
                    bytes.splice(to..to, block);
                } else {
                    let end = (to + block.len()).min(n);
                    bytes[to..end].copy_from_slice(&block[..end - to]);
                }
            }
            Mutation::HugeHeader { at, width, kind } => {
                let header_end = seed.header_end.min(n);
                if header_end > 0 && kind == 3 {
                    // a text header: huge sizes in place of the real ones
                    let text = String::from_utf8_lossy(&bytes[..header_end]).into_owned();
                    let huge = text
                        .replace("1280x720", "4294967295x4294967295")
                        .replace("640x480", "65535x65535")
                        .replace("Width 1280", "Width 65535")
                        .replace("height=720", "height=99999999999");
                    let tail = bytes[header_end..].to_vec();
                    bytes = huge.into_bytes();
                    bytes.extend_from_slice(&tail);
                    continue;
                }
                if seed.file_name == "events.txt" && kind == 3 {
                    let mut out = b"4294967295 4294967295\n".to_vec();
                    out.extend_from_slice(&bytes);
                    bytes = out;
                    continue;
                }
                // the header region (or the first 4 KB of a file without one)
                let region = header_end.max(4096).min(n);
                let start = ((at * region as f64) as usize).min(n - 1);
                let value: [u8; 8] = match kind {
                    0 => [0xff; 8],
                    1 => 0x7fff_ffffu32.to_le_bytes().repeat(2).try_into().unwrap(),
                    _ => (i64::MAX / 3).to_le_bytes(),
                };
                let end = (start + width).min(n);
                bytes[start..end].copy_from_slice(&value[..end - start]);
            }
        }
    }
    bytes
}

/// Decodes `bytes` as a file named `file_name`: `Ok` or an `InputError`, under the memory
/// bound and within a few seconds.
fn survives(file_name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(file_name);
    std::fs::write(&path, bytes).unwrap();
    let started = std::time::Instant::now();
    let (_result, peak) = peak_during(|| read_everything(&path));
    prop_assert!(
        peak < MEMORY_BOUND,
        "{} MB allocated for a {}-byte file",
        peak >> 20,
        bytes.len()
    );
    prop_assert!(
        started.elapsed() < std::time::Duration::from_secs(30),
        "{:?} for a {}-byte file",
        started.elapsed(),
        bytes.len()
    );
    Ok(())
}

#[test]
fn every_seed_decodes_cleanly_before_mutation() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for seed in seeds() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(seed.file_name);
        std::fs::write(&path, &seed.bytes).unwrap();
        let events = read_everything(&path)
            .unwrap_or_else(|e| panic!("{}: the unmutated seed fails: {e}", seed.name));
        assert!(events > 1000, "{}: {events} events", seed.name);
    }
}

#[test]
fn mutated_real_recordings_never_panic_or_blow_up() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let seeds = seeds();
    let cases = std::env::var("CTCAL_MUTATION_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000);
    let config = ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    };
    let count = seeds.len();
    proptest!(config, |(index in 0..count, mutations in proptest::collection::vec(mutation(), 1..4))| {
        let seed = &seeds[index];
        survives(seed.file_name, &apply(seed, &mutations))?;
    });
}

/// Runs the read path on `bytes` and returns the error message (the case must be refused)
/// or the event count, asserting the memory bound either way.
fn bounded(file_name: &str, bytes: &[u8], bound: usize) -> Result<u64, String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(file_name);
    std::fs::write(&path, bytes).unwrap();
    let (result, peak) = peak_during(|| read_everything(&path));
    assert!(peak < bound, "{file_name}: {} MB", peak >> 20);
    result.map_err(|e| e.to_string())
}

#[test]
fn named_hostile_cases_stay_within_memory() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // a 1e7 s gap in a text file: used to allocate a timeline of 1e9 windows
    let gap = b"240 180\n0.000001 1 1 1\n0.000002 2 2 0\n10000000.0 3 3 1\n";
    assert_eq!(bounded("events.txt", gap, 50 << 20), Ok(3));
    // a timestamp of 1e300 s
    let huge = b"0.1 1 1 1\n1e300 2 2 1\n";
    assert!(
        bounded("events.txt", huge, 50 << 20)
            .unwrap_err()
            .contains("line 2")
    );
    // 20,000 EVT3 clock wraps in a 100 KB file (each TIME_HIGH jumps back: a 24-bit loop,
    // 16.8 s), one event after each: 3.4e5 s of time, 3.4e7 windows of 10 ms
    let mut raw = b"% evt 3.0\n% geometry 640x480\n% end\n".to_vec();
    for i in 0..20_000u32 {
        let high: u16 = if i % 2 == 0 { 0xf00 } else { 0x001 };
        // TIME_HIGH, ADDR_Y = 5, ADDR_X = 7 (ON)
        for word in [0x8000 | high, 5, 0x2000 | 0x800 | 7] {
            raw.extend_from_slice(&word.to_le_bytes());
        }
    }
    assert!(raw.len() < 130_000);
    let events = bounded("wraps.raw", &raw, 100 << 20).unwrap();
    assert_eq!(events, 20_000);
    // a bit flip in the first AEDAT4 event time (bit 50: 35 years earlier, the file still
    // sorted): a time span of 35 years in 0.6 s of events
    let bytes = std::fs::read(shared_real("dvxplorer_tonic.aedat4")).unwrap();
    let flipped = flip_aedat4_time_bit(&bytes, 50);
    assert_eq!(bounded("rec.aedat4", &flipped, 200 << 20), Ok(111_954));
}

/// The AEDAT4 file with one bit of the first event's timestamp flipped (the file is
/// uncompressed-packet-aware: only LZ4/Zstd payloads are touched through decompression,
/// so this decodes, edits and re-encodes the first event packet).
fn flip_aedat4_time_bit(bytes: &[u8], bit: u32) -> Vec<u8> {
    // find the first event in the decoded stream by decoding through ctcal and locating
    // its 8 timestamp bytes in the raw file: DVXplorer packets are LZ4 frames, so flip the
    // bit in the decompressed packet and recompress it
    let header = u32::from_le_bytes(bytes[14..18].try_into().unwrap()) as usize;
    let at = 18 + header;
    let size = i32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap()) as usize;
    let packet = &bytes[at + 8..at + 8 + size];
    let mut decoded = Vec::new();
    use std::io::Read;
    lz4_flex::frame::FrameDecoder::new(packet)
        .read_to_end(&mut decoded)
        .expect("the first packet is an LZ4 frame");
    // the events vector: the last 16-byte records of the buffer; the first event's time is
    // the first record's first 8 bytes. Find it as the 8 bytes equal to the file's first
    // event time.
    let first_t = {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.aedat4");
        std::fs::write(&path, bytes).unwrap();
        let r = Recording::open(&path, &OpenOptions::default()).unwrap();
        let mut s = r.events().unwrap();
        s.next_chunk().unwrap().unwrap().t[0]
    };
    let needle = first_t.to_le_bytes();
    let offset = decoded
        .windows(8)
        .position(|w| w == needle)
        .expect("the first event time is in the first packet");
    let mut edited = decoded.clone();
    let t = i64::from_le_bytes(edited[offset..offset + 8].try_into().unwrap()) ^ (1 << bit);
    edited[offset..offset + 8].copy_from_slice(&t.to_le_bytes());
    let mut encoder = lz4_flex::frame::FrameEncoder::new(Vec::new());
    std::io::Write::write_all(&mut encoder, &edited).unwrap();
    let recompressed = encoder.finish().unwrap();
    let mut out = bytes[..at].to_vec();
    out.extend_from_slice(&bytes[at..at + 4]);
    out.extend_from_slice(&(recompressed.len() as i32).to_le_bytes());
    out.extend_from_slice(&recompressed);
    out.extend_from_slice(&bytes[at + 8 + size..]);
    // the packets after the first moved: move the header's data-table position with them
    // (it is the offset where the packets end, stored as an i64 in the header)
    let mut end = at;
    while end + 8 <= bytes.len() {
        let stream = i32::from_le_bytes(bytes[end..end + 4].try_into().unwrap());
        let len = i32::from_le_bytes(bytes[end + 4..end + 8].try_into().unwrap());
        if !(0..16).contains(&stream) || len < 0 || end + 8 + len as usize > bytes.len() {
            break;
        }
        end += 8 + len as usize;
    }
    let delta = recompressed.len() as i64 - size as i64;
    let old = (end as i64).to_le_bytes();
    let field = out[18..at]
        .windows(8)
        .position(|w| w == old)
        .expect("the header stores the data-table position")
        + 18;
    out[field..field + 8].copy_from_slice(&(end as i64 + delta).to_le_bytes());
    out
}

/// A grey PNG of `width` x `height` zeros, deflated row by row (a few hundred KB).
fn png_of_zeros(path: &Path, width: u32, height: u32) {
    use std::io::Write;
    let crc32 = |bytes: &[u8]| {
        let mut crc = 0xffff_ffffu32;
        for &b in bytes {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    };
    let mut deflate = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    let row = vec![0u8; width as usize + 1];
    for _ in 0..height {
        deflate.write_all(&row).unwrap();
    }
    let data = deflate.finish().unwrap();
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    for (kind, body) in [(&b"IHDR"[..], &ihdr[..]), (b"IDAT", &data), (b"IEND", &[])] {
        png.extend_from_slice(&(body.len() as u32).to_be_bytes());
        let mut typed = kind.to_vec();
        typed.extend_from_slice(body);
        png.extend_from_slice(&typed);
        png.extend_from_slice(&crc32(&typed).to_be_bytes());
    }
    std::fs::write(path, png).unwrap();
}

#[test]
fn claimed_sizes_are_checked_before_anything_is_allocated_for_them() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = tempfile::tempdir().unwrap();
    let sensor = ctcal::Sensor::new(240, 180);
    // a 1 KB .npy mask claiming 100000 x 100000 bytes (used to allocate 10 GB)
    let npy = dir.path().join("huge.npy");
    let mut header =
        "{'descr': '|u1', 'fortran_order': False, 'shape': (100000, 100000), }".to_string();
    while !(10 + header.len() + 1).is_multiple_of(64) {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.resize(bytes.len() + 1000, 0);
    std::fs::write(&npy, bytes).unwrap();
    let (result, peak) = peak_during(|| ctcal::io::mask::read_mask(&npy, sensor));
    assert!(result.unwrap_err().to_string().contains("(100000, 100000)"));
    assert!(peak < 1 << 20, "{} KB for the .npy header", peak >> 10);
    // a 400 KB PNG mask that decodes to 20000 x 20000 (used to take 2.3 GB)
    let png = dir.path().join("bomb.png");
    png_of_zeros(&png, 20_000, 20_000);
    let (result, peak) = peak_during(|| ctcal::io::mask::read_mask(&png, sensor));
    assert!(result.unwrap_err().to_string().contains("20000x20000"));
    assert!(peak < 1 << 20, "{} KB for the PNG header", peak >> 10);
    // the statistics of a 65535 x 65535 sensor whose events lie in a corner (the grid used
    // to take 68.7 GB): state for the corner only
    let mut text = String::from("65535 65535\n");
    for i in 0..100_000u32 {
        text.push_str(&format!(
            "{}.{:06} {} {} {}\n",
            i / 100_000,
            i % 100_000 * 10,
            i % 640,
            i / 640 % 480,
            i % 2
        ));
    }
    let events = dir.path().join("events.txt");
    std::fs::write(&events, text).unwrap();
    let options = OpenOptions {
        sensor: Some(ctcal::Sensor::new(65_535, 65_535)),
        ..OpenOptions::default()
    };
    let (stats, peak) = peak_during(|| {
        let recording = Recording::open(&events, &options).unwrap();
        let mut accumulator = StatsAccumulator::new(StatsOptions::default(), recording.sensor);
        let mut stream = recording.events().unwrap();
        while let Some(chunk) = stream.next_chunk().unwrap() {
            accumulator.add(chunk);
        }
        assert!(accumulator.over_budget().is_none());
        let resolved = recording.resolve_sensor(stream.max_coordinates());
        accumulator.finish(resolved.sensor, &resolved.source, &[])
    });
    let stats = stats.unwrap();
    assert_eq!((stats.events, stats.width), (100_000, 65_535));
    assert!(
        peak < 100 << 20,
        "{} MB for a 65535x65535 sensor",
        peak >> 20
    );
}
