//! The candidate effects of a fit without frames, in the order they are tried, each with
//! the evidence of the fit blocks and the parameter measured there.

use super::FitRun;
use super::model::NoiseModel;
use super::steps::{Candidate, Judging};
use crate::fit::Step;
use std::collections::BTreeMap;

/// Runs the loop from the ideal pixel: hot pixels, shot noise, leak, refractory period,
/// the threshold ratio.
pub(super) fn run_loop(judging: &Judging, run: &FitRun) -> (Vec<Step>, NoiseModel) {
    let mut model = NoiseModel::ideal();
    let mut steps = Vec::new();
    let makers: [fn(&FitRun, &NoiseModel) -> Candidate; 5] =
        [hot_pixels, shot_noise, leak, refractory, ratio];
    for make in makers {
        let (step, next) = judging.try_step(&model, make(run, &model));
        steps.push(step);
        model = next;
    }
    (steps, model)
}

/// The symmetric (shot-noise) part of the isolated rates, per polarity: the OFF rate
/// when ON is higher (the rest is leak), else their geometric mean (an OFF excess no
/// simulator models).
pub(super) fn symmetric_rate(run: &FitRun) -> Option<(f64, f64)> {
    let [Some((off, off_se)), Some((on, on_se))] = run.noise else {
        return None;
    };
    Some(if on >= off {
        (off, off_se)
    } else {
        let g = (on * off).sqrt();
        (
            g,
            0.5 * g * ((on_se / on.max(1e-12)).powi(2) + (off_se / off.max(1e-12)).powi(2)).sqrt(),
        )
    })
}

/// Supported events must outnumber the isolated ones by this factor, per pixel-second, for
/// their polarity balance to be the scene's: in a static scene the supported events are
/// noise events a neighbour's noise happened to support (8 neighbours at 1 Hz under +-10 ms
/// support about 15 % of them), whose balance is the noise's own.
const SCENE_DOMINATES: f64 = 10.0;

/// Isolated events with the scene's own polarity balance, where the scene is ON-dominated:
/// they are explained as the scene's own events that no neighbour supported as well as by
/// shot noise with leak.
pub(super) struct SceneLike {
    /// OFF/ON of the isolated events and of the scene's supported ones, with standard errors.
    pub isolated: (f64, f64),
    pub scene: (f64, f64),
    /// The shot noise's per-polarity rate if every isolated event beyond it is the scene's:
    /// `(OFF - scene OFF/ON x ON) / (1 - scene OFF/ON)`, at least 0.
    pub noise_at_least_hz: f64,
}

/// Where the isolated events may be the scene's own: the scene dominates (supported events
/// [`SCENE_DOMINATES`] times the isolated ones), fires more ON than OFF (OFF/ON below 1 by
/// two standard errors: Cp < Cn where brightness returns), and the isolated events' OFF/ON
/// matches the scene's within two standard errors. Scene events no neighbour supports
/// (sparse texture; a photoreceptor lagging the scene in the dark, whose late events
/// come after the neighbours fell silent) then give isolated events in the scene's balance,
/// ON in excess, which read as shot noise and leak: coverage draws 4004 and 6028, fitted
/// from their events, 0.39 and 0.51 Hz of shot noise with 0.62 and 0.38 Hz of leak where
/// neither has any, their isolated OFF/ON 0.24 and 0.40 against the scenes' 0.23 and 0.27.
pub(super) fn scene_like_isolated(run: &FitRun) -> Option<SceneLike> {
    SceneLike::of(run.noise, run.balance, run.signal_rate_hz)
}

impl SceneLike {
    /// [`scene_like_isolated`] from the isolated rates `[OFF, ON]` (Hz per pixel, standard
    /// errors), the scene's OFF/ON with its standard error and the supported events' rate
    /// per pixel.
    fn of(
        noise: [Option<(f64, f64)>; 2],
        balance: Option<(f64, f64)>,
        signal_rate_hz: f64,
    ) -> Option<SceneLike> {
        let [Some((off, off_se)), Some((on, on_se))] = noise else {
            return None;
        };
        let (scene, scene_se) = balance?;
        if on <= 0.0 || signal_rate_hz < SCENE_DOMINATES * (on + off) {
            return None;
        }
        if 1.0 - scene <= 2.0 * scene_se {
            return None;
        }
        let ratio = off / on;
        let ratio_se = ((off_se / on).powi(2) + (ratio * on_se / on).powi(2)).sqrt();
        let matches = (ratio - scene).abs() <= 2.0 * (ratio_se.powi(2) + scene_se.powi(2)).sqrt();
        matches.then(|| SceneLike {
            isolated: (ratio, ratio_se),
            scene: (scene, scene_se),
            noise_at_least_hz: ((off - scene * on) / (1.0 - scene)).max(0.0),
        })
    }

    /// Why the isolated events do not measure noise here.
    pub fn evidence(&self) -> String {
        format!(
            "the isolated events are OFF/ON = {:.3} +- {:.3}, the scene's own balance ({:.3} +- {:.3}): the scene's events that no neighbour supports (sparse texture, a photoreceptor lagging the scene in the dark) explain them as well as noise does",
            self.isolated.0, self.isolated.1, self.scene.0, self.scene.1
        )
    }
}

