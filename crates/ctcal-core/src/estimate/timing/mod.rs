//! Contrast thresholds from event timing, per pixel.
//!
//! At each event the pixel's memorised level moves by exactly one threshold to the level the
//! photoreceptor has at that moment (the remainder is kept), so between two consecutive
//! events of one pixel, at `t_i` and `t_j`, its log intensity changed by exactly
//! `L(t_j) - L(t_i) = +Cp` if the second event is ON and `-Cn` if it is OFF, whatever the
//! first one was (Lichtsteiner et al., JSSC 2008; the "event generation model" of Gallego et
//! al., TPAMI 2022). Measuring `L` at the event times from the frames, interpolated along the
//! optical flow ([`crate::estimate::frames`]), gives one sample of the pixel's threshold per
//! event ([`samples`]).
//!
//! The samples are fitted together ([`model`]): the thresholds, the leak drift (which makes
//! ON events come early and OFF events late, in proportion to the time between them) and the
//! frames' log offset `b` in `ln(DN + b)` (the one at which thresholds do not depend on
//! brightness; its interval, each polarity's own offset, and what they do to the thresholds,
//! are reported), and a trend with the events' distance from the frames, so that the
//! thresholds are read where the frames were measured rather than interpolated. Per pixel
//! the corrected samples are averaged into threshold maps; the frozen mismatch `ct_sigma` is
//! the spread of the map with each pixel's estimation noise removed: `sigma^2 = Var_p(C_p) -
//! mean_p(s^2 / n_p)`, `s^2` the pooled within-pixel variance of the samples.

pub mod model;
pub mod moments;
pub mod peak;
pub mod pixels;
pub mod response;
pub mod samples;
pub mod spread;

use crate::estimate::frames::PreparedFrames;
use crate::events::{EventChunk, Sensor, TimeUs};
use crate::sim::log_response::LogMap;
use crate::stats::jackknife::{t95_scale, weighted_jackknife_se};
use model::{Coefficients, fit_at, offset_interval, offset_root};
use moments::Resampler;
use pixels::{PixelSlots, pixel_sums};
use rayon::prelude::*;
pub use response::OtherResponse;
use samples::{Pair, collect};
use serde::Serialize;

/// Settings of the timing estimator.
#[derive(Clone, Debug)]
pub struct TimingOptions {
    /// Spatio-temporal support window for noise rejection (`None`: keep every event).
    pub support_window_us: Option<TimeUs>,
    /// Kept samples lie within this fraction of the mode on either side... below: mode *
    /// (1 - window), above: mode * (1 + 2 window).
    pub mode_window: f64,
    /// Bootstrap resamples for the statistical interval.
    pub bootstrap: usize,
    /// Fit the frames' log offset (else the frames' own, `PreparedFrames::offset`, is used).
    pub fit_offset: bool,
    /// With the offset, also try a pure `ln(DN + b)` against the frames' own response and
    /// keep the one whose samples agree better.
    pub choose_response: bool,
    /// Fit the leak drift.
    pub fit_leak: bool,
}

impl Default for TimingOptions {
    fn default() -> Self {
        Self {
            support_window_us: None,
            mode_window: 0.5,
            bootstrap: 200,
            fit_offset: false,
            choose_response: false,
            fit_leak: true,
        }
    }
}

/// The threshold estimate of one polarity.
#[derive(Clone, Debug, Serialize)]
pub struct PolarityEstimate {
    /// Mean over pixels of each pixel's threshold.
    pub ct: f64,
    /// Standard error of `ct`: the bootstrap over pixels, with the spread between the blocks
    /// of frames read (see [`between_blocks`]) added in quadrature where there are blocks
    /// (pixels and blocks are crossed: neither resampling sees the other's variation).
    pub standard_error: f64,
    /// The between-blocks standard error where the recording was read in blocks of frames
    /// (delete-one-block jackknife, scaled to a 95 % interval of `+-1.96` of it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub between_blocks_standard_error: Option<f64>,
    /// How far `ct` moves across the offset's 95 % interval (half the range), a systematic
    /// (0 where the range's ends are reached instead: `offset_reach`).
    pub offset_systematic: f64,
    /// Where a polarity gave no offset (the joint one a compromise, its range reaching
    /// down to none: [`with_polarity_offsets`]), `ct` at the range's two ends over `ct`,
    /// lower first: the thresholds' interval reaches them on their side
    /// ([`crate::estimate::interval::Measured::reaching`]); `[1, 1]` otherwise.
    #[serde(skip)]
    pub offset_reach: [f64; 2],
    /// Frozen mismatch, estimation noise removed.
    pub sigma: f64,
    pub sigma_standard_error: f64,
    /// The between-pixel variance of the per-pixel thresholds less their estimation noise,
    /// unclipped (negative where the noise explains the whole spread): `sigma` squared
    /// where positive. Its bootstrap standard error bounds a spread that is not resolved
    /// (the bootstrap of `sigma` itself collapses at zero).
    #[serde(skip)]
    pub excess_variance: f64,
    #[serde(skip)]
    pub excess_variance_standard_error: f64,
    /// Samples kept, and pixels with at least one.
    pub samples: usize,
    pub pixels: usize,
    /// Samples rejected as noise (outside the mode window).
    pub rejected: usize,
    /// Robust relative spread of the kept samples (1.4826 MAD / mode): how consistently the
    /// frames explain the events.
    pub sample_spread: f64,
    /// The share of `ct` the frames' interpolation took from the kept samples on average
    /// (the fitted trend with the events' distance from the frames, at the samples' mean
    /// distance, over `ct`; 0 where the trend was not fitted). Taken out of `ct`, whose
    /// samples are read at the frames.
    pub interpolation_share: f64,
    /// How far the polarity's samples peak at their mode above the noise beneath it
    /// ([`peak::Peak`]; `None` without a positive mode): where they do not, its events are
    /// mostly noise and `ct` is not a threshold.
    pub peak: Option<peak::Peak>,
}

/// Per-pixel thresholds (NaN without a sample) and sample counts, row-major.
#[derive(Clone, Debug)]
pub struct ThresholdMaps {
    pub width: usize,
    pub height: usize,
    pub ct_on: Vec<f32>,
    pub ct_off: Vec<f32>,
    pub count: Vec<u32>,
}

