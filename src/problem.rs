//! The gust-constrained design problem of a study as an [`optim::Problem`]: minimize mass subject
//! to RMS(output) ≤ limit, optionally a flutter margin (every p-k root at a speed above the flight
//! speed damped), and planform area = initial area, within the design bounds.
//! Objective and constraints are normalized (mass/mass₀, RMS/limit − 1, (g_KS − g_max)/0.1,
//! area/area₀ − 1) so the SQP sees quantities of order one.

use crate::case::{Case, ModeSelection};
use crate::flutter::margin::{FlutterMargin, DAMPING_SCALE};
use crate::gust::GustSettings;
use crate::optim::{EvalError, Gradients, Problem, Values};
use crate::pipeline::{evaluate, gradients, DampingSeed, Evaluation, OutputSeeds};
use anyhow::Context;

/// Bounds and constraint settings (SI).
#[derive(Clone, Debug)]
pub struct DesignSpec {
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    /// Index of the constrained gust output and its RMS limit (SI).
    pub output: usize,
    pub rms_limit: f64,
    pub mass0: f64,
    pub area0: f64,
    /// Keep the planform area at area0 (an equality constraint).
    pub fix_area: bool,
    /// The flutter-margin constraint, if any (the second inequality).
    pub flutter: Option<FlutterMargin>,
    /// The modal basis kept whole (the inequality after the flutter margin), when the study
    /// chooses its modes by the cutoff rule: see [`ModeFloor`].
    pub mode_floor: Option<ModeFloor>,
    /// The discrete gust peak limit (the last inequality), if any: see [`PeakLimit`].
    pub peak: Option<PeakLimit>,
}

/// A discrete gust peak limit in the optimization: KS(±y/limit over every time sample and gust)
/// − 1 ≤ 0 ([`crate::gust::discrete::PeakKs`]), on a time grid fixed for the whole run (chosen at
/// the initial design with twice the span the decay rule needs, so that a design change that
/// slows the decay does not wrap around; a change of grid between iterations would make the
/// constraint jump).
#[derive(Clone, Debug)]
pub struct PeakLimit {
    pub constraint: crate::case::PeakConstraint,
    pub grid: crate::gust::discrete::TimeGrid,
}

/// The transient analysis of a peak constraint's output over its gusts at evaluation `ev`, on
/// the grid of span `span` (s) or, with none, the one the decay rule picks for this model; the
/// memory of the grid limited to 2 GB.
pub fn peak_response(
    ev: &Evaluation,
    pc: &crate::case::PeakConstraint,
    span: Option<f64>,
) -> Result<crate::gust::discrete::TransientResponse, crate::gust::GustError> {
    let p = ev.problem();
    let ts = crate::gust::discrete::TransientSettings {
        span,
        omega_max: p.table_omega_max(),
        derivative: pc.derivatives(p.outputs.len()),
        keep_histories: false,
        max_bytes: 2e9,
    };
    Ok(crate::gust::discrete::transient(&p, &pc.gusts, &ts)?.0)
}

impl PeakLimit {
    /// The transient model of evaluation `ev` on the fixed grid and the aggregate.
    pub fn evaluate(
        &self,
        ev: &Evaluation,
    ) -> Result<
        (
            crate::gust::discrete::TransientModel,
            crate::gust::discrete::PeakKs,
        ),
        anyhow::Error,
    > {
        let p = ev.problem();
        let derivative = self.constraint.derivatives(p.outputs.len());
        let mut model =
            crate::gust::discrete::TransientModel::new(&p, &derivative, self.grid.clone())
                .context("discrete gust peak")?;
        let ks = crate::gust::discrete::PeakKs::evaluate(
            &mut model,
            &self.constraint.gusts,
            self.constraint.output,
            self.constraint.limit,
        );
        Ok((model, ks))
    }
}

/// A modal basis chosen by a frequency cutoff, kept so through an optimization: the constraints
/// see a fixed count of modes (`retained`, the count below the cutoff at the initial design: a
/// count that changed between iterations would make the constraints jump), and the modes they
/// leave out must stay above the cutoff. So at every design the retained modes are every mode
/// below the cutoff, and the optimizer cannot thin the wing until modes it does not see fall into
/// the flutter range.
///
/// The constraint is the KS aggregate of gⱼ = 1 − ω²ⱼ/ω²_cut over the `band` modes above the
/// retained ones, not the first of them alone: an optimum pushes several modes onto the cutoff
/// together (the flagship's DLM optimum had modes 12, 13 and 14 within 0.2 Hz of 226.4 Hz), where
/// the lowest eigenvalue has a kink and the SQP crawls (steps of 2⁻¹⁸, 76 iterations). A sum
/// over a whole cluster of eigenvalues is smooth where they cross; the band reaches far enough
/// up (as many modes as are retained: the resolution check's doubled basis) that the modes at its
/// edge weigh nothing, and the first mode beyond it must stay above [`FLOOR_GUARD`] × the cutoff
/// (an evaluation where it does not is refused).
#[derive(Clone, Copy, Debug)]
pub struct ModeFloor {
    pub retained: usize,
    pub omega_cut: f64,
    /// Modes retained+1 ..= retained+band enter the aggregate.
    pub band: usize,
}

