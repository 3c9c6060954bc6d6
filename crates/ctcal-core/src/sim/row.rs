//! One sensor row of the simulator: per-pixel state as a struct of arrays, advanced one
//! sample at a time in two phases.
//!
//! 1. A branch-free pass, compiled for AVX2 where the CPU has it, finds the pixels that
//!    provably cannot fire in the interval and advances them. Without filter, leak, shot
//!    noise or hot pixels this is a window test on intensity: a pixel is quiet when its old
//!    and new intensities lie strictly inside the window whose logs lie between its
//!    thresholds (`L^-1(ref - theta_off)`, `L^-1(ref + theta_on)`, narrowed by 1e-5 so
//!    rounding never lets a crossing through), so no logarithm is taken for quiet pixels.
//!    Otherwise the pass takes the log of the new frame, advances the filter, and checks the
//!    extreme points of the level over the interval: its end points, and behind the filter
//!    (`tau y' = u - y` with `u` linear) the input's start value when the level can turn
//!    where it meets a falling (or rising) input.
//! 2. The continuous-time update of [`super::pixel`] for every other ("busy") pixel.

use super::effects::bandwidth;
use super::log_response::LogMap;
use super::pixel::{EventSink, PixelModel, PixelState, Transition};
#[cfg(target_arch = "x86_64")]
use super::simd::use_avx2;
use crate::events::{Event, TimeUs};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Relative narrowing of the intensity window.
const WINDOW_MARGIN: f32 = 1e-5;

/// State only the full update touches.
#[derive(Clone, Debug)]
pub(super) struct Cold {
    pub frozen_on: f32,
    pub frozen_off: f32,
    pub noise_rate_per_us: f64,
    pub noise_on_share: f32,
    pub last_event_us: f64,
    pub next_noise_us: f64,
    pub next_hot_us: f64,
}

/// What every row needs to advance by one sample.
pub(super) struct Step<'a> {
    pub model: &'a PixelModel,
    pub log_map: LogMap,
    pub origin: TimeUs,
    pub t0: f64,
    pub t1: f64,
    pub transition: Transition,
}

impl Step<'_> {
    fn h(&self) -> f32 {
        (self.t1 - self.t0) as f32
    }
}

/// One sensor row.
pub(super) struct Row {
    pub y: u16,
    pub reference: Vec<f32>,
    pub filtered: Vec<f32>,
    /// Log input at the previous sample (not kept in window mode: recomputed from `dn`).
    pub input: Vec<f32>,
    pub dn: Vec<f32>,
    pub theta_on: Vec<f32>,
    pub theta_off: Vec<f32>,
    pub leak: Vec<f32>,
    /// The leak's growth per DN of the present intensity, log units per microsecond.
    pub leak_per_dn: Vec<f32>,
    /// Intensity window of the quiet test (window mode only).
    pub window_low: Vec<f32>,
    pub window_high: Vec<f32>,
    pub next_interrupt: Vec<f64>,
    /// 1 where the pixel needs the full update this interval (u32 to match f32 lanes).
    pub busy: Vec<u32>,
    /// Scratch: the filter output at the end of the interval (log mode with filter).
    pub filter_end: Vec<f32>,
    pub cold: Vec<Cold>,
    pub rng: Xoshiro256PlusPlus,
    pub events: Vec<Event>,
}

impl Row {
    /// Recomputes pixel `x`'s intensity window from its reference and thresholds.
    pub fn update_window(&mut self, x: usize, log_map: &LogMap) {
        let r = self.reference[x];
        self.window_low[x] = log_map.inverse(r - self.theta_off[x]) * (1.0 + WINDOW_MARGIN);
        self.window_high[x] = log_map.inverse(r + self.theta_on[x]) * (1.0 - WINDOW_MARGIN);
    }

