//! Reading a recording for the estimators and the fit (`ctcal::window`), with its warnings
//! and reading progress on stderr and its errors worded with the command's flags.

use super::{BadInput, Global, InputArgs, SelectionArgs, progress_bar, warn};
use ctcal::window::{LoadError, LoadObserver};
pub use ctcal::window::{Loaded, Window};
use std::cell::OnceCell;

/// Checks `--start`/`--end` as `stats` does.
pub fn check_window(start: Option<f64>, end: Option<f64>) -> Result<(), BadInput> {
    for (name, value) in [("--start", start), ("--end", end)] {
        if let Some(v) = value
            && !(v.is_finite() && (0.0..=1e12).contains(&v))
        {
            return Err(BadInput(format!(
                "{name} {v} must be a number of seconds from the first event, between 0 and 1e12\n  fix: give {name} in seconds from the first event"
            )));
        }
    }
    if let (Some(s), Some(e)) = (start, end)
        && e <= s
    {
        return Err(BadInput(format!(
            "--end {e} is not after --start {s}\n  fix: give an --end after --start (both in seconds from the first event)"
        )));
    }
    Ok(())
}

/// A load's error with the fix in the command's flags: an input error as it is (its exit
/// code follows it), the others as bad input.
pub fn hinted(error: LoadError) -> anyhow::Error {
    let text = match error {
        LoadError::Input(e) => return e.into(),
        LoadError::Window(text) => text,
        LoadError::TooManyEvents { path, max } => format!(
            "{}: more than {max} events in the selected time window\n  fix: select a shorter part of the recording with --start/--end (seconds from the first event)",
            path.display()
        ),
        LoadError::FrameSize {
            path,
            frames: (w, h),
            sensor,
        } => format!(
            "{}: the frames are {w}x{h} but the sensor is {sensor}\n  fix: pass --sensor {w}x{h} if the frames show the whole sensor",
            path.display()
        ),
        LoadError::OverBudget {
            path,
            sensor,
            reach: (max_x, max_y),
        } => format!(
            "{}: the {sensor} sensor has {} pixels; the estimators keep several maps of one value per pixel, more than the budget of {} pixels\n  fix: pass --sensor WxH with the camera's real size (the events reach x = {max_x}, y = {max_y}), or --force to use the memory anyway",
            path.display(),
            sensor.pixels(),
            ctcal::stats::PIXEL_BUDGET,
        ),
        LoadError::SelectionOverBudget { path, sensor } => format!(
            "{}: a pixel selection (--roi, --mask, --exclude-hot-pixels) of the {sensor} sensor keeps one flag per pixel ({} pixels), more than the budget of {} pixels\n  fix: pass --sensor WxH with the camera's real size, or --force to use the memory anyway",
            path.display(),
            sensor.pixels(),
            ctcal::stats::PIXEL_BUDGET,
        ),
        LoadError::Selection { path, problem, fix } => format!(
            "{}: {}",
            path.display(),
            super::flags::render(&problem.fixed_by(&fix))
        ),
    };
    BadInput(text).into()
}

/// Warnings on stderr and a progress bar over the events read.
struct Stderr<'a> {
    global: &'a Global,
    bar: OnceCell<indicatif::ProgressBar>,
}

impl LoadObserver for Stderr<'_> {
    fn warn(&self, message: &ctcal::hint::Text) {
        warn(self.global, &super::flags::render(message));
    }
    fn reading(&self, done: u64, total: u64) {
        self.bar
            .get_or_init(|| progress_bar(self.global, total, "reading events"))
            .set_position(done);
    }
}

/// Reads `input` for an estimate, and the pixels `selection` keeps.
pub fn load(
    input: &InputArgs,
    window: &Window,
    selection: &SelectionArgs,
    global: &Global,
) -> anyhow::Result<Loaded> {
    check_window(window.start_s, window.end_s)?;
    let observer = Stderr {
        global,
        bar: OnceCell::new(),
    };
    let loaded = ctcal::window::load(
        &input.input,
        &input.open_options(),
        window,
        &selection.spec(),
        global.force,
        &observer,
    );
    if let Some(bar) = observer.bar.get() {
        bar.finish_and_clear();
    }
    loaded.map_err(hinted)
}
