//! The fit of a window, on the region of the sensor it can afford: a sensor with more
//! pixels than a 346x260 one, or a window with more events than [`FIT_EVENTS`], is fitted
//! on the rectangle where its events are densest ([`ctcal_core::region`]), the hot pixels
//! it names given in the sensor's coordinates and the region named in `assumptions`. The
//! `ctcal fit` command, the report and the Python package all fit through here.
//!
//! The events bound it because the fit's cost is its simulations (150-300 of them), each
//! as long as the recording's changes are many: coverage draw 7034 (a 240x180 texture
//! turning fast, 4.2 M events in 1.46 s) ran 296 simulations in 886 s on one thread, its
//! busiest 117x87 region (10,179 pixels) 145 in 60 s with every interval still covering
//! the truth; draw 6024 (3.9 M events) 50 s on 11,000 pixels against 120 s wall on two
//! threads whole.

use crate::estimate::{EstimateError, Progress};
use crate::frame_blocks::LIMIT_PIXELS;
use crate::hint::Hint;
use crate::selection::Roi;
use crate::window::Loaded;
use ctcal_core::events::Sensor;
use ctcal_core::fit::{FitInput, FitOptions, FitResult};

/// The most pixels a fit simulates unless told otherwise: a 346x260 sensor's (the frame
/// limit's sensor, [`LIMIT_PIXELS`]).
pub const FIT_PIXELS: usize = LIMIT_PIXELS;

/// The most events a fit re-simulates unless told otherwise (each of its simulations makes
/// about as many): a window with more is fitted on a region of its sensor of about this
/// many events. The shared v2e cases and IJRR chunks hold 20,000-540,000.
pub const FIT_EVENTS: usize = 1_000_000;

/// The smallest region either budget cuts to (64 x 48 pixels' worth, or the whole of a
/// smaller sensor): below it the optical flow's pyramid and the 8 x 8 px tiles of the
/// statistics have too little room.
pub const MIN_REGION_PIXELS: usize = 64 * 48;

/// What a fit simulates, and `estimate aps` reads: pixels and events (0: no limit); a
/// window beyond either is measured on its busiest region within them (at least
/// [`MIN_REGION_PIXELS`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FitBudget {
    pub max_pixels: usize,
    pub max_events: usize,
}

impl Default for FitBudget {
    fn default() -> Self {
        Self {
            max_pixels: FIT_PIXELS,
            max_events: FIT_EVENTS,
        }
    }
}

/// The region a fit (or `estimate aps`) of `loaded` measures on within `budget`, and the
/// pixel limit it was cut to, where it is cut; `None` where the whole sensor fits.
fn region_within(loaded: &Loaded, budget: FitBudget) -> Option<(Roi, usize)> {
    let pixels = loaded.sensor.pixels();
    let by_pixels = if budget.max_pixels == 0 {
        pixels
    } else {
        budget.max_pixels.max(MIN_REGION_PIXELS).min(pixels)
    };
    // `of` pixels scaled to hold the budget where they hold `events` above it
    let within_events = |of: usize, events: usize| -> usize {
        if budget.max_events == 0 || events <= budget.max_events {
            return of;
        }
        let share = budget.max_events as f64 / events as f64;
        ((of as f64 * share) as usize).max(MIN_REGION_PIXELS)
    };
    let busiest = |limit: usize| {
        let limit = at_least_the_floor(loaded.sensor, limit);
        ctcal_core::region::busiest_region(&loaded.events, loaded.sensor, &loaded.excluded, limit)
    };
    let mut limit = by_pixels.min(within_events(pixels, kept_events(loaded, None)));
    let mut roi = busiest(limit)?;
    // the densest region holds more than its share of the events: shrunk in proportion
    // (twice at most) while it holds over a tenth more than the budget
    for _ in 0..2 {
        let inside = kept_events(loaded, Some(roi));
        if inside * 10 <= budget.max_events * 11 {
            break;
        }
        let next = within_events(limit, inside);
        if next >= limit {
            break;
        }
        limit = next;
        roi = busiest(limit)?;
    }
    Some((roi, limit))
}