/// The frames' log offset as the timing found (or was given) it.
#[derive(Clone, Debug, Serialize)]
pub struct Offset {
    /// DN added to the frames before the log.
    pub offset_dn: f32,
    /// Its 95 % interval; a side is `None` where the data do not bound it.
    pub ci95: [Option<f32>; 2],
    /// The offsets the thresholds' systematic error spans: the interval, with the prior
    /// range ([`OFFSET_PRIOR`]) where the data leave a side open, and the offsets the ON and
    /// the OFF samples each give.
    pub systematic_range: (f32, f32),
    /// The offset each polarity's samples alone give (ON, OFF; `None` where none within
    /// [`OFFSET_PRIOR`] makes them independent of brightness). One offset belongs to the frames, so their
    /// difference is what other brightness-dependent errors do to the fit.
    pub by_polarity: [Option<f32>; 2],
    /// A fitted offset one polarity's samples give no offset for anywhere in the search
    /// (no root of its level slope from -0.9 of the darkest DN to 255 DN; a root outside the
    /// prior is not this): the joint offset is a compromise, not a measurement
    /// ([`with_polarity_offsets`]).
    pub unconfirmed: bool,
    /// `fitted`, `given` (by the caller), or `not determined...` (the thresholds do not
    /// become independent of brightness at any offset, the photoreceptor's lag hides what
    /// the offset does, the root lies outside [`OFFSET_PRIOR`], or its interval spans the
    /// prior, [`NOT_BOUNDED`]: the frames' own kept, the prior range spanned).
    pub source: &'static str,
}

/// [`Offset::source`] of an offset whose root the level slope's chance error leaves
/// unbounded within [`OFFSET_PRIOR`] on both sides (each end of its 95 % interval open or
/// beyond the prior's).
pub const NOT_BOUNDED: &str =
    "not determined: the thresholds' change with brightness bounds the offset on neither side";

/// The range of offsets taken where the data do not bound it, DN: from none to the largest
/// met in practice with margin. DVS-Voltmeter's fits to real sensors put it at 20 (DAVIS346)
/// and 23 (DVS240) in 8-bit DN (Lin et al., ECCV 2022, `config.py`); DAVIS APS frames are
/// written with a black level of some tens of DN subtracted.
pub const OFFSET_PRIOR: (f32, f32) = (0.0, 60.0);

/// The leak drift the timing found.
#[derive(Clone, Debug, Serialize)]
pub struct Drift {
    /// Log units per second at DN 0, and its growth per DN.
    pub at_zero_dn: f64,
    pub per_dn: f64,
    /// At the frames' median DN (`median_dn`), with its bootstrap standard error.
    pub median_dn: f64,
    pub at_median_dn: f64,
    pub standard_error: f64,
    /// The growth's bootstrap standard error.
    pub per_dn_standard_error: f64,
}

/// Result of the timing estimator.
#[derive(Clone, Debug)]
pub struct TimingEstimate {
    /// The log response the samples were read through (the frames' own, or pure
    /// `ln(DN + b)` where that explains the events better).
    pub log_map: LogMap,
    pub on: PolarityEstimate,
    pub off: PolarityEstimate,
    pub maps: ThresholdMaps,
    /// How far the combined per-pixel spread ([`TimingEstimate::spread`]) moves across the
    /// offset's range (the larger change at its ends over 1.96), a systematic as
    /// [`PolarityEstimate::offset_systematic`] is for the thresholds.
    pub sigma_offset_systematic: f64,
    pub offset: Offset,
    pub drift: Drift,
    pub lag: Lag,
}

impl TimingEstimate {
    /// Each polarity's (ON, OFF) [`PolarityEstimate::offset_reach`].
    pub fn offset_reach(&self) -> [[f64; 2]; 2] {
        [self.on.offset_reach, self.off.offset_reach]
    }
}

/// The photoreceptor lag the timing found.
#[derive(Clone, Debug, Serialize)]
pub struct Lag {
    /// `tau (DN + b)`, seconds x DN, with its bootstrap standard error.
    pub tau_times_dn: f64,
    pub standard_error: f64,
    /// The cutoff it stands for at the frames' median DN, Hz (`None` where the lag is not
    /// positive), and that DN.
    pub cutoff_hz_at_median_dn: Option<f64>,
    pub median_dn: f64,
}

/// The share of the threshold (RMS over pairs) the photoreceptor's lag moves samples by,
/// above which the lag's brightness dependence cannot be told from the offset's: the lag
/// of a sensor without a bandwidth limit moves them by 0.2-0.3 % (v2e), interpolation of
/// 30 Hz frames by 2-4 % (ESIM, IEBCS); a dim scene's 30 Hz photoreceptor by 22 % (v2e).
const LAG_MASKS_OFFSET: f64 = 0.05;

/// The offsets the data may choose from when they constrain it, DN (a black level above
/// the frame's range would make no sense).
const OFFSET_SEARCH: (f32, f32) = (-0.9, 255.0);

/// The thresholds event timing finds, without their errors: what a caller that only
/// compares thresholds (the alignment's systematic) or only takes the response and offset
/// (the frames' preparation) needs. The same values [`estimate`] gives, at a fraction of
/// its cost (no bootstrap, no fits across the offset's range, no blocks' jackknife).
#[derive(Clone, Debug)]
pub struct Thresholds {
    pub log_map: LogMap,
    pub offset: Offset,
    /// The response not chosen, where the events cannot rule it out.
    pub other_response: Option<OtherResponse>,
    pub ct_on: f64,
    pub ct_off: f64,
}

/// The thresholds of [`estimate`] alone ([`Thresholds`]); `None` exactly where
/// [`estimate`] gives none.
pub fn thresholds(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    options: &TimingOptions,
) -> Option<Thresholds> {
    let central = Central::fit(events, frames, sensor, excluded, options)?;
    let fitted = central.fitted();
    // the estimate needs each polarity's per-pixel sums; without them it gives none
    polarity(&fitted, &central.coefficients, true, sensor)?;
    polarity(&fitted, &central.coefficients, false, sensor)?;
    Some(Thresholds {
        ct_on: central.coefficients.c_on,
        ct_off: central.coefficients.c_off,
        log_map: central.log_map,
        offset: central.offset,
        other_response: central.other_response,
    })
}

