//! Reading the natural-image prior at the recording's own sharpness. Events alone do not
//! fix a scene's contrast, but they do tell how sharp it is: an edge fires its events
//! within a pixel of travel, a smooth gradient one per threshold's worth of slope. The share
//! of a pixel's consecutive events of one polarity that follow within
//! [`super::scans::BURST_PX`] of travel is measured on the recording
//! ([`super::recording::BurstShare`]) and on every prior image under every blur of
//! [`super::prior::BLUR_PX`] at the threshold that image reads; each image and floor is
//! then read at the blur that gives the recording's share (interpolated between the two
//! blurs around it), so that a smooth scene is compared with smooth images and a sharp one
//! with sharp ones. Blur lowers an image's events per pixel of travel at a threshold by
//! up to a factor 3 (`prior::BLUR_PX` 0 -> 4 px), which the fixed prior otherwise read as
//! a higher threshold.
//!
//! What the share cannot tell apart: a slow photoreceptor (a dim scene) or a refractory
//! period spreads an edge's events in time, which reads as blur; where they do, the prior
//! is read at more blur than the optics have, and the threshold lower (said in the
//! assumptions).

use super::Calibration;
use super::prior::BLUR_PX;
use super::recording::RecordingRates;
use super::scans::{BURST_PX, Side, burst_fraction_at, invert};

/// Which prior image, blur and floor a calibration scanned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PriorTag {
    pub name: &'static str,
    pub image: usize,
    pub blur_px: f32,
    pub floor_of_mean: f32,
}

/// Where the recording's share lies against one image and floor's blurs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// Between two blurs, or at one.
    Inside,
    /// Burstier than the image at no blur (a sharper scene than the photograph): read at
    /// no blur.
    Sharper,
    /// Smoother than the image at the widest blur: read at it.
    Smoother,
}

/// One image and floor read at the recording's sharpness: calibrations `a` and `b` (two
/// blurs of it, or one twice), mixed with weight `weight_a` on `a`, at the blur that
/// stands for (px).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Selection {
    pub a: usize,
    pub b: usize,
    pub weight_a: f64,
    pub blur_px: f64,
    pub reach: Reach,
}

/// The burst share each calibration makes at the threshold it reads the recording at (the
/// geometric mean of its ON and OFF thresholds), NaN where it reads none.
fn shares(calibrations: &[Calibration], rates: &RecordingRates) -> Vec<f64> {
    calibrations
        .iter()
        .map(|c| {
            let on = invert(&c.curve, Side::On, rates.on_per_px).value();
            let off = invert(&c.curve, Side::Off, rates.off_per_px).value();
            match (on, off) {
                (Some(on), Some(off)) => burst_fraction_at(&c.curve, (on * off).sqrt()),
                _ => f64::NAN,
            }
        })
        .collect()
}

/// For every image and floor among `calibrations` (each blur of it a calibration, in
/// `tags`), the blurs whose burst shares bracket the recording's `share`.
pub(super) fn select(
    calibrations: &[Calibration],
    tags: &[PriorTag],
    rates: &RecordingRates,
    share: f64,
) -> Vec<Selection> {
    let at = shares(calibrations, rates);
    let mut groups: Vec<(usize, u32)> = tags
        .iter()
        .map(|t| (t.image, t.floor_of_mean.to_bits()))
        .collect();
    groups.sort_unstable();
    groups.dedup();
    groups
        .into_iter()
        .map(|(image, floor)| {
            let mut members: Vec<usize> = (0..tags.len())
                .filter(|&k| tags[k].image == image && tags[k].floor_of_mean.to_bits() == floor)
                .collect();
            members.sort_by(|&x, &y| tags[x].blur_px.total_cmp(&tags[y].blur_px));
            bracket(&members, &at, tags, share)
        })
        .collect()
}

/// The two neighbouring blurs of `members` (sharpest first) whose shares lie on either side
/// of `share`, the weight of the sharper from where `share` lies between them; members that
/// read no threshold are passed over.
fn bracket(members: &[usize], at: &[f64], tags: &[PriorTag], share: f64) -> Selection {
    let usable: Vec<usize> = members
        .iter()
        .copied()
        .filter(|&k| at[k].is_finite())
        .collect();
    let single = |k: usize, reach| Selection {
        a: k,
        b: k,
        weight_a: 1.0,
        blur_px: tags[k].blur_px as f64,
        reach,
    };
    let (Some(&sharpest), Some(&smoothest)) = (usable.first(), usable.last()) else {
        // no blur reads a threshold: the sharpest stands (it fails as it would alone)
        return single(members[0], Reach::Inside);
    };
    if share >= at[sharpest] {
        return single(sharpest, Reach::Sharper);
    }
    for pair in usable.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if at[a] >= share && share >= at[b] {
            let weight_a = if at[a] > at[b] {
                (share - at[b]) / (at[a] - at[b])
            } else {
                1.0
            };
            return Selection {
                a,
                b,
                weight_a,
                blur_px: weight_a * tags[a].blur_px as f64
                    + (1.0 - weight_a) * tags[b].blur_px as f64,
                reach: Reach::Inside,
            };
        }
    }
    // shares that do not fall monotonically with blur and miss the recording's, or a
    // smoother recording than the widest blur
    if share <= at[smoothest] {
        single(smoothest, Reach::Smoother)
    } else {
        let nearest = *usable
            .iter()
            .min_by(|&&x, &&y| (at[x] - share).abs().total_cmp(&(at[y] - share).abs()))
            .expect("usable is not empty");
        single(nearest, Reach::Inside)
    }
}