    /// Pixel `x` as one [`PixelState`].
    pub fn load(&self, x: usize, model: &PixelModel, log_map: &LogMap) -> PixelState {
        let input = if model.intensity_window {
            log_map.apply(self.dn[x])
        } else {
            self.input[x]
        };
        let filtered = if model.cutoff_hz.is_some() {
            self.filtered[x]
        } else {
            input
        };
        let mut p = PixelState::new(input, self.dn[x], self.theta_on[x], self.theta_off[x]);
        p.reference = self.reference[x];
        p.filtered = filtered;
        p.leak_per_us = self.leak[x];
        p.leak_per_dn_per_us = self.leak_per_dn[x];
        if model.per_pixel_history {
            let c = &self.cold[x];
            p.frozen_on = c.frozen_on;
            p.frozen_off = c.frozen_off;
            p.noise_rate_per_us = c.noise_rate_per_us;
            p.noise_on_share = c.noise_on_share;
            p.last_event_us = c.last_event_us;
            p.next_noise_us = c.next_noise_us;
            p.next_hot_us = c.next_hot_us;
        }
        p
    }

    fn store(&mut self, x: usize, p: &PixelState, step: &Step) {
        self.reference[x] = p.reference;
        self.filtered[x] = p.filtered;
        self.input[x] = p.input;
        self.dn[x] = p.dn;
        self.theta_on[x] = p.theta_on;
        self.theta_off[x] = p.theta_off;
        if step.model.intensity_window {
            self.update_window(x, &step.log_map);
        }
        if step.model.per_pixel_history {
            self.next_interrupt[x] = p.next_noise_us.min(p.next_hot_us);
            let c = &mut self.cold[x];
            c.last_event_us = p.last_event_us;
            c.next_noise_us = p.next_noise_us;
            c.next_hot_us = p.next_hot_us;
        }
    }

    /// Window mode: quiet when both intensities lie strictly inside the window.
    #[inline(always)]
    fn window_pass(&mut self, dn1: &[f32]) {
        let n = self.dn.len();
        let (dn, dn1, busy) = (&mut self.dn[..n], &dn1[..n], &mut self.busy[..n]);
        let (low, high) = (&self.window_low[..n], &self.window_high[..n]);
        for x in 0..n {
            let (old, new) = (dn[x], dn1[x]);
            let quiet =
                ((old > low[x]) & (old < high[x]) & (new > low[x]) & (new < high[x])) as u32;
            busy[x] = 1 - quiet;
            dn[x] = select(quiet, new, old);
        }
    }

    /// Log mode: the log of the new frame, the filter, and the quiet test on the extreme
    /// points of the level. `FILTER`: the low-pass is on; `HOLD`: the input holds, then steps
    /// at the end; `EFFECTS`: leak, shot noise or hot pixels are on (otherwise their arrays
    /// are neither read nor written, and neither is the intensity, which only the filter and
    /// shot noise use). The pass runs in three stages, each a loop of its own over slices
    /// cut to one length, with stores as selects, so that the compiler drops bounds checks
    /// and vectorises: the pixels an interruption falls on ([`Self::mark_interrupted`]), the
    /// filter ([`Self::filter_ends`]), and the quiet test with the quiet pixels' advance
    /// ([`Self::advance_quiet`]).
    #[inline(always)]
    fn quiet_pass<const FILTER: bool, const HOLD: bool, const EFFECTS: bool>(
        &mut self,
        u1: &[f32],
        dn1: &[f32],
        t1: f64,
        h: f32,
        cutoff: f32,
    ) {
        if EFFECTS {
            self.mark_interrupted(t1);
        }
        if FILTER {
            // the filter in a loop of its own: fewer live registers in each loop
            self.filter_ends::<HOLD>(u1, dn1, h, cutoff);
        }
        self.advance_quiet::<FILTER, HOLD, EFFECTS>(u1, dn1, h);
    }

    /// Marks busy the pixels whose next shot-noise or hot-pixel event falls before `t1`
    /// (and clears the mark of every other pixel).
    #[inline(always)]
    fn mark_interrupted(&mut self, t1: f64) {
        let n = self.reference.len();
        let busy = &mut self.busy[..n];
        for (b, &next) in busy.iter_mut().zip(&self.next_interrupt[..n]) {
            *b = (next < t1) as u32;
        }
    }