/// The central fit of the pairs: the response and offset chosen, the model fitted there.
struct Central {
    pairs: Vec<Pair>,
    log_map: LogMap,
    offset: Offset,
    other_response: Option<OtherResponse>,
    coefficients: Coefficients,
    values: model::Values,
    weights: Vec<f64>,
    slots: PixelSlots,
}

impl Central {
    /// The pairs of `events` against `frames`, the response and offset
    /// ([`response::choose`], [`with_polarity_offsets`]) and the fit at that offset; `None`
    /// where the fit fails.
    fn fit(
        events: &EventChunk,
        frames: &PreparedFrames,
        sensor: Sensor,
        excluded: &[bool],
        options: &TimingOptions,
    ) -> Option<Self> {
        let pairs = collect(
            events,
            frames,
            0,
            sensor,
            excluded,
            options.support_window_us,
        );
        let response::Chosen {
            log_map,
            offset,
            other,
        } = response::choose(&pairs, frames, options);
        let (offset, (coefficients, values, weights)) = {
            let fit = whole_fit(&pairs, &log_map, sensor.pixels(), options);
            let offset = with_polarity_offsets(offset, &pairs, options, &fit);
            let at_offset = fit(offset.offset_dn)?;
            (offset, at_offset)
        };
        let slots = PixelSlots::new(&pairs);
        Some(Self {
            pairs,
            log_map,
            offset,
            other_response: other,
            coefficients,
            values,
            weights,
            slots,
        })
    }

    /// Each polarity's peak (`[on, off]`) at the mode its kept samples were chosen around
    /// ([`model::kept`]: the mode at half the window).
    fn peaks(&self, window: f64) -> [Option<peak::Peak>; 2] {
        [true, false].map(|on| {
            let own: Vec<f64> = self
                .pairs
                .iter()
                .zip(&self.values.y)
                .filter(|(p, _)| p.on == on)
                .map(|(_, &y)| y)
                .collect();
            peak::Peak::of(&own, model::mode(&own, window / 2.0)?)
        })
    }

    fn fitted(&self) -> Fitted<'_> {
        Fitted {
            pairs: &self.pairs,
            slots: &self.slots,
            values: &self.values,
            weights: &self.weights,
        }
    }

    /// The estimate: the polarities `[on, off]` with their errors, the `maps`, the spread's
    /// offset systematic, and the offset, the lag and the drift the fit found (their
    /// standard errors from `boot`).
    fn into_estimate(
        self,
        [on, off]: [PolarityEstimate; 2],
        maps: ThresholdMaps,
        sigma_offset_systematic: f64,
        boot: &Bootstrap,
    ) -> TimingEstimate {
        let coefficients = &self.coefficients;
        let median_dn = median_level(&self.pairs);
        let cutoff = coefficients.cutoff_hz(median_dn, self.offset.offset_dn as f64);
        let drift_at_median = |c: &Coefficients| c.drift + c.drift_per_dn * median_dn;
        TimingEstimate {
            log_map: self.log_map,
            on,
            off,
            maps,
            sigma_offset_systematic,
            offset: self.offset,
            lag: Lag {
                tau_times_dn: coefficients.lag,
                standard_error: boot.lag,
                cutoff_hz_at_median_dn: cutoff,
                median_dn,
            },
            drift: Drift {
                at_zero_dn: coefficients.drift,
                per_dn: coefficients.drift_per_dn,
                median_dn,
                at_median_dn: drift_at_median(coefficients),
                standard_error: boot.drift,
                per_dn_standard_error: boot.drift_per_dn,
            },
        }
    }
}

/// [`fit_at`] of `pairs` through `log_map` with the options' window and leak: the whole
/// fit at an offset.
pub(super) fn whole_fit<'a>(
    pairs: &'a [Pair],
    log_map: &'a LogMap,
    pixels: usize,
    options: &'a TimingOptions,
) -> impl Fn(f32) -> Option<(Coefficients, model::Values, Vec<f64>)> + Sync + 'a {
    move |b: f32| {
        fit_at(
            pairs,
            log_map,
            b,
            options.mode_window,
            pixels,
            options.fit_leak,
        )
    }
}

/// Estimates per-pixel thresholds from the timing of `events` (time-sorted) against
/// `frames`. Pixels where `excluded` is set (hot pixels, outside a region) are left out.
/// `None` when there are too few samples.
pub fn estimate(
    events: &EventChunk,
    frames: &PreparedFrames,
    sensor: Sensor,
    excluded: &[bool],
    options: &TimingOptions,
) -> Option<TimingEstimate> {
    // the response is chosen where the frames are prepared ([`thresholds`], which carries
    // the other one); callers then fix it
    let central = Central::fit(events, frames, sensor, excluded, options)?;
    // the thresholds, and each polarity's per-pixel spread, across the offset's interval
    let ends = offset_ends(&central, sensor, options);
    let fitted = central.fitted();
    let boot = bootstrap(&fitted, sensor.pixels(), options);
    let blocks = between_blocks(&fitted, options.fit_leak);
    let (on, on_map) = polarity(&fitted, &central.coefficients, true, sensor)?;
    let (off, off_map) = polarity(&fitted, &central.coefficients, false, sensor)?;
    let sigma_offset_systematic = spread::offset_systematic(
        ends.iter().filter_map(|e| e.1.as_ref()),
        [&on, &off],
        [boot.excess_on, boot.excess_off],
    );
    let errors = Errors {
        boot: &boot,
        blocks,
        ends: &ends,
        central: &central.coefficients,
        unconfirmed: central.offset.unconfirmed || frames.offset_reached,
    };
    let peaks = central.peaks(options.mode_window);
    let polarities = [
        PolarityEstimate {
            peak: peaks[0],
            ..errors.polarity(on, true)
        },
        PolarityEstimate {
            peak: peaks[1],
            ..errors.polarity(off, false)
        },
    ];
    Some(central.into_estimate(
        polarities,
        maps(sensor, &on_map, &off_map),
        sigma_offset_systematic,
        &boot,
    ))
}

/// The fit at each end of the offset's systematic range (but the offset itself): the
/// coefficients there, and each polarity's per-pixel spread (`None` where a polarity fails).
type OffsetEnd = (Coefficients, Option<[PolarityEstimate; 2]>);

