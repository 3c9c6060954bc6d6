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

/// The ON excess of the isolated rates and its standard error.
pub(super) fn on_excess(run: &FitRun) -> Option<(f64, f64)> {
    let [Some((off, off_se)), Some((on, on_se))] = run.noise else {
        return None;
    };
    Some((on - off, (on_se * on_se + off_se * off_se).sqrt()))
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