/// The ON excess of the isolated rates and its standard error.
pub(super) fn on_excess(run: &FitRun) -> Option<(f64, f64)> {
    let [Some((off, off_se)), Some((on, on_se))] = run.noise else {
        return None;
    };
    Some((on - off, (on_se * on_se + off_se * off_se).sqrt()))
}

/// The least leak the isolated events hold where the scene fires more ON than OFF: the
/// isolated events are shot noise (`n` each polarity), leak (`l`, ON only) and the scene's
/// own unsupported events (`a` ON and `rho a` OFF, `rho` the scene's OFF/ON), and the counts
/// alone do not fix `a`. Its largest share (`n = 0`, `a = OFF / rho`) leaves
/// `l = ON - OFF / rho`; none leaves the ON excess `ON - OFF`. A scene with `Cp` 5.7 times
/// under `Cn` (coverage draw 12036, leak 0.041 Hz) fitted a leak of 1.02 [0.87, 1.20] Hz
/// from that excess. `None` where the scene is not ON-heavy by two standard errors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SceneShare {
    /// The scene's OFF/ON.
    pub rho: f64,
    /// `ON - OFF / rho`, Hz per pixel (negative: the scene explains every isolated ON event).
    pub leak_at_least_hz: f64,
}

pub(super) fn scene_share(run: &FitRun) -> Option<SceneShare> {
    SceneShare::of(run.noise, run.balance)
}

impl SceneShare {
    fn of(noise: [Option<(f64, f64)>; 2], balance: Option<(f64, f64)>) -> Option<Self> {
        let [Some((off, _)), Some((on, _))] = noise else {
            return None;
        };
        let (rho, rho_se) = balance?;
        (rho > 0.0 && 1.0 - rho > 2.0 * rho_se).then(|| SceneShare {
            rho,
            leak_at_least_hz: on - off / rho,
        })
    }

    pub fn text(&self, excess: f64) -> String {
        format!(
            "the scene fires OFF/ON = {:.3}, so the isolated events' ON excess ({excess:.4} Hz) may be the scene's own unsupported events as well as leak: were every isolated OFF event the scene's, the leak would be {:.4} Hz; the interval reaches down to that (with 2 standard errors); a static stretch of the recording, or grey frames, would tell them apart",
            self.rho,
            self.leak_at_least_hz.max(0.0)
        )
    }
}

/// A noise candidate (shot noise, leak) is not tried where the isolated events are in the
/// scene's own balance ([`scene_like_isolated`]); its evidence says why.
fn set_aside_where_scene_like(c: &mut Candidate, run: &FitRun) {
    if let Some(scene) = scene_like_isolated(run) {
        c.evidence = format!("{}; {}", c.evidence, scene.evidence());
        c.relevant = false;
    }
}

fn candidate(name: &'static str, model: NoiseModel) -> Candidate {
    Candidate {
        name,
        evidence: String::new(),
        score: 0.0,
        relevant: false,
        parameters: BTreeMap::new(),
        model,
    }
}

fn hot_pixels(run: &FitRun, current: &NoiseModel) -> Candidate {
    let mut c = candidate("hot_pixels", current.clone());
    if run.hot.is_empty() {
        c.evidence = "no pixel stands out from its neighbours".into();
        return c;
    }
    let strongest = run.hot.iter().map(|p| p.z).fold(0.0, f64::max);
    c.evidence = format!(
        "{} pixels fire far above their neighbours (robust z up to {strongest:.0}), e.g. {}",
        run.hot.len(),
        run.trains
            .iter()
            .take(4)
            .map(|p| format!("({}, {}) at {:.1} Hz", p.x, p.y, p.rate_hz))
            .collect::<Vec<_>>()
            .join(", ")
    );
    c.score = strongest;
    c.relevant = true;
    c.parameters = BTreeMap::from([("hot_pixels".to_string(), run.hot.len() as f64)]);
    c.model.hot_rates_hz = Some(run.trains.iter().map(|t| t.rate_hz).collect());
    c
}

fn shot_noise(run: &FitRun, current: &NoiseModel) -> Candidate {
    let mut c = candidate("shot_noise", current.clone());
    let Some((rate, se)) = symmetric_rate(run) else {
        c.evidence = "no quiet pixel-time to measure isolated events on".into();
        return c;
    };
    c.score = rate / se.max(1e-12);
    c.evidence = format!(
        "isolated events at quiet pixels: {:.4} Hz ON, {:.4} Hz OFF per pixel (symmetric part {rate:.4} +- {se:.4} Hz)",
        run.noise[1].map_or(0.0, |r| r.0),
        run.noise[0].map_or(0.0, |r| r.0),
    );
    c.relevant = rate > 2.0 * se;
    set_aside_where_scene_like(&mut c, run);
    c.parameters = BTreeMap::from([("shot_noise_rate_hz".to_string(), 2.0 * rate)]);
    c.model.noise_on_hz = rate;
    c.model.noise_off_hz = rate;
    c
}

