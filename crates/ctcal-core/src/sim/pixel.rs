//! The DVS pixel (Lichtsteiner, Posch & Delbruck, IEEE JSSC 2008) with every effect of
//! [`super::effects`], advanced one input interval at a time in continuous time.
//!
//! The pixel keeps a memorised log level `reference`. Its photoreceptor output `y(t)` is the
//! log input `u(t) = L(DN(t))` (see [`super::log_response`]), or a low-pass filtered copy of
//! it when bandwidth is modelled. With `d(t) = y(t) - reference(t)`, the pixel emits an ON
//! event when `d` reaches `theta_on` and an OFF event when it reaches `-theta_off`, and moves
//! its reference by that threshold (so the remainder is kept, as in v2e and ESIM).
//!
//! Between input samples the log input is linear in time (ESIM's and v2e's interpolation).
//! Crossing times are solved in closed form on that line, which is the limit of infinitely
//! fine temporal upsampling: events sit at their interpolated crossing times rather than
//! being spread evenly over the interval. Where the trajectory is not linear (behind the
//! low-pass filter) the interval is cut into adaptive sub-steps whose straight-line
//! approximation of `y` is within 0.2 % of a threshold, and crossings are interpolated within
//! each.

use super::effects::{bandwidth, mismatch, refractory, shot_noise};
use crate::events::{Event, TimeUs};
use rand::{Rng, RngExt};
use rand_xoshiro::Xoshiro256PlusPlus;

/// How the input gets from the previous sample to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transition {
    /// Linear in log intensity (video frames, rendered scenes).
    Linear,
    /// Held at the previous value, then a step at the new sample's time (a display refresh).
    Hold,
}

/// Per-simulation constants of the pixel update.
#[derive(Clone, Debug)]
pub struct PixelModel {
    pub refractory_us: f64,
    pub cutoff_hz: Option<f32>,
    pub sigma_temporal: Option<f32>,
    pub noise_bright_factor: f32,
    pub hot_rate_per_us: f64,
    /// Largest error of the straight-line approximation of the filtered level within a
    /// sub-step, as a fraction of the threshold.
    pub substep_tolerance: f32,
    pub max_substeps: u32,
    /// Leak, shot noise or hot pixels are on (the fast path then tracks drift, due
    /// interruptions and intensity).
    pub fast_path_effects: bool,
    /// Some effect needs per-pixel history beyond the levels (refractory timing, temporal
    /// threshold noise, noise and hot-pixel clocks).
    pub per_pixel_history: bool,
    /// No filter, leak, noise or hot pixels: quiet pixels are found by an intensity window
    /// (see [`super::row`]).
    pub intensity_window: bool,
}

/// One pixel's state. Times are microseconds since the simulation's first sample.
#[derive(Clone, Debug)]
pub struct PixelState {
    /// Memorised log level.
    pub reference: f32,
    /// Photoreceptor output (log domain).
    pub filtered: f32,
    /// Log input and intensity at the previous sample.
    pub input: f32,
    pub dn: f32,
    /// Thresholds in force now.
    pub theta_on: f32,
    pub theta_off: f32,
    /// Frozen per-pixel thresholds (temporal noise is drawn around these).
    pub frozen_on: f32,
    pub frozen_off: f32,
    /// Reference drift (leak), log units per microsecond, and its growth per DN of the
    /// present intensity (the leak that grows with the light).
    pub leak_per_us: f32,
    pub leak_per_dn_per_us: f32,
    /// Shot-noise candidate rate per microsecond and the ON share of its events.
    pub noise_rate_per_us: f64,
    pub noise_on_share: f32,
    pub last_event_us: f64,
    pub next_noise_us: f64,
    pub next_hot_us: f64,
}

/// Collects a pixel's events.
pub struct EventSink<'a> {
    pub events: &'a mut Vec<Event>,
    pub origin_us: TimeUs,
    pub x: u16,
    pub y: u16,
}

impl EventSink<'_> {
    #[inline]
    fn emit(&mut self, t_us: f64, on: bool) {
        // times since the first sample are never negative: adding a half and truncating
        // rounds to the nearest microsecond without a libm call
        self.events.push(Event {
            t: self.origin_us + (t_us + 0.5) as TimeUs,
            x: self.x,
            y: self.y,
            on,
        });
    }
}

#[inline(always)]
fn lerp(a: f32, b: f32, f: f32) -> f32 {
    a + (b - a) * f
}