/// The most the floor's KS aggregate may exceed the largest gⱼ, ln(band)/ρ (a fraction of
/// ω²_cut): with every mode of the band on the cutoff the modes are kept 1 % of the cutoff
/// frequency above it, with two 0.3 % (band 11); the sharpness ρ follows from the band.
pub const FLOOR_KS_BIAS: f64 = 0.02;

/// The first mode beyond the floor's band must stay above this multiple of the cutoff frequency
/// (there its KS weight is below e^{−0.21 ρ}, 1e-11 for the flagship's ρ = 120).
pub const FLOOR_GUARD: f64 = 1.1;

impl ModeFloor {
    /// The floor of a basis of `retained` modes below `omega_cut` (rad/s), its band as wide as
    /// the basis (at least 2 modes, at most the `dofs` − retained − 1 the plate has left).
    pub fn new(retained: usize, omega_cut: f64, dofs: usize) -> Self {
        let room = dofs.saturating_sub(retained + 1).max(1);
        Self {
            retained,
            omega_cut,
            band: retained.max(2).min(room),
        }
    }

    /// The KS sharpness ρ = ln(band)/[`FLOOR_KS_BIAS`].
    pub fn rho(&self) -> f64 {
        (self.band.max(2) as f64).ln() / FLOOR_KS_BIAS
    }

    /// gⱼ = 1 − ω²ⱼ/ω²_cut of the band's modes.
    fn margins(&self, modes: &crate::structure::Modes) -> Vec<f64> {
        let w2 = self.omega_cut * self.omega_cut;
        modes.modes[self.retained..self.retained + self.band]
            .iter()
            .map(|m| 1.0 - m.lambda / w2)
            .collect()
    }

    /// The modes of `plate` up to the first one beyond the band, and the constraint's value;
    /// an error where that mode has come below [`FLOOR_GUARD`] × the cutoff.
    pub fn evaluate(
        &self,
        selection: &ModeSelection,
        plate: &crate::structure::PlateModel,
    ) -> anyhow::Result<(crate::structure::Modes, f64)> {
        let last = self.retained + self.band;
        // the guard mode where the plate has one (a plate with no mode beyond the band has none)
        let modes = selection
            .solve_count(plate, (last + 1).min(selection.retained_dofs(plate)))
            .context("modal basis floor")?;
        let to_hz = |w: f64| w / (2.0 * std::f64::consts::PI);
        if let Some(beyond) = modes.modes.get(last) {
            let f = beyond.lambda.max(0.0).sqrt();
            if f < FLOOR_GUARD * self.omega_cut {
                anyhow::bail!(
                    "modal basis floor: mode {} has come down to {:.1} Hz, below {FLOOR_GUARD} × the cutoff {:.1} Hz: beyond the {} modes (from mode {}) the floor keeps above the cutoff",
                    last + 1,
                    to_hz(f),
                    to_hz(self.omega_cut),
                    self.band,
                    self.retained + 1
                );
            }
        }
        let (ks, _) = crate::flutter::margin::ks_max(&self.margins(&modes), self.rho());
        Ok((modes, ks))
    }

    /// The constraint's gradient in the design variables: the KS weights times the eigenvalue
    /// derivatives φⱼᵀ(∂K − λⱼ ∂M)φⱼ (the weighted sum over a cluster does not depend on which
    /// basis of its eigenspace the solver returned, for equal eigenvalues have equal weights).
    pub fn gradient(
        &self,
        plate: &crate::structure::PlateModel,
        modes: &crate::structure::Modes,
    ) -> Vec<f64> {
        let (_, weights) = crate::flutter::margin::ks_max(&self.margins(modes), self.rho());
        let mut seed = crate::structure::ModalSeed::zeros(modes);
        for (j, w) in weights.iter().enumerate() {
            seed.lambda[self.retained + j] = -w / (self.omega_cut * self.omega_cut);
        }
        crate::structure::modes_vjp(plate, modes, &seed)
    }
}

