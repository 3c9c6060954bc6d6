//! The natural-image prior of `estimate eppps` without frames. Events alone cannot tell a
//! scene's log contrast from the threshold (scaling both leaves every event unchanged), so
//! the recording is compared with line scans through natural photographs: each gives one
//! threshold, and their spread is the prior's share of the interval. The images, their
//! sources and licences are in `calib/priors/natural/README.md`; the spread of natural-scene
//! contrast they stand for is documented there (Tolhurst, Tadmor & Chao 1992; Frazor &
//! Geisler 2006). A recording whose frames show the scene but move too far between them for
//! the optical flow has its own frames scanned in the photographs' place
//! ([`frame_images`]): the contrast measured where the recording allows, the same prior of
//! the response's floor kept.
//!
//! The photographs are 8-bit sRGB; they are decoded to linear luminance `Y` and taken as
//! `ln(Y + f m)`, `m` the image's mean luminance: a DVS photoreceptor responds to the log of
//! its photocurrent plus its dark current (Lichtsteiner, Posch & Delbruck, JSSC 2008), and
//! the lens adds veiling glare in proportion to the scene's light, so the darkest parts of
//! a view never reach the log's steep end. How large that floor is against the scene's
//! light is not known without frames, and it moves the threshold read from a recording
//! as much as the choice of image does, so it is a prior of its own ([`FLOORS_OF_MEAN`]).

use super::scans::LogImage;
use crate::events::Frame;

/// The range of the floor `f` (as a fraction of the scene's mean luminance) the prior
/// spans, log-uniform: from veiling glare alone in a bright scene (glare indices of camera
/// lenses, ISO 9358, are 1-3 % of the scene's light) to a dark current as large as the
/// mean photocurrent in a dim one. Real DVS cameras measured in the log domain lie inside:
/// DVS-Voltmeter (Lin et al., ECCV 2022) calibrated `ln(DN + k2)` with k2 = 20 DN
/// (DAVIS346) and 23 DN (DVS240), 13-58 % of the mean at frame levels of 40-150 DN; ESIM's
/// default `ln(I + 0.001)` is the ideal end. v2e (Hu, Liu & Delbruck, CVPRW 2021) makes
/// the response linear below 20 DN to avoid the log's steep end, but through zero
/// (`I ln(20) / 20`), which is steeper than the log between 6.7 and 20 DN (up to 3x just
/// below 20): a scene that dim, made by v2e or by ctcal's simulator under v2e's
/// conventions, makes more events than any floor here allows, and its thresholds read low
/// (coverage draws 7023 at 11 DN and 8022 at 15 DN, `benches/coverage/eppps-scope-2026-12-04`).
pub const FLOOR_RANGE_OF_MEAN: (f32, f32) = (0.02, 1.0);

/// The floors the scans use: the 1/6, 1/2 and 5/6 quantiles of [`FLOOR_RANGE_OF_MEAN`]
/// (log-uniform), so that three points carry its centre and most of its spread.
pub const FLOORS_OF_MEAN: [f32; 3] = [0.0384, 0.1414, 0.5210];

/// [`FLOORS_OF_MEAN`] in percent, as the assumptions list them ("3.8 %, 14.1 %, 52.1 %").
pub fn floors_scanned() -> String {
    FLOORS_OF_MEAN
        .map(|f| format!("{:.1} %", 100.0 * f))
        .join(", ")
}

/// The prior images (binary PGM), embedded.
const IMAGES: [(&str, &[u8]); 6] = [
    (
        "astronaut",
        include_bytes!("../../../../../calib/priors/natural/astronaut.pgm"),
    ),
    (
        "china",
        include_bytes!("../../../../../calib/priors/natural/china.pgm"),
    ),
    (
        "flower",
        include_bytes!("../../../../../calib/priors/natural/flower.pgm"),
    ),
    (
        "grace_hopper",
        include_bytes!("../../../../../calib/priors/natural/grace_hopper.pgm"),
    ),
    (
        "rocket",
        include_bytes!("../../../../../calib/priors/natural/rocket.pgm"),
    ),
    (
        "coins",
        include_bytes!("../../../../../calib/priors/natural/coins.pgm"),
    ),
];

/// How many prior images there are.
pub const COUNT: usize = IMAGES.len();

/// How blurred the prior's images are scanned, a Gaussian's standard deviation in pixels
/// (in linear light, as optics blur): from the photographs' own sharpness to a scene whose
/// edges spread over several pixels. A sensor's optics and defocus blur its view, and a
/// scene may be smooth itself, by amounts a photograph does not carry; the recording's own
/// events tell how sharp its scene is (the share of an edge's events that follow within
/// a pixel of travel, [`super::scans::BURST_PX`]), and each image and floor is read at the
/// blur that gives the same share.
pub const BLUR_PX: [f32; 4] = [0.0, 1.0, 2.0, 4.0];