/// An exponential waiting time with the given rate (per microsecond).
#[inline]
pub fn exponential_us(rate_per_us: f64, rng: &mut impl Rng) -> f64 {
    if rate_per_us <= 0.0 {
        return f64::INFINITY;
    }
    let u: f64 = rng.random();
    -(1.0 - u).ln() / rate_per_us
}

impl PixelState {
    /// A pixel at rest at log level `input` (intensity `dn`) with the given thresholds.
    pub fn new(input: f32, dn: f32, theta_on: f32, theta_off: f32) -> Self {
        Self {
            reference: input,
            filtered: input,
            input,
            dn,
            theta_on,
            theta_off,
            frozen_on: theta_on,
            frozen_off: theta_off,
            leak_per_us: 0.0,
            leak_per_dn_per_us: 0.0,
            noise_rate_per_us: 0.0,
            noise_on_share: 0.5,
            last_event_us: f64::NEG_INFINITY,
            next_noise_us: f64::INFINITY,
            next_hot_us: f64::INFINITY,
        }
    }

    /// Advances from the previous sample (time `t0`) to a new sample `u1` (log) / `dn1`
    /// at time `t1`, emitting the interval's events in time order.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn advance(
        &mut self,
        model: &PixelModel,
        t0: f64,
        t1: f64,
        u1: f32,
        dn1: f32,
        transition: Transition,
        rng: &mut Xoshiro256PlusPlus,
        sink: &mut EventSink,
    ) {
        let (u0, dn0) = (self.input, self.dn);
        self.input = u1;
        self.dn = dn1;
        match transition {
            Transition::Linear => self.piece(model, t0, t1, u0, u1, dn0, dn1, rng, sink),
            Transition::Hold => {
                self.piece(model, t0, t1, u0, u0, dn0, dn0, rng, sink);
                self.piece(model, t1, t1, u0, u1, dn0, dn1, rng, sink);
            }
        }
    }

    /// A piece of input linear from `(sa, ua)` to `(sb, ub)`: one segment without the
    /// filter, else the filter's sub-steps ([`Self::filtered_piece`]).
    #[allow(clippy::too_many_arguments)]
    fn piece(
        &mut self,
        model: &PixelModel,
        sa: f64,
        sb: f64,
        ua: f32,
        ub: f32,
        dna: f32,
        dnb: f32,
        rng: &mut Xoshiro256PlusPlus,
        sink: &mut EventSink,
    ) {
        let Some(cutoff) = model.cutoff_hz else {
            self.segment(model, sa, sb, ua, ub, dna, dnb, rng, sink);
            self.filtered = ub;
            return;
        };
        if sb - sa <= 0.0 {
            // the filter cannot move in no time: a step is seen over the next piece
            return;
        }
        let tolerance = model.substep_tolerance * self.theta_on.min(self.theta_off);
        let piece = FilteredPiece::new(model, cutoff, tolerance, (sa, sb), (ua, ub), (dna, dnb));
        self.filtered_piece(model, &piece, rng, sink);
    }

    /// A piece of input behind the filter, in adaptive sub-steps
    /// ([`FilteredPiece::substep_end`]): each advances the filter output and passes the
    /// straight line between its ends to [`Self::segment`].
    fn filtered_piece(
        &mut self,
        model: &PixelModel,
        piece: &FilteredPiece,
        rng: &mut Xoshiro256PlusPlus,
        sink: &mut EventSink,
    ) {
        let (ua, ub) = (piece.ua, piece.ub);
        let mut s = piece.sa;
        let mut y = self.filtered;
        while s < piece.sb {
            let (f_s, dn_s) = piece.at(s);
            let next = piece.substep_end(s, f_s, dn_s, y);
            let (f_next, dn_next) = piece.at(next);
            let tau_mid = bandwidth::tau_us(0.5 * (dn_s + dn_next), piece.cutoff);
            let y_next = bandwidth::advance(
                y,
                lerp(ua, ub, f_s),
                lerp(ua, ub, f_next),
                (next - s) as f32,
                tau_mid,
            );
            self.segment(model, s, next, y, y_next, dn_s, dn_next, rng, sink);
            y = y_next;
            s = next;
        }
        self.filtered = y;
    }

    /// A straight segment of the photoreceptor output from `(ta, ya)` to `(tb, yb)`, cut at
    /// shot-noise and hot-pixel events.
    #[allow(clippy::too_many_arguments)]
    fn segment(
        &mut self,
        model: &PixelModel,
        ta: f64,
        tb: f64,
        ya: f32,
        yb: f32,
        dna: f32,
        dnb: f32,
        rng: &mut Xoshiro256PlusPlus,
        sink: &mut EventSink,
    ) {
        let (mut t, mut y) = (ta, ya);
        let leak = self.leak_per_us + self.leak_per_dn_per_us * 0.5 * (dna + dnb);
        let at = |time: f64, a: f32, b: f32| {
            if tb > ta {
                lerp(a, b, ((time - ta) / (tb - ta)) as f32)
            } else {
                b
            }
        };
        loop {
            let interrupt = self.next_noise_us.min(self.next_hot_us);
            if interrupt >= tb {
                self.crossings(model, (t, tb), (y, yb), leak, rng, sink);
                return;
            }
            let ti = interrupt.max(t);
            let yi = at(ti, ya, yb);
            self.crossings(model, (t, ti), (y, yi), leak, rng, sink);
            if self.next_hot_us <= self.next_noise_us {
                sink.emit(ti, true);
                self.next_hot_us = ti + exponential_us(model.hot_rate_per_us, rng);
            } else {
                self.next_noise_us = ti + exponential_us(self.noise_rate_per_us, rng);
                let keep =
                    shot_noise::brightness_factor(at(ti, dna, dnb), model.noise_bright_factor);
                if rng.random::<f32>() < keep {
                    let on = rng.random::<f32>() < self.noise_on_share;
                    sink.emit(ti, on);
                    // a noise event resets the pixel to its current level
                    self.reference = yi;
                }
            }
            t = ti;
            y = yi;
        }
    }

    /// Threshold crossings of `d = y - reference` on a straight segment, with the leak's
    /// drift (`leak_per_us`, log units per microsecond) and the refractory period.
    fn crossings(
        &mut self,
        model: &PixelModel,
        (ta, tb): (f64, f64),
        (ya, yb): (f32, f32),
        leak_per_us: f32,
        rng: &mut Xoshiro256PlusPlus,
        sink: &mut EventSink,
    ) {
        let h = tb - ta;
        let drift = leak_per_us * h as f32;
        let mut da = ya - self.reference;
        let mut db = yb - (self.reference - drift);
        let mut now = ta;
        loop {
            let allowed =
                refractory::earliest_event_us(self.last_event_us, model.refractory_us).max(now);
            if allowed > tb {
                break;
            }
            let d_allowed = if h > 0.0 {
                lerp(da, db, ((allowed - ta) / h) as f32)
            } else {
                db
            };
            let (on, t_fire) = if d_allowed >= self.theta_on {
                (true, allowed)
            } else if d_allowed <= -self.theta_off {
                (false, allowed)
            } else if db >= self.theta_on {
                let f = (self.theta_on - d_allowed) / (db - d_allowed);
                (true, allowed + (tb - allowed) * f as f64)
            } else if db <= -self.theta_off {
                let f = (-self.theta_off - d_allowed) / (db - d_allowed);
                (false, allowed + (tb - allowed) * f as f64)
            } else {
                break;
            };
            sink.emit(t_fire, on);
            if on {
                da -= self.theta_on;
                db -= self.theta_on;
                self.reference += self.theta_on;
            } else {
                da += self.theta_off;
                db += self.theta_off;
                self.reference -= self.theta_off;
            }
            self.last_event_us = t_fire;
            now = t_fire;
            if let Some(sigma) = model.sigma_temporal {
                self.theta_on = mismatch::redraw(self.frozen_on, sigma, rng);
                self.theta_off = mismatch::redraw(self.frozen_off, sigma, rng);
            }
        }
        self.reference -= drift;
    }
}