/// Images that must reproduce the recording's burst share for the others to be left out:
/// half of the prior's, so that the spread between those left is still measured (their
/// prediction interval widens the spread 2.5x for three images, see `prediction_scale`).
pub const MIN_MATCHING_IMAGES: usize = 3;

/// The prior read at a recording's sharpness: the recording's burst share, every image and
/// floor's selection, and those kept.
#[derive(Clone, Debug)]
pub struct Reading {
    pub share: f64,
    pub pairs: usize,
    pub all: Vec<Selection>,
    pub kept: Vec<Selection>,
}

impl Reading {
    /// Approximate Bayesian computation by rejection (Beaumont, Zhang & Balding, Genetics
    /// 2002): blur is a nuisance parameter of the prior and the burst share a summary
    /// statistic; an image and floor that make the recording's share at no blur scanned
    /// cannot have made the recording and is left out, as long as at least
    /// [`MIN_MATCHING_IMAGES`] images make it (otherwise every one stays, at the blur
    /// nearest, and [`Reading::describe`] says which way that reads).
    pub fn new(share: f64, pairs: usize, all: Vec<Selection>, tags: &[PriorTag]) -> Self {
        let inside: Vec<Selection> = all
            .iter()
            .copied()
            .filter(|s| s.reach == Reach::Inside)
            .collect();
        let mut images: Vec<usize> = inside.iter().map(|s| tags[s.a].image).collect();
        images.sort_unstable();
        images.dedup();
        let kept = if images.len() >= MIN_MATCHING_IMAGES {
            inside
        } else {
            all.clone()
        };
        Reading {
            share,
            pairs,
            all,
            kept,
        }
    }

    /// What the reading did, for `assumptions`: the recording's burst share, the blurs
    /// chosen (median, range), and the images and floors beyond the blurs scanned.
    pub fn describe(&self) -> String {
        let mut blurs: Vec<f64> = self.kept.iter().map(|s| s.blur_px).collect();
        blurs.sort_by(f64::total_cmp);
        let count = |reach| self.all.iter().filter(|s| s.reach == reach).count();
        let (sharper, smoother) = (count(Reach::Sharper), count(Reach::Smoother));
        let n = self.all.len();
        let mut text = format!(
            "prior read at the recording's sharpness: {:.1} % of its {} consecutive same-polarity event pairs at a pixel follow within {BURST_PX:.0} px of travel (an edge's burst); each image and floor is read at the blur (Gaussian, linear light, 0-{:.0} px) whose scans give that share at their threshold: median {:.1} px, range {:.1}-{:.1} px",
            100.0 * self.share,
            self.pairs,
            BLUR_PX[BLUR_PX.len() - 1],
            blurs.get(blurs.len() / 2).copied().unwrap_or(f64::NAN),
            blurs.first().copied().unwrap_or(f64::NAN),
            blurs.last().copied().unwrap_or(f64::NAN),
        );
        if self.kept.len() < n {
            text += &format!(
                "; {} of {n} make that share at no blur scanned ({sharper} smoother than the recording even unblurred, {smoother} burstier even at the widest blur) and are left out (rejection: they cannot have made this recording)",
                n - self.kept.len()
            );
        } else {
            if sharper > 0 {
                text += &format!(
                    "; {sharper} of {n} are smoother than the recording even unblurred, and too few images match to leave them out: read unblurred, a sharper scene than these images, which makes more events, so they read it low"
                );
            }
            if smoother > 0 {
                text += &format!(
                    "; {smoother} of {n} are burstier than the recording even at the widest blur, and too few images match to leave them out: read there, a smoother scene, which makes fewer events, so they read it high"
                );
            }
        }
        text + "; a slow photoreceptor (dim light) or a refractory period spreads an edge's events in time like blur, and reads the threshold low"
    }
}

/// The calibrations the selections read, each mixed from its two blurs: events per pixel
/// of travel (and burst shares) weighted between the two curves, point by point.
pub(super) fn mix(
    calibrations: &[Calibration],
    tags: &[PriorTag],
    selections: &[Selection],
) -> Vec<Calibration> {
    selections
        .iter()
        .map(|s| {
            let (a, b) = (&calibrations[s.a], &calibrations[s.b]);
            let w = s.weight_a;
            let blend = |x: f64, y: f64| w * x + (1.0 - w) * y;
            let curve = a
                .curve
                .iter()
                .zip(&b.curve)
                .map(|(p, q)| {
                    let mut m = *p;
                    m.on_per_px = blend(p.on_per_px, q.on_per_px);
                    m.off_per_px = blend(p.off_per_px, q.off_per_px);
                    m.active_fraction = blend(p.active_fraction, q.active_fraction);
                    m.events_per_scan = blend(p.events_per_scan, q.events_per_scan);
                    m.burst_fraction = blend(p.burst_fraction, q.burst_fraction);
                    m
                })
                .collect();
            let tag = tags[s.a];
            Calibration {
                image: Some(tag.image),
                name: format!(
                    "{} (blur {:.1} px, floor {:.1} % of its mean)",
                    tag.name,
                    s.blur_px,
                    100.0 * tag.floor_of_mean
                ),
                curve,
            }
        })
        .collect()
}