/// The whole fit of `central`'s pairs at each end of its offset's systematic range
/// ([`OffsetEnd`]), in parallel; an end that fails is left out.
fn offset_ends(central: &Central, sensor: Sensor, options: &TimingOptions) -> Vec<OffsetEnd> {
    let fit = whole_fit(&central.pairs, &central.log_map, sensor.pixels(), options);
    let (lo, hi) = central.offset.systematic_range;
    [lo, hi]
        .par_iter()
        .filter(|&&b| b != central.offset.offset_dn)
        .filter_map(|&b| {
            let (c, values, weights) = fit(b)?;
            let fitted = Fitted {
                pairs: &central.pairs,
                slots: &central.slots,
                values: &values,
                weights: &weights,
            };
            let spread = polarity(&fitted, &c, true, sensor)
                .zip(polarity(&fitted, &c, false, sensor))
                .map(|(on, off)| [on.0, off.0]);
            Some((c, spread))
        })
        .collect()
}

/// What a polarity's errors are made of: the bootstrap over pixels, the spread between
/// blocks of frames, and the thresholds' change across the offset's range.
struct Errors<'a> {
    boot: &'a Bootstrap,
    blocks: Option<[f64; 2]>,
    ends: &'a [OffsetEnd],
    /// The coefficients at the offset.
    central: &'a Coefficients,
    /// A polarity gave no offset: the ends' thresholds are reached, not only spread.
    unconfirmed: bool,
}

impl Errors<'_> {
    /// The polarity `estimate` (ON where `on`) with its standard errors and its offset
    /// systematic (the largest change at the range's ends, as a standard error).
    fn polarity(&self, estimate: PolarityEstimate, on: bool) -> PolarityEstimate {
        let boot = self.boot;
        let (se, sigma_se, excess_se) = if on {
            (boot.on, boot.sigma_on, boot.excess_on)
        } else {
            (boot.off, boot.sigma_off, boot.excess_off)
        };
        let block = self.blocks.map(|b| b[if on { 0 } else { 1 }]);
        let pick = |c: &Coefficients| if on { c.c_on } else { c.c_off };
        let shift = self
            .ends
            .iter()
            .map(|e| (pick(&e.0) - pick(self.central)).abs())
            .fold(0.0, f64::max)
            / 1.96;
        let ratios = self
            .ends
            .iter()
            .map(|e| pick(&e.0) / pick(self.central))
            .filter(|r| self.unconfirmed && r.is_finite() && *r > 0.0);
        let offset_reach = ratios.fold([1.0f64; 2], |[lo, hi], r| [lo.min(r), hi.max(r)]);
        PolarityEstimate {
            standard_error: block.map_or(se, |b| b.hypot(se)),
            between_blocks_standard_error: block,
            // a reached end is the systematic on its side alone, not a spread both ways
            offset_systematic: if self.unconfirmed { 0.0 } else { shift },
            offset_reach,
            sigma_standard_error: sigma_se,
            excess_variance_standard_error: excess_se,
            ..estimate
        }
    }
}

/// The whole fit at one offset ([`fit_at`] with the response and options fixed).
pub(super) type Fit<'a> =
    dyn Fn(f32) -> Option<(Coefficients, model::Values, Vec<f64>)> + Sync + 'a;

/// The offset: fitted (root of the level slope, interval from its bootstrap error), given,
/// or not determined (the frames' own kept; its interval the whole search range).
pub(super) fn find_offset(
    pairs: &[Pair],
    frames: &PreparedFrames,
    options: &TimingOptions,
    fit: &Fit<'_>,
) -> Offset {
    if !options.fit_offset {
        return Offset {
            offset_dn: frames.offset,
            ci95: [Some(frames.offset); 2],
            systematic_range: frames.offset_range,
            by_polarity: [None; 2],
            unconfirmed: false,
            source: "given",
        };
    }
    let not_determined = Offset {
        offset_dn: frames.offset,
        ci95: [None, None],
        systematic_range: OFFSET_PRIOR,
        by_polarity: [None; 2],
        unconfirmed: false,
        source: "not determined",
    };
    // a strong lag also makes dark pixels' thresholds look larger; the offset would absorb it
    if lag_strength(pairs, frames, options, fit)
        .is_some_and(|(share, z)| share > LAG_MASKS_OFFSET && z > 3.0)
    {
        return Offset {
            source: "not determined: the photoreceptor's lag",
            ..not_determined
        };
    }
    let range = search_range(pairs);
    let slope = model::Memo::new(|b: f32| fit(b).map(|f| f.0.level_slope));
    let slope = |b: f32| slope.at(b);
    let Some(root) = offset_root(&slope, range) else {
        return not_determined;
    };
    let Some(bound) = slope_bound(pairs, frames, options, fit, root) else {
        return not_determined;
    };
    let ci95 = offset_interval(&slope, root, bound, range);
    classified(root, ci95, not_determined)
}

/// The level slope's 95 % chance bound at `root`: 1.96 standard deviations of the slope
/// over 40 bootstrap draws of the pixels' samples (`None` where the fit at the root fails).
fn slope_bound(
    pairs: &[Pair],
    frames: &PreparedFrames,
    options: &TimingOptions,
    fit: &Fit<'_>,
    root: f32,
) -> Option<f64> {
    let (_, values, weights) = fit(root)?;
    let pixels = frames.width * frames.height;
    let slots = PixelSlots::new(pairs);
    let resampler = Resampler::new(pairs, &slots, &values, &weights, pixels);
    let slopes: Vec<f64> = in_order(40, |k| {
        resampler
            .fit(&resampler.draw(500 + k as u64), options.fit_leak)
            .map(|c| c.level_slope)
    });
    Some(1.96 * std_dev(&slopes))
}

