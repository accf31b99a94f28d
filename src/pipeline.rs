//! The forward evaluation design vector → outputs, and its adjoint, stage by stage.
//!
//! Forward: x → plate model (mass, area) → modes → transfer → GAFs → gust response (RMS of each
//! output). Reverse: one sweep back through the same stages; each stage offers the product of its
//! own Jacobian transpose, and the chain rule lives here only.
//!
//! Complex-to-real derivatives (paper Sec. III): the RMS is real while the GAFs, η and H are
//! complex; every complex seed Q̄ here is ∂J/∂Re Q + i ∂J/∂Im Q, so that dJ = Re(conj(Q̄) dQ).
//! This is the "flip the sign of the imaginary part" of the paper: the linearization of J with
//! respect to a complex state z is conj(Q̄)ᵀ, not Q̄ᵀ.

use crate::aero::AeroModel;
use crate::case::{Case, StudyError};
use crate::flutter::margin::{ks_max, ks_rho, zeros_like, DampingRoot, FlutterMargin, PK_STEPS};
use crate::flutter::{check_stability, PkProblem};
use crate::gust::{
    self, FrequencyGrid, GustProblem, GustResponse, GustSettings, Quantity, ResidualGafs,
};
use crate::structure::modal::SAMPLED;
use crate::structure::residual::{residual_shapes, residual_shapes_vjp};
use crate::structure::{
    mass_grad, modes_vjp, root_bending_moment, root_bending_moment_vjp, ModalSeed, Modes,
    PlateModel, Sampler,
};
use crate::wing::{DesignVector, N_PLANFORM};
use anyhow::{Context, Result};
use gustkit_core::GafTable;

/// One evaluation of the design, with what the adjoint needs.
pub struct Evaluation {
    pub x: Vec<f64>,
    pub mass_kg: f64,
    pub area_m2: f64,
    pub freq_hz: Vec<f64>,
    /// RMS of each output, m.
    pub rms_m: Vec<f64>,
    /// Zero-crossing rate of each output, Hz.
    pub n0_hz: Vec<f64>,
    pub plate: PlateModel,
    pub modes: Modes,
    pub aero: AeroModel,
    pub table: GafTable,
    pub grid: FrequencyGrid,
    pub response: GustResponse,
    samplers: Vec<Option<Sampler>>,
    outputs_s: Vec<Vec<f64>>,
    /// The outputs' residual shapes and their GAF rows (mode acceleration), if the study asks.
    pub residual: Option<Residual>,
    settings: GustSettings,
}

/// The mode-acceleration part of a model: each output's residual shape (nodal) and GAF rows.
#[derive(Clone, Debug)]
pub struct Residual {
    pub shapes: Vec<Vec<f64>>,
    pub gafs: ResidualGafs,
}

/// The samplers of the gust outputs: a point's for a displacement, none for the root moment.
fn output_samplers(plate: &PlateModel, settings: &GustSettings) -> Vec<Option<Sampler>> {
    settings
        .outputs
        .iter()
        .map(|o| match o.quantity {
            Quantity::Displacement { point } => Some(Sampler::new(plate, &[point])),
            Quantity::RootBendingMoment => None,
        })
        .collect()
}

/// The modes followed by the residual shapes, as the aerodynamic model takes them.
fn with_residual<'a>(modes: &'a Modes, shapes: &'a [Vec<f64>]) -> Vec<&'a [f64]> {
    let mut all = crate::transfer::mode_shapes(modes);
    all.extend(shapes.iter().map(Vec::as_slice));
    all
}

/// The GAF table of the modes and, with mode acceleration, the residual rows, from one call of
/// the aerodynamic model (its factorizations shared).
pub(crate) fn tables(
    plate: &PlateModel,
    modes: &Modes,
    aero: &AeroModel,
    settings: Option<&GustSettings>,
) -> Result<(GafTable, Option<Residual>)> {
    tables_in_groups(
        plate,
        modes,
        aero,
        settings,
        aero.k.len(),
        None,
        &mut |_| Ok(()),
    )
}

