//! Splines from structural grids to aerodynamic points (Nastran's SPLINE1, SPLINE4: infinite
//! plate; SPLINE2: beam), as matrices from the g-set to the normal displacement w and its
//! streamwise slope ∂w/∂x at each point. Their transposes carry aerodynamic forces back to the
//! grids.
//!
//! Infinite plate (Harder & Desmarais, J. Aircraft 9(2), 1972): w(x, y) = a₀ + a₁x + a₂y +
//! Σ Fᵢ rᵢ² ln rᵢ² in the plane of the lifting surface, with ΣFᵢ = ΣFᵢxᵢ = ΣFᵢyᵢ = 0; the grids
//! attach by their displacement normal to the plane. The interpolant does not change with the
//! length unit (the r² ln L² part of a rescaling is a quadratic that the constraints reduce to
//! a constant), so coordinates are centred and scaled before solving.
//!
//! Beam (Nastran's linear spline): a free beam along the y axis of the spline's frame with
//! bending stiffness EI = 1 and torsional stiffness GJ = 1/DTOR, displacement
//! w(ξ, η) = w(η) − ξ θ(η) at chordwise offset ξ; grids attach by w, by the bending slope
//! (rotation about the frame's x axis) unless DTHX = −1 and by the twist (rotation about y)
//! unless DTHY = −1, each with its attachment flexibility (DZ, DTHX, DTHY) added to the
//! diagonal. Green's functions of the energy ½∫(EI w''² + GJ θ'²): w = |Δ|³/12 per unit force,
//! θ = −DTOR |Δ|/2 per unit torque.

use super::structure::{Frame, Structure};
use super::NastranError;
use faer::prelude::Solve;
use faer::Mat;

type R<T> = Result<T, NastranError>;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A spline's interpolation: rows = aerodynamic points, columns = g-set components.
#[derive(Clone, Debug)]
pub struct SplineRows {
    /// Normal displacement w at each point.
    pub value: Mat<f64>,
    /// Its derivative along the flow direction, ∂w/∂x.
    pub slope: Mat<f64>,
}

/// The coefficients of a grid's displacement along `dir` (basic) over its six components.
fn translation_along(s: &Structure, grid: usize, dir: [f64; 3]) -> [(usize, f64); 3] {
    let f = s.cd[grid];
    std::array::from_fn(|c| (6 * grid + c, dot(f.axes[c], dir)))
}

/// The coefficients of a grid's rotation about `dir` (basic).
fn rotation_about(s: &Structure, grid: usize, dir: [f64; 3]) -> [(usize, f64); 3] {
    let f = s.cd[grid];
    std::array::from_fn(|c| (6 * grid + 3 + c, dot(f.axes[c], dir)))
}

/// Whether the polynomial (rigid-body) columns of a spline system are independent: the
/// smallest eigenvalue of Pᵀ P above 1e-12 of the largest. With them independent and no two
/// measures alike, the system of a conditionally positive definite kernel is regular.
fn full_rank(p: &[[f64; 3]]) -> bool {
    let g = Mat::<f64>::from_fn(3, 3, |i, j| p.iter().map(|r| r[i] * r[j]).sum());
    match g.self_adjoint_eigen(faer::Side::Lower) {
        Ok(e) => e.S()[0] > 1e-12 * e.S()[2],
        Err(_) => false,
    }
}

