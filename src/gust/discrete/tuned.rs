//! The tuned 1-cos gust search of CS-25.341(a)(3): the gust gradient H over its range, the
//! peaks of every output, positive and negative, at each H (the envelope), and per output the
//! critical H of each sign, refined about the worst point of the grid.

use super::analysis::{
    transient, ProfileResponse, TransientModel, TransientResponse, TransientSettings,
};
use super::profile::GustProfile;
use super::transient::{Peak, TRUNCATION_TOLERANCE, WRAP_TOLERANCE};
use crate::gust::response::{GustError, GustProblem};

/// Golden-section steps of the refinement: the bracket of two grid intervals shrinks to
/// 0.618¹⁴ = 1.2e-3 of itself.
pub const REFINE_STEPS: usize = 14;

/// One gust gradient's response.
#[derive(Clone, Debug)]
pub struct EnvelopePoint {
    /// H (m).
    pub gradient: f64,
    /// U_ds (m/s, true airspeed).
    pub amplitude: f64,
    /// Per output, (maximum, minimum).
    pub peaks: Vec<(Peak, Peak)>,
    /// Whether the point was added by the refinement (not on the search grid).
    pub refined: bool,
}

/// The critical gust of one output and sign.
#[derive(Clone, Copy, Debug)]
pub struct CriticalGust {
    pub gradient: f64,
    pub amplitude: f64,
    pub peak: Peak,
}

/// The result of the tuned search.
#[derive(Clone, Debug)]
pub struct TunedResult {
    /// Every H evaluated, in increasing H.
    pub envelope: Vec<EnvelopePoint>,
    /// Per output, the critical (maximum, minimum) gusts.
    pub critical: Vec<(CriticalGust, CriticalGust)>,
    /// The grid, span and checks of the analysis.
    pub response: TransientResponse,
    /// Per output, the histories at its critical H of each sign.
    pub histories: Vec<(Vec<f64>, Vec<f64>)>,
    /// The largest wrap-around and truncation fractions over every profile evaluated.
    pub wrap_max: f64,
    pub truncated_max: f64,
}

/// `points` equally spaced gust gradients over `range` (m); one point: the range's start.
pub fn gradient_grid(range: [f64; 2], points: usize) -> Vec<f64> {
    if points == 1 {
        return vec![range[0]];
    }
    (0..points)
        .map(|i| range[0] + (range[1] - range[0]) * i as f64 / (points - 1) as f64)
        .collect()
}

fn one_minus_cosine(h: f64, amplitude: &dyn Fn(f64) -> f64, velocity: f64) -> GustProfile {
    GustProfile::OneMinusCosine {
        gradient: h,
        amplitude: amplitude(h),
        velocity,
    }
}