/// The offset a `root` with its 95 % interval `ci95` stands for: fitted, or not determined
/// (`not_determined` with its source) where the interval spans the prior on both sides or
/// the root lies beyond the prior.
fn classified(root: f32, ci95: [Option<f32>; 2], not_determined: Offset) -> Offset {
    let open_below = ci95[0].is_none_or(|lo| lo <= OFFSET_PRIOR.0);
    let open_above = ci95[1].is_none_or(|hi| hi >= OFFSET_PRIOR.1);
    if open_below && open_above {
        // the level slope's chance error spans the whole prior range: the root is a start,
        // not a measurement (coverage draw 13037, frames at 11 DN: a root of 35 DN, open
        // above and at -2.3 DN below, read through by eppps as the response shrank its
        // contrasts 5x)
        return Offset {
            source: NOT_BOUNDED,
            ..not_determined
        };
    }
    if !(OFFSET_PRIOR.0..=OFFSET_PRIOR.1).contains(&root) {
        // a black level beyond any met in practice: more likely an effect the timing model
        // lacks (refractory delays, a nonlinear response) than the frames' offset
        return Offset {
            systematic_range: (
                OFFSET_PRIOR.0.min(ci95[0].unwrap_or(root)),
                OFFSET_PRIOR.1.max(ci95[1].unwrap_or(root)),
            ),
            source: "not determined: the fitted offset lies outside the range met in practice",
            ..not_determined
        };
    }
    Offset {
        offset_dn: root,
        ci95,
        systematic_range: (
            ci95[0].unwrap_or(OFFSET_PRIOR.0.min(root)),
            ci95[1].unwrap_or(OFFSET_PRIOR.1.max(root)),
        ),
        by_polarity: [None; 2],
        unconfirmed: false,
        source: "fitted",
    }
}

/// The offsets the data may choose from: [`OFFSET_SEARCH`], its lower end scaled by the
/// darkest DN a pair reads (so that `DN + b` stays positive).
fn search_range(pairs: &[Pair]) -> (f32, f32) {
    let floor = pairs
        .iter()
        .map(|p| p.dn0.min(p.dn1))
        .fold(f32::INFINITY, f32::min);
    (OFFSET_SEARCH.0 * floor.max(0.0), OFFSET_SEARCH.1)
}

/// A fitted offset with the offsets the ON and the OFF samples each give (within
/// [`OFFSET_PRIOR`]: beyond, no black level, as for the joint one) joined to its systematic
/// range, and that range widened by their disagreement ([`disagreement_range`]); found for
/// the chosen response only. Other offsets are returned as they are.
///
/// Where one polarity gives no offset anywhere in the search (a root outside the prior is
/// not this), no black level makes its thresholds stop depending on brightness: something else that depends on brightness
/// moves its samples, and the joint offset is a compromise between that and the other
/// polarity, not a measurement. The systematic range then reaches down to no offset, the
/// frames as written (the prior's lower end), and the thresholds' intervals reach the
/// thresholds at its ends ([`PolarityEstimate::offset_reach`]). Coverage draw 49 (ctcal: a
/// 19 DN natural image, a 4.85 ms refractory period, no offset): the ON samples' slope
/// stays below zero from -0.9 of the darkest DN to 255 DN, the joint offset came out at
/// 27.6 DN (95 % 26.9 .. 28.4) and the thresholds at 0.133 [0.089, 0.178] and 0.121 for a
/// true 0.711 and 0.602; read at b = 0 they are 0.751 and 0.671. Reaching the prior's upper
/// end as well (60 DN) widened the five other such draws of seeds 1-100, all covered, by
/// 1.5-2.5 times, for nothing the data showed
/// (`benches/coverage/mismatch-limit-2026-12-08/offset.md`).
fn with_polarity_offsets(
    offset: Offset,
    pairs: &[Pair],
    options: &TimingOptions,
    fit: &Fit<'_>,
) -> Offset {
    if offset.source != "fitted" {
        return offset;
    }
    let found = polarity_offsets(pairs, options, fit, search_range(pairs));
    let unconfirmed = found.iter().any(Option::is_none);
    let by_polarity = found.map(|b| b.filter(|b| (OFFSET_PRIOR.0..=OFFSET_PRIOR.1).contains(b)));
    let systematic_range = by_polarity
        .iter()
        .flatten()
        .copied()
        .chain(
            disagreement_range(offset.offset_dn, by_polarity)
                .into_iter()
                .flatten(),
        )
        .fold(offset.systematic_range, |(lo, hi), b| {
            (lo.min(b), hi.max(b))
        });
    let systematic_range = if unconfirmed {
        // no black level explains one polarity: down to none, the frames as written
        (systematic_range.0.min(OFFSET_PRIOR.0), systematic_range.1)
    } else {
        systematic_range
    };
    Offset {
        systematic_range,
        by_polarity,
        unconfirmed,
        ..offset
    }
}

/// The offsets an effect other than the offset may have moved the joint `offset` over,
/// given the ON and the OFF samples' own offsets `by_polarity`: `offset -+ |on - off|`,
/// within [`OFFSET_PRIOR`]. One offset belongs to the frames, so the polarities part only
/// where something else that depends on brightness moves their samples (a scene whose
/// dark and bright parts move or occlude differently, a noise that grows with
/// brightness). If it moves each polarity's root by an independent error of one size `s`,
/// their difference has a standard deviation of `s sqrt(2)` and the joint root's error
/// (their mean) one of `s / sqrt(2)`: half the difference as one standard deviation,
/// about the whole difference as 95 %. On IEBCS coverage draw 13025 (true offset 0.03 DN)
/// the ON samples gave 9.6 DN and the OFF samples 44.8, the joint 23.4 (95 % 17.4 .. 30.6),
/// and the thresholds read at 23.4 lay 15 % (ON) and 24 % (OFF) below the truth; at 0 DN
/// they are 2 % above and 2 % below it. `None` where a polarity gives no offset.
fn disagreement_range(offset: f32, by_polarity: [Option<f32>; 2]) -> Option<[f32; 2]> {
    let [Some(on), Some(off)] = by_polarity else {
        return None;
    };
    let apart = (on - off).abs();
    Some([
        (offset - apart).max(OFFSET_PRIOR.0),
        (offset + apart).min(OFFSET_PRIOR.1),
    ])
}

