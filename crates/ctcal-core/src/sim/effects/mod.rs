//! The non-ideal pixel effects, one module each: its equation, where it comes from, and a
//! hand-computed unit test. The per-pixel update in [`super::pixel`] calls into these.

pub mod bandwidth;
pub mod hot_pixels;
pub mod jitter;
pub mod leak;
pub mod mismatch;
pub mod refractory;
pub mod shot_noise;