    /// The filter output at the end of the interval, of every pixel, into `filter_end`
    /// (the input held at its start value when `HOLD`, else linear to `u1`).
    #[inline(always)]
    fn filter_ends<const HOLD: bool>(&mut self, u1: &[f32], dn1: &[f32], h: f32, cutoff: f32) {
        let n = self.reference.len();
        let (u1, dn1) = (&u1[..n], &dn1[..n]);
        let (input, filtered, dn) = (&self.input[..n], &self.filtered[..n], &self.dn[..n]);
        let filter_end = &mut self.filter_end[..n];
        let inverse_h = 1.0 / h;
        for x in 0..n {
            let (u0, y0, dn0) = (input[x], filtered[x], dn[x]);
            let (u_end, dn_end) = if HOLD { (u0, dn0) } else { (u1[x], dn1[x]) };
            let rate = bandwidth::rate_per_us(0.5 * (dn0 + dn_end), cutoff);
            filter_end[x] = bandwidth::advance_with_rate(y0, u0, u_end, h, inverse_h, rate);
        }
    }

    /// The quiet test of every pixel ([`stays_inside`], and with `EFFECTS` not marked
    /// busy), with the quiet pixels advanced to the end of the interval (reference drifted
    /// by the leak, input, filter and intensity at their new values) and `busy` set for the
    /// others.
    #[inline(always)]
    fn advance_quiet<const FILTER: bool, const HOLD: bool, const EFFECTS: bool>(
        &mut self,
        u1: &[f32],
        dn1: &[f32],
        h: f32,
    ) {
        let n = self.reference.len();
        let (u1, dn1) = (&u1[..n], &dn1[..n]);
        let busy = &mut self.busy[..n];
        let reference = &mut self.reference[..n];
        let filtered = &mut self.filtered[..n];
        let input = &mut self.input[..n];
        let dn = &mut self.dn[..n];
        let (theta_on, theta_off) = (&self.theta_on[..n], &self.theta_off[..n]);
        let (leak, leak_per_dn) = (&self.leak[..n], &self.leak_per_dn[..n]);
        let filter_end = &self.filter_end[..n];
        for x in 0..n {
            let (u0, r) = (input[x], reference[x]);
            let u_end = if HOLD { u0 } else { u1[x] };
            let drift = if EFFECTS {
                // the intensity's mean over the interval, as the busy path's segments
                let dn_end = if HOLD { dn[x] } else { dn1[x] };
                (leak[x] + leak_per_dn[x] * 0.5 * (dn[x] + dn_end)) * h
            } else {
                0.0
            };
            let (y0, y1) = if FILTER {
                (filtered[x], filter_end[x])
            } else {
                (u0, u_end)
            };
            let (top, bottom) = (theta_on[x] + r - drift, r - theta_off[x]);
            let mut quiet = stays_inside::<FILTER, HOLD>([u0, u_end, u1[x]], [y0, y1], top, bottom);
            if EFFECTS {
                quiet &= 1 - busy[x];
            }
            busy[x] = 1 - quiet;
            if EFFECTS {
                reference[x] = select(quiet, r - drift, r);
            }
            input[x] = select(quiet, u1[x], u0);
            if FILTER {
                filtered[x] = select(quiet, y1, y0);
            }
            if FILTER || EFFECTS {
                dn[x] = select(quiet, dn1[x], dn[x]);
            }
        }
    }

    /// The vectorisable phase (inlined into both the plain and the AVX2 entry points).
    #[inline(always)]
    fn vector_work(&mut self, step: &Step, dn1: &[f32], u1: &mut [f32]) {
        let model = step.model;
        if model.intensity_window {
            self.window_pass(dn1);
            return;
        }
        step.log_map.apply_frame(dn1, u1);
        let h = step.h();
        // a zero-length interval (two samples at one time) cannot move the filter
        let cutoff = model.cutoff_hz.filter(|_| h > 0.0);
        let c = cutoff.unwrap_or(1.0);
        let t1 = step.t1;
        macro_rules! pass {
            ($($f:literal, $h:literal, $e:literal);*) => {
                match (cutoff.is_some(), step.transition == Transition::Hold, model.fast_path_effects) {
                    $(($f, $h, $e) => self.quiet_pass::<$f, $h, $e>(u1, dn1, t1, h, c),)*
                }
            };
        }
        pass!(false, false, false; false, false, true; false, true, false; false, true, true;
              true, false, false; true, false, true; true, true, false; true, true, true);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn vector_work_avx2(&mut self, step: &Step, dn1: &[f32], u1: &mut [f32]) {
        self.vector_work(step, dn1, u1);
    }

    /// Phase 1: the quiet pixels (same results with or without AVX2).
    fn vector_phase(&mut self, step: &Step, dn1: &[f32], u1: &mut [f32]) {
        self.events.clear();
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: use_avx2() is true only when the CPU supports AVX2.
            unsafe { self.vector_work_avx2(step, dn1, u1) };
            return;
        }
        self.vector_work(step, dn1, u1);
    }

