//! Design variables on a Nastran model's properties, related the way SOL 200's DVPREL1 relates
//! them (property = C0 + Σ COEFᵢ · xᵢ), and what an optimization of the model needs at a
//! design: its structural mass, the random gust response of the outputs it constrains, and
//! their exact derivatives with respect to every design variable.
//!
//! The derivatives are forward mode, one design variable at a time, sharing the design's
//! response: per variable, ∂K and ∂M of the properties it moves (exact, `Structure::
//! shell_thickness_derivative`, `Structure::bar_property_derivative`), Nelson's mode
//! derivatives, and the response's tangent (`random::random_response_derivatives`). Its
//! cost grows with the number of design variables, which suits the tens that sizing studies of
//! a wing's properties use.

use super::bulk::BulkData;
use super::random::{
    random_response_derivatives, random_response_vjp, random_response_with, KInterpolation, Lfd,
    ModeDirection, Quantity, RandomDerivative, RandomRow,
};
use super::structure::{
    constrained, mode_adjoint, mode_derivatives, subcase_modes, BarDimension, RealModes, Structure,
};
use super::{NastranError, Subcase};
use faer::Mat;

type R<T> = Result<T, NastranError>;

/// The property field a relation sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PropertyField {
    /// PSHELL's T.
    ShellThickness,
    /// PBAR's or PBEAM's A, I1, I2 or J.
    Bar(BarDimension),
}

/// One DVPREL1-like relation: the field `field` of property `pid` is `c0 + Σ coef · x[dv]`.
#[derive(Clone, Debug, PartialEq)]
pub struct PropertyRelation {
    /// The card as the user named it (PSHELL, PBAR or PBEAM).
    pub card: String,
    pub pid: u32,
    /// The field's name as the user wrote it (T, A, I1, I2, J).
    pub field_name: String,
    pub field: PropertyField,
    pub c0: f64,
    /// (design variable index, coefficient).
    pub terms: Vec<(usize, f64)>,
}

impl PropertyRelation {
    /// A relation checked against the model: the card names a property of the model whose
    /// kind has the field. The error names the card, the id and what the model has.
    pub fn new(
        b: &BulkData,
        card: &str,
        pid: u32,
        field_name: &str,
        c0: f64,
        terms: Vec<(usize, f64)>,
    ) -> R<Self> {
        let card_up = card.to_ascii_uppercase();
        let what = format!("{card_up} {pid}");
        let field = match card_up.as_str() {
            "PSHELL" => {
                if !b.pshells.contains_key(&pid) {
                    return Err(NastranError::model(
                        &what,
                        "is not a property of the model (no PSHELL has this id)".into(),
                    ));
                }
                if !field_name.eq_ignore_ascii_case("T") {
                    return Err(NastranError::model(
                        &what,
                        format!("field {field_name} cannot be a design variable: PSHELL's is T"),
                    ));
                }
                PropertyField::ShellThickness
            }
            "PBAR" | "PBEAM" => {
                if !b.bar_properties.contains_key(&pid) {
                    return Err(NastranError::model(
                        &what,
                        "is not a property of the model (no PBAR or PBEAM has this id)".into(),
                    ));
                }
                let dim = BarDimension::from_field(field_name).ok_or_else(|| {
                    NastranError::model(
                        &what,
                        format!("field {field_name} cannot be a design variable: {card_up}'s are A, I1, I2 and J"),
                    )
                })?;
                PropertyField::Bar(dim)
            }
            _ => {
                return Err(NastranError::model(
                    &what,
                    "properties of PSHELL, PBAR and PBEAM cards can be design variables; this card cannot".into(),
                ))
            }
        };
        Ok(Self {
            card: card_up,
            pid,
            field_name: field_name.to_ascii_uppercase(),
            field,
            c0,
            terms,
        })
    }

    /// `PBAR 3 A`.
    pub fn label(&self) -> String {
        format!("{} {} {}", self.card, self.pid, self.field_name)
    }

    /// The field's value at design `x`.
    pub fn value(&self, x: &[f64]) -> f64 {
        self.c0 + self.terms.iter().map(|&(i, c)| c * x[i]).sum::<f64>()
    }

    /// The field's value in the model.
    pub fn current(&self, b: &BulkData) -> f64 {
        match self.field {
            PropertyField::ShellThickness => b.pshells[&self.pid].t,
            PropertyField::Bar(dim) => {
                let p = &b.bar_properties[&self.pid];
                match dim {
                    BarDimension::Area => p.area,
                    BarDimension::I1 => p.i1,
                    BarDimension::I2 => p.i2,
                    BarDimension::J => p.j,
                }
            }
        }
    }