/// The offset the ON and the OFF samples each give: the root of each polarity's own level
/// slope within `range` (`fit` the whole fit at an offset, whose pairs and weights each
/// polarity's fit keeps).
fn polarity_offsets(
    pairs: &[Pair],
    options: &TimingOptions,
    fit: &Fit<'_>,
    range: (f32, f32),
) -> [Option<f32>; 2] {
    // both polarities' slopes from one whole fit at each offset: their bisections start
    // at the same ends and halves and part only where the slopes' signs differ
    let slopes = model::Memo::new(|b: f32| {
        let (_, values, weights) = fit(b)?;
        let slope = |on: bool| {
            let own: Vec<f64> = pairs
                .iter()
                .zip(&weights)
                .map(|(p, &w)| if p.on == on { w } else { 0.0 })
                .collect();
            model::fit_one_polarity(pairs, &values, &own, options.fit_leak).map(|c| c.level_slope)
        };
        Some([slope(true), slope(false)])
    });
    let slope = |b: f32, on: bool| slopes.at(b).and_then(|s| s[usize::from(!on)]);
    let (on, off) = rayon::join(
        || offset_root(&|b| slope(b, true), range),
        || offset_root(&|b| slope(b, false), range),
    );
    [on, off]
}

/// How much the photoreceptor's lag moves the samples at the frames' own offset: the
/// weighted RMS of `kappa x` over the mean threshold, and the lag in its bootstrap standard
/// errors.
fn lag_strength(
    pairs: &[Pair],
    frames: &PreparedFrames,
    options: &TimingOptions,
    fit: &Fit<'_>,
) -> Option<(f64, f64)> {
    let (c, values, weights) = fit(frames.offset)?;
    let pixels = frames.width * frames.height;
    let slots = PixelSlots::new(pairs);
    let resampler = Resampler::new(pairs, &slots, &values, &weights, pixels);
    let lags: Vec<f64> = in_order(30, |k| {
        resampler
            .fit(&resampler.draw(900 + k as u64), options.fit_leak)
            .map(|c| c.lag)
    });
    let wsum: f64 = weights.iter().sum();
    let rms = (values
        .lag
        .iter()
        .zip(&weights)
        .map(|(x, w)| w * (c.lag * x).powi(2))
        .sum::<f64>()
        / wsum.max(1e-12))
    .sqrt();
    Some((
        rms / (0.5 * (c.c_on + c.c_off)),
        c.lag / std_dev(&lags).max(1e-12),
    ))
}

/// Bootstrap standard errors over pixels (the fit's pairs and values fixed).
struct Bootstrap {
    on: f64,
    off: f64,
    sigma_on: f64,
    sigma_off: f64,
    excess_on: f64,
    excess_off: f64,
    drift: f64,
    drift_per_dn: f64,
    lag: f64,
}

/// The pairs at the fitted offset: their values and weights, and their pixels' slots.
struct Fitted<'a> {
    pairs: &'a [Pair],
    slots: &'a PixelSlots,
    values: &'a model::Values,
    weights: &'a [f64],
}

/// The bootstrap draws, each from its own seed (`11 + k`), run on every thread and kept in
/// draw order: the same draws whatever the thread count.
fn bootstrap(fitted: &Fitted, pixels: usize, options: &TimingOptions) -> Bootstrap {
    let Fitted {
        pairs,
        slots,
        values,
        weights,
    } = *fitted;
    let median_dn = median_level(pairs);
    let resampler = Resampler::new(pairs, slots, values, weights, pixels);
    let draw = |k: usize| -> Option<[f64; 9]> {
        let (c, sums) = resampler.fit_and_sums(&resampler.draw(11 + k as u64), options.fit_leak)?;
        let [off, on] = sums.map(|sums| sums.map_or(0.0, |s| mean_and_excess(&s).1));
        Some([
            c.c_on,
            c.c_off,
            sigma_of(on),
            sigma_of(off),
            c.drift + c.drift_per_dn * median_dn,
            c.lag,
            on,
            off,
            c.drift_per_dn,
        ])
    };
    let draws: Vec<[f64; 9]> = in_order(options.bootstrap, draw);
    let sd = |k: usize| std_dev(&draws.iter().map(|d| d[k]).collect::<Vec<_>>());
    Bootstrap {
        on: sd(0),
        off: sd(1),
        sigma_on: sd(2),
        sigma_off: sd(3),
        excess_on: sd(6),
        excess_off: sd(7),
        drift: sd(4),
        drift_per_dn: sd(8),
        lag: sd(5),
    }
}

/// The thresholds' standard error between the blocks of frames read from a longer
/// recording (ON, OFF; `None` when it was read whole, in fewer than three blocks with
/// samples, or a block's leave-one-out fit fails): the delete-one-block jackknife for
/// blocks of unequal size (the delete-m_j jackknife, Busing, Meijer & van der Leeden,
/// *Statistics and Computing* 9, 1999; Künsch 1989 for blocks of a series), each block
/// sized by its pairs' weight. It sees what the bootstrap over pixels cannot: thresholds
/// that change over the recording (with brightness, temperature, bias drift) and the scene
/// each block happens to show. With few blocks the jackknife's own error is large, so it is
/// scaled by `t(0.975, B - 1) / 1.96` (2.57 / 1.96 for six blocks) to give a 95 % interval
/// as `+-1.96` of it.
fn between_blocks(fitted: &Fitted, fit_leak: bool) -> Option<[f64; 2]> {
    let Fitted {
        pairs,
        values,
        weights,
        ..
    } = *fitted;
    let mut sizes: std::collections::BTreeMap<u16, f64> = Default::default();
    for (p, &w) in pairs.iter().zip(weights.iter()) {
        if w > 0.0 {
            *sizes.entry(p.block).or_default() += w;
        }
    }
    if sizes.len() < 3 {
        return None;
    }
    let whole = model::fit(pairs, values, weights, fit_leak)?;
    let left_out = |block: u16| -> Option<[f64; 2]> {
        let w: Vec<f64> = pairs
            .iter()
            .zip(weights.iter())
            .map(|(p, &w)| if p.block == block { 0.0 } else { w })
            .collect();
        let c = model::fit(pairs, values, &w, fit_leak)?;
        Some([c.c_on, c.c_off])
    };
    let blocks: Vec<(u16, f64)> = sizes.into_iter().collect();
    let fits: Vec<[f64; 2]> = blocks
        .par_iter()
        .map(|&(b, _)| left_out(b))
        .collect::<Option<_>>()?;
    let sizes: Vec<f64> = blocks.iter().map(|b| b.1).collect();
    let scale = t95_scale(blocks.len());
    let whole = [whole.c_on, whole.c_off];
    let se = |k: usize| {
        weighted_jackknife_se(
            whole[k],
            &fits.iter().map(|f| f[k]).collect::<Vec<_>>(),
            &sizes,
        ) * scale
    };
    Some([se(0), se(1)])
}