/// A prior image under one blur and floor: its name, the blur (px), the floor (fraction of
/// its mean luminance) and its log luminance.
pub struct PriorImage {
    pub name: &'static str,
    /// Which photograph (its place in the list): its blurs and floors share it.
    pub image: usize,
    pub blur_px: f32,
    pub floor_of_mean: f32,
    pub log: LogImage,
}

impl PriorImage {
    /// Which image, blur and floor this is.
    pub fn tag(&self) -> super::sharpness::PriorTag {
        super::sharpness::PriorTag {
            name: self.name,
            image: self.image,
            blur_px: self.blur_px,
            floor_of_mean: self.floor_of_mean,
        }
    }

    /// The image, blur and floor, as named in the estimate's report.
    pub fn label(&self) -> String {
        format!(
            "{} (blur {} px, floor {:.1} % of its mean)",
            self.name,
            self.blur_px,
            100.0 * self.floor_of_mean
        )
    }
}

/// The first `n` prior images (all when `n` is larger), each under every blur of
/// [`BLUR_PX`] and floor of [`FLOORS_OF_MEAN`] (image by image, blur by blur).
pub fn images(n: usize) -> Vec<PriorImage> {
    IMAGES
        .iter()
        .take(n)
        .enumerate()
        .flat_map(|(image, (name, bytes))| {
            let linear =
                decode(bytes).expect("the embedded prior images are valid PGM (unit test)");
            under_blurs_and_floors(name, image, linear)
        })
        .collect()
}

/// The names of the recording's frames read in the photographs' place.
const FRAME_NAMES: [&str; COUNT] = [
    "the recording's frame 1",
    "the recording's frame 2",
    "the recording's frame 3",
    "the recording's frame 4",
    "the recording's frame 5",
    "the recording's frame 6",
];

/// Up to `n` (at most [`COUNT`]) of the recording's own frames, evenly spread over it, in
/// the photographs' place, each under every blur and floor as a photograph is: where the
/// motion outruns the frames' optical flow their pixels cannot be followed, but each frame
/// still shows the scene's contrast, which is what the photographs stand in for. A frame's
/// DN is linear in the light up to the sensor's offset (`ln(DN + b)`), which the floors'
/// range holds as it holds a photograph's dark current and glare.
pub fn frame_images(frames: &[Frame], n: usize) -> Vec<PriorImage> {
    spread_over(frames, n)
        .enumerate()
        .flat_map(|(i, frame)| {
            let linear = LinearImage {
                width: frame.width as usize,
                height: frame.height as usize,
                data: frame.pixels.iter().map(|&v| v as f32).collect(),
            };
            under_blurs_and_floors(FRAME_NAMES[i], i, linear)
        })
        .collect()
}

/// Up to `n` (at most [`COUNT`]) of `frames`, evenly spread over them.
fn spread_over(frames: &[Frame], n: usize) -> impl Iterator<Item = &Frame> {
    let count = frames.len();
    let k = n.min(COUNT).min(count);
    (0..k).map(move |i| {
        &frames[if k > 1 {
            i * (count - 1) / (k - 1)
        } else {
            count / 2
        }]
    })
}

/// The median DN of the pixels of the frames [`frame_images`] reads that are reliable
/// intensities (neither near black, at most 3 DN, nor clipped, at least 254 DN, as
/// [`crate::estimate::frames::reliable_pair`]); `None` where none is.
pub fn median_reliable_dn(frames: &[Frame]) -> Option<f64> {
    let mut histogram = [0u64; 256];
    for frame in spread_over(frames, COUNT) {
        for &v in &frame.pixels {
            histogram[v as usize] += 1;
        }
    }
    // DN 4..=253: neither near black nor clipped
    crate::stats::robust::histogram_median(&histogram[4..254]).map(|k| k as f64 + 4.0)
}

/// `linear` (image number `image`, called `name`) under every blur of [`BLUR_PX`] and
/// floor of [`FLOORS_OF_MEAN`], blur by blur.
fn under_blurs_and_floors(
    name: &'static str,
    image: usize,
    linear: LinearImage,
) -> impl Iterator<Item = PriorImage> {
    BLUR_PX.into_iter().flat_map(move |blur_px| {
        let blurred = linear.blurred(blur_px);
        FLOORS_OF_MEAN.map(|floor_of_mean| PriorImage {
            name,
            image,
            blur_px,
            floor_of_mean,
            log: blurred.log_above(floor_of_mean),
        })
    })
}

