//! A stimulus seen through a [`ScreenWarp`], rendered once per display instead of once per
//! frame where it can be: most sensor pixels see a footprint of the screen that shows one
//! whole DN all over (inside a square of a checkerboard), and such a pixel's camera DN
//! depends only on that DN and the display. Each frame's footprints are classified once per
//! stimulus ([`Footprints`]); a display renders a uniform screen once per DN it meets
//! ([`Uniform`]), and a frame takes those values for its uniform footprints and sums only
//! the others ([`camera_dn`]). Every value is the sum [`ScreenWarp::apply`] makes, term by
//! term in the same order, so the camera DN keep their bits.

use super::display::DisplayModel;
use super::screen_geometry::ScreenWarp;

/// Marks a footprint that does not show one whole DN all over.
const MIXED: u16 = u16::MAX;

/// Per sensor pixel of one stimulus frame, the whole screen DN (0-255) every stimulus pixel
/// of its footprint shows, or [`MIXED`]; and the DN that occur.
#[derive(Clone, Debug)]
pub struct Footprints {
    dn: Vec<u16>,
    levels: Vec<u16>,
}

impl Footprints {
    /// The footprints of the screen frame `screen` (stimulus-sized screen DN) through `warp`.
    pub fn of(warp: &ScreenWarp, screen: &[f32]) -> Self {
        let pixels = warp.sensor_size().0 * warp.sensor_size().1;
        Self::with_levels((0..pixels).map(|p| uniform_dn(warp, p, screen)).collect())
    }

    /// The footprints of every frame of a stimulus, a DN kept only where the whole stimulus
    /// shows it uniformly to at least as many footprints as the sensor has pixels (its image
    /// costs a frame's rendering; a stimulus with soft edges shows many DN to a few
    /// footprints each).
    pub fn of_frames(warp: &ScreenWarp, frames: &[crate::events::Frame]) -> Vec<Self> {
        let pixels = warp.sensor_size().0 * warp.sensor_size().1;
        let mut all: Vec<Self> = frames
            .iter()
            .map(|f| {
                let screen: Vec<f32> = f.pixels.iter().map(|&v| v as f32).collect();
                Self::of(warp, &screen)
            })
            .collect();
        let mut uses = [0usize; 256];
        for &v in all.iter().flat_map(|f| &f.dn).filter(|&&v| v != MIXED) {
            uses[v as usize] += 1;
        }
        for frame in &mut all {
            let dn = std::mem::take(&mut frame.dn);
            let kept = |v: u16| v != MIXED && uses[v as usize] >= pixels;
            *frame = Self::with_levels(
                dn.into_iter()
                    .map(|v| if kept(v) { v } else { MIXED })
                    .collect(),
            );
        }
        all
    }

    /// Footprints `dn` with the DN that occur among them.
    fn with_levels(dn: Vec<u16>) -> Self {
        let mut seen = [false; 256];
        for &v in dn.iter().filter(|&&v| v != MIXED) {
            seen[v as usize] = true;
        }
        let levels = (0..256u16).filter(|&v| seen[v as usize]).collect();
        Self { dn, levels }
    }
}

/// The whole DN footprint `p` shows all over, or [`MIXED`] (an empty footprint too).
fn uniform_dn(warp: &ScreenWarp, p: usize, screen: &[f32]) -> u16 {
    let footprint = warp.footprint(p);
    let Some(&(first, _)) = footprint.first() else {
        return MIXED;
    };
    let dn = screen[first as usize];
    let whole = (0.0..=255.0).contains(&dn) && dn.fract() == 0.0;
    if whole && footprint.iter().all(|&(i, _)| screen[i as usize] == dn) {
        dn as u16
    } else {
        MIXED
    }
}

/// One display's sensor images (before blur) of a screen uniformly at each DN it was asked
/// for, made on demand (empty: not made yet).
#[derive(Clone, Debug, Default)]
pub struct Uniform {
    images: Vec<Vec<f32>>,
}

impl Uniform {
    /// Makes the images of the DN `levels` that are not made yet.
    fn make(&mut self, model: &DisplayModel, warp: &ScreenWarp, levels: &[u16]) {
        if self.images.is_empty() {
            self.images = vec![Vec::new(); 256];
        }
        let (w, h) = warp.sensor_size();
        let ambient = model.luminance_dn(0.0);
        for &dn in levels {
            let image = &mut self.images[dn as usize];
            if image.is_empty() {
                let lit = model.lit_value(dn as f32);
                *image = (0..w * h)
                    .map(|p| warp.sensor_value(p, |_| lit, ambient))
                    .collect();
            }
        }
    }
}

/// [`super::screen_geometry::camera_dn`] of the frame `screen` whose footprints are
/// `footprints`, the uniform ones from `uniform` (of this `model` and `warp` only): the same
/// values.
pub fn camera_dn(
    model: &DisplayModel,
    warp: &ScreenWarp,
    screen: &[f32],
    footprints: &Footprints,
    uniform: &mut Uniform,
) -> Vec<f32> {
    uniform.make(model, warp, &footprints.levels);
    let ambient = model.luminance_dn(0.0);
    let images = &uniform.images;
    let out = footprints
        .dn
        .iter()
        .enumerate()
        .map(|(p, &dn)| {
            if dn == MIXED {
                warp.sensor_value(p, |i| model.lit_value(screen[i]), ambient)
            } else {
                images[dn as usize][p]
            }
        })
        .collect();
    let (w, h) = warp.sensor_size();
    model.blur(out, w, h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::DisplayParams;
    use crate::sim::screen_geometry::{Homography, ScreenGeometry};

    /// Through a perspective warp with lens distortion, a checkerboard of three levels (and a
    /// frame with fractional and out-of-range DN) makes the same bits as the full rendering,
    /// under displays with and without blur.
    #[test]
    fn uniform_footprints_render_the_same_bits() {
        let geometry = ScreenGeometry {
            homography: Homography([[0.9, 0.1, 20.0], [-0.05, 0.8, 15.0], [0.001, 0.0004, 1.0]]),
            k1: 0.02,
            stimulus: (60, 40),
            sensor: (100, 80),
        };
        let warp = ScreenWarp::new(&geometry);
        let checker = |shift: usize| -> Vec<f32> {
            (0..60 * 40)
                .map(|i| {
                    let (x, y) = (i % 60 + shift, i / 60);
                    [0.0, 128.0, 255.0][(x / 7 + y / 7) % 3]
                })
                .collect()
        };
        let mut odd = checker(3);
        odd[..5].copy_from_slice(&[0.5, -3.0, 300.0, f32::NAN, 127.25]);
        let frames = [checker(0), checker(2), odd];
        for blur in [None, Some(0.3), Some(1.2)] {
            let model = DisplayModel::new(&DisplayParams {
                refresh_hz: 60.0,
                gamma: 2.1,
                black_level: 0.02,
                white_dn: 180.0,
                blur_px: blur,
                time_offset_s: None,
            });
            let mut uniform = Uniform::default();
            for screen in &frames {
                let footprints = Footprints::of(&warp, screen);
                let fast = camera_dn(&model, &warp, screen, &footprints, &mut uniform);
                let full = super::super::screen_geometry::camera_dn(&model, &warp, screen);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&full), "{blur:?}");
                let uniform = footprints.dn.iter().filter(|&&d| d != MIXED).count();
                assert!(uniform > 1000, "{uniform}");
            }
        }
    }
}
