//! Whether a pixel's silences leave room for a hot pixel's train: a defective pixel fires
//! a Poisson train at its rate throughout, so its longest silence is bounded; a low
//! threshold under mismatch fires in bursts while its brightness moves its way and falls
//! silent between them.

use crate::events::TimeUs;

/// The significance at which a pixel's longest silence rejects the train (about 40 pixels
/// are tested in a fit: 0.001 each keeps the family's false rejections near 4 %).
const SILENCE_SIGNIFICANCE: f64 = 1e-3;

/// A stretch of this long without any event on the whole sensor is a pause of the
/// recording (events not read, a stop), not a pixel's silence.
const SENSOR_PAUSE_US: TimeUs = 10_000;

/// The span judged and the sensor's pauses in it ([`SENSOR_PAUSE_US`]), read once from
/// every event of the sensor over that span (`all`, time-sorted) for all named pixels.
pub(super) struct SensorTime {
    /// First event, and a microsecond past the last.
    span: Option<(TimeUs, TimeUs)>,
    pauses: Vec<(TimeUs, TimeUs)>,
}

impl SensorTime {
    pub(super) fn of(all: &[TimeUs]) -> Self {
        Self {
            span: all.first().zip(all.last()).map(|(&a, &z)| (a, z + 1)),
            pauses: all
                .windows(2)
                .filter(|w| w[1] - w[0] > SENSOR_PAUSE_US)
                .map(|w| (w[0], w[1]))
                .collect(),
        }
    }

    /// The active time of [a, b): its length less the sensor's pauses inside it.
    fn active(&self, a: TimeUs, b: TimeUs) -> TimeUs {
        let paused: TimeUs = self.pauses[self.pauses.partition_point(|&(_, z)| z <= a)..]
            .iter()
            .take_while(|&&(p, _)| p < b)
            .map(|&(p, z)| (z.min(b) - p.max(a)).max(0))
            .sum();
        b - a - paused
    }
}

/// Whether a pixel's own events (`own`, time-sorted) fall silent for longer than a Poisson
/// train at `rate_hz` allows. The train's events are among the pixel's whatever the scene
/// adds, so every silence of the pixel is a silence of the train. Over `T` seconds a train
/// has on average `rate * T * exp(-rate * g)` gaps of `g` or longer, and its first and last
/// events leave the span's ends open for `g` with probability `exp(-rate * g)` each, so a
/// silence of `g` somewhere has probability at most `(2 + rate * T) * exp(-rate * g)`
/// (Markov's inequality on the number of such gaps). Below [`SILENCE_SIGNIFICANCE`] the
/// train is rejected. A low threshold under mismatch fires only while its brightness moves
/// its way: bursts on rising edges, silence between them (coverage draw 59: ON bursts of
/// 100-265 events in a frame interval and none in the next), a defective pixel at its rate
/// throughout. `sensor`: the span judged, whose pauses ([`SENSOR_PAUSE_US`]) count as
/// neither silence nor time. The test assumes a
/// constant rate: a blinking (random-telegraph) defect is not a train and is left to the
/// scene too.
pub(super) fn silent_beyond_a_train(own: &[TimeUs], rate_hz: f64, sensor: &SensorTime) -> bool {
    let Some((first, end)) = sensor.span else {
        return false;
    };
    if rate_hz <= 0.0 {
        return false;
    }
    let edges = std::iter::once(first)
        .chain(own.iter().copied().filter(|t| (first..end).contains(t)))
        .chain(std::iter::once(end))
        .collect::<Vec<_>>();
    let longest_us = edges
        .windows(2)
        .map(|w| sensor.active(w[0], w[1]))
        .max()
        .unwrap_or(0);
    let seconds = sensor.active(first, end) as f64 * 1e-6;
    let longest = longest_us as f64 * 1e-6;
    (2.0 + rate_hz * seconds) * (-rate_hz * longest).exp() < SILENCE_SIGNIFICANCE
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::effects::fixture::{poisson_times, rng};

    /// Coverage draw 59's pixel (206, 74): ON every 1.4-2.0 ms for 135 ms while its
    /// brightness rises (a threshold near 0.01), then silent for 144 ms. A train at 196 Hz
    /// (its excess's lower end) leaves a 144 ms silence with probability below
    /// (2 + 196 * 0.279) * exp(-196 * 0.144) = 3e-11: rejected. Poisson trains at 196 Hz,
    /// alone or with bursts of scene events, are not, over 200 draws (each is rejected with
    /// probability below 0.001).
    #[test]
    fn a_pixel_silent_longer_than_its_train_allows_is_the_scene() {
        let sensor: Vec<TimeUs> = (0..279_000).step_by(50).map(|t| t + 4_000).collect();
        let bursts: Vec<TimeUs> = (0..90).map(|k| 5_000 + k * 1_500).collect();
        assert!(silent_beyond_a_train(
            &bursts,
            196.0,
            &SensorTime::of(&sensor)
        ));
        let mut rng = rng(3);
        for draw in 0..200 {
            let mut train = poisson_times(&mut rng, 196.0, 0.004, 0.283);
            if draw % 2 == 1 {
                train.extend(bursts.iter().copied());
                train.sort_unstable();
            }
            assert!(
                !silent_beyond_a_train(&train, 196.0, &SensorTime::of(&sensor)),
                "draw {draw}"
            );
        }
    }

    /// A pause of the whole sensor (events not read between blocks) is neither silence nor
    /// time: a train at 200 Hz whose events stop with the sensor's for 200 ms is kept, and
    /// rejected once the sensor fires through the same 200 ms.
    #[test]
    fn a_pause_of_the_sensor_is_not_a_pixel_silence() {
        let mut rng = rng(5);
        let mut train = poisson_times(&mut rng, 200.0, 0.0, 0.2);
        train.extend(poisson_times(&mut rng, 200.0, 0.4, 0.6));
        let paused: Vec<TimeUs> = (0..600_000)
            .step_by(100)
            .filter(|t| !(200_000..400_000).contains(t))
            .collect();
        assert!(!silent_beyond_a_train(
            &train,
            200.0,
            &SensorTime::of(&paused)
        ));
        let busy: Vec<TimeUs> = (0..600_000).step_by(100).collect();
        assert!(silent_beyond_a_train(&train, 200.0, &SensorTime::of(&busy)));
    }
}
