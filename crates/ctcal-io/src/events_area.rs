//! The sensor a window's per-pixel work covers when a file states a sensor far larger than
//! its events reach. The estimators and the fit keep several maps of one value per pixel,
//! so a header that claims 4096x4096 over a 1280x720 camera's events would size them (and
//! divide per-pixel fractions such as the hot-pixel share) by the claim: memory and results
//! must follow the events, not what a header says. Where the stated sensor has more than
//! [`MAX_STATED_OVER_REACH`] times the pixels of the events' reach (the rectangle from
//! pixel 0 to the largest x and y, and a region's), the window works on that reach and says
//! so. A size the caller gave, a size the grey frames fix, a mask of the stated size and a
//! size inferred from the events (a known sensor's) are kept as they are.

use crate::events::Sensor;
use crate::hint::{Hint, Text};
use crate::recording::{FRAMES_SENSOR, GIVEN_SENSOR, ResolvedSensor};
use std::path::Path;

/// How many times the events' reach a stated sensor may hold before the window works on
/// the reach: a hardware region or a lens that leaves part of a real sensor dark stays
/// under it (a quarter of the sensor reached from pixel 0 across and down), a size
/// mistyped or invented by a converter does not.
pub const MAX_STATED_OVER_REACH: usize = 4;

/// The events' reach in place of `resolved` where `resolved` is a stated size over
/// [`MAX_STATED_OVER_REACH`] times it; `None` where the stated size stands. `fixed`: the
/// frames or a mask fix the size.
pub fn reach_instead(
    resolved: &ResolvedSensor,
    reach: Option<(u16, u16)>,
    fixed: bool,
    path: &Path,
) -> Option<(ResolvedSensor, String)> {
    let (max_x, max_y) = reach?;
    // a size inferred from the events is a known sensor's, already bounded by them
    let inferred = resolved.warning.is_some();
    if fixed || inferred || resolved.source == GIVEN_SENSOR || resolved.source == FRAMES_SENSOR {
        return None;
    }
    let area = Sensor::new(max_x.saturating_add(1), max_y.saturating_add(1));
    let stated = resolved.sensor;
    if stated.pixels() <= MAX_STATED_OVER_REACH * area.pixels() {
        return None;
    }
    let note = format!(
        "sensor: {stated} stated ({}), but the events reach only {area} (x < {}, y < {}); the per-pixel maps and every per-pixel share cover those {} pixels, not the {} stated (a stated size over {MAX_STATED_OVER_REACH} times the events' reach)",
        resolved.source,
        area.width,
        area.height,
        area.pixels(),
        stated.pixels(),
    );
    let warning = Text::from(format!("{}: {note}; ", path.display()))
        .act(Hint::Sensor(None))
        .words(" with the camera's real size if the events do not reach all of it");
    Some((
        ResolvedSensor {
            sensor: area,
            source: format!("the events' reach ({stated} stated: {})", resolved.source),
            warning: Some(warning),
        },
        note,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stated(w: u16, h: u16, source: &str) -> ResolvedSensor {
        ResolvedSensor {
            sensor: Sensor::new(w, h),
            source: source.into(),
            warning: None,
        }
    }

    #[test]
    fn a_claim_over_four_times_the_reach_gives_way_to_the_reach() {
        let path = Path::new("g.raw");
        let header = stated(4096, 4096, "% geometry");
        let (area, note) = reach_instead(&header, Some((1279, 719)), false, path).unwrap();
        assert_eq!(area.sensor, Sensor::new(1280, 720));
        assert!(
            note.contains("921600 pixels, not the 16777216 stated"),
            "{note}"
        );
        // a quarter of the sensor reached stands (a hardware region, a dark corner)
        let evk4 = stated(1280, 720, "% geometry");
        assert!(reach_instead(&evk4, Some((639, 359)), false, path).is_none());
        // just under a quarter does not
        assert!(reach_instead(&evk4, Some((638, 359)), false, path).is_some());
        // a size given, the frames' size or a mask's stand whatever the events reach
        for source in [GIVEN_SENSOR, FRAMES_SENSOR] {
            assert!(
                reach_instead(&stated(4096, 4096, source), Some((9, 9)), false, path).is_none()
            );
        }
        assert!(reach_instead(&header, Some((9, 9)), true, path).is_none());
        assert!(reach_instead(&header, None, false, path).is_none());
        let inferred = ResolvedSensor {
            warning: Some(Text::from("the file does not state the sensor size")),
            ..stated(1280, 720, "inferred: EVK4")
        };
        assert!(reach_instead(&inferred, Some((9, 9)), false, path).is_none());
    }
}
