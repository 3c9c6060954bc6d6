//! Drawing a peer simulator for a case ([`draw_peer`]): the case's drawn thresholds (and,
//! where the peer has the effect, its drawn strengths) in the peer's own parameters, the
//! rest around the peer's published values.
//!
//! - ESIM (`rpg_esim` defaults): `ln(DN/255 + eps)` with eps 0.001 (ESIM's default) or the
//!   case's drawn `eps`; the drawn mismatch as ESIM's per-interval threshold spread; the
//!   drawn refractory period (ESIM drops changes inside it).
//! - DVS-Voltmeter (`config.py`): one threshold, `1/k1`, the mean of the two drawn (its
//!   thresholds are +-1 volt); `k2` (the log offset, DN) log-uniform in 5-40 around the
//!   published 20 (DAVIS346) and 23 (DVS240); `k3` (diffusion), `k4` (leak) and `k6`
//!   log-uniform over the published two cameras' values widened by a factor 3, `k5` (the
//!   brightness-proportional leak) between the two (5e-9 to 5e-8 per DN per us: already
//!   12 ON events a second at 255 DN for DVS240's thresholds; three times that made
//!   recordings of leak events only).
//! - IEBCS (`dvs_sensor.py` defaults): the drawn thresholds and spread (redrawn after every
//!   event), the drawn refractory period (else IEBCS's 100 us), the drawn bandwidth as the
//!   cutoff at 255 DN (else IEBCS's 40 us at 1e4 lux), latency 20-500 us with 2-50 us jitter
//!   (IEBCS's 100 / 10 us inside), the drawn shot noise as its ON rate with OFF 1-10x lower
//!   (else its 0.1 / 0.01 Hz).

use super::case::Generator;
use super::draw::{log_uniform, uniform};
use crate::sim::PixelParams;
use crate::sim::peers::{Peer, esim, iebcs, voltmeter};
use rand::Rng;

/// The peer of `generator` for a case drawn with `params` (`None` for ctcal itself), and the
/// case's parameters in ctcal's terms: the peer's thresholds, the display kept.
pub fn draw_peer(
    rng: &mut impl Rng,
    generator: Generator,
    params: &PixelParams,
) -> Option<(Peer, PixelParams)> {
    let peer = match generator {
        Generator::Ctcal => return None,
        Generator::Esim => Peer::Esim(draw_esim(params)),
        Generator::Voltmeter => Peer::Voltmeter(draw_voltmeter(rng, params)),
        Generator::Iebcs => Peer::Iebcs(draw_iebcs(rng, params)),
    };
    let truth = peer.truth().expect("drawn peers have no noise files");
    let mut ctcal = PixelParams::ideal(truth.ct_on, truth.ct_off);
    ctcal.seed = params.seed;
    ctcal.display = params.display.clone();
    Some((peer, ctcal))
}

fn draw_esim(params: &PixelParams) -> esim::Params {
    let sigma = params.ct_sigma.unwrap_or(0.0);
    esim::Params {
        contrast_threshold_pos: params.ct_on,
        contrast_threshold_neg: params.ct_off,
        contrast_threshold_sigma_pos: sigma,
        contrast_threshold_sigma_neg: sigma,
        refractory_period_ns: (params.refractory_s() * 1e9).round() as u64,
        use_log_image: true,
        log_eps: params.log_eps.unwrap_or(esim::Params::default().log_eps),
    }
}

fn draw_voltmeter(rng: &mut impl Rng, params: &PixelParams) -> voltmeter::Params {
    let (a, b) = (voltmeter::Params::dvs346().k, voltmeter::Params::dvs240().k);
    let mut around = |i: usize, widen: f64| {
        let (lo, hi) = (a[i].min(b[i]), a[i].max(b[i]));
        log_uniform(rng, lo / widen, hi * widen)
    };
    let (k3, k4, k5, k6) = (
        around(2, 3.0),
        around(3, 3.0),
        around(4, 1.0),
        around(5, 3.0),
    );
    voltmeter::Params {
        camera_type: "drawn".into(),
        k: [
            2.0 / (params.ct_on + params.ct_off),
            log_uniform(rng, 5.0, 40.0),
            k3,
            k4,
            k5,
            k6,
        ],
    }
}

fn draw_iebcs(rng: &mut impl Rng, params: &PixelParams) -> iebcs::Params {
    let default = iebcs::Params::default();
    let tau_us = params.cutoff_hz().map_or(default.tau_us, |hz| {
        (default.lux_at_255 + 1.0) * 1e3 / (std::f64::consts::TAU * hz)
    });
    let (bgnp_hz, bgnn_hz) = match params.shot_noise_rate_hz {
        Some(rate) => (rate, rate / uniform(rng, 1.0, 10.0)),
        None => (default.bgnp_hz, default.bgnn_hz),
    };
    iebcs::Params {
        th_pos: params.ct_on,
        th_neg: params.ct_off,
        th_noise: params.ct_sigma.unwrap_or(0.0),
        lat_us: log_uniform(rng, 20.0, 500.0),
        jit_us: log_uniform(rng, 2.0, 50.0),
        ref_us: params
            .refractory_s
            .map_or(default.ref_us, |s| (s * 1e6).round() as u64),
        tau_us,
        bgnp_hz,
        bgnn_hz,
        ..default
    }
}