/// The lowest and highest log-luminance standard deviation of the prior's photographs
/// over the floors scanned (unblurred): the contrast the prior stands for. A scene `k`
/// times less contrasty than these makes the events they make at a threshold `k` times
/// lower, so events alone read its threshold `k` times high.
pub fn log_std_range() -> (f64, f64) {
    static RANGE: std::sync::OnceLock<(f64, f64)> = std::sync::OnceLock::new();
    *RANGE.get_or_init(|| {
        IMAGES
            .iter()
            .filter_map(|(_, bytes)| decode(bytes))
            .flat_map(|linear| FLOORS_OF_MEAN.map(|floor| linear.log_above(floor).std()))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                (lo.min(s), hi.max(s))
            })
    })
}

/// A prior image in linear luminance (fraction of white), row-major.
struct LinearImage {
    width: usize,
    height: usize,
    data: Vec<f32>,
}

impl LinearImage {
    fn mean(&self) -> f32 {
        (self.data.iter().map(|&v| v as f64).sum::<f64>() / self.data.len().max(1) as f64) as f32
    }

    /// Blurred by a Gaussian of `sigma_px` (separable, edges held; 0: as it is).
    fn blurred(&self, sigma_px: f32) -> LinearImage {
        if sigma_px <= 0.0 {
            return LinearImage {
                width: self.width,
                height: self.height,
                data: self.data.clone(),
            };
        }
        let radius = (3.0 * sigma_px).ceil() as isize;
        let kernel: Vec<f32> = (-radius..=radius)
            .map(|k| (-0.5 * (k as f32 / sigma_px).powi(2)).exp())
            .collect();
        let total: f32 = kernel.iter().sum();
        let (w, h) = (self.width as isize, self.height as isize);
        let pass = |data: &[f32], step: (isize, isize)| -> Vec<f32> {
            (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| {
                    kernel
                        .iter()
                        .zip(-radius..=radius)
                        .map(|(weight, k)| {
                            let (sx, sy) = (
                                (x + k * step.0).clamp(0, w - 1),
                                (y + k * step.1).clamp(0, h - 1),
                            );
                            weight * data[(sy * w + sx) as usize]
                        })
                        .sum::<f32>()
                        / total
                })
                .collect()
        };
        let rows = pass(&self.data, (1, 0));
        LinearImage {
            width: self.width,
            height: self.height,
            data: pass(&rows, (0, 1)),
        }
    }

    /// `ln(Y + floor_of_mean * mean)`.
    fn log_above(&self, floor_of_mean: f32) -> LogImage {
        let floor = floor_of_mean * self.mean();
        LogImage {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(|&y| (y + floor).ln()).collect(),
        }
    }
}