fn leak(run: &FitRun, current: &NoiseModel) -> Candidate {
    let mut c = candidate("leak", current.clone());
    let Some((excess, se)) = on_excess(run) else {
        c.evidence = "no quiet pixel-time to measure isolated events on".into();
        return c;
    };
    c.score = excess / se.max(1e-12);
    c.evidence = format!(
        "isolated ON events exceed OFF by {excess:.4} +- {se:.4} Hz per pixel (leak fires ON only)"
    );
    c.relevant = excess > 2.0 * se;
    set_aside_where_scene_like(&mut c, run);
    c.parameters = BTreeMap::from([("leak_rate_hz".to_string(), excess.max(0.0))]);
    c.model.noise_on_hz = current.noise_on_hz + excess.max(0.0);
    c
}

fn refractory(run: &FitRun, current: &NoiseModel) -> Candidate {
    let mut c = candidate("refractory", current.clone());
    let Some(edge) = &run.edge else {
        c.evidence = "too few same-pixel intervals to see their short end".into();
        return c;
    };
    c.score = edge.score();
    c.evidence = if edge.found {
        format!(
            "{} same-pixel intervals below {:.1} us against {} in [{:.1}, {:.1}) us: a lower edge",
            edge.below,
            edge.edge_us,
            edge.above,
            edge.edge_us,
            2.0 * edge.edge_us
        )
    } else if let Some(why) = &edge.not_refractory {
        why.clone()
    } else {
        format!(
            "short same-pixel intervals come down to {:.0} us with no gap",
            edge.edge_us
        )
    };
    c.relevant = edge.found;
    c.parameters = BTreeMap::from([("refractory_s".to_string(), edge.edge_us * 1e-6)]);
    c.model.refractory = true;
    c
}

fn ratio(run: &FitRun, current: &NoiseModel) -> Candidate {
    let mut c = candidate("thresholds", current.clone());
    let Some((balance, se)) = run.balance else {
        c.evidence = "too few supported events of one polarity for a balance".into();
        return c;
    };
    c.score = balance.ln().abs() / (se / balance).max(1e-12);
    c.evidence = format!(
        "the scene's events are OFF/ON = {balance:.3} +- {se:.3} (fit blocks): Cp/Cn where brightness returns"
    );
    c.relevant = c.score > 2.0;
    c.parameters = BTreeMap::from([("ct_on / ct_off".to_string(), balance)]);
    c.model.balance = balance;
    c
}

#[cfg(test)]
mod tests {

    /// Hand-computed: isolated OFF 0.2, ON 1.0 Hz and a scene of OFF/ON 0.25 leave at least
    /// 1.0 - 0.2 / 0.25 = 0.2 Hz of leak; a balanced scene (0.95 +- 0.05) is no share.
    #[test]
    fn the_scene_s_share_bounds_the_leak_from_below() {
        let noise = [Some((0.2, 0.01)), Some((1.0, 0.02))];
        let share = SceneShare::of(noise, Some((0.25, 0.02))).unwrap();
        assert!((share.leak_at_least_hz - 0.2).abs() < 1e-12, "{share:?}");
        assert_eq!(SceneShare::of(noise, Some((0.95, 0.05))), None);
        assert_eq!(SceneShare::of([None, noise[1]], Some((0.25, 0.02))), None);
    }

    use super::*;

    /// Coverage draw 4004 read from its events (an ON-dominated texture at 399 px/s, no
    /// noise): its isolated events, 0.81 Hz ON and 0.20 Hz OFF, have the scene's balance.
    #[test]
    fn isolated_events_in_the_scenes_balance_are_not_read_as_noise() {
        let draw_4004 = SceneLike::of(
            [Some((0.1950, 0.0059)), Some((0.8125, 0.0119))],
            Some((0.228, 0.0169)),
            40.0,
        )
        .expect("the scene's balance");
        // shot noise could be as low as (0.195 - 0.228 x 0.8125) / 0.772
        assert!((draw_4004.noise_at_least_hz - 0.0126).abs() < 0.001);
        // shot noise (1:1) in an ON-dominated moving scene is not the scene's balance
        let noise = [Some((1.0, 0.01)), Some((1.0, 0.01))];
        assert!(SceneLike::of(noise, Some((0.3, 0.02)), 40.0).is_none());
        // a static scene with leak: the supported events are noise a neighbour's noise
        // supported, in the noise's own balance, and do not outnumber the isolated ones
        let leak = [Some((1.0, 0.01)), Some((2.0, 0.02))];
        assert!(SceneLike::of(leak, Some((0.5, 0.02)), 0.5).is_none());
        assert!(SceneLike::of(leak, Some((0.5, 0.02)), 40.0).is_some());
        // a balanced scene: the ON excess is not the scene's
        assert!(SceneLike::of(leak, Some((0.98, 0.05)), 40.0).is_none());
    }
}