/// KS weights and the p-k roots of the last flutter-margin evaluation.
type FlutterState = (Vec<f64>, DampingSeed);

/// The transient model and KS aggregate of the last peak-limit evaluation.
type PeakState = (
    crate::gust::discrete::TransientModel,
    crate::gust::discrete::PeakKs,
);

/// The last point evaluated with what its gradient needs.
type LastEvaluation = (
    Evaluation,
    Option<FlutterState>,
    Option<crate::structure::Modes>,
    Option<PeakState>,
);

/// The design problem of a case; caches the last evaluation for its gradient.
pub struct DesignProblem<'a> {
    pub case: &'a Case,
    pub settings: GustSettings,
    pub spec: DesignSpec,
    last: Option<LastEvaluation>,
    /// The largest p-k damping up to the margin speed at every point evaluated (with a flutter
    /// margin): the quantity the KS constraint bounds, for the report.
    pub damping_peaks: Vec<(Vec<f64>, f64)>,
    /// The peak KS aggregate and the largest sampled |y| over the limit at every point evaluated
    /// (with a peak limit), for the report.
    pub peak_values: Vec<(Vec<f64>, f64, f64)>,
    /// Wall time of every function (values) and gradient evaluated, s.
    pub function_times: Vec<f64>,
    pub gradient_times: Vec<f64>,
    /// An LFD model's GMRES iterations a right-hand side in every function's GAF table and in
    /// every gradient's adjoint solves (empty for other fidelities).
    pub function_gmres: Vec<f64>,
    pub gradient_gmres: Vec<f64>,
}

impl<'a> DesignProblem<'a> {
    pub fn new(case: &'a Case, settings: GustSettings, spec: DesignSpec) -> Self {
        Self {
            case,
            settings,
            spec,
            last: None,
            damping_peaks: Vec::new(),
            peak_values: Vec::new(),
            function_times: Vec::new(),
            gradient_times: Vec::new(),
            function_gmres: Vec::new(),
            gradient_gmres: Vec::new(),
        }
    }

    /// The LFD warm-start store's last GMRES iterations a right-hand side (table, adjoints).
    fn gmres_per_rhs(&self) -> (Option<f64>, Option<f64>) {
        match &self.case.cache_dir {
            Some(dir) => crate::aero::lfd::warm_start_iterations(dir),
            None => (None, None),
        }
    }

    /// The last evaluation (at the last point asked for).
    pub fn last(&self) -> Option<&Evaluation> {
        self.last.as_ref().map(|l| &l.0)
    }
}

/// The records a [`DesignProblem`] keeps with each checkpoint, so that a resumed run reports the
/// damping peaks and evaluation times of the whole run without evaluating again.
#[derive(serde::Serialize, serde::Deserialize)]
struct Records {
    damping_peaks: Vec<(Vec<f64>, f64)>,
    function_times: Vec<f64>,
    gradient_times: Vec<f64>,
    #[serde(default)]
    function_gmres: Vec<f64>,
    #[serde(default)]
    gradient_gmres: Vec<f64>,
}