/// Searches H over `range` (m) on `points` equally spaced values, then refines the critical H
/// of every output and sign by golden section between the grid neighbours of its worst point
/// (a local refinement: the grid must be fine enough to bracket the worst peak, which 20
/// points over CS-25's range do for responses that vary smoothly with H). `amplitude(H)` gives
/// U_ds (m/s), `velocity` the flight speed.
pub fn tuned_search(
    p: &GustProblem,
    s: &TransientSettings,
    range: [f64; 2],
    points: usize,
    amplitude: &dyn Fn(f64) -> f64,
    velocity: f64,
) -> Result<TunedResult, GustError> {
    if !(range[0] > 0.0 && range[1] >= range[0])
        || points == 0
        || (points == 1 && range[1] > range[0])
    {
        return Err(GustError::Input(format!(
            "the gust gradients: need 0 < H_min ≤ H_max and at least 2 points for a range (got {:?} m, {points} points)",
            range
        )));
    }
    let grid_h = gradient_grid(range, points);
    let profiles: Vec<GustProfile> = grid_h
        .iter()
        .map(|&h| one_minus_cosine(h, amplitude, velocity))
        .collect();
    let quiet = TransientSettings {
        keep_histories: false,
        ..s.clone()
    };
    let (response, mut model) = transient(p, &profiles, &quiet)?;
    let mut envelope: Vec<EnvelopePoint> = grid_h
        .iter()
        .zip(&response.profiles)
        .map(|(&h, r)| EnvelopePoint {
            gradient: h,
            amplitude: amplitude(h),
            peaks: r.peaks.clone(),
            refined: false,
        })
        .collect();
    let mut wrap_max = response
        .profiles
        .iter()
        .flat_map(|r| r.wrap.iter().copied())
        .fold(0.0, f64::max);
    let mut truncated_max = response
        .profiles
        .iter()
        .map(|r| r.truncated)
        .fold(0.0, f64::max);
    let n_out = p.outputs.len();
    let mut critical = Vec::with_capacity(n_out);
    let mut eval = |h: f64,
                    model: &mut TransientModel,
                    envelope: &mut Vec<EnvelopePoint>|
     -> ProfileResponse {
        let r = model.respond(&one_minus_cosine(h, amplitude, velocity), false);
        wrap_max = r.wrap.iter().copied().fold(wrap_max, f64::max);
        truncated_max = truncated_max.max(r.truncated);
        envelope.push(EnvelopePoint {
            gradient: h,
            amplitude: amplitude(h),
            peaks: r.peaks.clone(),
            refined: true,
        });
        r
    };
    for y in 0..n_out {
        let mut pair = Vec::with_capacity(2);
        for sign in [1.0, -1.0] {
            let value = |pk: &(Peak, Peak)| if sign > 0.0 { pk.0.value } else { -pk.1.value };
            let pick = |pk: &(Peak, Peak)| if sign > 0.0 { pk.0 } else { pk.1 };
            let worst = (0..grid_h.len())
                .max_by(|&a, &b| {
                    value(&envelope[a].peaks[y]).total_cmp(&value(&envelope[b].peaks[y]))
                })
                .expect("at least one gradient");
            let mut best = CriticalGust {
                gradient: grid_h[worst],
                amplitude: amplitude(grid_h[worst]),
                peak: pick(&envelope[worst].peaks[y]),
            };
            if grid_h.len() > 1 {
                let (mut a, mut b) = (
                    grid_h[worst.saturating_sub(1)],
                    grid_h[(worst + 1).min(grid_h.len() - 1)],
                );
                let phi = 0.5 * (5f64.sqrt() - 1.0);
                let mut c = b - phi * (b - a);
                let mut d = a + phi * (b - a);
                let mut fc = eval(c, &mut model, &mut envelope);
                let mut fd = eval(d, &mut model, &mut envelope);
                for _ in 0..REFINE_STEPS {
                    let (vc, vd) = (value(&fc.peaks[y]), value(&fd.peaks[y]));
                    for (h, f, v) in [(c, &fc, vc), (d, &fd, vd)] {
                        if v > value_of(&best, sign) {
                            best = CriticalGust {
                                gradient: h,
                                amplitude: amplitude(h),
                                peak: pick(&f.peaks[y]),
                            };
                        }
                    }
                    if vc > vd {
                        b = d;
                        d = c;
                        fd = fc;
                        c = b - phi * (b - a);
                        fc = eval(c, &mut model, &mut envelope);
                    } else {
                        a = c;
                        c = d;
                        fc = fd;
                        d = a + phi * (b - a);
                        fd = eval(d, &mut model, &mut envelope);
                    }
                }
            }
            pair.push(best);
        }
        critical.push((pair[0], pair[1]));
    }
    if wrap_max > WRAP_TOLERANCE || truncated_max > TRUNCATION_TOLERANCE {
        // the refinement's gradients lie inside the grid's range, whose ends passed both checks
        return Err(GustError::Input(format!(
            "a refined gust gradient failed the checks of the grid (wrap-around {wrap_max:.2e}, truncated energy {truncated_max:.2e}): lengthen discrete_gust.time_span_s or narrow the gradient range"
        )));
    }
    envelope.sort_by(|a, b| a.gradient.total_cmp(&b.gradient));
    let histories = critical
        .iter()
        .enumerate()
        .map(|(y, (hi, lo))| {
            let mut run = |c: &CriticalGust| {
                let r = model.respond(&one_minus_cosine(c.gradient, amplitude, velocity), true);
                r.histories[y].clone()
            };
            (run(hi), run(lo))
        })
        .collect();
    Ok(TunedResult {
        envelope,
        critical,
        response,
        histories,
        wrap_max,
        truncated_max,
    })
}

fn value_of(c: &CriticalGust, sign: f64) -> f64 {
    sign * c.peak.value
}

#[cfg(test)]
mod tests;