/// Solves the square spline system S z = rhs for the columns of rhs, refusing a singular one.
fn solve(system: &Mat<f64>, rhs: &Mat<f64>, what: &str, hint: &str) -> R<Mat<f64>> {
    let lu = system.full_piv_lu();
    let z = lu.solve(rhs);
    // a singular system shows as a residual of the order of the solution itself
    let residual = system * &z - rhs;
    let (mut rn, mut zn, mut sn) = (0.0f64, 0.0f64, 0.0f64);
    let mut finite = true;
    for j in 0..z.ncols() {
        for i in 0..z.nrows() {
            finite &= z[(i, j)].is_finite();
            rn = rn.max(residual[(i, j)].abs());
            zn = zn.max(z[(i, j)].abs());
        }
    }
    for j in 0..system.ncols() {
        for i in 0..system.nrows() {
            sn = sn.max(system[(i, j)].abs());
        }
    }
    let rhs_n = (0..rhs.ncols())
        .flat_map(|j| (0..rhs.nrows()).map(move |i| (i, j)))
        .fold(0.0f64, |m, (i, j)| m.max(rhs[(i, j)].abs()));
    if !finite
        || !(rn <= 1e-8 * (sn * zn).max(rhs_n))
        || zn > 1e14 * rhs_n.max(1.0) / sn.max(f64::MIN_POSITIVE)
    {
        return Err(NastranError::model(
            what,
            format!("its spline system is singular: {hint}"),
        ));
    }
    Ok(z)
}

/// The infinite-plate spline over `grids` (g-set grid indices) in the plane through `origin`
/// with in-plane axes `x_axis` (the flow direction) and `y_axis` and normal `normal`, evaluated
/// at `points` (basic).
pub fn infinite_plate(
    s: &Structure,
    grids: &[usize],
    origin: [f64; 3],
    axes: [[f64; 3]; 3],
    points: &[[f64; 3]],
    what: &str,
) -> R<SplineRows> {
    let [x_axis, y_axis, normal] = axes;
    let local = |p: [f64; 3]| {
        let d = [p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]];
        [dot(d, x_axis), dot(d, y_axis)]
    };
    let mut xy: Vec<[f64; 2]> = grids.iter().map(|&g| local(s.position[g])).collect();
    let m = xy.len();
    if m < 3 {
        return Err(NastranError::model(
            what,
            format!(
                "an infinite-plate spline needs at least 3 grids not on one line (its set has {m})"
            ),
        ));
    }
    // centre and scale (the interpolant does not depend on either)
    let c = [
        xy.iter().map(|p| p[0]).sum::<f64>() / m as f64,
        xy.iter().map(|p| p[1]).sum::<f64>() / m as f64,
    ];
    let l = xy
        .iter()
        .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    for p in &mut xy {
        *p = [(p[0] - c[0]) / l, (p[1] - c[1]) / l];
    }
    let kernel = |a: [f64; 2], b: [f64; 2]| {
        let r2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
        if r2 > 0.0 {
            r2 * r2.ln()
        } else {
            0.0
        }
    };
    // ∂/∂x of r² ln r² = 2 (x − xᵢ)(ln r² + 1)
    let kernel_x = |a: [f64; 2], b: [f64; 2]| {
        let r2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
        if r2 > 0.0 {
            2.0 * (a[0] - b[0]) * (r2.ln() + 1.0)
        } else {
            0.0
        }
    };
    let singular =
        |why: &str| NastranError::model(what, format!("its spline system is singular: {why}"));
    let rigid: Vec<[f64; 3]> = xy.iter().map(|p| [1.0, p[0], p[1]]).collect();
    if !full_rank(&rigid) {
        return Err(singular(
            "its grids lie on one line (use a beam spline, SPLINE2)",
        ));
    }
    for i in 0..m {
        for j in 0..i {
            if (xy[i][0] - xy[j][0]).hypot(xy[i][1] - xy[j][1]) < 1e-9 {
                return Err(singular(&format!(
                    "grids {} and {} coincide in its plane",
                    s.grid_ids[grids[j]], s.grid_ids[grids[i]]
                )));
            }
        }
    }
    let n = m + 3;
    let system = Mat::from_fn(n, n, |i, j| match (i < m, j < m) {
        (true, true) => kernel(xy[i], xy[j]),
        (true, false) => [1.0, xy[i][0], xy[i][1]][j - m],
        (false, true) => [1.0, xy[j][0], xy[j][1]][i - m],
        (false, false) => 0.0,
    });
    let rhs = Mat::from_fn(n, m, |i, j| if i == j { 1.0 } else { 0.0 });
    let inv = solve(
        &system,
        &rhs,
        what,
        "its grids lie on one line (use a beam spline, SPLINE2) or two grids coincide",
    )?;
    let ng = s.k_gg.nrows();
    let mut value = Mat::<f64>::zeros(points.len(), ng);
    let mut slope = Mat::<f64>::zeros(points.len(), ng);
    let attach: Vec<[(usize, f64); 3]> = grids
        .iter()
        .map(|&g| translation_along(s, g, normal))
        .collect();
    for (p, &pt) in points.iter().enumerate() {
        let q = local(pt);
        let q = [(q[0] - c[0]) / l, (q[1] - c[1]) / l];
        let row: Vec<f64> = (0..n)
            .map(|i| {
                if i < m {
                    kernel(q, xy[i])
                } else {
                    [1.0, q[0], q[1]][i - m]
                }
            })
            .collect();
        // d/dx of the scaled coordinate is 1/l
        let row_x: Vec<f64> = (0..n)
            .map(|i| {
                if i < m {
                    kernel_x(q, xy[i]) / l
                } else {
                    [0.0, 1.0 / l, 0.0][i - m]
                }
            })
            .collect();
        for j in 0..m {
            let (mut v, mut vx) = (0.0, 0.0);
            for i in 0..n {
                v += row[i] * inv[(i, j)];
                vx += row_x[i] * inv[(i, j)];
            }
            for &(dof, f) in &attach[j] {
                value[(p, dof)] += v * f;
                slope[(p, dof)] += vx * f;
            }
        }
    }
    Ok(SplineRows { value, slope })
}