/// `limit` raised where the region of the sensor's aspect it gives would hold fewer than
/// [`MIN_REGION_PIXELS`] (a 346x260 sensor's region of 3,072 pixels rounds down to 63x48).
fn at_least_the_floor(sensor: Sensor, limit: usize) -> usize {
    let area = |limit| {
        ctcal_core::region::region_size(sensor, limit)
            .map_or(sensor.pixels(), |(w, h)| w as usize * h as usize)
    };
    let mut raised = limit;
    while raised < sensor.pixels() && area(raised) < MIN_REGION_PIXELS.min(sensor.pixels()) {
        raised += 1;
    }
    raised
}

/// The events of `loaded` at the pixels it keeps (a `--roi` or mask leaves the others
/// out), inside `roi` where given: what the budget counts.
fn kept_events(loaded: &Loaded, roi: Option<Roi>) -> usize {
    let width = loaded.sensor.width as usize;
    let e = &loaded.events;
    e.x.iter()
        .zip(&e.y)
        .filter(|&(&x, &y)| {
            let kept = loaded
                .excluded
                .get(y as usize * width + x as usize)
                .is_some_and(|&excluded| !excluded);
            kept && roi.is_none_or(|r| r.holds(x, y))
        })
        .count()
}

impl Loaded {
    /// The window as the fit reads it.
    pub fn fit_input(&self) -> FitInput<'_> {
        FitInput {
            sensor: self.sensor,
            events: &self.events,
            frames: &self.frames,
            excluded: &self.excluded,
            unread: &self.unread,
        }
    }

    /// The same window on the pixels of `roi` only, as a sensor of the region's size.
    pub fn within(&self, roi: Roi) -> Loaded {
        let selection = self.selection.within(roi);
        Loaded {
            recording: self.recording.clone(),
            sensor: roi.as_sensor(),
            sensor_source: self.sensor_source.clone(),
            events: self.events.within(roi),
            frames: self.frames.iter().map(|f| f.within(roi)).collect(),
            frames_available: self.frames_available,
            frame_limit: self.frame_limit,
            unread: self.unread.clone(),
            excluded: selection.excluded(),
            selection,
            notes: self.notes.clone(),
            recording_notes: self.recording_notes.clone(),
        }
    }
}

/// Where a measurement within a budget was made: the region it was cut to, and what
/// `assumptions` says of it (the region, or a budget the whole sensor could not be cut to).
pub(crate) struct Placed {
    pub roi: Option<Roi>,
    pub note: Option<String>,
}

/// `measure` of `loaded`, or of its busiest region within `budget` where `allowed` and it
/// has more pixels or events than that; with where it was measured.
pub(crate) fn on_region<T>(
    loaded: &Loaded,
    budget: FitBudget,
    (measured, allowed): (Measured, bool),
    measure: impl FnOnce(&Loaded) -> Result<T, EstimateError>,
) -> Result<(T, Placed), EstimateError> {
    let region = allowed.then(|| region_within(loaded, budget)).flatten();
    let cut = region.map(|(roi, _)| loaded.within(roi));
    let input = cut.as_ref().unwrap_or(loaded);
    let result = measure(input).map_err(|e| match region {
        Some((roi, _)) => on_region_refused(e, roi, input, budget),
        None => e,
    })?;
    let placed = match region {
        Some((roi, limit)) => {
            let inside = kept_events(input, None);
            Placed {
                roi: Some(roi),
                note: Some(region_note(measured, roi, loaded, budget, (limit, inside))),
            }
        }
        None => Placed {
            roi: None,
            note: allowed
                .then(|| unmet_budget(measured, loaded, budget))
                .flatten(),
        },
    };
    Ok((result, placed))
}

/// What `assumptions` says where the window holds over a tenth more events than the budget
/// and no region was cut (the sensor is no larger than the smallest region).
fn unmet_budget(measured: Measured, loaded: &Loaded, budget: FitBudget) -> Option<String> {
    let events = kept_events(loaded, None);
    (budget.max_events != 0 && events * 10 > budget.max_events * 11).then(|| {
        format!(
            "{} on the whole {} sensor although its {events} events are more than the budget of {}: a region must keep {MIN_REGION_PIXELS} pixels at least (below that the optical flow's pyramid and the statistics' 8 x 8 px tiles have too little room), which this sensor does not exceed",
            measured.verb(),
            loaded.sensor,
            budget.max_events
        )
    })
}

