//! Cost of one LFD frequency against the time domain that gives the same answer, on the NACA
//! 64A010 O-mesh family at M = 0.4, k = 0.5: per mesh level, the time of one frequency with its
//! three right-hand sides (gust, plunge, pitch: factorization and solves) and the time of the
//! tiny-amplitude BDF2 runs that reproduce them to 4 digits (400 steps a period, 20 periods of
//! transient and 3 fitted — the settings of `studies/verify_naca64a010_lfd_gust.json`), one run per
//! right-hand side, estimated from the measured cost of 40 time steps. The ratio at the paper's
//! own settings (about 100 steps a period, 12 + 3 periods: 3 digits) is printed too.
//! Run with `cargo bench -p gustkit-cfd --bench lfd`.

use gustkit_cfd::airfoil::AirfoilShape;
use gustkit_cfd::deform::Deformation;
use gustkit_cfd::lfd::{HarmonicGust, LfdOperator, Symbol};
use gustkit_cfd::residual::{free_stream, Euler, Gust};
use gustkit_cfd::steady::SteadyParams;
use gustkit_cfd::unsteady::march;
use num_complex::Complex64 as C64;
use std::time::Instant;

fn main() {
    let sec = AirfoilShape::naca64a010();
    let (mach, k) = (0.4, 0.5);
    let omega = 2.0 * k * mach;
    let period = 2.0 * std::f64::consts::PI / omega;
    println!(
        "{:>7} {:>11} {:>13} {:>15} {:>15} {:>16} {:>9} {:>13}",
        "cells",
        "steady [s]",
        "Jacobian [s]",
        "LFD 3 rhs [s]",
        "time step [ms]",
        "time domain [s]",
        "ratio",
        "ratio (paper)"
    );
    for level in 0..3 {
        let s = 1usize << level;
        let mesh = sec.o_mesh(32 * s, 16 * s, 50.0, 0.02 / s as f64 / 50.0, 1.0);
        let e = Euler::new(mesh, free_stream(mach, 0.0));
        let n = e.mesh.n_cells;
        let t = Instant::now();
        let (q0, _) = e
            .solve_steady(
                vec![e.q_inf; n],
                &SteadyParams {
                    exact_jacobian: true,
                    ..SteadyParams::default()
                },
            )
            .expect("steady solve");
        let steady = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let lfd = LfdOperator::new(e.clone(), q0.clone());
        let jacobian = t.elapsed().as_secs_f64();
        // plunge and pitch about the quarter chord, spread by inverse-distance weighting
        let d = Deformation::new(&lfd.euler.mesh, 10.0);
        let nodes = &lfd.euler.mesh.nodes;
        let shapes: Vec<Vec<[C64; 3]>> = [
            |_: &[f64; 3]| [0.0, 1.0, 0.0],
            |p: &[f64; 3]| [p[1], -(p[0] + 0.25), 0.0],
        ]
        .iter()
        .map(|f| {
            let wall: Vec<[f64; 3]> = d.wall_nodes.iter().map(|&i| f(&nodes[i])).collect();
            d.apply(&wall)
                .iter()
                .map(|p| p.map(|v| C64::new(v, 0.0)))
                .collect()
        })
        .collect();
        let t = Instant::now();
        let f = lfd.factor(omega, Symbol::Exact).expect("factor");
        let mut rhs: Vec<Vec<C64>> = shapes.iter().map(|x| lfd.motion_rhs(f.s, x)).collect();
        rhs.push(lfd.gust_rhs(
            omega,
            &HarmonicGust {
                convection: mach,
                x0: 0.0,
            },
        ));
        lfd.solve(&f, &rhs).expect("LFD solve");
        let lfd_time = t.elapsed().as_secs_f64();
        // the time domain: a tiny gust, the preconditioner kept for the run
        let (steps_per_period, probe_steps) = (400, 40);
        let dt = period / steps_per_period as f64;
        let params = SteadyParams::small_amplitude();
        let gust = Gust::Sine {
            amplitude: 1e-5,
            omega,
            convection: mach,
            x0: 0.0,
        };
        let mut e2 = e.clone();
        let t = Instant::now();
        march(&mut e2, q0, Some(&gust), None, dt, probe_steps, &params).expect("time domain");
        let per_step = t.elapsed().as_secs_f64() / probe_steps as f64;
        let runs = rhs.len() as f64;
        let time_domain = runs * per_step * (23 * steps_per_period) as f64;
        let paper = runs * per_step * (15 * 100) as f64;
        println!(
            "{n:>7} {steady:>11.2} {jacobian:>13.2} {lfd_time:>15.2} {:>15.1} {time_domain:>16.0} {:>9.0} {:>13.0}",
            1e3 * per_step,
            time_domain / lfd_time,
            paper / lfd_time
        );
    }
}