/// The attachment of a beam spline: flexibilities (None: not attached) and DTOR.
#[derive(Clone, Copy, Debug)]
pub struct BeamAttachment {
    pub dz: f64,
    pub dthx: Option<f64>,
    pub dthy: Option<f64>,
    pub dtor: f64,
}

/// What a beam-spline measure is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Measure {
    /// w − ξθ at (ξ, η).
    W { xi: f64, eta: f64 },
    /// w'(η), the bending slope.
    Slope { eta: f64 },
    /// θ(η), the twist.
    Twist { eta: f64 },
}

impl Measure {
    fn eta(&self) -> f64 {
        match *self {
            Measure::W { eta, .. } | Measure::Slope { eta } | Measure::Twist { eta } => eta,
        }
    }
    /// Its torsion factor (−ξ for w, 1 for the twist, 0 for the slope).
    fn torsion(&self) -> f64 {
        match *self {
            Measure::W { xi, .. } => -xi,
            Measure::Twist { .. } => 1.0,
            Measure::Slope { .. } => 0.0,
        }
    }
    /// The rigid-body row [a₀, a₁, b₀] (w = a₀ + a₁η, θ = b₀).
    fn rigid(&self) -> [f64; 3] {
        match *self {
            Measure::W { xi, eta } => [1.0, eta, -xi],
            Measure::Slope { .. } => [0.0, 1.0, 0.0],
            Measure::Twist { .. } => [0.0, 0.0, 1.0],
        }
    }
}

/// A beam-spline measure with its g-set coefficients and attachment flexibility.
type Attached = (Measure, Vec<(usize, f64)>, f64);

/// The beam spline's Green's function between measure `a` and load `b`.
fn beam_green(a: &Measure, b: &Measure, dtor: f64) -> f64 {
    let d = a.eta() - b.eta();
    let ad = d.abs();
    let bending = match (a, b) {
        (Measure::W { .. }, Measure::W { .. }) => ad * ad * ad / 12.0,
        (Measure::Slope { .. }, Measure::W { .. }) => d * ad / 4.0,
        (Measure::W { .. }, Measure::Slope { .. }) => -d * ad / 4.0,
        (Measure::Slope { .. }, Measure::Slope { .. }) => -ad / 2.0,
        _ => 0.0,
    };
    bending + a.torsion() * b.torsion() * (-dtor * ad / 2.0)
}

