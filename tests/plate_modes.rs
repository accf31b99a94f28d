//! Modal analysis against plate theory (Leissa) and the AGARD 445.6 reference frequencies.

mod common;

use faer::Mat;
use gustkit::structure::{modal, Clamp, Field, Orthotropic, PlateMesh, PlateModel};
use gustkit::wing::{DesignVector, Planform};

/// Isotropic square cantilever (C-F-F-F) plate of side a, thickness h, n × n elements.
fn square_plate(n: usize) -> (PlateModel, f64) {
    let (a, h, e, nu, rho) = (1.0, 0.01, 70e9, 0.3, 2700.0);
    let mesh = PlateMesh::new(n, n, 1, &Clamp::All).unwrap();
    let design = DesignVector {
        thickness: vec![h; n * n],
        planform: Planform {
            span: a,
            sweep_c4: 0.0,
            root_chord: a,
            tip_chord: a,
        },
    };
    let model = PlateModel::new(mesh, Orthotropic::isotropic(e, nu, rho), design).unwrap();
    let d = e * h.powi(3) / (12.0 * (1.0 - nu * nu));
    // λ = ω a² √(ρh/D)
    (model, a * a * (rho * h / d).sqrt())
}

/// Leissa (1973), cantilever square plate, ν = 0.3: λ = 3.492, 8.525, 21.43, 27.33, 31.11.
/// DKQ discretizes thin-plate (Kirchhoff) theory, so on refinement each λ must converge at the
/// element's O(h²) rate (successive changes shrinking by about 4, asserted > 2.5) and the 24 × 24
/// mesh must agree with Leissa within 1 %. Leissa's values come from a 36-term Ritz series, which
/// bounds from above: a converged value slightly below them is expected.
#[test]
fn cantilever_square_plate_matches_leissa() {
    let leissa = [3.492, 8.525, 21.43, 27.33, 31.11];
    let mut history: Vec<Vec<f64>> = Vec::new();
    for n in [6, 12, 24] {
        let (model, scale) = square_plate(n);
        let modes = modal::solve(&model, 5, 0.0, &[Field::Bending]).unwrap();
        let lam: Vec<f64> = modes.omega().iter().map(|w| w * scale).collect();
        println!("{n:>3} x {n:<3} λ = {lam:.4?}");
        history.push(lam);
    }
    for m in 0..5 {
        let d1 = (history[1][m] - history[0][m]).abs();
        let d2 = (history[2][m] - history[1][m]).abs();
        println!(
            "mode {}: changes {d1:.2e} then {d2:.2e}, ratio {:.1}",
            m + 1,
            d1 / d2
        );
        assert!(d1 / d2 > 2.5, "mode {} does not converge at O(h^2)", m + 1);
        let err = ((history[2][m] - leissa[m]) / leissa[m]).abs();
        assert!(err < 0.01, "mode {}: 24 x 24 error {err}", m + 1);
    }
}

fn agard_model(refine: usize, clamp: Clamp) -> PlateModel {
    common::agard_plate(refine, clamp)
}

/// AGARD 445.6 weakened model 3 (Yates): 9.60, 38.17, 48.35, 91.54 Hz, mass about 1.69 kg.
#[test]
fn agard445_frequencies_and_mass() {
    let yates = [9.60, 38.17, 48.35, 91.54];
    for clamp in [Clamp::All, Clamp::Interior] {
        let model = agard_model(1, clamp.clone());
        let modes = modal::solve(&model, 6, 0.0, &Field::ALL).unwrap();
        let f = modes.freq_hz();
        println!("{clamp:?}: mass {:.4} kg, f = {f:.3?}", model.mass());
    }
    // patch refinement: each design variable's patch split into r × r elements; the change of
    // every frequency must shrink as the mesh is refined (DKQ converges at O(h²))
    let mut hist = Vec::new();
    for r in [1, 2, 3] {
        let model = agard_model(r, Clamp::All);
        let modes = modal::solve(&model, 4, 0.0, &[Field::Bending]).unwrap();
        println!("refine {r}: f = {:.3?}", modes.freq_hz());
        hist.push(modes.freq_hz());
    }
    for m in 0..4 {
        let d1 = (hist[1][m] - hist[0][m]).abs();
        let d2 = (hist[2][m] - hist[1][m]).abs();
        assert!(d2 < 0.6 * d1, "mode {m}: changes {d1} then {d2}");
        // the 10 x 10 design mesh is within 2 % of the refined one
        assert!(((hist[0][m] - hist[2][m]) / hist[2][m]).abs() < 0.02);
    }
    let model = agard_model(1, Clamp::All);
    let modes = modal::solve(&model, 6, 0.0, &Field::ALL).unwrap();
    let f = modes.freq_hz();
    assert!((model.mass() - 1.69).abs() < 0.02, "mass {}", model.mass());
    for (fi, yi) in f.iter().zip(yates) {
        assert!(((fi - yi) / yi).abs() < 0.05, "{fi} vs {yi}");
    }
}

