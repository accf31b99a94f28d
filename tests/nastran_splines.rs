//! The Nastran splines against each other and against the field they interpolate (issue 29):
//! a smooth bending-and-twist field of a wing, w(x, y) = a y²(3 s − y) + (x − x_ea) b y², given
//! to the grids of an infinite-plate spline (SPLINE1, and SPLINE4 naming the same boxes by an
//! AELIST) or of a beam spline on the elastic axis (SPLINE2, w, slope and twist attached),
//! and the splines' displacement and streamwise slope at the DLM's control and doublet points
//! against the field's own.

use gustkit::nastran::aero::{lifting_surfaces, spline_rows};
use gustkit::nastran::bulk::BulkData;
use gustkit::nastran::structure::Structure;
use gustkit::nastran::Input;

mod common;

/// Semispan, chord and elastic axis of the wing (m).
const SPAN: f64 = 2.0;
const CHORD: f64 = 0.5;
const X_EA: f64 = 0.2;
/// Bending and twist amplitudes.
const A: f64 = 0.01;
const B: f64 = 0.05;

fn field(x: f64, y: f64) -> (f64, f64, f64) {
    // w, ∂w/∂x, ∂w/∂y
    let w = A * y * y * (3.0 * SPAN - y) + (x - X_EA) * B * y * y;
    let wx = B * y * y;
    let wy = A * (6.0 * SPAN * y - 3.0 * y * y) + (x - X_EA) * 2.0 * B * y;
    (w, wx, wy)
}

/// Which spline moves the panel.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Spline1,
    Spline4,
    Spline2,
}

/// The largest differences of the spline's displacement and streamwise slope at the DLM's
/// points from the field's, relative to the field's largest displacement and slope, with `n`
/// spanwise grid intervals.
fn spline_error(kind: Kind, n: usize) -> (f64, f64) {
    let mut d = String::from("SOL 145\nCEND\nBEGIN BULK\n");
    let mut grid_xy = Vec::new();
    let chordwise: Vec<f64> = match kind {
        Kind::Spline2 => vec![X_EA],
        // refined with the span: square cells (chord / (n/4) = span / n)
        _ => (0..=n / 4)
            .map(|i| CHORD * i as f64 / (n / 4) as f64)
            .collect(),
    };
    for j in 0..=n {
        for &x in &chordwise {
            let y = SPAN * j as f64 / n as f64;
            grid_xy.push((x, y));
            d.push_str(&format!("GRID,{},,{x},{y},0.\n", grid_xy.len()));
        }
    }
    d.push_str("AERO,0,100.,0.5,1.2\nCAERO1,1001,1000,,8,6,,,1,+CA\n");
    d.push_str(&format!(
        "+CA,0.,0.,0.,{CHORD},0.,{SPAN},0.,{CHORD}\nPAERO1,1000\n"
    ));
    let last = grid_xy.len();
    d.push_str(&match kind {
        Kind::Spline1 => format!("SPLINE1,100,1001,1001,1048,10\nSET1,10,1,THRU,{last}\n"),
        Kind::Spline4 => {
            format!("SPLINE4,100,1001,20,,10\nAELIST,20,1001,THRU,1048\nSET1,10,1,THRU,{last}\n")
        }
        Kind::Spline2 => {
            format!("SPLINE2,100,1001,1001,1048,10,0.,1.,,+SP\n+SP,0.,0.\nSET1,10,1,THRU,{last}\n")
        }
    });
    d.push_str("ENDDATA\n");
    let dir = common::scratch("nastran", &format!("splines-{kind:?}-{n}"));
    let file = dir.join("wing.bdf");
    std::fs::write(&file, d).unwrap();
    let input = Input::read(&file).unwrap();
    let b = BulkData::from_cards(&input.deck.bulk).unwrap();
    let s = Structure::assemble(&b, None).unwrap();
    let surf = lifting_surfaces(&b, &s).unwrap();
    let (rows, unmoved) = spline_rows(&b, &s, &surf).unwrap();
    assert!(unmoved.is_empty());
    // the field at the grids: T3 = w, R1 = ∂w/∂y, R2 = −∂w/∂x
    let ng = s.k_gg.nrows();
    let mut u = vec![0.0; ng];
    for (g, &(x, y)) in grid_xy.iter().enumerate() {
        let (w, wx, wy) = field(x, y);
        let id = g as u32 + 1;
        u[s.dof(id, 3).unwrap()] = w;
        u[s.dof(id, 4).unwrap()] = wy;
        u[s.dof(id, 5).unwrap()] = -wx;
    }
    let points = &<gustkit_dlm::Dlm as gustkit_core::Aerodynamics>::surface(&surf.dlm).points;
    let (mut err_w, mut err_wx, mut big_w, mut big_wx) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (p, pt) in points.iter().enumerate() {
        let (w, wx, _) = field(pt[0], pt[1]);
        let (mut sw, mut swx) = (0.0, 0.0);
        for (j, uj) in u.iter().enumerate() {
            sw += rows.value[(p, j)] * uj;
            swx += rows.slope[(p, j)] * uj;
        }
        err_w = err_w.max((sw - w).abs());
        err_wx = err_wx.max((swx - wx).abs());
        big_w = big_w.max(w.abs());
        big_wx = big_wx.max(wx.abs());
    }
    (err_w / big_w, err_wx / big_wx)
}