/// `draw(k)` for `k` in `0..n` on every thread, the results that exist in the order of `k`.
fn in_order<T: Send>(n: usize, draw: impl Fn(usize) -> Option<T> + Sync + Send) -> Vec<T> {
    let all: Vec<Option<T>> = (0..n).into_par_iter().map(draw).collect();
    all.into_iter().flatten().collect()
}

/// The median DN of the pairs' middles.
fn median_level(pairs: &[Pair]) -> f64 {
    let mut levels: Vec<f32> = pairs.iter().map(|p| 0.5 * (p.dn0 + p.dn1)).collect();
    if levels.is_empty() {
        return 0.0;
    }
    let mid = levels.len() / 2;
    *levels.select_nth_unstable_by(mid, f32::total_cmp).1 as f64
}

/// One polarity's estimate and its per-pixel sums.
fn polarity(
    fitted: &Fitted,
    c: &Coefficients,
    on: bool,
    sensor: Sensor,
) -> Option<(PolarityEstimate, Vec<(f64, u32)>)> {
    let Fitted {
        pairs,
        slots,
        values,
        weights: weight,
    } = *fitted;
    let (sums, which) = pixel_sums(pairs, slots, values, weight, c, on)?;
    let (_, excess) = mean_and_excess(&sums);
    let ct = if on { c.c_on } else { c.c_off };
    let own: Vec<(usize, f64)> = pairs
        .iter()
        .enumerate()
        .filter(|(_, p)| p.on == on)
        .map(|(i, _)| (i, c.corrected(&pairs[i], values, i)))
        .collect();
    let kept: Vec<f64> = own
        .iter()
        .filter(|(i, _)| weight[*i] > 0.0)
        .map(|v| v.1)
        .collect();
    let mut map = vec![(0.0, 0u32); sensor.pixels()];
    for ((s, n, _), &p) in sums.iter().zip(&which) {
        map[p] = (*s, *n);
    }
    Some((
        PolarityEstimate {
            ct,
            standard_error: 0.0,
            between_blocks_standard_error: None,
            offset_systematic: 0.0,
            offset_reach: [1.0; 2],
            sigma: sigma_of(excess),
            sigma_standard_error: 0.0,
            excess_variance: excess,
            excess_variance_standard_error: 0.0,
            samples: kept.len(),
            pixels: sums.len(),
            rejected: own.len() - kept.len(),
            sample_spread: sample_spread(&kept, ct),
            interpolation_share: interpolation_share(pairs, weight, c, on, ct),
            peak: None,
        },
        map,
    ))
}

/// The robust relative spread of the `kept` samples about `ct`: 1.4826 MAD over `ct`
/// (NaN without samples).
fn sample_spread(kept: &[f64], ct: f64) -> f64 {
    let mut deviations: Vec<f64> = kept.iter().map(|v| (v - ct).abs()).collect();
    if deviations.is_empty() {
        f64::NAN
    } else {
        let mid = deviations.len() / 2;
        1.4826 * *deviations.select_nth_unstable_by(mid, f64::total_cmp).1 / ct
    }
}

/// The share of `ct` the frames' interpolation took from polarity `on`'s kept samples:
/// the fitted trend at their mean distance from the frames (weighted as fitted) over `ct`.
fn interpolation_share(pairs: &[Pair], weight: &[f64], c: &Coefficients, on: bool, ct: f64) -> f64 {
    let (distance, total) = pairs
        .iter()
        .zip(weight)
        .filter(|(p, w)| p.on == on && **w > 0.0)
        .fold((0.0, 0.0), |(d, t), (p, w)| {
            (d + w * p.interpolation(), t + w)
        });
    let trend = if on { c.interp_on } else { c.interp_off };
    -trend * distance / total.max(1e-300) / ct
}

fn maps(sensor: Sensor, on: &[(f64, u32)], off: &[(f64, u32)]) -> ThresholdMaps {
    let mean = |v: &[(f64, u32)]| -> Vec<f32> {
        v.iter()
            .map(|&(s, n)| {
                if n > 0 {
                    (s / n as f64) as f32
                } else {
                    f32::NAN
                }
            })
            .collect()
    };
    ThresholdMaps {
        width: sensor.width as usize,
        height: sensor.height as usize,
        ct_on: mean(on),
        ct_off: mean(off),
        count: on.iter().zip(off).map(|(a, b)| a.1 + b.1).collect(),
    }
}

/// How consistently the frames, their times moved by `shift`, explain the events: the mean
/// over polarities of the robust relative spread of the samples around their mode, at the
/// frames' own offset (smallest when the frames' times are aligned with the events').
/// `None` with too few samples.
pub fn spread(
    events: &EventChunk,
    frames: &PreparedFrames,
    shift: TimeUs,
    sensor: Sensor,
    excluded: &[bool],
    options: &TimingOptions,
) -> Option<f64> {
    // only the samples and their polarity: 8 bytes a pair rather than a whole pair and
    // its model values (the alignment tries nine shifts, two at a time)
    let mut samples: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    samples::PairSource {
        events,
        frames,
        shift,
        sensor,
        excluded,
        support_window_us: options.support_window_us,
    }
    .for_each(samples::Read::DnOnly, |p| {
        samples[p.on as usize].push(model::sample(&p, &frames.log_map, frames.offset));
    });
    let mut total = 0.0;
    for on in [true, false] {
        let own = &samples[on as usize];
        let m = model::mode(own, options.mode_window / 2.0)?;
        let (lo, hi) = (
            m * (1.0 - options.mode_window),
            m * (1.0 + 2.0 * options.mode_window),
        );
        let mut deviations: Vec<f64> = own
            .iter()
            .filter(|&&v| v >= lo && v <= hi)
            .map(|v| (v - m).abs())
            .collect();
        if deviations.len() < 10 {
            return None;
        }
        let mid = deviations.len() / 2;
        total += 0.5 * 1.4826 * *deviations.select_nth_unstable_by(mid, f64::total_cmp).1 / m;
    }
    Some(total)
}

/// The frozen spread of an excess variance (zero where the noise explains it all).
fn sigma_of(excess_variance: f64) -> f64 {
    excess_variance.max(0.0).sqrt()
}