    /// Advances the row by one sample: the quiet pixels, then the busy ones
    /// ([`Self::vector_phase`], [`Self::busy_phase`]).
    pub fn advance(&mut self, step: &Step, dn1: &[f32], u1: &mut [f32]) {
        self.vector_phase(step, dn1, u1);
        self.busy_phase(step, dn1, u1);
    }

    /// Calls `f` for every busy pixel (blocks of 16 quiet pixels are skipped with one OR).
    #[inline(always)]
    fn for_each_busy(busy: &[u32], mut f: impl FnMut(usize)) {
        const BLOCK: usize = 16;
        for (block, flags) in busy.chunks(BLOCK).enumerate() {
            if flags.iter().fold(0, |a, &b| a | b) == 0 {
                continue;
            }
            for (i, &flag) in flags.iter().enumerate() {
                if flag != 0 {
                    f(block * BLOCK + i);
                }
            }
        }
    }

    /// Phase 2: the full update of every busy pixel. In window mode `u1` was not computed
    /// and the log is taken here, for busy pixels only.
    fn busy_phase(&mut self, step: &Step, dn1: &[f32], u1: &[f32]) {
        let busy = std::mem::take(&mut self.busy);
        Self::for_each_busy(&busy, |x| {
            let u = if step.model.intensity_window {
                step.log_map.apply(dn1[x])
            } else {
                u1[x]
            };
            self.full_update(x, step, u, dn1[x]);
        });
        self.busy = busy;
    }

    /// The continuous-time update of one pixel (see [`PixelState::advance`]).
    #[inline(never)]
    fn full_update(&mut self, x: usize, step: &Step, u1: f32, dn1: f32) {
        let mut pixel = self.load(x, step.model, &step.log_map);
        let mut sink = EventSink {
            events: &mut self.events,
            origin_us: step.origin,
            x: x as u16,
            y: self.y,
        };
        pixel.advance(
            step.model,
            step.t0,
            step.t1,
            u1,
            dn1,
            step.transition,
            &mut self.rng,
            &mut sink,
        );
        self.store(x, &pixel, step);
    }
}

/// `new` where `quiet` is 1, else `old`: a bitwise select, branch-free and exact (a value
/// select can otherwise become a select of addresses, which does not vectorise).
#[inline(always)]
fn select(quiet: u32, new: f32, old: f32) -> f32 {
    let mask = 0u32.wrapping_sub(quiet);
    f32::from_bits((new.to_bits() & mask) | (old.to_bits() & !mask))
}

/// 1 where a pixel's level stays strictly between `bottom` and `top` over the interval,
/// judged on its extreme points: the input `[u0, u_end, u1]` (at the start, at the end of
/// the piece before the step, and after the step when `HOLD`) and the filter output
/// `[y0, y1]` at the start and end. Comparisons only (no min/max), so the loop around it
/// vectorises.
#[inline(always)]
fn stays_inside<const FILTER: bool, const HOLD: bool>(
    [u0, u_end, u1]: [f32; 3],
    [y0, y1]: [f32; 2],
    top: f32,
    bottom: f32,
) -> u32 {
    let inside = |v: f32| ((v < top) & (v > bottom)) as u32;
    let mut quiet = if FILTER {
        // Behind the filter the level moves monotonically between its end points
        // unless it meets the input, which is a maximum only when the input falls
        // (then it lies below the input's start u0), a minimum only when it rises.
        let interior = ((u_end < u0) & (y0 < u0)) | ((u_end > u0) & (y0 > u0));
        inside(y0) & inside(y1) & (inside(u0) | !interior as u32)
    } else {
        inside(u0) & inside(u_end)
    };
    if HOLD && !FILTER {
        quiet &= inside(u1);
    }
    quiet
}