/// SPLINE4 is SPLINE1's infinite plate (Harder–Desmarais) naming its boxes by an AELIST: the
/// same rows to round-off. On the smooth field both splines converge to it as the grid is
/// refined (8, 16, 32 spanwise intervals; the plate's grid in square cells, the beam's on the
/// axis). Measured, relative to the field's largest displacement and slope:
///
/// | spanwise intervals | infinite plate: w / ∂w/∂x | beam: w / ∂w/∂x |
/// |---:|---:|---:|
/// | 8 | 9.8e-3 / 8.9e-2 | 1.1e-3 / 4.4e-3 |
/// | 16 | 1.5e-3 / 4.0e-2 | 2.1e-12 / 9.9e-13 |
/// | 32 | 3.0e-4 / 8.1e-3 | 1.9e-11 / 6.7e-12 |
///
/// The infinite plate's errors fall at least 8-fold over the two halvings (h^1.5, a thin-plate
/// spline's rate near the edge of its data; measured 32- and 11-fold); the beam spline, with
/// w, slope and twist attached, reproduces this field to round-off from 16 intervals on
/// (asserted 1e-10; on 8 intervals 1.1e-3 and 4.4e-3, asserted below 1e-2). So the two agree
/// with each other to the plate's error.
#[test]
fn splines_converge_to_a_smooth_field_and_to_each_other() {
    for n in [8, 16] {
        let one = spline_error(Kind::Spline1, n);
        let four = spline_error(Kind::Spline4, n);
        assert!(
            (one.0 - four.0).abs() < 1e-14 && (one.1 - four.1).abs() < 1e-14,
            "{one:?} {four:?}"
        );
    }
    for kind in [Kind::Spline1, Kind::Spline2] {
        let errors: Vec<(f64, f64)> = [8, 16, 32].iter().map(|&n| spline_error(kind, n)).collect();
        eprintln!("{kind:?}: {errors:?}");
        match kind {
            Kind::Spline1 => {
                assert!(errors[2].0 < errors[0].0 / 8.0, "{errors:?}");
                assert!(errors[2].1 < errors[0].1 / 8.0, "{errors:?}");
                assert!(
                    errors[1].0 < errors[0].0 && errors[2].0 < errors[1].0,
                    "{errors:?}"
                );
            }
            _ => {
                assert!(errors[0].0 < 1e-2 && errors[0].1 < 1e-2, "{errors:?}");
                for e in &errors[1..] {
                    assert!(e.0 < 1e-10 && e.1 < 1e-10, "{errors:?}");
                }
            }
        }
    }
}
