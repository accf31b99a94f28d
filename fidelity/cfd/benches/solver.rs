//! Cost of the Euler solver on the NACA 64A010 O-mesh family (cells ×4 a level): residual time
//! per cell (first and second order), exact first-order Jacobian assembly, and the steady
//! Newton–Krylov solve at M = 0.4, α = 1°. Run with `cargo bench -p gustkit-cfd --bench solver`.

use gustkit_cfd::airfoil::AirfoilShape;
use gustkit_cfd::residual::{free_stream, Euler, Order};
use gustkit_cfd::steady::SteadyParams;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let sec = AirfoilShape::naca64a010();
    println!(
        "{:>7} {:>16} {:>16} {:>14} {:>12} {:>9}",
        "cells", "R 1st [ns/cell]", "R 2nd [ns/cell]", "Jacobian [ms]", "steady [s]", "Newton"
    );
    for level in 0..4 {
        let s = 1usize << level;
        let mesh = sec.o_mesh(32 * s, 16 * s, 50.0, 0.0004 / s as f64, 1.0);
        let e = Euler::new(mesh, free_stream(0.4, 1f64.to_radians()));
        let n = e.mesh.n_cells;
        let q = vec![e.q_inf; n];
        let time = |f: &dyn Fn()| {
            median(
                (0..7)
                    .map(|_| {
                        let t = Instant::now();
                        f();
                        t.elapsed().as_secs_f64()
                    })
                    .collect(),
            )
        };
        let r1 = time(&|| {
            std::hint::black_box(e.residual_and_fluxes(&q, Order::First));
        });
        let r2 = time(&|| {
            std::hint::black_box(e.residual_and_fluxes(&q, Order::Second));
        });
        let jac = time(&|| {
            std::hint::black_box(e.jacobian(&q));
        });
        let t = Instant::now();
        let (_, info) = e
            .solve_steady(q.clone(), &SteadyParams::default())
            .expect("steady solve");
        let steady = t.elapsed().as_secs_f64();
        println!(
            "{n:>7} {:>16.1} {:>16.1} {:>14.2} {:>12.2} {:>9}",
            1e9 * r1 / n as f64,
            1e9 * r2 / n as f64,
            1e3 * jac,
            steady,
            info.iterations
        );
    }
}
