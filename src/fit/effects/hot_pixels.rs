//! Hot pixels: a few pixels fire far more than their neighbourhood whatever the scene (a
//! leaky or defective pixel; [`crate::sim::effects::hot_pixels`]).
//!
//! Signature: pixels far above the count distribution of their neighbours in the
//! recording but not in the model ([`crate::stats::hot_pixels`], robust z-score against the
//! busiest 8-neighbour). They are masked (left out of every statistic, named in the result)
//! rather than simulated: a simulator places its hot pixels at random, so comparing them
//! pixel by pixel would be meaningless; the fraction and rate are reported for simulation.

use super::{Context, Effect, Evidence};
use crate::stats::hot_pixels::{HotPixel, find_hot_pixels};

/// The recording's hot pixels (fit blocks) that the model does not have.
pub fn find(c: &Context) -> Vec<HotPixel> {
    let g = c.geometry;
    let (w, h) = (g.sensor.width as usize, g.sensor.height as usize);
    let duration = g.duration_of(c.subset);
    let mut real = c.real.pixels_of(c.geometry, c.subset);
    let sim = c.sim.pixels_of(c.geometry, c.subset);
    for (k, r) in c.kept.iter().zip(real.iter_mut()) {
        if !k {
            *r = 0;
        }
    }
    let simulated = find_hot_pixels(&sim, w, h, duration);
    find_hot_pixels(&real, w, h, duration)
        .into_iter()
        .filter(|p| !simulated.iter().any(|s| (s.x, s.y) == (p.x, p.y)))
        .collect()
}

pub fn evidence(c: &Context) -> Evidence {
    let hot = find(c);
    if hot.is_empty() {
        return Evidence::none(Effect::HotPixels, "no pixel stands out from its neighbours");
    }
    let strongest = hot.iter().map(|p| p.z).fold(0.0, f64::max);
    Evidence {
        effect: Effect::HotPixels,
        score: strongest,
        relevant: true,
        text: format!(
            "{} pixels fire far above their neighbours (robust z up to {strongest:.0}), e.g. {}",
            hot.len(),
            hot.iter()
                .take(4)
                .map(|p| format!("({}, {}) at {:.1} Hz", p.x, p.y, p.rate_hz))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        start: None,
    }
}