    fn set(&self, b: &mut BulkData, v: f64) {
        match self.field {
            PropertyField::ShellThickness => {
                if let Some(p) = b.pshells.get_mut(&self.pid) {
                    p.t = v;
                }
            }
            PropertyField::Bar(dim) => {
                if let Some(p) = b.bar_properties.get_mut(&self.pid) {
                    match dim {
                        BarDimension::Area => p.area = v,
                        BarDimension::I1 => p.i1 = v,
                        BarDimension::I2 => p.i2 = v,
                        BarDimension::J => p.j = v,
                    }
                }
            }
        }
    }

    /// ∂K/∂p and ∂M/∂p (g-set) of this field.
    fn derivative(&self, s: &Structure, b: &BulkData) -> R<(Mat<f64>, Mat<f64>)> {
        match self.field {
            PropertyField::ShellThickness => s.shell_thickness_derivative(b, self.pid),
            PropertyField::Bar(dim) => s.bar_property_derivative(b, self.pid, dim),
        }
    }
}

/// The memory the forward mode may hold in design variables' dense ∂K and ∂M at once (a group
/// of variables is swept together, sharing one response; 16 n_g² bytes a variable).
const DERIVATIVE_BUDGET_BYTES: f64 = 2e9;

/// The model at design `x`: every related field set to its relation's value. A value that is
/// not positive (a section or thickness the elements cannot have) is refused naming the field.
pub fn apply(base: &BulkData, relations: &[PropertyRelation], x: &[f64]) -> R<BulkData> {
    let mut b = base.clone();
    for r in relations {
        let v = r.value(x);
        if !(v > 0.0 && v.is_finite()) {
            return Err(NastranError::model(
                &r.label(),
                format!("is {v:.6e} at this design: the relation must keep it positive (check its C0, coefficients and the variables' bounds)"),
            ));
        }
        r.set(&mut b, v);
    }
    Ok(b)
}

/// The structural mass in the model's mass unit (PARAM WTMASS applied, as in M): uᵀ M u for a
/// rigid unit translation u along each basic axis, averaged over the three (they agree unless
/// scalar masses act along one axis only), as Nastran's grid-point weight generator sums the
/// translational masses.
pub fn translational_mass(s: &Structure, m: &Mat<f64>) -> f64 {
    let n = m.nrows();
    let mut total = 0.0;
    for axis in 0..3 {
        let mut u = vec![0.0; n];
        for (i, frame) in s.cd.iter().enumerate() {
            for (c, a) in frame.axes.iter().enumerate() {
                u[6 * i + c] = a[axis];
            }
        }
        let mut quad = 0.0;
        for (j, &uj) in u.iter().enumerate() {
            if uj != 0.0 {
                quad += uj * (0..n).map(|i| u[i] * m[(i, j)]).sum::<f64>();
            }
        }
        total += quad;
    }
    total / 3.0
}

/// An output of the random response by Nastran's label (`9T3`, `9R1`, `ACCE 9T3`,
/// `SPCF 11R3`, `MODE 2`) as a request (grid or mode, component, quantity). A monitor
/// component (`ROOT CMX`) is no request: every MONPNT1 of the model is part of the response.
pub fn parse_output(label: &str) -> Option<(u32, u8, Quantity)> {
    let t = label.trim();
    let (quantity, rest) = if let Some(r) = t.strip_prefix("ACCE ") {
        (Quantity::Acceleration, r.trim())
    } else if let Some(r) = t.strip_prefix("SPCF ") {
        (Quantity::SpcForce, r.trim())
    } else if let Some(r) = t.strip_prefix("MODE ") {
        return r
            .trim()
            .parse::<u32>()
            .ok()
            .filter(|&m| m > 0)
            .map(|m| (m, 0, Quantity::Mode));
    } else {
        (Quantity::Displacement, t)
    };
    let at = rest.find(['T', 'R'])?;
    let grid: u32 = rest[..at].parse().ok()?;
    let axis: u8 = rest[at + 1..]
        .parse()
        .ok()
        .filter(|c| (1..=3).contains(c))?;
    let comp = if &rest[at..=at] == "T" {
        axis
    } else {
        axis + 3
    };
    Some((grid, comp, quantity))
}

/// What an optimization of a Nastran model evaluates: the base model, the subcase whose random
/// gust response is constrained, the relations, the outputs and the modes kept.
#[derive(Clone, Debug)]
pub struct DesignModel {
    pub base: BulkData,
    pub sub: Subcase,
    pub relations: Vec<PropertyRelation>,
    /// The constrained outputs as requests, in the order of their labels.
    pub requests: Vec<(u32, u8, Quantity)>,
    pub interpolation: KInterpolation,
    /// The number of design variables.
    pub n_variables: usize,
    /// The modes the response keeps at every design: those the subcase's METHOD (and PARAM
    /// LMODES) keep at the initial design, so the response is one smooth function of the
    /// design (a mode entering the METHOD's range would make it jump).
    pub n_modes: usize,
    /// The LFD in place of the panels' DLM (built once: the splines follow the grids, which
    /// sizing does not move).
    pub lfd: Option<Lfd>,
}