/// A piece of input linear in time from `(sa, ua)` (intensity `dna`) to `(sb, ub)`
/// (`dnb`), of length `h > 0`, as the filter's sub-steps see it: its slope, the filter's
/// cutoff, the largest error allowed of a sub-step's straight line (log units) and the
/// shortest sub-step.
#[derive(Clone, Copy, Debug)]
struct FilteredPiece {
    sa: f64,
    sb: f64,
    h: f64,
    ua: f32,
    ub: f32,
    dna: f32,
    dnb: f32,
    slope: f32,
    cutoff: f32,
    tolerance: f32,
    min_step: f64,
}

impl FilteredPiece {
    /// The piece from `sa` to `sb` with the input `(ua, ub)` and intensity `(dna, dnb)` at
    /// its ends, sub-stepped to within `tolerance` (log units) in at most
    /// `model.max_substeps` sub-steps.
    fn new(
        model: &PixelModel,
        cutoff: f32,
        tolerance: f32,
        (sa, sb): (f64, f64),
        (ua, ub): (f32, f32),
        (dna, dnb): (f32, f32),
    ) -> Self {
        let h = sb - sa;
        Self {
            sa,
            sb,
            h,
            ua,
            ub,
            dna,
            dnb,
            slope: (ub - ua) / h as f32,
            cutoff,
            tolerance,
            min_step: h / model.max_substeps as f64,
        }
    }