/// The mean of per-pixel thresholds and the frozen spread with estimation noise removed,
/// from per-pixel (sum, count, sum of squares).
#[cfg(test)]
fn mean_and_sigma(pixels: &[(f64, u32, f64)]) -> (f64, f64) {
    let (mean, excess) = mean_and_excess(pixels);
    (mean, sigma_of(excess))
}

/// The mean of per-pixel thresholds and their between-pixel variance less the estimation
/// noise of each pixel's mean (the pooled within-pixel variance over its sample count),
/// unclipped, from per-pixel (sum, count, sum of squares).
fn mean_and_excess(pixels: &[(f64, u32, f64)]) -> (f64, f64) {
    let n = pixels.len() as f64;
    let means: Vec<f64> = pixels.iter().map(|&(s, c, _)| s / c as f64).collect();
    let mean = means.iter().sum::<f64>() / n;
    let between = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    // pooled within-pixel variance over pixels with two samples or more
    let (mut within, mut dof) = (0.0, 0.0);
    for &(s, c, sq) in pixels {
        if c >= 2 {
            within += sq - s * s / c as f64;
            dof += (c - 1) as f64;
        }
    }
    let pooled = if dof > 0.0 { within / dof } else { 0.0 };
    let noise = pixels
        .iter()
        .map(|&(_, c, _)| pooled / c as f64)
        .sum::<f64>()
        / n;
    (mean, between - noise)
}

fn std_dev(values: &[f64]) -> f64 {
    crate::stats::robust::sample_std_dev(values).unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_removes_the_estimation_noise_of_each_pixel() {
        // every pixel has the same threshold 0.3 and two samples, each off by +-0.05 (all
        // four combinations equally often): the pixel means spread by 0.035, all of it noise
        let sample = |i: usize, bit: usize| if (i >> bit) & 1 == 0 { 0.35 } else { 0.25 };
        let pixels: Vec<(f64, u32, f64)> = (0..1000)
            .map(|i| {
                let (a, b) = (sample(i, 0), sample(i, 1));
                (a + b, 2, a * a + b * b)
            })
            .collect();
        let (mean, sigma) = mean_and_sigma(&pixels);
        assert!((mean - 0.3).abs() < 1e-3, "{mean}");
        assert!(sigma < 0.005, "{sigma}");
        // a real spread of 0.03 on top is recovered: shift half the pixels by +-0.03
        let shifted: Vec<(f64, u32, f64)> = pixels
            .iter()
            .enumerate()
            .map(|(i, &(s, c, _))| {
                let d = if (i >> 2) & 1 == 0 { 0.03 } else { -0.03 };
                let (a, b) = (sample(i, 0) + d, sample(i, 1) + d);
                (s + 2.0 * d, c, a * a + b * b)
            })
            .collect();
        let (_, sigma) = mean_and_sigma(&shifted);
        assert!((sigma - 0.03).abs() < 0.004, "{sigma}");
    }

    /// One or two samples per pixel, each off by +-0.1, no real spread: the pixel means
    /// spread less than their noise predicts in about half of such draws, and the excess is
    /// then negative (kept, so a bootstrap can follow it through zero), not clipped.
    #[test]
    fn the_excess_variance_is_not_clipped_at_zero() {
        let sample = |i: usize| if i.is_multiple_of(2) { 0.4 } else { 0.2 };
        // pixels with two samples: both the same side (+-0.1) or one each (0)
        let mut pixels: Vec<(f64, u32, f64)> = (0..400)
            .map(|i| {
                let (a, b) = (sample(i), sample(i / 2));
                (a + b, 2, a * a + b * b)
            })
            .collect();
        // and single samples whose spread is smaller than the pooled noise predicts
        pixels.extend((0..400).map(|_| (0.3, 1, 0.09)));
        let (mean, excess) = mean_and_excess(&pixels);
        assert!((mean - 0.3).abs() < 1e-9, "{mean}");
        assert!(excess < -0.001, "{excess}");
        assert_eq!(mean_and_sigma(&pixels).1, 0.0);
    }

    #[test]
    fn polarities_that_disagree_widen_the_offsets_range_by_their_difference_within_the_prior() {
        // draw 13025: the joint 23.4, ON 9.6, OFF 44.8: 35.2 apart, cut at the prior's ends
        let [lo, hi] = disagreement_range(23.4, [Some(9.6), Some(44.8)]).unwrap();
        assert!(lo == 0.0 && (hi - 58.6).abs() < 1e-4, "{lo} {hi}");
        // polarities within a DN of each other move the range by that DN
        let [lo, hi] = disagreement_range(2.9, [Some(2.2), Some(3.5)]).unwrap();
        assert!(
            (lo - 1.6).abs() < 1e-5 && (hi - 4.2).abs() < 1e-5,
            "{lo} {hi}"
        );
        assert_eq!(
            disagreement_range(60.0, [Some(59.0), Some(61.0)]),
            Some([58.0, 60.0])
        );
        assert_eq!(disagreement_range(5.0, [None, Some(3.0)]), None);
    }

    #[test]
    fn the_mode_ignores_a_broad_noise_floor() {
        // 600 samples at 0.30 +- 0.01 and 400 spread evenly over 0..1
        let mut values: Vec<f64> = (0..600).map(|i| 0.29 + 0.02 * (i as f64 / 600.0)).collect();
        values.extend((0..400).map(|i| i as f64 / 400.0));
        let m = model::mode(&values, 0.25).unwrap();
        assert!((m - 0.30).abs() < 0.01, "{m}");
    }

    #[test]
    fn the_mode_is_the_largest_peak_when_the_median_lies_in_a_smaller_one() {
        // 520 noise samples over 0.06-0.12 and 480 threshold samples at 0.33-0.37: the
        // median (0.12) lies in the noise, whose window holds fewer samples than the
        // threshold's; mean shift from the median alone ends at 0.09
        let mut values: Vec<f64> = (0..520).map(|i| 0.06 + 0.06 * (i as f64 / 520.0)).collect();
        values.extend((0..480).map(|i| 0.33 + 0.04 * (i as f64 / 480.0)));
        let m = model::mode(&values, 0.25).unwrap();
        assert!((m - 0.35).abs() < 0.01, "{m}");
    }
}