/// The model analysed at one design.
#[derive(Clone, Debug)]
pub struct DesignPoint {
    pub x: Vec<f64>,
    pub bulk: BulkData,
    pub structure: Structure,
    pub modes: RealModes,
    pub mass: f64,
    /// The random response of the requests (their order), then of every monitor component of
    /// the model (`NAME CMX`).
    pub rows: Vec<RandomRow>,
    /// What the response noticed (one line each).
    pub warnings: Vec<String>,
}

/// The derivatives of a design's mass and responses, one entry a design variable.
#[derive(Clone, Debug)]
pub struct DesignGradients {
    pub mass: Vec<f64>,
    /// `[variable][output]`.
    pub outputs: Vec<Vec<RandomDerivative>>,
}

impl DesignModel {
    /// The model at `x` with its modes (the lowest `n_modes`), mass and response.
    pub fn analyse(&self, x: &[f64]) -> R<DesignPoint> {
        let bulk = apply(&self.base, &self.relations, x)?;
        let (structure, mut modes) = subcase_modes(&bulk, &self.sub)?;
        if modes.lambda.len() < self.n_modes {
            return Err(NastranError::model(
                "METHOD",
                format!(
                    "finds {} modes at this design; the optimization keeps the {} found at the initial design: widen the EIGR/EIGRL's frequency range or give ND",
                    modes.lambda.len(),
                    self.n_modes
                ),
            ));
        }
        truncate(&mut modes, self.n_modes);
        let mass = translational_mass(&structure, &structure.m_gg);
        let (rows, warnings) = random_response_with(
            &bulk,
            &self.sub,
            &structure,
            &modes,
            &self.requests,
            &self.interpolation,
            self.lfd.clone(),
        )?;
        Ok(DesignPoint {
            x: x.to_vec(),
            bulk,
            structure,
            modes,
            mass,
            rows,
            warnings,
        })
    }

    /// Exact derivatives of the mass and of every output's RMS and N0 at an analysed design,
    /// with respect to each design variable.
    pub fn gradients(&self, p: &DesignPoint) -> R<DesignGradients> {
        let s = &p.structure;
        let spc = constrained(s, &p.bulk, self.sub.selections.get("SPC").copied())?;
        let ng = s.k_gg.nrows();
        // the variables' dense ∂K, ∂M (16 n_g² bytes each) in groups that fit the budget
        let per_variable = 16.0 * (ng * ng) as f64;
        let group = ((DERIVATIVE_BUDGET_BYTES / per_variable).floor() as usize).max(1);
        let which: Vec<usize> = (0..self.n_modes).collect();
        let variables: Vec<usize> = (0..self.n_variables).collect();
        let (mut mass, mut outputs) = (Vec::new(), Vec::new());
        for vars in variables.chunks(group) {
            let dks = vars
                .iter()
                .map(|&v| self.variable_direction(s, &p.bulk, v))
                .collect::<R<Vec<_>>>()?;
            let mut directions = Vec::with_capacity(dks.len());
            for (dk, dm) in &dks {
                let d = mode_derivatives(s, &spc, &p.modes, (dk, dm), &which)?;
                directions.push(ModeDirection {
                    d_lambda: d.iter().map(|x| x.0).collect(),
                    d_phi_g: Mat::from_fn(ng, d.len(), |i, c| d[c].1[i]),
                    dk,
                    dm,
                });
            }
            outputs.extend(random_response_derivatives(
                &p.bulk,
                &self.sub,
                s,
                &p.modes,
                &self.requests,
                &self.interpolation,
                self.lfd.clone(),
                &directions,
            )?);
            mass.extend(dks.iter().map(|(_, dm)| translational_mass(s, dm)));
        }
        Ok(DesignGradients { mass, outputs })
    }

    /// ∂K and ∂M (g-set) along design variable `v`: Σ coefficient × the field's derivative
    /// over the relations that name it.
    fn variable_direction(&self, s: &Structure, b: &BulkData, v: usize) -> R<(Mat<f64>, Mat<f64>)> {
        let ng = s.k_gg.nrows();
        let (mut dk, mut dm) = (Mat::<f64>::zeros(ng, ng), Mat::<f64>::zeros(ng, ng));
        for r in &self.relations {
            let coefficients: Vec<f64> = r.terms.iter().filter(|t| t.0 == v).map(|t| t.1).collect();
            if coefficients.is_empty() {
                continue;
            }
            let (pk, pm) = r.derivative(s, b)?;
            for c in coefficients {
                dk += faer::Scale(c) * &pk;
                dm += faer::Scale(c) * &pm;
            }
        }
        Ok((dk, dm))
    }
}