/// The calibrations `selections` read (the ones a second pass must scan), in order, and
/// the selections renumbered onto that list.
pub fn used(selections: &[Selection]) -> (Vec<usize>, Vec<Selection>) {
    let mut list: Vec<usize> = selections.iter().flat_map(|s| [s.a, s.b]).collect();
    list.sort_unstable();
    list.dedup();
    let at = |k: usize| list.binary_search(&k).expect("listed");
    let renumbered = selections
        .iter()
        .map(|s| Selection {
            a: at(s.a),
            b: at(s.b),
            ..*s
        })
        .collect();
    (list, renumbered)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tags() -> Vec<PriorTag> {
        [0.0f32, 1.0, 2.0, 4.0]
            .into_iter()
            .map(|blur_px| PriorTag {
                name: "test",
                image: 0,
                blur_px,
                floor_of_mean: 0.1,
            })
            .collect()
    }

    #[test]
    fn the_recording_s_share_picks_the_blurs_around_it() {
        let tags = tags();
        let members = [0, 1, 2, 3];
        // shares falling with blur: 0.6, 0.4, 0.1, 0.0
        let at = [0.6, 0.4, 0.1, 0.0];
        let s = bracket(&members, &at, &tags, 0.25);
        assert_eq!((s.a, s.b, s.reach), (1, 2, Reach::Inside));
        assert!((s.weight_a - 0.5).abs() < 1e-12 && (s.blur_px - 1.5).abs() < 1e-12);
        // burstier than the photograph: no blur; smoother than the widest: the widest
        assert_eq!(bracket(&members, &at, &tags, 0.8).reach, Reach::Sharper);
        assert_eq!(bracket(&members, &at, &tags, 0.8).blur_px, 0.0);
        let smooth = bracket(&members, &[0.6, 0.4, 0.1, 0.05], &tags, 0.0);
        assert_eq!((smooth.a, smooth.reach), (3, Reach::Smoother));
        // a blur that reads no threshold is passed over
        let s = bracket(&members, &[0.6, f64::NAN, 0.2, 0.0], &tags, 0.4);
        assert_eq!((s.a, s.b), (0, 2));
        assert!((s.weight_a - 0.5).abs() < 1e-12);
    }

    #[test]
    fn images_that_cannot_make_the_recording_s_share_are_left_out_when_others_can() {
        let tag = |image| PriorTag {
            name: "test",
            image,
            blur_px: 0.0,
            floor_of_mean: 0.1,
        };
        let tags: Vec<PriorTag> = (0..4).map(tag).collect();
        let pick = |a, reach| Selection {
            a,
            b: a,
            weight_a: 1.0,
            blur_px: 1.0,
            reach,
        };
        let inside = |k| pick(k, Reach::Inside);
        // three images make the share: the fourth, burstier even at the widest blur, goes
        let all = vec![inside(0), inside(1), inside(2), pick(3, Reach::Smoother)];
        let reading = Reading::new(0.5, 1000, all.clone(), &tags);
        assert_eq!(reading.kept, all[..3].to_vec());
        assert!(
            reading
                .describe()
                .contains("1 of 4 make that share at no blur scanned")
        );
        // two images are too few to judge the others by: every one stays, and the
        // direction each reads is said
        let all = vec![
            inside(0),
            inside(1),
            pick(2, Reach::Sharper),
            pick(3, Reach::Smoother),
        ];
        let reading = Reading::new(0.5, 1000, all.clone(), &tags);
        assert_eq!(reading.kept, all);
        let text = reading.describe();
        assert!(
            text.contains("1 of 4 are smoother than the recording even unblurred"),
            "{text}"
        );
        assert!(text.contains("so they read it high"), "{text}");
    }

    #[test]
    fn selections_are_renumbered_onto_the_calibrations_they_use() {
        let picks = [
            Selection {
                a: 5,
                b: 6,
                weight_a: 0.3,
                blur_px: 1.7,
                reach: Reach::Inside,
            },
            Selection {
                a: 9,
                b: 9,
                weight_a: 1.0,
                blur_px: 0.0,
                reach: Reach::Sharper,
            },
        ];
        let (list, renumbered) = used(&picks);
        assert_eq!(list, vec![5, 6, 9]);
        assert_eq!((renumbered[0].a, renumbered[0].b), (0, 1));
        assert_eq!((renumbered[1].a, renumbered[1].b), (2, 2));
    }
}
