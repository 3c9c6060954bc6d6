//! The natural-image prior of `estimate eppps` without frames. Events alone cannot tell a
//! scene's log contrast from the threshold (scaling both leaves every event unchanged), so
//! the recording is compared with line scans through natural photographs: each gives one
//! threshold, and their spread is the prior's share of the interval. The images, their
//! sources and licences are in `calib/priors/natural/README.md`; the spread of natural-scene
//! contrast they stand for is documented there (Tolhurst, Tadmor & Chao 1992; Frazor &
//! Geisler 2006).
//!
//! The photographs are 8-bit sRGB; they are decoded to linear luminance and taken as
//! `ln(Y + 0.005)`: the 0.5 %-of-white floor stands for the flare and dark current that keep
//! a real pixel's log response finite in the deepest shadows of a scene.

use super::scans::LogImage;

/// The floor added to linear luminance (fraction of white) before the log.
pub const LUMINANCE_FLOOR: f32 = 0.005;

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

/// A prior image: its name and log luminance.
pub struct PriorImage {
    pub name: &'static str,
    pub log: LogImage,
}

/// The first `n` prior images (all when `n` is larger).
pub fn images(n: usize) -> Vec<PriorImage> {
    IMAGES
        .iter()
        .take(n)
        .map(|(name, bytes)| PriorImage {
            name,
            log: decode(bytes).expect("the embedded prior images are valid PGM (unit test)"),
        })
        .collect()
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

/// A binary 8-bit PGM (`P5`, maxval 255) as log luminance.
fn decode(bytes: &[u8]) -> Option<LogImage> {
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
    let table: Vec<f32> = (0..=255u8)
        .map(|v| (linear(v) + LUMINANCE_FLOOR).ln())
        .collect();
    Some(LogImage {
        width,
        height,
        data: pixels.iter().map(|&v| table[v as usize]).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_prior_image_decodes() {
        let all = images(usize::MAX);
        assert_eq!(all.len(), COUNT);
        for image in &all {
            assert_eq!(image.log.width, 256, "{}", image.name);
            assert!(image.log.height >= 150, "{}", image.name);
            let (lo, hi) = image
                .log
                .data
                .iter()
                .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
            // from near the floor up to at least half of white
            assert!(
                lo < -3.0 && hi > (0.5f32).ln(),
                "{}: {lo} .. {hi}",
                image.name
            );
        }
        assert!((linear(255) - 1.0).abs() < 1e-6 && linear(0) == 0.0);
    }
}