impl DesignModel {
    /// The reverse mode: the gradients of functionals J = Σ_y (r̄_y RMS_y + n̄_y N0_y) of the
    /// outputs (`functionals[f][y] = (r̄_y, n̄_y)`) and of the mass with respect to every design
    /// variable, `[functional][variable]`. Per functional: the response's reverse sweep to seeds
    /// on the modes (`random::random_response_vjp`), one adjoint solve a mode
    /// (`structure::mode_adjoint`), then per related field the pairing with its ∂K and ∂M — so
    /// the cost grows with the number of functionals, not of variables.
    pub fn gradients_reverse(
        &self,
        p: &DesignPoint,
        functionals: &[Vec<(f64, f64)>],
    ) -> R<ReverseGradients> {
        let s = &p.structure;
        let spc = constrained(s, &p.bulk, self.sub.selections.get("SPC").copied())?;
        let seeds = random_response_vjp(
            &p.bulk,
            &self.sub,
            s,
            &p.modes,
            &self.requests,
            &self.interpolation,
            self.lfd.clone(),
            functionals,
        )?;
        let which: Vec<usize> = (0..self.n_modes).collect();
        let adjoints = seeds
            .iter()
            .map(|ms| mode_adjoint(s, &spc, &p.modes, &which, (&ms.lambda, &ms.phi_g)))
            .collect::<R<Vec<_>>>()?;
        let mut out = ReverseGradients {
            mass: vec![0.0; self.n_variables],
            functionals: vec![vec![0.0; self.n_variables]; functionals.len()],
        };
        let ng = s.k_gg.nrows();
        for r in &self.relations {
            let (dk, dm) = r.derivative(s, &p.bulk)?;
            let d_mass = translational_mass(s, &dm);
            let per_functional: Vec<f64> = adjoints
                .iter()
                .zip(&seeds)
                .map(|(adj, ms)| {
                    let mut v = adj.along(&p.modes, (&dk, &dm));
                    // the constraint forces' and monitors' rows meet lᵀ∂Kφ and lᵀ∂Mφ directly
                    for (l, k_bar, m_bar) in &ms.direct {
                        let rows: Vec<usize> = (0..ng).filter(|&i| l[i] != 0.0).collect();
                        for m in 0..self.n_modes {
                            let (mut dkp, mut dmp) = (0.0, 0.0);
                            for &i in &rows {
                                for j in 0..ng {
                                    let phi = p.modes.phi_g[(j, m)];
                                    dkp += l[i] * dk[(i, j)] * phi;
                                    dmp += l[i] * dm[(i, j)] * phi;
                                }
                            }
                            v += k_bar[m] * dkp + m_bar[m] * dmp;
                        }
                    }
                    v
                })
                .collect();
            for &(var, coef) in &r.terms {
                out.mass[var] += coef * d_mass;
                for (f, g) in per_functional.iter().enumerate() {
                    out.functionals[f][var] += coef * g;
                }
            }
        }
        Ok(out)
    }
}

/// What [`DesignModel::gradients_reverse`] gives: the mass's gradient and each functional's,
/// one entry a design variable.
#[derive(Clone, Debug)]
pub struct ReverseGradients {
    pub mass: Vec<f64>,
    pub functionals: Vec<Vec<f64>>,
}

/// Keeps the lowest `n` modes.
fn truncate(modes: &mut RealModes, n: usize) {
    modes.lambda.truncate(n);
    let g = modes.phi_g.subcols(0, n).to_owned();
    let a = modes.phi_a.subcols(0, n).to_owned();
    modes.phi_g = g;
    modes.phi_a = a;
}

/// Whether `label` has the form of a monitor component's (`NAME CX` … `NAME CMZ`).
pub fn is_monitor_label(label: &str) -> bool {
    let t = label.trim();
    ["CX", "CY", "CZ", "CMX", "CMY", "CMZ"]
        .iter()
        .any(|c| t.len() > c.len() + 1 && t.ends_with(&format!(" {c}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every label form Nastran prints reads back as its request; anything else is refused.
    #[test]
    fn output_labels_read_back() {
        assert_eq!(parse_output("9T3"), Some((9, 3, Quantity::Displacement)));
        assert_eq!(parse_output("12R2"), Some((12, 5, Quantity::Displacement)));
        assert_eq!(
            parse_output("ACCE 9T3"),
            Some((9, 3, Quantity::Acceleration))
        );
        assert_eq!(parse_output("SPCF 11R3"), Some((11, 6, Quantity::SpcForce)));
        assert_eq!(parse_output("MODE 2"), Some((2, 0, Quantity::Mode)));
        for bad in [
            "", "9", "9T4", "T3", "MODE 0", "MODE x", "9X3", "ACCE", "9T",
        ] {
            assert_eq!(parse_output(bad), None, "{bad}");
        }
    }
}
