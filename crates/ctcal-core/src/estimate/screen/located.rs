//! The screen as `estimate screen` uses it: registered ([`super::register`]), snapped to
//! the 1:1 mapping where a stimulus of the sensor's size registers within 0.35 px
//! of it wherever it was measured (the matched points; resampling an exact 1:1 mapping
//! would only blur it), and described for the results.

use super::register::{self, Inputs, Registration};
use crate::sim::DisplayParams;
use crate::sim::screen_geometry::{ScreenGeometry, ScreenWarp};
use serde_json::{Value, json};
use std::sync::Arc;

/// Corner displacement below which a same-size registration is taken as 1:1, pixels.
const SNAP_PX: f64 = 0.35;

/// Where the screen is, as the simulation uses it.
pub struct Located {
    pub registration: Registration,
    /// `None`: screen pixels on sensor pixels 1:1.
    pub warp: Option<Arc<ScreenWarp>>,
    /// Sensor pixels that see only the screen.
    pub on_screen: Vec<bool>,
    /// The registration's corner displacement from 1:1 when it was snapped to it.
    pub snapped: Option<f64>,
    /// How far the screen's corners moved when re-registered through the fitted display.
    pub refined_change_px: Option<f64>,
}

impl Located {
    pub fn new(registration: Registration) -> Self {
        let g = &registration.geometry;
        let identity = ScreenGeometry::identity(g.stimulus, g.sensor);
        let change = register::support_change(g, &identity, &registration.support);
        if g.stimulus == g.sensor && change < SNAP_PX {
            let on_screen = vec![true; g.sensor.0 * g.sensor.1];
            return Self {
                registration,
                warp: None,
                on_screen,
                snapped: Some(change),
                refined_change_px: None,
            };
        }
        Self {
            on_screen: registration.warp.on_screen(),
            warp: Some(registration.warp.clone()),
            registration,
            snapped: None,
            refined_change_px: None,
        }
    }

    /// Registers the screen through `display`.
    pub fn find(inputs: &Inputs, display: &DisplayParams) -> Result<Self, String> {
        register::register(inputs, display).map(Self::new)
    }

    /// The stimulus corners on the sensor (top-left, top-right, bottom-right, bottom-left).
    fn corners(&self) -> Vec<Option<[f64; 2]>> {
        let g = &self.registration.geometry;
        let (w, h) = (g.stimulus.0 as f64, g.stimulus.1 as f64);
        [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
            .into_iter()
            .map(|s| g.to_sensor(s).map(|p| [p.0, p.1]))
            .collect()
    }

    /// The `registration` object of the results.
    pub fn json(&self) -> Value {
        let r = &self.registration;
        json!({
            "homography": r.geometry.homography.0,
            "k1": r.geometry.k1,
            "k1_p_value": r.k1_p_value,
            "stimulus_size": [r.geometry.stimulus.0, r.geometry.stimulus.1],
            "corners_px": self.corners(),
            "error_rms_px": r.rms_px,
            "error_median_px": r.median_px,
            "points": r.points,
            "outliers": r.outliers,
            "coarse_score": r.coarse_score,
            "iterations": r.iterations,
            "on_screen_px": self.on_screen.iter().filter(|&&o| o).count(),
            "one_to_one": self.warp.is_none(),
            "refined_change_px": self.refined_change_px,
        })
    }

    /// The assumption that says how the screen was placed.
    pub fn assumption(&self) -> String {
        let r = &self.registration;
        let found = format!(
            "the screen was registered from the events of the stimulus ({} matched patches, {} left out as outliers): reprojection error {:.2} px RMS ({:.2} px median)",
            r.points, r.outliers, r.rms_px, r.median_px
        );
        match self.snapped {
            Some(change) => format!(
                "{found}; wherever it was measured it lies within {change:.2} px of the 1:1 mapping, so screen pixels are taken to map 1:1 onto sensor pixels"
            ),
            None => format!(
                "{found}; a homography{} maps the stimulus onto the sensor, the light of each sensor pixel is the screen's over its footprint, and the {} pixels that do not see only the screen are left out",
                if r.geometry.k1 != 0.0 {
                    format!(" with radial distortion k1 = {:.4}", r.geometry.k1)
                } else {
                    String::new()
                },
                self.on_screen.iter().filter(|&&o| !o).count()
            ),
        }
    }
}