/// sRGB-encoded 8-bit value to linear luminance (IEC 61966-2-1).
fn linear(v: u8) -> f32 {
    let v = v as f32 / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// A binary 8-bit PGM (`P5`, maxval 255) as linear luminance.
fn decode(bytes: &[u8]) -> Option<LinearImage> {
    // header: magic, width, height, maxval, each after whitespace (no comments in ours)
    let mut fields = Vec::new();
    let mut i = 0;
    while fields.len() < 4 {
        while bytes.get(i)?.is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while !bytes.get(i)?.is_ascii_whitespace() {
            i += 1;
        }
        fields.push(std::str::from_utf8(&bytes[start..i]).ok()?);
    }
    let (width, height): (usize, usize) = (fields[1].parse().ok()?, fields[2].parse().ok()?);
    if fields[0] != "P5" || fields[3] != "255" {
        return None;
    }
    let pixels = bytes.get(i + 1..i + 1 + width * height)?;
    let table: Vec<f32> = (0..=255u8).map(linear).collect();
    Some(LinearImage {
        width,
        height,
        data: pixels.iter().map(|&v| table[v as usize]).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(t: i64, pixels: Vec<u8>) -> Frame {
        Frame {
            t,
            width: 4,
            height: 2,
            pixels,
            exposure_us: None,
        }
    }

    #[test]
    fn the_recordings_frames_are_read_evenly_spread_as_photographs_are() {
        // ten frames, each one DN: the six read are 0, 1, 3, 5, 7 and 9 (i * 9 / 5)
        let frames: Vec<Frame> = (0..10).map(|k| frame(k, vec![10 + k as u8; 8])).collect();
        let images = frame_images(&frames, 6);
        assert_eq!(images.len(), 6 * BLUR_PX.len() * FLOORS_OF_MEAN.len());
        let levels: Vec<f32> = images
            .iter()
            .filter(|i| i.blur_px == 0.0 && i.floor_of_mean == FLOORS_OF_MEAN[0])
            .map(|i| (i.log.data[0].exp() / (1.0 + FLOORS_OF_MEAN[0])).round())
            .collect();
        assert_eq!(levels, [10.0, 11.0, 13.0, 15.0, 17.0, 19.0]);
        assert_eq!(images[0].name, "the recording's frame 1");
        // fewer frames than images asked for: each once; one frame: that one
        assert_eq!(frame_images(&frames[..2], 6).len(), 2 * 12);
        assert_eq!(
            frame_images(&frames[..1], 6)[0].log.data[0],
            images[0].log.data[0]
        );
        assert!(frame_images(&[], 6).is_empty());
    }

    #[test]
    fn the_frames_median_leaves_out_black_and_clipped_pixels() {
        // 0, 2, 3 (near black) and 255 (clipped) left out: the median of 5, 7, 9, 200
        let frames = [frame(0, vec![0, 2, 3, 5, 7, 9, 200, 255])];
        assert_eq!(median_reliable_dn(&frames), Some(7.0));
        assert_eq!(
            median_reliable_dn(&[frame(0, vec![0, 1, 2, 3, 254, 255, 255, 0])]),
            None
        );
    }

    #[test]
    fn every_prior_image_decodes_under_every_blur_and_floor() {
        let all = images(usize::MAX);
        assert_eq!(all.len(), COUNT * BLUR_PX.len() * FLOORS_OF_MEAN.len());
        for image in &all {
            assert_eq!(image.log.width, 256, "{}", image.name);
            assert!(image.log.height >= 150, "{}", image.name);
            let linear = decode(IMAGES.iter().find(|i| i.0 == image.name).unwrap().1)
                .unwrap()
                .blurred(image.blur_px);
            let floor = image.floor_of_mean * linear.mean();
            let (lo, hi) = image
                .log
                .data
                .iter()
                .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
            if image.blur_px > 0.0 {
                continue;
            }
            // the darkest pixels reach down to the floor (their own light is at most as
            // large as it), the brightest above half of white
            assert!(
                lo < floor.ln() + 2f32.ln(),
                "{}: {lo} vs {}",
                image.label(),
                floor.ln()
            );
            assert!(hi > (0.5f32).ln(), "{}: {hi}", image.label());
        }
        assert!((linear(255) - 1.0).abs() < 1e-6 && linear(0) == 0.0);
    }

    #[test]
    fn the_floors_are_the_quantiles_of_their_log_uniform_range() {
        let (a, b) = FLOOR_RANGE_OF_MEAN;
        for (floor, q) in FLOORS_OF_MEAN.iter().zip([1.0f32 / 6.0, 0.5, 5.0 / 6.0]) {
            let expected = (a.ln() + q * (b.ln() - a.ln())).exp();
            assert!(
                (floor / expected - 1.0).abs() < 1e-3,
                "{floor} vs {expected}"
            );
        }
    }

    #[test]
    fn the_prior_s_contrast_spans_its_photographs_over_the_floors() {
        // computed independently with NumPy from the PGMs (sRGB decoded, ln(Y + f mean)):
        // rocket at the highest floor 0.497, grace_hopper at the lowest 1.580
        let (lo, hi) = log_std_range();
        assert!((lo - 0.497).abs() < 0.005, "{lo}");
        assert!((hi - 1.580).abs() < 0.005, "{hi}");
    }

    #[test]
    fn a_higher_floor_or_a_wider_blur_lowers_the_log_contrast_of_the_same_image() {
        // the mean absolute difference of neighbouring log values: what the scans count
        let contrast = |log: &LogImage| {
            let mut sum = 0.0f64;
            for row in log.data.chunks(log.width) {
                sum += row
                    .windows(2)
                    .map(|w| (w[1] - w[0]).abs() as f64)
                    .sum::<f64>();
            }
            sum / (log.height * (log.width - 1)) as f64
        };
        let all = images(1);
        // each step along the floors (or the blurs) of the images `keep` picks lowers it
        let falling = |keep: &dyn Fn(&PriorImage) -> bool| {
            let values: Vec<f64> = all
                .iter()
                .filter(|i| keep(i))
                .map(|i| contrast(&i.log))
                .collect();
            assert!(values.windows(2).all(|w| w[1] < 0.9 * w[0]), "{values:?}");
            values.len()
        };
        for blur in BLUR_PX {
            assert_eq!(falling(&|i| i.blur_px == blur), FLOORS_OF_MEAN.len());
        }
        // and a wider blur lowers it at any floor, the light's mean kept
        for floor in FLOORS_OF_MEAN {
            falling(&|i| i.floor_of_mean == floor);
        }
        let linear = decode(IMAGES[0].1).unwrap();
        for blur in BLUR_PX {
            let m = linear.blurred(blur).mean();
            assert!((m / linear.mean() - 1.0).abs() < 0.01, "{blur}: {m}");
        }
    }
}