/// The solver's modes are M-orthonormal and diagonalize K: Φᵀ M Φ = I and Φᵀ K Φ = diag(ω²), which
/// is what the generalized matrices M̄ = I, K̄ = diag(ω²) claim.
#[test]
fn generalized_matrices_are_consistent() {
    let model = agard_model(1, Clamp::Interior);
    let modes = modal::solve(&model, 6, 0.02, &[Field::Bending]).unwrap();
    let (k, m) = model.assemble(Field::Bending);
    let phi = Mat::from_fn(k.nrows(), modes.len(), |r, c| {
        gustkit::structure::modal::field_dofs(&model, Field::Bending, &modes.modes[c].shape)[r]
    });
    let mbar = phi.transpose() * &m * &phi;
    let kbar = phi.transpose() * &k * &phi;
    let (gm, gk, gc) = (
        modes.generalized_mass(),
        modes.generalized_stiffness(),
        modes.generalized_damping(),
    );
    for i in 0..modes.len() {
        for j in 0..modes.len() {
            assert!((mbar[(i, j)] - gm[(i, j)]).abs() < 1e-10);
            assert!((kbar[(i, j)] - gk[(i, j)]).abs() < 1e-10 * gk[(5, 5)]);
        }
        assert!((gc[(i, i)] - 2.0 * 0.02 * modes.modes[i].omega()).abs() < 1e-12 * gc[(i, i)]);
    }
}

/// Root bending moment by the mode-displacement method: with the complete set of bending modes, a
/// static load F gives η_m = φ_mᵀF/ω_m² and Σ_m S_m η_m equals the moment of the load about the root
/// line, Σ (F_z y + F_{w_y}), to round-off (equilibrium of the clamped plate).
#[test]
fn root_bending_moment_mode_displacement_is_exact_with_all_modes() {
    use gustkit::structure::{modal::field_dofs, root_bending_moment};
    let model = agard_model(1, Clamp::Interior);
    let n = model.n_dofs(Field::Bending);
    let modes = modal::solve(&model, n, 0.0, &[Field::Bending]).unwrap();
    let s = root_bending_moment(&model, &modes);
    // a load: pressure-like nodal forces growing toward the tip, plus nodal moments
    let xy = model.node_xy();
    let nodal_len = 5 * xy.len();
    let mut f = vec![0.0; nodal_len];
    for (i, p) in xy.iter().enumerate() {
        if model.mesh.clamped[i] {
            continue;
        }
        f[5 * i] = 1.0 + 3.0 * p[1] - 0.5 * p[0];
        f[5 * i + 2] = 0.2 * p[0];
    }
    let direct: f64 = xy
        .iter()
        .enumerate()
        .filter(|(i, _)| !model.mesh.clamped[*i])
        .map(|(i, p)| f[5 * i] * p[1] + f[5 * i + 2])
        .sum();
    let ff = field_dofs(&model, Field::Bending, &f);
    let modal_sum: f64 = modes
        .modes
        .iter()
        .zip(&s)
        .map(|(m, sm)| {
            let phi = field_dofs(&model, Field::Bending, &m.shape);
            let eta: f64 = phi.iter().zip(&ff).map(|(a, b)| a * b).sum::<f64>() / m.lambda;
            sm * eta
        })
        .sum();
    println!("direct {direct:.12e} modal {modal_sum:.12e}");
    assert!((modal_sum - direct).abs() < 1e-8 * direct.abs());
}

/// The partial modal solve (Lanczos on L⁻¹ M L⁻ᵀ) against the complete dense decomposition, on
/// the AGARD plate (bending, interior clamp, refine 1 and 2: 336 and 1 386 DOFs) and the
/// membrane field: the 6 lowest eigenvalues to 1e-12 relative, the mass-normalized modes to
/// 1e-9 of their largest entry (sign aligned; eigenvector error ≈ residual / relative gap), and
/// Nelson's expansion Σ_{j≠c} φ_j (φ_jᵀ r)/(λ_c − λ_j) equal to the complete spectrum's sum to
/// 1e-8 of its largest entry (the sum over all n modes carries the rounding of the highest ones).
#[test]
fn partial_modes_match_the_complete_decomposition() {
    for (refine, field) in [
        (1, Field::Bending),
        (2, Field::Bending),
        (1, Field::Membrane),
    ] {
        let model = agard_model(refine, Clamp::Interior);
        let part = modal::solve_field(&model, field, 6).unwrap();
        let full = modal::solve_field_complete(&model, field).unwrap();
        let n = full.lambda.len();
        assert_eq!(part.lambda.len(), 6);
        for c in 0..6 {
            let (lp, lf) = (part.lambda[c], full.lambda[c]);
            assert!(
                (lp - lf).abs() <= 1e-12 * lf,
                "{field:?} λ{c}: {lp} vs {lf}"
            );
            let (a, b) = (part.mode_vector(c), full.mode_vector(c));
            let sign = a.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>().signum();
            let big = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let worst = a
                .iter()
                .zip(&b)
                .fold(0.0f64, |m, (x, y)| m.max((x - sign * y).abs()));
            assert!(worst <= 1e-9 * big, "{field:?} φ{c}: {worst:e} of {big:e}");
            // a seed with every component present
            let r: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin() + 0.1).collect();
            let nelson = part.expansion(c, &r);
            let mut sum = vec![0.0; n];
            for j in (0..n).filter(|&j| j != c) {
                let pj = full.mode_vector(j);
                let w = pj.iter().zip(&r).map(|(x, y)| x * y).sum::<f64>()
                    / (full.lambda[c] - full.lambda[j]);
                sum.iter_mut().zip(&pj).for_each(|(s, p)| *s += w * p);
            }
            let big = sum.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let worst = nelson
                .iter()
                .zip(&sum)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(
                worst <= 1e-8 * big,
                "{field:?} expansion {c}: {worst:e} of {big:e}"
            );
        }
    }
}

