//! Where a model is still wrong: the residuals of a simulation against the recording,
//! broken down by scene intensity, by local rate of log-intensity change (supported
//! events), by polarity, by position, over time and by frequency (the event-rate spectrum), with the background
//! rates and the same-pixel interval distributions. The effect library reads its evidence
//! from these ([`super::effects`]); the report plots them before and after each effect.

use super::metric::{background_rates, normalised};
use super::observe::{
    CELLS, CHANGE_BINS, CHANGE_EDGES, Geometry, INTENSITY_BINS, INTERVAL_BINS, Observed, REGIONS,
    Subset, TIMELINE_BIN_US, cell_of, interval_bin_start,
};
use serde::Serialize;

/// Real and simulated counts of one bin, and their log ratio `ln((s + 1/2) / (r + 1/2))`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bin {
    /// What the bin is (e.g. `20-40 DN`).
    pub label: String,
    /// A number for plotting (bin centre, region index, block start).
    pub x: f64,
    pub real: u64,
    pub simulated: u64,
    pub log_ratio: f64,
}

fn bin(label: String, x: f64, real: u64, simulated: u64) -> Bin {
    Bin {
        label,
        x,
        real,
        simulated,
        log_ratio: ((simulated as f64 + 0.5) / (real as f64 + 0.5)).ln(),
    }
}

/// Unsupported-event rates of one intensity bin, events per pixel-second.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BackgroundBin {
    pub intensity_dn: f64,
    pub real_on_hz: Option<f64>,
    pub simulated_on_hz: Option<f64>,
    pub real_off_hz: Option<f64>,
    pub simulated_off_hz: Option<f64>,
}

/// Normalised same-pixel interval histograms.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IntervalDistributions {
    /// Lower edge of each bin, seconds.
    pub bin_start_s: Vec<f64>,
    pub real: Vec<f64>,
    pub simulated: Vec<f64>,
}

/// Power spectra of the event-rate timeline (1 ms bins), each normalised by its median.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Spectrum {
    pub frequency_hz: Vec<f64>,
    pub real: Vec<f64>,
    pub simulated: Vec<f64>,
}

/// Every breakdown of a model's residuals (over the fit blocks).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Residuals {
    pub by_intensity: Vec<Bin>,
    /// By intensity, ON and OFF apart.
    pub by_intensity_on: Vec<Bin>,
    pub by_intensity_off: Vec<Bin>,
    pub by_rate_of_change: Vec<Bin>,
    pub by_polarity: Vec<Bin>,
    pub by_region: Vec<Bin>,
    pub over_time: Vec<Bin>,
    pub background: Vec<BackgroundBin>,
    pub intervals: IntervalDistributions,
    pub spectrum: Spectrum,
}

fn dn_label(i: usize) -> String {
    let edges = super::observe::INTENSITY_EDGES;
    let lower = if i == 0 { 0.0 } else { edges[i - 1] };
    match edges.get(i) {
        Some(upper) => format!("{lower:.0}-{upper:.0} DN"),
        None => format!("{lower:.0}+ DN"),
    }
}