/// The derivatives ∂/∂ξ and ∂/∂η of the measure w − ξθ at (ξ, η) against load `b`.
fn beam_green_w_derivatives(xi: f64, eta: f64, b: &Measure, dtor: f64) -> (f64, f64) {
    let d = eta - b.eta();
    let ad = d.abs();
    let sign = d.signum();
    // bending part of w(η) and its η-derivative
    let bend_eta = match b {
        Measure::W { .. } => d * ad / 4.0,
        Measure::Slope { .. } => -ad / 2.0,
        Measure::Twist { .. } => 0.0,
    };
    // twist θ(η) = tb (−DTOR |Δ|/2) and its η-derivative
    let tb = b.torsion();
    let theta = tb * (-dtor * ad / 2.0);
    let theta_eta = tb * (-dtor * sign / 2.0);
    (-theta, bend_eta - xi * theta_eta)
}

/// The beam spline over `grids` with its axis the y axis of `frame`, the normal displacement
/// along `normal` (the lifting surface's), evaluated at `points`; ∂/∂x along `flow`.
pub fn beam(
    s: &Structure,
    grids: &[usize],
    frame: &Frame,
    normal: [f64; 3],
    flow: [f64; 3],
    att: BeamAttachment,
    points: &[[f64; 3]],
    what: &str,
) -> R<SplineRows> {
    let [fx, fy, fz] = frame.axes;
    // the spline's w is along its frame's z; the surface's normal is that or its opposite
    let orientation = dot(fz, normal);
    if orientation.abs() < 0.999 {
        return Err(NastranError::model(what, "its coordinate system (CID) must have its x–y plane in the plane of the lifting surface (z along the surface's normal or against it)".into()));
    }
    let sign = orientation.signum();
    let local = |p: [f64; 3]| {
        let d = [
            p[0] - frame.origin[0],
            p[1] - frame.origin[1],
            p[2] - frame.origin[2],
        ];
        (dot(d, fx), dot(d, fy))
    };
    // measures and their attachments (g-set coefficients, flexibility)
    let mut measures: Vec<Attached> = Vec::new();
    for &g in grids {
        let (xi, eta) = local(s.position[g]);
        measures.push((
            Measure::W { xi, eta },
            translation_along(s, g, fz).to_vec(),
            att.dz,
        ));
        if let Some(f) = att.dthx {
            measures.push((Measure::Slope { eta }, rotation_about(s, g, fx).to_vec(), f));
        }
        if let Some(f) = att.dthy {
            measures.push((Measure::Twist { eta }, rotation_about(s, g, fy).to_vec(), f));
        }
    }
    let m = measures.len();
    let rigid: Vec<[f64; 3]> = measures.iter().map(|(me, _, _)| me.rigid()).collect();
    let duplicate = (0..m).any(|i| {
        (0..i).any(|j| {
            let (a, b) = (&measures[i].0, &measures[j].0);
            std::mem::discriminant(a) == std::mem::discriminant(b)
                && (a.eta() - b.eta()).abs() < 1e-9
                && (a.torsion() - b.torsion()).abs() < 1e-9
        })
    });
    if !full_rank(&rigid) || duplicate {
        return Err(NastranError::model(what, "its spline system is singular: it needs grids at two span stations at least, a twist (a grid off the axis or an attached rotation, DTHY ≠ −1) and no two grids at the same place".into()));
    }
    let n = m + 3;
    let system = Mat::from_fn(n, n, |i, j| match (i < m, j < m) {
        (true, true) => {
            beam_green(&measures[i].0, &measures[j].0, att.dtor)
                + if i == j { measures[i].2 } else { 0.0 }
        }
        (true, false) => measures[i].0.rigid()[j - m],
        (false, true) => measures[j].0.rigid()[i - m],
        (false, false) => 0.0,
    });
    let rhs = Mat::from_fn(n, m, |i, j| if i == j { 1.0 } else { 0.0 });
    let inv = solve(&system, &rhs, what, "it needs grids at two span stations at least, and a twist: a grid off the axis or an attached rotation (DTHY ≠ −1)")?;
    let ng = s.k_gg.nrows();
    let mut value = Mat::<f64>::zeros(points.len(), ng);
    let mut slope = Mat::<f64>::zeros(points.len(), ng);
    // ∂/∂x (flow) = (flow·x̂) ∂/∂ξ + (flow·ŷ) ∂/∂η
    let (cx, cy) = (dot(flow, fx), dot(flow, fy));
    for (p, &pt) in points.iter().enumerate() {
        let (xi, eta) = local(pt);
        let here = Measure::W { xi, eta };
        let mut row = vec![0.0; n];
        let mut row_x = vec![0.0; n];
        for i in 0..m {
            row[i] = beam_green(&here, &measures[i].0, att.dtor);
            let (dxi, deta) = beam_green_w_derivatives(xi, eta, &measures[i].0, att.dtor);
            row_x[i] = cx * dxi + cy * deta;
        }
        let rigid = here.rigid();
        row[m..m + 3].copy_from_slice(&rigid);
        // rigid part: ∂/∂ξ (a₀ + a₁η − ξb₀) = −b₀, ∂/∂η = a₁
        row_x[m + 1] = cy;
        row_x[m + 2] = -cx;
        for j in 0..m {
            let (mut v, mut vx) = (0.0, 0.0);
            for i in 0..n {
                v += row[i] * inv[(i, j)];
                vx += row_x[i] * inv[(i, j)];
            }
            for &(dof, f) in &measures[j].1 {
                value[(p, dof)] += sign * v * f;
                slope[(p, dof)] += sign * vx * f;
            }
        }
    }
    Ok(SplineRows { value, slope })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nastran::bulk::BulkData;
    use crate::nastran::Deck;
    use std::path::Path;

    /// A structure of free grids at `xy` (z = 0), displacement frame `cd` (0: basic).
    fn grids(xy: &[[f64; 2]], cd_deck: &str, cd: u32) -> Structure {
        let mut text = String::from("BEGIN BULK\n");
        text.push_str(cd_deck);
        for (i, p) in xy.iter().enumerate() {
            text.push_str(&format!("GRID,{},,{},{},0.,{cd}\n", i + 1, p[0], p[1]));
        }
        let d = Deck::from_text(Path::new("s.bdf"), &text).unwrap();
        Structure::assemble(&BulkData::from_cards(&d.bulk).unwrap(), None).unwrap()
    }

    /// `v` with its components along `columns` removed (Gram–Schmidt on the columns).
    fn orthogonal_to(mut v: Vec<f64>, columns: &[Vec<f64>]) -> Vec<f64> {
        let mut basis: Vec<Vec<f64>> = Vec::new();
        for col in columns {
            let mut u = col.clone();
            for b in &basis {
                let d: f64 = u.iter().zip(b).map(|(x, y)| x * y).sum();
                u.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
            }
            let nu = u.iter().map(|x| x * x).sum::<f64>().sqrt();
            u.iter_mut().for_each(|x| *x /= nu);
            let d: f64 = v.iter().zip(&u).map(|(x, y)| x * y).sum();
            v.iter_mut().zip(&u).for_each(|(x, y)| *x -= d * y);
            basis.push(u);
        }
        v
    }

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The infinite-plate spline reproduces every function of its own space exactly: f = a₀ +
    /// a₁x + a₂y + Σ cₖ rₖ² ln rₖ² with centres at the grids and Σc = Σcx = Σcy = 0, sampled
    /// at the grids (in a displacement frame turned about two axes), is given back at random
    /// points to 1e-9 of its range, and ∂f/∂x to 1e-8; grids on one line are refused.
    #[test]
    fn infinite_plate_reproduces_its_space() {
        let mut seed = 7u64;
        let xy: Vec<[f64; 2]> = (0..12)
            .map(|_| [100.0 * lcg(&mut seed), 300.0 * lcg(&mut seed)])
            .collect();
        let cd = "CORD2R,5,,0.,0.,0.,0.2,-0.3,1.\n,1.,0.4,0.1\n";
        let s = grids(&xy, cd, 5);
        // coefficients orthogonal to [1, x, y]
        let c = orthogonal_to(
            (0..xy.len()).map(|_| lcg(&mut seed) - 0.5).collect(),
            &[
                xy.iter().map(|_| 1.0).collect(),
                xy.iter().map(|p| p[0]).collect(),
                xy.iter().map(|p| p[1]).collect(),
            ],
        );
        let f = |p: [f64; 2]| {
            let mut v = 0.3 + 0.01 * p[0] - 0.02 * p[1];
            let mut vx = 0.01;
            for (k, q) in xy.iter().enumerate() {
                let r2 = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                if r2 > 0.0 {
                    v += 1e-4 * c[k] * r2 * r2.ln();
                    vx += 1e-4 * c[k] * 2.0 * (p[0] - q[0]) * (r2.ln() + 1.0);
                }
            }
            (v, vx)
        };
        // grid displacements: normal (basic z) displacement f, expressed in frame 5
        let frame = s.cd[0];
        let mut u = vec![0.0; s.k_gg.nrows()];
        for (i, &p) in xy.iter().enumerate() {
            let w = f(p).0;
            for comp in 0..3 {
                u[6 * i + comp] = frame.axes[comp][2] * w;
            }
        }
        let points: Vec<[f64; 3]> = (0..20)
            .map(|_| {
                [
                    120.0 * lcg(&mut seed) - 10.0,
                    320.0 * lcg(&mut seed) - 10.0,
                    0.0,
                ]
            })
            .collect();
        let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let idx: Vec<usize> = (0..xy.len()).collect();
        let rows = infinite_plate(&s, &idx, [0.0; 3], axes, &points, "SPLINE1 1").unwrap();
        let range = xy.iter().map(|&p| f(p).0.abs()).fold(0.0, f64::max);
        for (p, &pt) in points.iter().enumerate() {
            let (v, vx) = f([pt[0], pt[1]]);
            let got: f64 = (0..u.len()).map(|j| rows.value[(p, j)] * u[j]).sum();
            let got_x: f64 = (0..u.len()).map(|j| rows.slope[(p, j)] * u[j]).sum();
            assert!((got - v).abs() < 1e-9 * range, "{got} vs {v}");
            assert!(
                (got_x - vx).abs() < 1e-8 * vx.abs().max(0.01),
                "{got_x} vs {vx}"
            );
        }
        let line: Vec<[f64; 2]> = (0..5).map(|i| [i as f64, 2.0 * i as f64]).collect();
        let s = grids(&line, "", 0);
        let e = infinite_plate(&s, &[0, 1, 2, 3, 4], [0.0; 3], axes, &points, "SPLINE1 9")
            .unwrap_err()
            .to_string();
        assert!(e.contains("SPLINE1 9") && e.contains("one line"), "{e}");
    }

    /// The beam spline reproduces its own space: w − ξθ from equilibrated forces, bending
    /// moments and torques at the grids plus a rigid motion, the grids attached by w, the slope
    /// and the twist, on an axis swept 20° in a turned frame; values at random points to 1e-9
    /// of the range, ∂w/∂x (flow along basic x) against central differences of the value rows
    /// to 1e-6; with only w attached and every grid on the axis the twist is undetermined and
    /// the spline is refused.
    #[test]
    fn beam_spline_reproduces_its_space() {
        let sweep = 20f64.to_radians();
        let frame = Frame {
            origin: [1.0, 0.5, 0.0],
            axes: [
                [sweep.cos(), -sweep.sin(), 0.0],
                [sweep.sin(), sweep.cos(), 0.0],
                [0.0, 0.0, 1.0],
            ],
        };
        let mut seed = 11u64;
        let stations: Vec<(f64, f64)> = (0..6)
            .map(|i| {
                (
                    0.4 * lcg(&mut seed) - 0.2,
                    1.0 * i as f64 + 0.3 * lcg(&mut seed),
                )
            })
            .collect();
        let xy: Vec<[f64; 2]> = stations
            .iter()
            .map(|&(xi, eta)| {
                let p = frame.to_basic([xi, eta, 0.0]);
                [p[0], p[1]]
            })
            .collect();
        let s = grids(&xy, "", 0);
        let att = BeamAttachment {
            dz: 0.0,
            dthx: Some(0.0),
            dthy: Some(0.0),
            dtor: 2.5,
        };
        let loads: Vec<Measure> = stations
            .iter()
            .flat_map(|&(xi, eta)| {
                [
                    Measure::W { xi, eta },
                    Measure::Slope { eta },
                    Measure::Twist { eta },
                ]
            })
            .collect();
        // equilibrated loads: orthogonal to the rigid rows
        let l = orthogonal_to(
            (0..loads.len()).map(|_| lcg(&mut seed) - 0.5).collect(),
            &(0..3)
                .map(|k| loads.iter().map(|m| m.rigid()[k]).collect())
                .collect::<Vec<_>>(),
        );
        let rigid = [0.1, -0.05, 0.02];
        let field = |m: &Measure| -> f64 {
            loads
                .iter()
                .zip(&l)
                .map(|(b, lb)| beam_green(m, b, att.dtor) * lb)
                .sum::<f64>()
                + m.rigid().iter().zip(rigid).map(|(a, b)| a * b).sum::<f64>()
        };
        let mut u = vec![0.0; s.k_gg.nrows()];
        for (i, &(xi, eta)) in stations.iter().enumerate() {
            u[6 * i + 2] = field(&Measure::W { xi, eta });
            let (slope, twist) = (
                field(&Measure::Slope { eta }),
                field(&Measure::Twist { eta }),
            );
            for c in 0..3 {
                u[6 * i + 3 + c] = slope * frame.axes[0][c] + twist * frame.axes[1][c];
            }
        }
        let points: Vec<[f64; 3]> = (0..15)
            .map(|_| frame.to_basic([1.0 * lcg(&mut seed) - 0.5, 6.0 * lcg(&mut seed), 0.0]))
            .collect();
        let idx: Vec<usize> = (0..stations.len()).collect();
        let spline_at = |pts: &[[f64; 3]]| {
            beam(
                &s,
                &idx,
                &frame,
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 0.0],
                att,
                pts,
                "SPLINE2 3",
            )
            .unwrap()
        };
        let rows = spline_at(&points);
        let range = stations
            .iter()
            .map(|&(xi, eta)| field(&Measure::W { xi, eta }).abs())
            .fold(0.0, f64::max);
        let h = 1e-5;
        let shifted =
            |dx: f64| -> Vec<[f64; 3]> { points.iter().map(|p| [p[0] + dx, p[1], p[2]]).collect() };
        let plus = spline_at(&shifted(h));
        let minus = spline_at(&shifted(-h));
        let apply =
            |m: &Mat<f64>, p: usize| -> f64 { (0..u.len()).map(|j| m[(p, j)] * u[j]).sum() };
        for (p, &pt) in points.iter().enumerate() {
            let d = [pt[0] - frame.origin[0], pt[1] - frame.origin[1], 0.0];
            let (xi, eta) = (dot(d, frame.axes[0]), dot(d, frame.axes[1]));
            let want = field(&Measure::W { xi, eta });
            let got = apply(&rows.value, p);
            assert!((got - want).abs() < 1e-9 * range, "{got} vs {want}");
            let fd = (apply(&plus.value, p) - apply(&minus.value, p)) / (2.0 * h);
            let gx = apply(&rows.slope, p);
            assert!(
                (gx - fd).abs() < 1e-6 * fd.abs().max(range),
                "slope {gx} vs {fd}"
            );
        }
        let on_axis: Vec<[f64; 2]> = (0..4).map(|i| [0.0, i as f64]).collect();
        let s = grids(&on_axis, "", 0);
        let basic = Frame {
            origin: [0.0; 3],
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        let free = BeamAttachment {
            dz: 0.0,
            dthx: None,
            dthy: None,
            dtor: 1.0,
        };
        let e = beam(
            &s,
            &[0, 1, 2, 3],
            &basic,
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            free,
            &points,
            "SPLINE2 8",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("SPLINE2 8") && e.contains("singular"), "{e}");
    }
}