/// Isotropic rectangular cantilever plate (clamped root), `nx × ny` elements, thickness of each
/// element column given chordwise.
fn rectangular_plate(span: f64, chord: f64, columns: &[f64], ny: usize) -> PlateModel {
    let nx = columns.len();
    let mesh = PlateMesh::new(nx, ny, 1, &Clamp::All).unwrap();
    let thickness = (0..ny).flat_map(|_| columns.iter().copied()).collect();
    let design = DesignVector {
        thickness,
        planform: Planform {
            span,
            sweep_c4: 0.0,
            root_chord: chord,
            tip_chord: chord,
        },
    };
    PlateModel::new(mesh, Orthotropic::isotropic(70e9, 0.3, 2700.0), design).unwrap()
}

/// A slender plate (span 1 m, chord 0.08 m, 2 mm) is a beam: Euler–Bernoulli bending at
/// f_n = (β_n L)² / (2π L²) √(D c / m) with β_n L = 1.875, 4.694, 7.855, 10.996 and St Venant torsion
/// of a thin strip at f_1 = √(G J / I_p) / (4 L), J = c t³/3, I_p = ρ t c³/12. Beam theory orders the
/// first five modes B1 B2 B3 T1 B4 (1.7, 10.8, 30.3, 39.5, 59.3 Hz; the next, B5 at 98 Hz, is far);
/// the names must follow that order and each frequency lie within 10 % of its beam value (the plate
/// is neither a narrow beam nor a wide plate: 1 − ν² moves bending by 5 %).
#[test]
fn slender_plate_modes_are_named_as_the_beam_they_are() {
    let (span, chord, t, e, nu, rho) = (1.0, 0.08, 0.002, 70e9, 0.3, 2700.0);
    let model = rectangular_plate(span, chord, &[t; 4], 40);
    let modes = modal::solve(&model, 5, 0.0, &[Field::Bending]).unwrap();
    let names = gustkit::structure::shape_name::mode_names(&model, &modes);
    let bend = (e * t * t / (12.0 * (1.0 - nu * nu) * rho)).sqrt() / (2.0 * std::f64::consts::PI);
    let g = e / (2.0 * (1.0 + nu));
    let torsion = (4.0 * g * t * t / (rho * chord * chord)).sqrt() / (4.0 * span);
    let beam = [
        1.875f64.powi(2) * bend,
        4.694f64.powi(2) * bend,
        7.855f64.powi(2) * bend,
        torsion,
        10.996f64.powi(2) * bend,
    ];
    let expected = [
        "1st bending",
        "2nd bending",
        "3rd bending",
        "1st torsion",
        "4th bending",
    ];
    for (i, f) in modes.freq_hz().iter().enumerate() {
        println!(
            "mode {}: {f:.2} Hz (beam {:.2} Hz), {}",
            i + 1,
            beam[i],
            names[i]
        );
        assert_eq!(names[i], expected[i], "mode {}", i + 1);
        assert!((f / beam[i] - 1.0).abs() < 0.10, "mode {}: {f} Hz", i + 1);
    }
}

/// A square plate whose aft eighth is a tenth as thick has modes living in that strip alone (a
/// trailing-edge panel). Where at least 80 % of a mode's squared deflection lies on the strip's
/// nodes, the name must not call it bending or torsion of the wing.
#[test]
fn local_trailing_edge_modes_are_not_called_bending() {
    let mut columns = [0.01; 8];
    columns[7] = 0.001;
    let model = rectangular_plate(0.5, 0.5, &columns, 8);
    let modes = modal::solve(&model, 8, 0.0, &[Field::Bending]).unwrap();
    let names = gustkit::structure::shape_name::mode_names(&model, &modes);
    let mut local = 0;
    for (m, name) in modes.modes.iter().zip(&names) {
        let (mut strip, mut all) = (0.0, 0.0);
        for (n, node) in model.mesh.nodes.iter().enumerate() {
            let w2 = m.shape[gustkit::structure::model::NODAL * n].powi(2);
            all += w2;
            if node[0] > 0.8 {
                strip += w2;
            }
        }
        println!(
            "{:.2} Hz: {name}, {:.0} % on the strip",
            m.freq_hz(),
            100.0 * strip / all
        );
        if strip / all > 0.8 {
            local += 1;
            assert!(
                !name.contains("bending") && !name.contains("torsion"),
                "a local mode named {name}"
            );
        }
    }
    assert!(
        local >= 2,
        "the plate has too few local modes to test the rule"
    );
}
