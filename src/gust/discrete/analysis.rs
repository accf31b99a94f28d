//! The transient response of a modal gust problem (paper Eq. 16's system) to discrete gust
//! profiles: one uniform frequency grid whose span makes every response decay, the transfer
//! functions solved once on it and shared by all profiles, and per profile and output the time
//! history and its peaks.

use super::profile::GustProfile;
use super::transient::{
    extremes, truncated_energy, wrap_fraction, Peak, Synthesizer, TimeGrid, TRUNCATION_TOLERANCE,
    WRAP_TOLERANCE,
};
use crate::gust::response::{
    frequency_response, FrequencyGrid, FrequencyResponse, GustError, GustProblem,
};
use faer::c64;

/// Times the span may be doubled when the response has not decayed within it.
pub const MAX_DOUBLINGS: usize = 6;

/// What the transient analysis needs beyond the modal problem.
#[derive(Clone, Debug)]
pub struct TransientSettings {
    /// The time span T (s); `None`: [`initial_span`], doubled until every response decays.
    pub span: Option<f64>,
    /// The grid's largest frequency (rad/s): the GAF table's highest k, k_max U/b.
    pub omega_max: f64,
    /// Per output, the order of the time derivative taken (0 the output itself, 2 its
    /// acceleration).
    pub derivative: Vec<u32>,
    /// Whether the histories themselves are kept (the peaks always are).
    pub keep_histories: bool,
    /// The memory the grid and histories may take (bytes).
    pub max_bytes: f64,
}

/// The response to one profile.
#[derive(Clone, Debug)]
pub struct ProfileResponse {
    /// Per output, (maximum, minimum).
    pub peaks: Vec<(Peak, Peak)>,
    /// Per output, the history on the grid's times (empty unless kept).
    pub histories: Vec<Vec<f64>>,
    /// Per output, what the window's last tenth still holds over the peak.
    pub wrap: Vec<f64>,
    /// The fraction of the profile's energy beyond the grid's last frequency.
    pub truncated: f64,
}

/// The transient analysis of several profiles on one grid.
#[derive(Clone, Debug)]
pub struct TransientResponse {
    pub grid: TimeGrid,
    /// Whether the span was chosen (and perhaps doubled) rather than given.
    pub span_chosen: bool,
    pub profiles: Vec<ProfileResponse>,
}

impl TransientResponse {
    /// The largest |y| of output `y` over every profile (the sampled peaks, refined).
    pub fn largest_abs(&self, y: usize) -> f64 {
        self.profiles
            .iter()
            .map(|pr| pr.peaks[y].0.value.abs().max(pr.peaks[y].1.value.abs()))
            .fold(0.0, f64::max)
    }
}

/// The first span tried: four times the longest profile's end, and at least 30 periods of the
/// lowest natural frequency (an aeroelastic mode of damping ratio ζ keeps e^{−2π·30ζ} of its
/// amplitude after them: 1.5e-4 at ζ = 0.05; lighter damping is caught by the wrap check).
pub fn initial_span(profiles: &[GustProfile], omega_n: &[f64]) -> f64 {
    let t_end = profiles
        .iter()
        .map(|p| p.support().1)
        .fold(0.0f64, f64::max);
    let w1 = omega_n
        .iter()
        .copied()
        .filter(|w| *w > 0.0)
        .fold(f64::INFINITY, f64::min);
    let periods = if w1.is_finite() {
        30.0 * 2.0 * std::f64::consts::PI / w1
    } else {
        0.0
    };
    (4.0 * t_end).max(periods)
}

/// Problem `p` with the uniform frequency grid of `grid` (its weights unused).
fn with_grid<'a>(p: &GustProblem<'a>, grid: &TimeGrid) -> GustProblem<'a> {
    let mut q = p.clone();
    q.grid = FrequencyGrid {
        omega: grid.omega.clone(),
        weights: vec![0.0; grid.omega.len()],
    };
    q
}

/// A problem's transfer functions on one time grid, ready for any profile: Eq. 16 is solved
/// once, each profile then costs its spectrum and one inverse FFT an output.
pub struct TransientModel {
    pub grid: TimeGrid,
    /// The time-derivative order of each output.
    pub derivative: Vec<u32>,
    /// Eq. 16 on the grid: η, H_y and the factorizations the reverse mode reuses.
    pub response: FrequencyResponse,
    /// (iω)^d H_y(ω) per output and grid frequency.
    transfer: Vec<Vec<c64>>,
    syn: Synthesizer,
    spectrum: Vec<c64>,
    product: Vec<c64>,
    y: Vec<f64>,
}

impl TransientModel {
    /// Solves the problem's frequency response on `grid`, the outputs differentiated
    /// `derivative[y]` times in time.
    pub fn new(p: &GustProblem, derivative: &[u32], grid: TimeGrid) -> Result<Self, GustError> {
        let q = with_grid(p, &grid);
        let fr = frequency_response(&q)?;
        let transfer =
            fr.h.iter()
                .zip(derivative)
                .map(|(hy, &d)| {
                    hy.iter()
                        .zip(&grid.omega)
                        .map(|(h, &w)| h * c64::new(0.0, w).powu(d))
                        .collect()
                })
                .collect();
        Ok(Self {
            derivative: derivative.to_vec(),
            response: fr,
            syn: Synthesizer::new(&grid),
            spectrum: vec![c64::new(0.0, 0.0); grid.omega.len()],
            product: vec![c64::new(0.0, 0.0); grid.omega.len()],
            y: vec![0.0; grid.time.len()],
            transfer,
            grid,
        })
    }

    /// The inverse transform of the grid (the reverse mode runs its adjoint).
    pub fn synthesizer(&mut self) -> &mut Synthesizer {
        &mut self.syn
    }