/// How many shapes [`tables`] gives GAFs of: the modes and, with mode acceleration, the
/// residual shapes.
pub(crate) fn table_shapes(
    plate: &PlateModel,
    modes: &Modes,
    settings: Option<&GustSettings>,
) -> usize {
    modes.len()
        + settings.filter(|s| s.mode_acceleration).map_or(0, |s| {
            residual_shapes(plate, modes, &output_samplers(plate, s)).len()
        })
}

/// [`tables`] in groups of `group` reduced frequencies (one a thread gives the parallelism of
/// the whole table), for a table too long to lose: the rows of `done` (a partial table of the
/// same shapes, in any order) are not computed again, and `keep` receives the rows computed so
/// far (`done`'s and the new ones) after each group — a checkpoint. Each frequency's GAFs are
/// independent of the others', so the table is the one [`tables`] gives.
pub(crate) fn tables_in_groups(
    plate: &PlateModel,
    modes: &Modes,
    aero: &AeroModel,
    settings: Option<&GustSettings>,
    group: usize,
    done: Option<GafTable>,
    keep: &mut dyn FnMut(&GafTable) -> Result<()>,
) -> Result<(GafTable, Option<Residual>)> {
    let shapes = match settings.filter(|s| s.mode_acceleration) {
        Some(settings) => residual_shapes(plate, modes, &output_samplers(plate, settings)),
        None => Vec::new(),
    };
    let all_shapes = with_residual(modes, &shapes);
    let surface = aero.transfer.shapes_on_surface(plate, &all_shapes);
    let mut rows = done.unwrap_or_else(|| GafTable::zeros(&aero.flight, &[], all_shapes.len()));
    let todo: Vec<f64> = aero
        .k
        .iter()
        .copied()
        .filter(|k| !rows.k.iter().any(|&d| gustkit_core::aero::same_k(d, *k)))
        .collect();
    for ks in todo.chunks(group.max(1)) {
        let part = aero
            .fidelity
            .gafs(&aero.flight, &surface, ks)
            .map_err(|e| anyhow::Error::new(e).context("aerodynamics"))?;
        rows.k.extend(part.k);
        rows.q_ss.extend(part.q_ss);
        rows.q_gs.extend(part.q_gs);
        keep(&rows)?;
    }
    // the rows in the study's order
    let mut all = GafTable::zeros(&aero.flight, &aero.k, all_shapes.len());
    for (i, k) in aero.k.iter().enumerate() {
        let j = rows
            .k
            .iter()
            .position(|&d| gustkit_core::aero::same_k(d, *k))
            .expect("every k computed or done");
        all.q_ss[i] = rows.q_ss[j].clone();
        all.q_gs[i] = rows.q_gs[j].clone();
    }
    if shapes.is_empty() {
        return Ok((all, None));
    }
    let (table, gafs) = ResidualGafs::split(&all, modes.len());
    Ok((table, Some(Residual { shapes, gafs })))
}

impl Evaluation {
    fn pk(&self) -> PkProblem<'_> {
        PkProblem::new(&self.modes, &self.table, self.aero.flight.density)
    }

    /// The p-k roots at every speed up to the margin speed of `m`, and the KS aggregate of their
    /// dampings with its weights.
    pub fn flutter_damping(&self, m: &FlutterMargin) -> Result<(f64, Vec<f64>, DampingSeed)> {
        let velocity = m.speed_factor * self.aero.flight.velocity;
        let roots = self
            .pk()
            .roots_up_to(velocity, PK_STEPS)
            .map_err(|e| anyhow::anyhow!("flutter margin at {velocity:.2} m/s: {e}"))?;
        let g: Vec<f64> = roots.iter().map(|r| r.g).collect();
        let (ks, weights) = ks_max(&g, ks_rho(g.len()));
        Ok((
            ks,
            weights,
            DampingSeed {
                g_bar: vec![0.0; roots.len()],
                roots,
            },
        ))
    }

    /// The gust settings it was evaluated with.
    pub fn settings(&self) -> &GustSettings {
        &self.settings
    }

    /// The stochastic gust problem of this evaluation (Eqs. 16–18 on its grid).
    pub fn problem(&self) -> GustProblem<'_> {
        GustProblem {
            omega_n: self.modes.omega(),
            damping_ratio: self.modes.damping_ratio,
            table: &self.table,
            q_inf: self.aero.flight.q_inf(),
            velocity: self.aero.flight.velocity,
            turbulence: self.settings.turbulence,
            grid: self.grid.clone(),
            outputs: self.outputs_s.clone(),
            max_tail: self.settings.max_tail,
            residual: self.residual.as_ref().map(|r| &r.gafs),
        }
    }
}