/// A refusal of the region the budget cut `input` to: the region and the budget named,
/// with a larger budget as a further fix (the whole sensor may hold what the region lacks).
fn on_region_refused(
    e: EstimateError,
    roi: Roi,
    input: &Loaded,
    budget: FitBudget,
) -> EstimateError {
    let limit = |n: usize, what: &str| match n {
        0 => format!("no limit of {what}"),
        n => format!("{n} {what}"),
    };
    let problem = format!(
        "{} (on the busiest region x {}..{}, y {}..{}: {} pixels and {} events, where the window is beyond the budget of {} and {})",
        e.problem,
        roi.x0,
        roi.x1,
        roi.y0,
        roi.y1,
        input.sensor.pixels(),
        kept_events(input, None),
        limit(budget.max_events, "events"),
        limit(budget.max_pixels, "pixels")
    );
    let fix = e
        .fix
        .words("; or, to measure more of the sensor, ")
        .act(Hint::Budget);
    EstimateError::new(problem, fix)
}

/// `ctcal fit` of `loaded` with `options`, on its busiest region within `budget` (at
/// most `max_pixels` pixels, about `max_events` events; 0: no limit) where it has frames
/// and more pixels or events than that; the window's notes and the recording's biases
/// added.
pub fn fit(
    loaded: &Loaded,
    options: &FitOptions,
    budget: FitBudget,
    progress: Progress,
) -> Result<FitResult, EstimateError> {
    // a bad option is the caller's, not the region's: refused before any cut
    options.check()?;
    let framed = loaded.frames.len() >= 2;
    let (mut result, placed) = on_region(loaded, budget, (Measured::Fit, framed), |input| {
        ctcal_core::fit::fit(&input.fit_input(), options, progress)
    })?;
    if let Some(roi) = placed.roi {
        for p in &mut result.hot_pixels_masked {
            (p.x, p.y) = (p.x + roi.x0, p.y + roi.y0);
        }
    }
    result.assumptions.extend(placed.note);
    result.assumptions.extend(loaded.notes.iter().cloned());
    result.biases = loaded.recording.biases();
    Ok(result)
}

/// What measures on a region: its verb, the cost the events bound, and what it measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Measured {
    Fit,
    Aps,
}

impl Measured {
    fn verb(self) -> &'static str {
        match self {
            Measured::Fit => "fitted",
            Measured::Aps => "measured by `estimate aps`",
        }
    }

    fn handles(self) -> &'static str {
        match self {
            Measured::Fit => "simulated",
            Measured::Aps => "measured",
        }
    }

    fn cost(self) -> &'static str {
        match self {
            Measured::Fit => "a fit re-simulates, each of its simulations making as many",
            Measured::Aps => {
                "`estimate aps` reads, its per-event timing and its re-simulations of the frames growing with them"
            }
        }
    }

    fn what(self) -> &'static str {
        match self {
            Measured::Fit => {
                "thresholds, mismatch and noise rates are per-pixel and measured there, their intervals from these pixels alone"
            }
            Measured::Aps => {
                "thresholds and their spread are per-pixel and measured there, their intervals from these pixels alone; the threshold maps are NaN outside it"
            }
        }
    }
}

/// What a measurement on a region says in `assumptions` (`limit` the pixels it was cut to,
/// `inside` the events in it).
fn region_note(
    measured: Measured,
    roi: Roi,
    loaded: &Loaded,
    budget: FitBudget,
    (limit, inside): (usize, usize),
) -> String {
    let (rw, rh) = (roi.width() as usize, roi.height() as usize);
    let pixels_bind = budget.max_pixels != 0 && limit >= budget.max_pixels;
    let why = if pixels_bind {
        format!(
            "at most {} are {}",
            budget.max_pixels.max(MIN_REGION_PIXELS),
            measured.handles()
        )
    } else {
        format!(
            "the window's {} events are more than the {} {}: {inside} events here",
            kept_events(loaded, None),
            budget.max_events,
            measured.cost()
        )
    };
    format!(
        "{} on the region x {}..{}, y {}..{} of the {} sensor ({} of {} pixels; {why}; the frames cut to it): the {rw}x{rh} rectangle, of the sensor's aspect, where the events are densest (each pixel counted up to the 99th percentile of the pixels' counts and to twice its busiest neighbour's, so that hot pixels do not choose it); {}; a variation of the thresholds across the sensor beyond the per-pixel mismatch, and hot pixels outside the region, are not seen",
        measured.verb(),
        roi.x0,
        roi.x1,
        roi.y0,
        roi.y1,
        loaded.sensor,
        rw * rh,
        loaded.sensor.pixels(),
        measured.what()
    )
}