    /// The fraction of the piece at time `s`, and the intensity there.
    #[inline(always)]
    fn at(&self, s: f64) -> (f32, f32) {
        let f = ((s - self.sa) / self.h) as f32;
        (f, lerp(self.dna, self.dnb, f))
    }

    /// The end of the sub-step that starts at time `s` (fraction `f_s` of the piece,
    /// intensity `dn_s`) with filter output `y`. Behind the filter y = U(s) + T e^(-s/tau):
    /// a line U tracking the input with lag b*tau plus a decaying transient T. A chord
    /// over a sub-step of length h misses the exponential by at most |T| (h/tau)^2 / 8, so
    /// h is chosen to keep that below `tolerance`; once the transient has decayed, one
    /// sub-step spans the rest of the piece.
    #[inline(always)]
    fn substep_end(&self, s: f64, f_s: f32, dn_s: f32, y: f32) -> f64 {
        let tau = bandwidth::tau_us(dn_s, self.cutoff);
        let transient = (y - (lerp(self.ua, self.ub, f_s) - self.slope * tau)).abs();
        let allowed = if transient > 0.0 {
            tau as f64 * (8.0 * self.tolerance as f64 / transient as f64).sqrt()
        } else {
            f64::INFINITY
        };
        if self.sb - s <= allowed.max(self.min_step) {
            self.sb
        } else {
            s + allowed.max(self.min_step)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn ideal() -> PixelModel {
        PixelModel {
            refractory_us: 0.0,
            cutoff_hz: None,
            sigma_temporal: None,
            noise_bright_factor: 0.25,
            hot_rate_per_us: 0.0,
            substep_tolerance: 0.002,
            max_substeps: 64,
            fast_path_effects: true,
            per_pixel_history: true,
            intensity_window: false,
        }
    }

    fn run(
        model: &PixelModel,
        pixel: &mut PixelState,
        samples: &[(f64, f32)],
        transition: Transition,
    ) -> Vec<Event> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut events = Vec::new();
        let mut t_prev = samples[0].0;
        for &(t, u) in &samples[1..] {
            let mut sink = EventSink {
                events: &mut events,
                origin_us: 0,
                x: 0,
                y: 0,
            };
            pixel.advance(
                model,
                t_prev,
                t,
                u,
                u.exp(),
                transition,
                &mut rng,
                &mut sink,
            );
            t_prev = t;
        }
        events
    }

    #[test]
    fn events_sit_at_interpolated_crossing_times_and_keep_the_remainder() {
        // log rises 0 -> 1 over 1000 us with theta 0.3: crossings at 300, 600, 900 us
        let mut p = PixelState::new(0.0, 1.0, 0.3, 0.3);
        let events = run(
            &ideal(),
            &mut p,
            &[(0.0, 0.0), (1000.0, 1.0)],
            Transition::Linear,
        );
        let times: Vec<i64> = events.iter().map(|e| e.t).collect();
        assert_eq!(times, vec![300, 600, 900]);
        assert!(events.iter().all(|e| e.on));
        assert!((p.reference - 0.9).abs() < 1e-6);
        // back down to 0.05: OFF crossings at 0.6, 0.3 (levels), i.e. 0.95 -> ... times
        let events = run(
            &ideal(),
            &mut p,
            &[(1000.0, 1.0), (2000.0, 0.05)],
            Transition::Linear,
        );
        assert_eq!(events.len(), 2);
        assert!(events.iter().all(|e| !e.on));
        // d = 0.9 - 0.3 = 0.6 reached when u = 0.6: (1 - 0.6) / 0.95 * 1000 us after 1000
        assert_eq!(events[0].t, 1000 + (0.4f64 / 0.95 * 1000.0).round() as i64);
    }

    #[test]
    fn refractory_delays_a_pending_change_instead_of_losing_it() {
        let model = PixelModel {
            refractory_us: 500.0,
            ..ideal()
        };
        let mut p = PixelState::new(0.0, 1.0, 0.3, 0.3);
        let events = run(
            &model,
            &mut p,
            &[(0.0, 0.0), (1000.0, 1.0), (2000.0, 1.0)],
            Transition::Linear,
        );
        let times: Vec<i64> = events.iter().map(|e| e.t).collect();
        // first crossing at 300 us, then blocked until 800 and 1300 (still beyond threshold)
        assert_eq!(times, vec![300, 800, 1300]);
    }

    #[test]
    fn a_display_step_fires_every_crossing_at_the_refresh() {
        let mut p = PixelState::new(0.0, 1.0, 0.3, 0.3);
        let events = run(
            &ideal(),
            &mut p,
            &[(0.0, 0.0), (1000.0, 1.0)],
            Transition::Hold,
        );
        assert_eq!(
            events.iter().map(|e| e.t).collect::<Vec<_>>(),
            vec![1000, 1000, 1000]
        );
    }

    #[test]
    fn leak_makes_on_events_at_the_leak_rate() {
        // drift 0.3 per 1e6 us: one ON event per second in a static scene
        let mut p = PixelState::new(1.0, 2.7, 0.3, 0.3);
        p.leak_per_us = 0.3e-6;
        let samples: Vec<(f64, f32)> = (0..=400).map(|k| (k as f64 * 10_000.0, 1.0)).collect();
        let events = run(&ideal(), &mut p, &samples, Transition::Linear);
        assert_eq!(events.len(), 4);
        assert!(events.iter().all(|e| e.on));
        // (f32 arithmetic on the drifting reference: within tens of microseconds)
        assert!((events[0].t - 1_000_000).abs() <= 50, "{}", events[0].t);
    }

    #[test]
    fn low_pass_delays_and_smooths_a_step() {
        // a step of 1.0 through the filter: crossings at -tau * ln(1 - k * 0.3)
        let model = PixelModel {
            cutoff_hz: Some(1.0),
            ..ideal()
        };
        let dn = 255.0; // cutoff 1 Hz * 275/275: tau = 1/(2 pi) s
        let tau = bandwidth::tau_us(dn, 1.0) as f64;
        let mut p = PixelState::new(0.0, dn, 0.3, 0.3);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut events = Vec::new();
        let mut sink = EventSink {
            events: &mut events,
            origin_us: 0,
            x: 0,
            y: 0,
        };
        p.dn = dn;
        p.advance(
            &model,
            0.0,
            0.0,
            1.0,
            dn,
            Transition::Hold,
            &mut rng,
            &mut sink,
        );
        p.advance(
            &model,
            0.0,
            10.0 * tau,
            1.0,
            dn,
            Transition::Linear,
            &mut rng,
            &mut sink,
        );
        assert_eq!(events.len(), 3);
        for (k, e) in events.iter().enumerate() {
            let expected = -tau * (1.0 - 0.3 * (k + 1) as f64).ln();
            assert!(
                (e.t as f64 - expected).abs() / expected < 0.01,
                "{} vs {expected}",
                e.t
            );
        }
    }

    #[test]
    fn shot_noise_fires_at_the_brightness_scaled_rate_and_resets() {
        let mut p = PixelState::new(90f32.ln(), 90.0, 0.4, 0.4);
        p.noise_rate_per_us = 1e-6 * 100.0; // 100 Hz candidates
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
        p.next_noise_us = exponential_us(p.noise_rate_per_us, &mut rng);
        let mut events = Vec::new();
        let u = 90f32.ln();
        for k in 0..1000 {
            let mut sink = EventSink {
                events: &mut events,
                origin_us: 0,
                x: 0,
                y: 0,
            };
            let (t0, t1) = (k as f64 * 10_000.0, (k + 1) as f64 * 10_000.0);
            p.advance(
                &ideal(),
                t0,
                t1,
                u,
                90.0,
                Transition::Linear,
                &mut rng,
                &mut sink,
            );
        }
        // 10 s at 100 Hz * brightness factor 0.7 = 700 events, Poisson sd 26
        assert!(
            (events.len() as f64 - 700.0).abs() < 4.0 * 26.5,
            "{}",
            events.len()
        );
        let on = events.iter().filter(|e| e.on).count() as f64 / events.len() as f64;
        assert!((on - 0.5).abs() < 0.06);
        assert!((p.reference - u).abs() < 1e-6);
    }
}