/// Seeds on the outputs for [`gradient`].
#[derive(Clone, Debug, Default)]
pub struct OutputSeeds {
    pub mass: f64,
    pub area: f64,
    /// One per gust output (RMS in m).
    pub rms: Vec<f64>,
    /// Seeds on the damping of p-k roots at one speed.
    pub damping: Option<DampingSeed>,
    /// Seeds already carried back to the modal gust problem (GAF table, ω_n², output vectors,
    /// residual rows) by a functional of the transfer functions of its own (a discrete gust
    /// peak, [`crate::gust::discrete::PeakKs::vjp`]).
    pub gust: Option<crate::gust::GustGradient>,
}

/// Seeds `g_bar` on the damping of p-k `roots` (from [`Evaluation::flutter_damping`]).
#[derive(Clone, Debug)]
pub struct DampingSeed {
    pub roots: Vec<DampingRoot>,
    pub g_bar: Vec<f64>,
}

impl DampingSeed {
    /// The largest damping of the roots: what the KS aggregate bounds from above.
    pub fn peak(&self) -> f64 {
        self.roots
            .iter()
            .map(|r| r.g)
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// A design's aeroelastic model: plate, modes, aerodynamic model and its GAF table.
pub struct Aeroelastic {
    pub x: Vec<f64>,
    pub plate: PlateModel,
    pub modes: Modes,
    pub aero: AeroModel,
    pub table: GafTable,
    /// The residual rows of the gust outputs, where the model was made for a gust response by
    /// the mode-acceleration method ([`respond`] makes them otherwise).
    pub residual: Option<Residual>,
}

/// Evaluates a design of the case.
pub fn evaluate(case: &Case, settings: &GustSettings, x: &[f64]) -> Result<Evaluation> {
    respond(aeroelastic_for(case, x, Some(settings))?, settings)
}

/// The aeroelastic model of a design: plate, modes, aerodynamic model, GAFs.
pub fn aeroelastic(case: &Case, x: &[f64]) -> Result<Aeroelastic> {
    aeroelastic_for(case, x, None)
}

/// [`aeroelastic`], with the residual rows of the outputs of `settings` where they ask for the
/// mode-acceleration method.
pub fn aeroelastic_for(
    case: &Case,
    x: &[f64],
    settings: Option<&GustSettings>,
) -> Result<Aeroelastic> {
    let plate = case
        .model_at(DesignVector::from_slice(x))
        .map_err(|e: StudyError| anyhow::anyhow!("design: {}", e.reason))?;
    // the aerodynamic model and what of it does not need the modes (a DLM's influence matrices)
    // run beside the modal analysis
    let (modes, aero) = rayon::join(
        || case.solve_modes(&plate).context("modal analysis"),
        || {
            let aero = case.aero_model(&plate)?;
            aero.fidelity.prepare(&aero.flight, &aero.k);
            anyhow::Ok(aero)
        },
    );
    let (modes, aero) = (modes?, aero?);
    let (table, residual) = tables(&plate, &modes, &aero, settings)?;
    Ok(Aeroelastic {
        x: x.to_vec(),
        plate,
        modes,
        aero,
        table,
        residual,
    })
}

/// The gust response of an aeroelastic model (Eqs. 16–18), after the check that it is stable at
/// the flight condition (an unstable model has no stationary response).
pub fn respond(a: Aeroelastic, settings: &GustSettings) -> Result<Evaluation> {
    let Aeroelastic {
        x,
        plate,
        modes,
        aero,
        table,
        residual,
    } = a;
    let residual = match residual {
        Some(r) => Some(r),
        None if settings.mode_acceleration => tables(&plate, &modes, &aero, Some(settings))?.1,
        None => None,
    };
    let f = &aero.flight;
    let omega_max = table.k.last().copied().unwrap_or(0.0) * f.velocity / f.b_ref;
    let grid = FrequencyGrid::log(settings.omega_min, omega_max, settings.points)?;
    let samplers = output_samplers(&plate, settings);
    let outputs_s: Vec<Vec<f64>> = samplers
        .iter()
        .map(|s| match s {
            Some(s) => modes
                .modes
                .iter()
                .map(|m| s.sample(&plate, &m.shape)[0][0])
                .collect(),
            None => root_bending_moment(&plate, &modes),
        })
        .collect();
    let mut ev = Evaluation {
        x,
        mass_kg: plate.mass(),
        area_m2: plate.planform().area(),
        freq_hz: modes.freq_hz(),
        rms_m: Vec::new(),
        n0_hz: Vec::new(),
        plate,
        modes,
        aero,
        table,
        grid,
        response: GustResponse::default(),
        samplers,
        outputs_s,
        residual,
        settings: settings.clone(),
    };
    // the stability check and the response side by side (the p-k's few roots a speed leave a
    // thread idle that the response's frequencies fill); an unstable model's error comes first
    let (stable, response) = rayon::join(
        || check_stability(&ev.modes, &ev.table, &ev.aero.flight),
        || gust::solve(&ev.problem()),
    );
    // an input that cannot give a response (a grid that leaves turbulence out) is named before
    // any verdict on the model's stability, which such input may not reach
    if let Err(e @ (gust::GustError::Input(_) | gust::GustError::GridTooShort { .. })) = &response {
        return Err(anyhow::Error::new(e.clone()));
    }
    stable?;
    let response = response?;
    ev.rms_m = response.rms.clone();
    ev.n0_hz = response.n0.clone();
    ev.response = response;
    Ok(ev)
}

/// A design analysed for a report or a comparison: its gust response, or, where its model is
/// unstable at the flight condition (no stationary response exists), the model and the verdict's
/// words. The one analysis of a design with any fidelity: the analysis run's second fidelity, the
/// optimization's cross-evaluation and the resolution check all take it.
pub enum Analysis {
    Response(Box<Evaluation>),
    Unstable {
        model: Box<Aeroelastic>,
        reason: String,
    },
}

impl Analysis {
    /// The aerodynamic model, modes and GAF table of the design (either way).
    pub fn parts(&self) -> (&AeroModel, &Modes, &GafTable) {
        match self {
            Analysis::Response(ev) => (&ev.aero, &ev.modes, &ev.table),
            Analysis::Unstable { model, .. } => (&model.aero, &model.modes, &model.table),
        }
    }

    /// The gust response, or why there is none.
    pub fn response(&self) -> std::result::Result<&Evaluation, &str> {
        match self {
            Analysis::Response(ev) => Ok(ev),
            Analysis::Unstable { reason, .. } => Err(reason),
        }
    }
}

/// The stability verdict of a model at the flight condition and, where it is stable, its gust
/// response ([`Analysis`]).
pub fn analyse(a: Aeroelastic, settings: &GustSettings) -> Result<Analysis> {
    if let Err(e) = check_stability(&a.modes, &a.table, &a.aero.flight) {
        return Ok(Analysis::Unstable {
            model: Box::new(a),
            reason: format!("{e:#}"),
        });
    }
    Ok(Analysis::Response(Box::new(respond(a, settings)?)))
}

/// Gradient of Σ seeds · outputs with respect to the design vector, in one reverse sweep.
pub fn gradient(ev: &Evaluation, seeds: &OutputSeeds) -> Result<Vec<f64>> {
    let mut g = gradients(ev, std::slice::from_ref(seeds))?;
    Ok(g.pop().expect("one seed, one gradient"))
}

/// One gradient per set of seeds, with a single reverse pass through the aerodynamic model for
/// all of them (its influence matrices, factorizations and geometry derivatives are shared).
pub fn gradients(ev: &Evaluation, all: &[OutputSeeds]) -> Result<Vec<Vec<f64>>> {
    let n = ev.x.len();
    // stage 1, per seed set: direct terms, and seeds on the GAF table, ω_n², shapes, planform
    struct Partial {
        g: Vec<f64>,
        modal_seed: ModalSeed,
        p_bar: [f64; N_PLANFORM],
        table_bar: Option<GafTable>,
        rows_bar: Option<ResidualGafs>,
    }
    let mut partials = Vec::with_capacity(all.len());
    for seeds in all {
        let mut g = vec![0.0; n];
        if seeds.mass != 0.0 {
            for (gi, mi) in g.iter_mut().zip(mass_grad(&ev.plate)) {
                *gi += seeds.mass * mi;
            }
        }
        if seeds.area != 0.0 {
            for (k, a) in ev.plate.planform().area_grad().iter().enumerate() {
                g[n - N_PLANFORM + k] += seeds.area * a;
            }
        }
        let mut modal_seed = ModalSeed::zeros(&ev.modes);
        let mut p_bar = [0.0; N_PLANFORM];
        let mut rows_bar = None;
        let rms_seeded = seeds.rms.iter().any(|s| *s != 0.0);
        let table_bar = if rms_seeded || seeds.damping.is_some() || seeds.gust.is_some() {
            let mut table_bar = zeros_like(&ev.table);
            // p-k dampings → GAF table, ω_n²
            if let Some(d) = &seeds.damping {
                let pk = ev.pk();
                for (root, g_bar) in d.roots.iter().zip(&d.g_bar) {
                    if *g_bar == 0.0 {
                        continue;
                    }
                    let (om_bar, t_bar) = pk
                        .damping_vjp(root, *g_bar)
                        .map_err(|e| anyhow::anyhow!("flutter margin reverse mode: {e}"))?;
                    for (l, v) in modal_seed.lambda.iter_mut().zip(om_bar) {
                        *l += v;
                    }
                    add_table(&mut table_bar, &t_bar);
                }
            }
            let mut modal_parts = Vec::new();
            if rms_seeded {
                modal_parts.push(gust::rms_vjp(&ev.problem(), &ev.response, &seeds.rms)?);
            }
            if let Some(gg) = &seeds.gust {
                modal_parts.push(gg.clone());
            }
            for gg in modal_parts {
                let rows = gust_seeds(ev, gg, &mut table_bar, &mut modal_seed, &mut p_bar, &mut g);
                rows_bar = match (rows_bar, rows) {
                    (Some(mut a), Some(b)) => {
                        add_rows(&mut a, &b);
                        Some(a)
                    }
                    (a, b) => a.or(b),
                };
            }
            Some(table_bar)
        } else {
            None
        };
        partials.push(Partial {
            g,
            modal_seed,
            p_bar,
            table_bar,
            rows_bar,
        });
    }
    // stage 2: GAFs → mode shapes on the aerodynamic surface, aerodynamic geometry, transfer
    // (with mode acceleration, the shapes are the modes followed by the residual shapes)
    let n_modes = ev.modes.len();
    let tables: Vec<GafTable> = partials
        .iter()
        .filter_map(|p| {
            let t = p.table_bar.as_ref()?;
            Some(match &ev.residual {
                None => t.clone(),
                Some(r) => {
                    let zero = ResidualGafs::zeros(t.k.len(), r.shapes.len(), n_modes);
                    ResidualGafs::join(t, p.rows_bar.as_ref().unwrap_or(&zero))
                }
            })
        })
        .collect();
    let mut aero = if tables.is_empty() {
        Vec::new()
    } else {
        let shapes = match &ev.residual {
            None => crate::transfer::mode_shapes(&ev.modes),
            Some(r) => with_residual(&ev.modes, &r.shapes),
        };
        ev.aero
            .gafs_vjp_many_shapes(&ev.plate, &shapes, &tables)
            .map_err(|e| anyhow::anyhow!("aerodynamics reverse mode: {e}"))?
    }
    .into_iter();
    // stage 3: modes → design
    let mut out = Vec::with_capacity(partials.len());
    for mut p in partials {
        if p.table_bar.is_some() {
            let (shapes, pb) = aero.next().expect("one aerodynamic gradient per table");
            for (m, s) in shapes.iter().take(n_modes).enumerate() {
                add_into(&mut p.modal_seed.shape[m], s);
            }
            if shapes.len() > n_modes {
                // residual shapes → modes, stiffness, mass, output geometry
                let (seed, direct) =
                    residual_shapes_vjp(&ev.plate, &ev.modes, &ev.samplers, &shapes[n_modes..]);
                for m in 0..n_modes {
                    p.modal_seed.lambda[m] += seed.lambda[m];
                    if !seed.shape[m].is_empty() {
                        add_into(&mut p.modal_seed.shape[m], &seed.shape[m]);
                    }
                }
                for (gi, v) in p.g.iter_mut().zip(direct) {
                    *gi += v;
                }
            }
            for k in 0..N_PLANFORM {
                p.p_bar[k] += pb[k];
            }
            for (gi, v) in
                p.g.iter_mut()
                    .zip(modes_vjp(&ev.plate, &ev.modes, &p.modal_seed))
            {
                *gi += v;
            }
            for k in 0..N_PLANFORM {
                p.g[n - N_PLANFORM + k] += p.p_bar[k];
            }
        }
        out.push(p.g);
    }
    Ok(out)
}

/// acc += r over the residual rows.
fn add_rows(acc: &mut ResidualGafs, r: &ResidualGafs) {
    for (a, b) in acc
        .q_ws
        .iter_mut()
        .flatten()
        .flatten()
        .zip(r.q_ws.iter().flatten().flatten())
    {
        *a += b;
    }
    for (a, b) in acc.q_wg.iter_mut().flatten().zip(r.q_wg.iter().flatten()) {
        *a += b;
    }
}

/// The gust-response part of the reverse sweep: seeds on the modal gust problem (from the RMS or
/// a discrete gust peak) → seeds on the GAF table, on ω_n², on the output mode samples (mode
/// shapes, planform) and direct design terms; returns the seeds on the residual rows (mode
/// acceleration).
fn gust_seeds(
    ev: &Evaluation,
    gg: crate::gust::GustGradient,
    table_bar: &mut GafTable,
    modal_seed: &mut ModalSeed,
    p_bar: &mut [f64; N_PLANFORM],
    g: &mut [f64],
) -> Option<ResidualGafs> {
    add_table(table_bar, &gg.table);
    for (l, v) in modal_seed.lambda.iter_mut().zip(&gg.lambda) {
        *l += v;
    }
    // S = mode deflection at each output point, or the modal root bending moment
    for (y, sampler) in ev.samplers.iter().enumerate() {
        let Some(sampler) = sampler else {
            let (seed, direct) = root_bending_moment_vjp(&ev.plate, &ev.modes, &gg.outputs[y]);
            for m in 0..ev.modes.len() {
                modal_seed.lambda[m] += seed.lambda[m];
                if !seed.shape[m].is_empty() {
                    add_into(&mut modal_seed.shape[m], &seed.shape[m]);
                }
            }
            for (gi, v) in g.iter_mut().zip(direct) {
                *gi += v;
            }
            continue;
        };
        for (m, mode) in ev.modes.modes.iter().enumerate() {
            let s = gg.outputs[y][m];
            if s == 0.0 {
                continue;
            }
            let mut seed = [0.0; SAMPLED];
            seed[0] = s;
            let (nodal, pb) = sampler.sample_vjp(&ev.plate, &mode.shape, &[seed]);
            add_into(&mut modal_seed.shape[m], &nodal);
            for k in 0..N_PLANFORM {
                p_bar[k] += pb[k];
            }
        }
    }
    gg.residual
}

/// acc += t over both parts of a GAF table.
fn add_table(acc: &mut GafTable, t: &GafTable) {
    for (a, b) in acc
        .q_ss
        .iter_mut()
        .flatten()
        .flatten()
        .zip(t.q_ss.iter().flatten().flatten())
    {
        *a += b;
    }
    for (a, b) in acc.q_gs.iter_mut().flatten().zip(t.q_gs.iter().flatten()) {
        *a += b;
    }
}

fn add_into(acc: &mut Vec<f64>, v: &[f64]) {
    if acc.is_empty() {
        acc.extend_from_slice(v);
    } else {
        for (a, b) in acc.iter_mut().zip(v) {
            *a += b;
        }
    }
}