    /// The problem `p` on this model's frequency grid (for the reverse mode).
    pub fn on_grid<'a>(&self, p: &GustProblem<'a>) -> GustProblem<'a> {
        with_grid(p, &self.grid)
    }

    /// The history of output `y` for profile `g` into `out` (one value per time sample).
    pub fn history(&mut self, g: &GustProfile, y: usize, out: &mut [f64]) {
        for (w, o) in self.spectrum.iter_mut().zip(&self.grid.omega) {
            *w = g.spectrum(*o);
        }
        for ((pr, h), w) in self
            .product
            .iter_mut()
            .zip(&self.transfer[y])
            .zip(&self.spectrum)
        {
            *pr = h * w;
        }
        self.syn.history(&self.product, out);
    }

    /// The outputs' response to profile `g`: peaks, wrap fractions, the truncated energy, and
    /// the histories if `keep`.
    pub fn respond(&mut self, g: &GustProfile, keep: bool) -> ProfileResponse {
        for (w, o) in self.spectrum.iter_mut().zip(&self.grid.omega) {
            *w = g.spectrum(*o);
        }
        let mut r = ProfileResponse {
            peaks: Vec::new(),
            histories: Vec::new(),
            wrap: Vec::new(),
            truncated: truncated_energy(g, &self.grid),
        };
        for t in &self.transfer {
            for ((pr, h), w) in self.product.iter_mut().zip(t).zip(&self.spectrum) {
                *pr = h * w;
            }
            self.syn.history(&self.product, &mut self.y);
            r.peaks.push(extremes(&self.grid.time, &self.y));
            r.wrap.push(wrap_fraction(&self.y));
            if keep {
                r.histories.push(self.y.clone());
            }
        }
        r
    }
}

/// The responses of the problem's outputs to each profile. With no span given, the span starts
/// at [`initial_span`] and doubles (at most [`MAX_DOUBLINGS`] times, within the memory limit)
/// until every response keeps less than [`WRAP_TOLERANCE`] in its last tenth; a given span that
/// does not is an error, as is a profile with more than [`TRUNCATION_TOLERANCE`] of its energy
/// beyond the grid.
pub fn transient(
    p: &GustProblem,
    profiles: &[GustProfile],
    s: &TransientSettings,
) -> Result<(TransientResponse, TransientModel), GustError> {
    if s.derivative.len() != p.outputs.len() {
        return Err(GustError::Input(format!(
            "one derivative order an output: {} for {} outputs",
            s.derivative.len(),
            p.outputs.len()
        )));
    }
    for (i, g) in profiles.iter().enumerate() {
        g.validate()
            .map_err(|e| GustError::Input(format!("gust profile {}: {e}", i + 1)))?;
    }
    let mut span = s.span.unwrap_or_else(|| initial_span(profiles, &p.omega_n));
    let mut doublings = 0;
    loop {
        let bytes = TimeGrid::bytes(
            span,
            s.omega_max,
            p.outputs.len() * if s.keep_histories { profiles.len() } else { 1 },
        );
        if bytes > s.max_bytes {
            return Err(GustError::Input(format!(
                "a time span of {span:.3} s up to {:.1} rad/s needs about {:.2} GB for its grid and histories, above the limit of {:.2} GB: shorten the span (discrete_gust.time_span_s) or raise the memory limit",
                s.omega_max,
                bytes / 1e9,
                s.max_bytes / 1e9
            )));
        }
        let grid = TimeGrid::new(span, s.omega_max).map_err(GustError::Input)?;
        let mut model = TransientModel::new(p, &s.derivative, grid)?;
        let responses: Vec<ProfileResponse> = profiles
            .iter()
            .map(|g| model.respond(g, s.keep_histories))
            .collect();
        if let Some((i, r)) = responses
            .iter()
            .enumerate()
            .find(|(_, r)| r.truncated > TRUNCATION_TOLERANCE)
        {
            return Err(GustError::Input(format!(
                "gust profile {} keeps {:.2e} of its energy beyond the GAF table's highest frequency ({:.1} rad/s; limit {TRUNCATION_TOLERANCE:.0e}): the profile changes faster than the table resolves; extend aero.reduced_frequencies or smooth the profile (a longer gust gradient, a ramp over a few hundredths of a second)",
                i + 1,
                r.truncated,
                s.omega_max
            )));
        }
        let worst = responses
            .iter()
            .enumerate()
            .flat_map(|(i, r)| r.wrap.iter().enumerate().map(move |(y, w)| (i, y, *w)))
            .fold((0, 0, 0.0f64), |a, b| if b.2 > a.2 { b } else { a });
        if worst.2 <= WRAP_TOLERANCE {
            let response = TransientResponse {
                grid: model.grid.clone(),
                span_chosen: s.span.is_none(),
                profiles: responses,
            };
            return Ok((response, model));
        }
        if s.span.is_some() || doublings == MAX_DOUBLINGS {
            return Err(GustError::Input(format!(
                "the response of output {} to gust profile {} keeps {:.2e} of its peak in the last tenth of the {span:.3} s time span (limit {WRAP_TOLERANCE:.0e}): the slowest mode has not decayed and would wrap around onto the start; {}",
                worst.1 + 1,
                worst.0 + 1,
                worst.2,
                if s.span.is_some() {
                    format!("lengthen discrete_gust.time_span_s (to about {:.3} s) or leave it out to have it chosen", 2.0 * span)
                } else {
                    format!("even after {MAX_DOUBLINGS} doublings: the system is (nearly) undamped; check the flutter margin and the damping ratio")
                }
            )));
        }
        span *= 2.0;
        doublings += 1;
    }
}

#[cfg(test)]
mod tests;