impl Problem for DesignProblem<'_> {
    fn lower(&self) -> Vec<f64> {
        self.spec.lower.clone()
    }
    fn state(&self) -> serde_json::Value {
        serde_json::to_value(Records {
            damping_peaks: self.damping_peaks.clone(),
            function_times: self.function_times.clone(),
            gradient_times: self.gradient_times.clone(),
            function_gmres: self.function_gmres.clone(),
            gradient_gmres: self.gradient_gmres.clone(),
        })
        .unwrap_or(serde_json::Value::Null)
    }
    fn restore(&mut self, state: &serde_json::Value) -> Result<(), EvalError> {
        // a checkpoint of an older revision has no records: the report evaluates what it needs
        if state.is_null() {
            return Ok(());
        }
        let r: Records = serde_json::from_value(state.clone())?;
        // the records of the earlier sessions come first, in the order they were made
        self.damping_peaks.splice(0..0, r.damping_peaks);
        self.function_times.splice(0..0, r.function_times);
        self.gradient_times.splice(0..0, r.gradient_times);
        self.function_gmres.splice(0..0, r.function_gmres);
        self.gradient_gmres.splice(0..0, r.gradient_gmres);
        Ok(())
    }
    fn upper(&self) -> Vec<f64> {
        self.spec.upper.clone()
    }
    fn values(&mut self, x: &[f64]) -> Result<Values, EvalError> {
        let t0 = std::time::Instant::now();
        let ev = evaluate(self.case, &self.settings, x)?;
        let mut ineq = vec![ev.rms_m[self.spec.output] / self.spec.rms_limit - 1.0];
        let mut flutter = None;
        if let Some(m) = &self.spec.flutter {
            let (ks, weights, seed) = ev.flutter_damping(m)?;
            ineq.push((ks - m.damping_max) / DAMPING_SCALE);
            self.damping_peaks.push((x.to_vec(), seed.peak()));
            flutter = Some((weights, seed));
        }
        let mut floor_modes = None;
        if let Some(floor) = &self.spec.mode_floor {
            let (modes, c) = floor.evaluate(&self.case.modes, &ev.plate)?;
            ineq.push(c);
            floor_modes = Some(modes);
        }
        let mut peak = None;
        if let Some(pl) = &self.spec.peak {
            let (model, ks) = pl.evaluate(&ev)?;
            ineq.push(ks.ks - 1.0);
            self.peak_values.push((x.to_vec(), ks.ks, ks.peak));
            peak = Some((model, ks));
        }
        let v = Values {
            f: ev.mass_kg / self.spec.mass0,
            eq: if self.spec.fix_area {
                vec![ev.area_m2 / self.spec.area0 - 1.0]
            } else {
                Vec::new()
            },
            ineq,
        };
        self.last = Some((ev, flutter, floor_modes, peak));
        self.function_times.push(t0.elapsed().as_secs_f64());
        if let (Some(per_rhs), _) = self.gmres_per_rhs() {
            self.function_gmres.push(per_rhs);
        }
        Ok(v)
    }
    fn gradients(&mut self, x: &[f64]) -> Result<Gradients, EvalError> {
        if self.last.as_ref().is_none_or(|e| e.0.x != x) {
            self.values(x)?;
        }
        // the peak's reverse mode through its transient model (taken out for the mutable FFT
        // plan, put back after)
        let mut peak_state = self.last.as_mut().and_then(|l| l.3.take());
        let peak_gradient = match (&self.spec.peak, peak_state.as_mut()) {
            (Some(pl), Some((model, ks))) => {
                let ev = &self.last.as_ref().expect("evaluated").0;
                Some(
                    ks.vjp(model, &ev.problem(), &pl.constraint.gusts, 1.0)
                        .context("discrete gust peak reverse mode")?,
                )
            }
            _ => None,
        };
        if let Some(l) = self.last.as_mut() {
            l.3 = peak_state;
        }
        let (ev, flutter, floor_modes, _) = self.last.as_ref().expect("evaluated");
        let n_out = ev.rms_m.len();
        let seeds = |mass: f64, area: f64, rms: f64| OutputSeeds {
            mass,
            area,
            rms: (0..n_out)
                .map(|i| if i == self.spec.output { rms } else { 0.0 })
                .collect(),
            damping: None,
            gust: None,
        };
        let mut all = vec![
            seeds(1.0 / self.spec.mass0, 0.0, 0.0),
            seeds(0.0, 1.0 / self.spec.area0, 0.0),
            seeds(0.0, 0.0, 1.0 / self.spec.rms_limit),
        ];
        if let Some((weights, seed)) = flutter {
            let mut s = seeds(0.0, 0.0, 0.0);
            let mut d = seed.clone();
            d.g_bar = weights.iter().map(|w| w / DAMPING_SCALE).collect();
            s.damping = Some(d);
            all.push(s);
        }
        let has_peak = peak_gradient.is_some();
        if let Some(gg) = peak_gradient {
            let mut s = seeds(0.0, 0.0, 0.0);
            s.gust = Some(gg);
            all.push(s);
        }
        let t0 = std::time::Instant::now();
        let mut g = gradients(ev, &all)?.into_iter();
        self.gradient_times.push(t0.elapsed().as_secs_f64());
        if let (_, Some(per_rhs)) = self.gmres_per_rhs() {
            self.gradient_gmres.push(per_rhs);
        }
        let (f, h) = (g.next().expect("mass"), g.next().expect("area"));
        let mut ineq: Vec<Vec<f64>> = g.collect();
        // the order of the values: RMS, flutter margin, mode floor, peak
        let peak = if has_peak { ineq.pop() } else { None };
        if let (Some(floor), Some(modes)) = (&self.spec.mode_floor, floor_modes) {
            ineq.push(floor.gradient(&ev.plate, modes));
        }
        ineq.extend(peak);
        Ok(Gradients {
            f,
            eq: if self.spec.fix_area {
                vec![h]
            } else {
                Vec::new()
            },
            ineq,
        })
    }
}