/// The residuals of `sim` against `real` over `subset`.
pub fn residuals(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> Residuals {
    let cells = CellCounts {
        real: real.cells_of(g, subset),
        sim: sim.cells_of(g, subset),
    };
    Residuals {
        by_intensity: cells.by_intensity(g, None),
        by_intensity_on: cells.by_intensity(g, Some(1)),
        by_intensity_off: cells.by_intensity(g, Some(0)),
        by_rate_of_change: cells.by_rate_of_change(g),
        by_polarity: by_polarity(real, sim, g, subset),
        by_region: by_region(real, sim, g, subset),
        over_time: over_time(real, sim, g, subset),
        background: background(real, sim, g, subset),
        intervals: IntervalDistributions {
            bin_start_s: (0..INTERVAL_BINS).map(interval_bin_start).collect(),
            real: normalised(&real.intervals_of(g, subset)),
            simulated: normalised(&sim.intervals_of(g, subset)),
        },
        spectrum: spectrum(real, sim),
    }
}

/// The count cells (intensity x rate of change x polarity) of the recording and of the
/// simulation over one subset.
struct CellCounts {
    real: Vec<u32>,
    sim: Vec<u32>,
}

impl CellCounts {
    /// The bin of the cells `pick` keeps (by intensity bin, change bin, polarity).
    fn bin(&self, label: String, x: f64, pick: impl Fn(usize, usize, usize) -> bool) -> Bin {
        let sum = |c: &[u32]| -> u64 {
            (0..CELLS)
                .filter(|&i| {
                    let (intensity, change, pol) = cell_of(i);
                    pick(intensity, change, pol)
                })
                .map(|i| c[i] as u64)
                .sum()
        };
        bin(label, x, sum(&self.real), sum(&self.sim))
    }

    /// By scene intensity, of one polarity or (`None`) both.
    fn by_intensity(&self, g: &Geometry, pol: Option<usize>) -> Vec<Bin> {
        (0..INTENSITY_BINS)
            .map(|i| {
                let pick = |k: usize, _: usize, p: usize| k == i && pol.is_none_or(|q| q == p);
                self.bin(dn_label(i), g.intensity_centres[i], pick)
            })
            .collect()
    }

    /// By local rate of log-intensity change.
    fn by_rate_of_change(&self, g: &Geometry) -> Vec<Bin> {
        (0..CHANGE_BINS)
            .map(|i| {
                let lower = if i == 0 { 0.0 } else { CHANGE_EDGES[i - 1] };
                let label = match CHANGE_EDGES.get(i) {
                    Some(upper) => format!("{lower}-{upper} /s"),
                    None => format!("{lower}+ /s"),
                };
                self.bin(label, g.change_centres[i], |_, k, _| k == i)
            })
            .collect()
    }
}

/// OFF and ON events.
fn by_polarity(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> Vec<Bin> {
    let ([r_off, r_on], [s_off, s_on]) = (real.polarity_of(g, subset), sim.polarity_of(g, subset));
    vec![
        bin("OFF".into(), 0.0, r_off, s_off),
        bin("ON".into(), 1.0, r_on, s_on),
    ]
}

/// Events of both polarities by region of the sensor.
fn by_region(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> Vec<Bin> {
    let (rr, sr) = (real.regions_of(g, subset), sim.regions_of(g, subset));
    (0..REGIONS)
        .map(|region| {
            let both = |c: &[u32]| (c[2 * region] + c[2 * region + 1]) as u64;
            bin(
                format!("region {region}"),
                region as f64,
                both(&rr),
                both(&sr),
            )
        })
        .collect()
}

/// Events of both polarities by block of the subset.
fn over_time(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> Vec<Bin> {
    (0..g.blocks)
        .filter(|&b| g.in_subset(b, subset))
        .map(|b| {
            let one = |o: &Observed| o.polarity[b][0] + o.polarity[b][1];
            bin(format!("block {b}"), b as f64, one(real), one(sim))
        })
        .collect()
}

/// Unsupported-event rates by intensity bin, ON and OFF.
fn background(real: &Observed, sim: &Observed, g: &Geometry, subset: Subset) -> Vec<BackgroundBin> {
    let (rb, sb) = (
        background_rates(real, g, subset),
        background_rates(sim, g, subset),
    );
    (0..INTENSITY_BINS)
        .map(|i| BackgroundBin {
            intensity_dn: g.intensity_centres[i],
            real_on_hz: rb[2 * i + 1],
            simulated_on_hz: sb[2 * i + 1],
            real_off_hz: rb[2 * i],
            simulated_off_hz: sb[2 * i],
        })
        .collect()
}

/// The power spectra of both event-rate timelines ([`power_spectrum`]).
fn spectrum(real: &Observed, sim: &Observed) -> Spectrum {
    let (frequency_hz, real_power) = power_spectrum(&real.timeline);
    let (_, simulated_power) = power_spectrum(&sim.timeline);
    Spectrum {
        frequency_hz,
        real: real_power,
        simulated: simulated_power,
    }
}

/// The power spectrum of an event-rate timeline (1 ms bins, mean removed, Hann window),
/// averaged into at most 400 frequencies up to 500 Hz, normalised by its median.
pub fn power_spectrum(timeline: &[u32]) -> (Vec<f64>, Vec<f64>) {
    let n = timeline.len();
    if n < 64 {
        return (Vec::new(), Vec::new());
    }
    let mean = timeline.iter().map(|&v| v as f64).sum::<f64>() / n as f64;
    let mut buffer: Vec<rustfft::num_complex::Complex<f64>> = timeline
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            let hann = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos();
            rustfft::num_complex::Complex::new((v as f64 - mean) * hann, 0.0)
        })
        .collect();
    rustfft::FftPlanner::new()
        .plan_fft_forward(n)
        .process(&mut buffer);
    let resolution = 1e6 / (TIMELINE_BIN_US as f64 * n as f64);
    let bins = n / 2;
    let group = bins.div_ceil(400).max(1);
    let mut frequency = Vec::new();
    let mut power = Vec::new();
    for start in (1..bins).step_by(group) {
        let end = (start + group).min(bins);
        frequency.push(0.5 * (start + end - 1) as f64 * resolution);
        power.push(
            buffer[start..end].iter().map(|c| c.norm_sqr()).sum::<f64>() / (end - start) as f64,
        );
    }
    let mut sorted = power.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted
        .get(sorted.len() / 2)
        .copied()
        .unwrap_or(1.0)
        .max(1e-12);
    (frequency, power.iter().map(|p| p / median).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refresh_shows_as_a_spectral_line() {
        // 2 s of 1 ms bins: a 75 Hz square wave on top of noise-free constant activity
        let timeline: Vec<u32> = (0..2000)
            .map(|i| {
                if (i as f64 * 0.075).fract() < 0.2 {
                    50
                } else {
                    10
                }
            })
            .collect();
        let (f, p) = power_spectrum(&timeline);
        let peak = p
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap()
            .0;
        assert!((f[peak] - 75.0).abs() < 1.0, "{}", f[peak]);
        assert!(p[peak] > 100.0);
    }
}
