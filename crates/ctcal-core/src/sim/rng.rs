//! Seeding. Every random stream is derived from the simulation seed and a stream label, so
//! results do not depend on thread count or scheduling: initial draws (thresholds, leak
//! factors, hot pixels) come from one sequential stream per purpose, and each sensor row
//! owns a generator for the draws of its pixels' updates (shot noise, temporal threshold
//! noise, hot-pixel trains), consumed in a fixed pixel order. Xoshiro256++ (Blackman &
//! Vigna 2018) is fast and its output is portable across platforms and crate versions.

use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// SplitMix64 finaliser: decorrelates nearby seeds.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Purposes of the random streams.
#[derive(Clone, Copy, Debug)]
pub enum Stream {
    Thresholds = 1,
    Leak = 2,
    HotPixels = 3,
    Rows = 4,
    Jitter = 5,
    Scene = 6,
}

/// The generator for `stream` (and `index`, e.g. a row) of simulation `seed`.
pub fn generator(seed: u64, stream: Stream, index: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(mix(mix(seed ^ mix(stream as u64)) ^ index))
}
