//! The CFD fidelity on the AGARD 445.6 wing (built-in O-H mesh, M = 0.5, second order): per mesh
//! level the cells, the memory (peak resident set of the process so far), the steady solve
//! (Newton–Krylov, block ILU(1) in RCM order), the exact Jacobian's assembly, one frequency's block ILU(1)
//! factorization (first-order Jacobian, reverse Cuthill–McKee order: the wing studies'
//! default), the GMRES iterations and time of one right-hand side, the same right-hand side at
//! k = 0.98 with other ILU settings, and the whole GAF table (11 reduced frequencies × (6 modes + the gust), frequencies and right-hand sides in
//! parallel), with core-seconds per cell beside the paper's 70.5 min on 400 cores for 219 555
//! nodes; then the reverse mode (its Jacobians by colouring, every GAF entry seeded) with its
//! memory. Each figure is one run (these solves take seconds to minutes); the thread count is
//! printed. `cargo bench -p gustkit-cfd --bench wing` runs the coarse level;
//! `WING_LEVELS=coarse,medium` adds the medium one (about 10 minutes, 3.5 GB);
//! `WING_REVERSE=0` stops after the GAF table. `WING_BATCHES=1,4,12` times one frequency's 12
//! right-hand sides (k = 0.5, forward and transposed) solved by GMRES in lockstep batches of
//! each size (`WING_REPEAT` repetitions after a warm-up, default 3; `WING_RESTART` sets their
//! GMRES restart length, default 80); `WING_TABLE=0` stops after it; `WING_PRECONDITIONERS=none` skips the preconditioner table;
//! `WING_DEFORM=0` skips the mesh deformation's figures (one mode shape a call against all at once).

use gustkit_cfd::deform::Deformation;
use gustkit_cfd::ilu::{IluOrdering, IluParams, IluPrecision};
use gustkit_cfd::lfd::{HarmonicGust, LfdOperator, Preconditioner, Symbol};
use gustkit_cfd::lfd_model::Lfd;
use gustkit_cfd::residual::{free_stream, Euler};
use gustkit_cfd::steady::{NewtonLinearSolver, SteadyParams};
use gustkit_cfd::wing_mesh::{WingMesh, WingMeshSpec};
use gustkit_core::scalar::Dual;
use gustkit_core::{Aerodynamics, AerodynamicsReverse, FlightCondition, ModalSurface};
use std::time::Instant;

/// Peak resident memory of this process, GB (Linux), or NaN.
fn peak_gb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1e6)
}

/// Restarts the peak resident memory from the present one (Linux), so that each stage's peak is
/// its own.
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// NACA 65A004 half-thickness by linear interpolation of its ordinates.
fn naca65a004(x: f64) -> f64 {
    const X: [f64; 24] = [
        0.0, 0.005, 0.0125, 0.025, 0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50,
        0.55, 0.60, 0.65, 0.70, 0.75, 0.80, 0.85, 0.90, 0.95, 1.00,
    ];
    const Z: [f64; 24] = [
        0.0, 0.00304, 0.00469, 0.00647, 0.00875, 0.01213, 0.01459, 0.01645, 0.01788, 0.01892,
        0.01962, 0.01997, 0.01996, 0.01954, 0.01868, 0.01743, 0.01586, 0.01402, 0.01195, 0.00967,
        0.00729, 0.00490, 0.00250, 0.00009,
    ];
    let i = X.partition_point(|v| *v <= x).clamp(1, 23);
    Z[i - 1] + (Z[i] - Z[i - 1]) * (x - X[i - 1]) / (X[i] - X[i - 1])
}

/// The gust right-hand side at ω (unit amplitude, convected at the free stream).
fn gust_rhs(op: &LfdOperator, omega: f64, mach: f64) -> Vec<num_complex::Complex64> {
    op.gust_rhs(
        omega,
        &HarmonicGust {
            convection: mach,
            x0: 0.0,
        },
    )
}

/// One right-hand side (the gust at k = 0.98, the hardest of the table on the medium mesh) with
/// each preconditioner of `WING_PRECONDITIONERS` (comma-separated `matrix:fill:ordering` with an
/// optional `:precision`, matrix `first`/`exact`, ordering `natural`/`rcm`, precision of the
/// stored factors `single` (default) or `double`; default the first-order Jacobian's ILU(0) in
/// the mesh's order and ILU(1) in RCM order in both precisions, the wing studies' default being
/// ILU(1), RCM, single): stored blocks and bytes, factorization time, GMRES iterations and time.
fn preconditioner_table(e: &Euler, q0: &[gustkit_cfd::residual::State<f64>], mach: f64, c: f64) {
    let list = std::env::var("WING_PRECONDITIONERS")
        .unwrap_or_else(|_| "first:0:natural,first:1:rcm:double,first:1:rcm".into());
    if list == "none" {
        return;
    }
    let omega = 0.98 * mach / (0.5 * c);
    for item in list.split(',') {
        let f: Vec<&str> = item.split(':').collect();
        let (matrix, fill, ordering) = (f[0], f[1].parse::<usize>().expect("fill"), f[2]);
        let pre = if matrix == "exact" {
            Preconditioner::BlockIlu
        } else {
            Preconditioner::FirstOrderIlu
        };
        let mut op = LfdOperator::with_preconditioner(e.clone(), q0.to_vec(), pre);
        op.params.tolerance = 1e-8;
        op.params.ilu = IluParams {
            fill,
            ordering: if ordering == "rcm" {
                IluOrdering::ReverseCuthillMckee
            } else {
                IluOrdering::Natural
            },
            precision: if f.get(3) == Some(&"double") {
                IluPrecision::Double
            } else {
                IluPrecision::Single
            },
        };
        let t = Instant::now();
        let fac = match op.factor(omega, Symbol::Exact) {
            Ok(f) => f,
            Err(err) => {
                println!("  {item}: {err}");
                continue;
            }
        };
        let t_fac = t.elapsed().as_secs_f64();
        let gust = gust_rhs(&op, omega, mach);
        let t = Instant::now();
        match op.solve(&fac, &[gust]) {
            Ok(sol) => println!(
                "  {item}: {} blocks/row ({:.0} B a cell), factor {t_fac:.2} s, one right-hand side at k = 0.98: {} GMRES iterations, {:.2} s; peak memory {:.2} GB",
                fac.n_blocks() as f64 / e.mesh.n_cells as f64,
                fac.bytes() as f64 / e.mesh.n_cells as f64,
                sol[0].1.iterations,
                t.elapsed().as_secs_f64(),
                peak_gb()
            ),
            Err(err) => println!("  {item}: factor {t_fac:.2} s, {err}"),
        }
    }
}

/// Median, min and max of some timings.
fn spread(mut t: Vec<f64>) -> (f64, f64, f64) {
    t.sort_by(f64::total_cmp);
    (t[t.len() / 2], t[0], t[t.len() - 1])
}

/// The timed repetitions after a warm-up (`WING_REPEAT`, default 3, at least 1).
fn repeat_count() -> usize {
    std::env::var("WING_REPEAT")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(3)
        .max(1)
}

/// One frequency's 12 right-hand sides (gusts convected at 0.6 to 1.15 times the free stream:
/// as many distinct solutions as a table's modes and gust) solved forward and transposed in
/// lockstep batches of each size of `WING_BATCHES`: time (median, min, max of `WING_REPEAT`
/// after a warm-up), GMRES iterations, and whether the answers are the one-at-a-time ones.
fn batch_table(op: &mut LfdOperator, f: &gustkit_cfd::lfd::Factored, omega: f64, mach: f64) {
    let Ok(list) = std::env::var("WING_BATCHES") else {
        return;
    };
    let repeat = repeat_count();
    let rhs: Vec<_> = (0..12)
        .map(|i| {
            op.gust_rhs(
                omega,
                &HarmonicGust {
                    convection: mach * (0.6 + 0.05 * i as f64),
                    x0: 0.0,
                },
            )
        })
        .collect();
    let reverse = gustkit_cfd::adjoint::LfdReverse::new(op);
    let restart = op.params.restart;
    if let Some(r) = std::env::var("WING_RESTART")
        .ok()
        .and_then(|r| r.parse().ok())
    {
        op.params.restart = r;
    }
    println!(
        "  12 right-hand sides at k = 0.5, GMRES restart {}, tolerance {:.0e}:",
        op.params.restart, op.params.tolerance
    );
    let mut first: Option<Vec<Vec<num_complex::Complex64>>> = None;
    for b in list
        .split(',')
        .map(|b| b.trim().parse::<usize>().expect("batch size"))
    {
        op.params.batch = b;
        let (mut forward, mut transposed) = (Vec::new(), Vec::new());
        let mut its = (0, 0);
        let mut answers = Vec::new();
        for rep in 0..=repeat {
            let t = Instant::now();
            let fw = op.solve(f, &rhs).expect("forward solves");
            let t_fw = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let tr = reverse
                .solve_transpose(op, f, &rhs)
                .expect("transposed solves");
            let t_tr = t.elapsed().as_secs_f64();
            if rep > 0 {
                forward.push(t_fw);
                transposed.push(t_tr);
            }
            its = (
                fw.iter().map(|s| s.1.iterations).sum::<usize>(),
                tr.iter().map(|s| s.1.iterations).sum::<usize>(),
            );
            answers = fw.into_iter().chain(tr).map(|s| s.0).collect();
        }
        let same = match &first {
            None => {
                first = Some(answers);
                "the reference".to_string()
            }
            Some(a) => (a == &answers).to_string(),
        };
        let (fm, fl, fh) = spread(forward);
        let (tm, tl, th) = spread(transposed);
        println!(
            "  batch {b:>2}: 12 forward solves {fm:.2} s (min {fl:.2}, max {fh:.2}; {} GMRES iterations), 12 transposed {tm:.2} s (min {tl:.2}, max {th:.2}; {} iterations), {repeat} repetitions after a warm-up; answers equal to batch-1's bit for bit: {same}; peak memory {:.2} GB",
            its.0,
            its.1,
            peak_gb()
        );
    }
    op.params.batch = 1;
    op.params.restart = restart;
}

/// One way of computing a deformation figure, returning the bits of its answers.
type Timed<'a> = Box<dyn Fn() -> Vec<Vec<u64>> + 'a>;

/// The mesh deformation of 11 mode shapes (the design loop's function), its transpose for 22
/// seeds (two gradients' modes) and its dual-number form along one planform tangent (the
/// gradient's geometry part, once a tangent): one field a call against all in one call (a
/// node's distances and weights once for all fields), `WING_REPEAT` repetitions after a
/// warm-up, with whether the answers agree bit for bit. `WING_DEFORM=0` skips it.
fn deform_table(mesh: &gustkit_cfd::mesh::Mesh, root_chord: f64) {
    if std::env::var("WING_DEFORM").as_deref() == Ok("0") {
        return;
    }
    let repeat = repeat_count();
    let d = Deformation::new(mesh, 5.0 * root_chord);
    let nw = d.wall_nodes.len();
    let walls: Vec<Vec<[f64; 3]>> = (0..11)
        .map(|m| {
            (0..nw)
                .map(|i| {
                    let x = i as f64 / nw as f64;
                    [0.0, 0.0, (x * (m + 1) as f64).sin()]
                })
                .collect()
        })
        .collect();
    let walls: Vec<&[[f64; 3]]> = walls.iter().map(Vec::as_slice).collect();
    let seeds: Vec<Vec<[f64; 3]>> = (0..22)
        .map(|m| {
            (0..mesh.nodes.len())
                .map(|n| [0.0, ((n * (m + 1)) as f64 * 1e-3).cos(), 1.0])
                .collect()
        })
        .collect();
    let seeds: Vec<&[[f64; 3]]> = seeds.iter().map(Vec::as_slice).collect();
    let nodes: Vec<[Dual<1>; 3]> = mesh
        .nodes
        .iter()
        .map(|p| std::array::from_fn(|k| Dual::new(p[k], [0.1 * p[k]])))
        .collect();
    let radius = Dual::new(d.radius, [0.5]);
    let time = |f: &dyn Fn() -> Vec<Vec<u64>>| {
        let mut times = Vec::new();
        let mut out = Vec::new();
        for rep in 0..=repeat {
            let t = Instant::now();
            out = f();
            if rep > 0 {
                times.push(t.elapsed().as_secs_f64());
            }
        }
        (spread(times), out)
    };
    let bits = |v: &[[f64; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect();
    let dual_bits = |v: &[[Dual<1>; 3]]| {
        v.iter()
            .flatten()
            .flat_map(|x| [x.v.to_bits(), x.d[0].to_bits()])
            .collect()
    };
    let cases: [(&str, Timed, Timed); 3] = [
        (
            "11 mode shapes spread",
            Box::new(|| walls.iter().map(|w| bits(&d.apply(w))).collect()),
            Box::new(|| d.apply_many(&walls).iter().map(|v| bits(v)).collect()),
        ),
        (
            "22 seeds through the transpose",
            Box::new(|| seeds.iter().map(|s| bits(&d.apply_transpose(s))).collect()),
            Box::new(|| {
                d.apply_transpose_many(&seeds)
                    .iter()
                    .map(|v| bits(v))
                    .collect()
            }),
        ),
        (
            "11 mode shapes along a planform tangent (dual numbers)",
            Box::new(|| {
                walls
                    .iter()
                    .map(|w| dual_bits(&d.apply_at(&nodes, radius, w)))
                    .collect()
            }),
            Box::new(|| {
                d.apply_at_many(&nodes, radius, &walls)
                    .iter()
                    .map(|v| dual_bits(v))
                    .collect()
            }),
        ),
    ];
    println!(
        "  mesh deformation ({} nodes, {nw} wall nodes), {repeat} repetitions after a warm-up:",
        mesh.nodes.len()
    );
    for (name, one, many) in &cases {
        let ((om, ol, oh), a) = time(one.as_ref());
        let ((mm, ml, mh), b) = time(many.as_ref());
        println!(
            "    {name}: one a call {om:.3} s (min {ol:.3}, max {oh:.3}), together {mm:.3} s (min {ml:.3}, max {mh:.3}); the same bits: {}",
            a == b
        );
    }
}

fn main() {
    let levels = std::env::var("WING_LEVELS").unwrap_or_else(|_| "coarse".into());
    let threads = rayon::current_num_threads();
    println!("threads: {threads} (RAYON_NUM_THREADS); every figure one run");
    let p = [0.762, 45f64.to_radians(), 0.5587, 0.3682];
    let mach = 0.5;
    for level in levels.split(',') {
        let spec = WingMeshSpec::level(level).expect("coarse, medium or fine");
        let t = Instant::now();
        let wing = WingMesh::new(p, &naca65a004, &spec);
        let t_mesh = t.elapsed().as_secs_f64();
        let q = wing.quality();
        deform_table(&wing.mesh, p[2]);
        let e = Euler::new(wing.mesh.clone(), free_stream(mach, 0.0));
        let n = e.mesh.n_cells;
        let t = Instant::now();
        let params = SteadyParams {
            linear_solver: NewtonLinearSolver::BlockIlu,
            ilu: IluParams {
                fill: 1,
                ordering: IluOrdering::ReverseCuthillMckee,
                ..IluParams::default()
            },
            ..SteadyParams::default()
        };
        let (q0, info) = e.solve_steady(vec![e.q_inf; n], &params).expect("steady");
        let t_steady = t.elapsed().as_secs_f64();
        preconditioner_table(&e, &q0, mach, p[2]);
        let t = Instant::now();
        let mut op = LfdOperator::with_preconditioner(e, q0, Preconditioner::FirstOrderIlu);
        op.params.tolerance = 1e-8;
        op.params.ilu = IluParams {
            fill: 1,
            ordering: IluOrdering::ReverseCuthillMckee,
            ..IluParams::default()
        };
        let t_jac = t.elapsed().as_secs_f64();
        let omega = 0.5 * mach / (0.5 * p[2]);
        let t = Instant::now();
        let f = op.factor(omega, Symbol::Exact).expect("factor");
        let t_fac = t.elapsed().as_secs_f64();
        let gust = gust_rhs(&op, omega, mach);
        let t = Instant::now();
        let sol = op.solve(&f, &[gust]).expect("solve");
        let t_rhs = t.elapsed().as_secs_f64();
        batch_table(&mut op, &f, omega, mach);
        drop(f);
        if std::env::var("WING_TABLE").as_deref() == Ok("0") {
            println!(
                "{level}: {n} cells; steady {t_steady:.1} s; Jacobian {t_jac:.2} s; ILU(1) factor {t_fac:.2} s; one right-hand side {t_rhs:.2} s ({} GMRES iterations); GAF table not run (WING_TABLE=0)",
                sol[0].1.iterations
            );
            continue;
        }
        // six smooth shapes on the wall (bending and torsion polynomials), 11 frequencies
        // (the forward solutions stay in memory here: the studies' scratch files are
        // gustkit's, whose `gustkit gafs` measures them)
        let model = Lfd::new(op, 1.0, 1.0, 5.0 * p[2]);
        let pts = &model.surface().points;
        let mut modes = ModalSurface::zeros(6, pts.len());
        for (i, x) in pts.iter().enumerate() {
            let (eta, xi) = (x[1] / p[0], x[0] - 0.25 * p[2] - x[1]);
            let w = [
                eta * eta,
                eta * xi,
                eta.powi(3),
                eta * eta * xi,
                eta.powi(4),
                eta * xi * xi,
            ];
            for m in 0..6 {
                modes.disp[m][i] = [0.0, 0.0, 0.01 * w[m]];
            }
        }
        let flight = FlightCondition {
            mach,
            velocity: 172.8,
            density: 0.2139,
            b_ref: 0.5 * p[2],
            x_ref: 0.0,
        };
        let k = [
            0.0, 0.02, 0.08, 0.18, 0.32, 0.5, 0.72, 0.98, 1.28, 1.62, 2.0,
        ];
        let peak_build = peak_gb();
        reset_peak();
        let t = Instant::now();
        let mut seed = model.gafs(&flight, &modes, &k).expect("GAF table");
        let t_table = t.elapsed().as_secs_f64();
        let peak_table = peak_gb();
        if std::env::var("WING_REVERSE").as_deref() == Ok("0") {
            println!(
                "{level}: {n} cells; GAF table (11 k × 7 right-hand sides) {t_table:.1} s; peak memory: model {peak_build:.2} GB, GAF table {peak_table:.2} GB ({:.1} kB a cell); reverse not run (WING_REVERSE=0)",
                peak_table * 1e6 / n as f64
            );
            continue;
        }
        reset_peak();
        // the reverse mode: its Jacobians once (all but ∂R/∂x, which each sweep recomputes),
        // then every GAF entry seeded
        let t = Instant::now();
        let rev = model.reverse_linearizations();
        let t_rev = t.elapsed().as_secs_f64();
        for q in seed.q_ss.iter_mut().flatten().flatten() {
            *q = num_complex::Complex64::new(1.0, 0.5);
        }
        for q in seed.q_gs.iter_mut().flatten() {
            *q = num_complex::Complex64::new(0.5, -1.0);
        }
        let t = Instant::now();
        model
            .gafs_vjp(&flight, &modes, &k, &seed)
            .expect("GAF reverse");
        let t_vjp = t.elapsed().as_secs_f64();
        println!(
            "{level}: {n} cells (quality: min volume {:.2e} m³, aspect ratio ≤ {:.0}, non-orthogonality ≤ {:.1}°); mesh {t_mesh:.2} s; steady {t_steady:.1} s ({} Newton iterations to {:.1e}); Jacobian {t_jac:.2} s; first-order block ILU(1), RCM, at k = 0.5 {t_fac:.2} s; one right-hand side {t_rhs:.2} s ({} GMRES iterations); GAF table (11 k × 7 right-hand sides) {t_table:.1} s = {:.4} core-s per cell; peak memory {:.2} GB",
            q.min_volume,
            q.max_aspect_ratio,
            q.max_skewness_deg,
            info.iterations,
            info.residual_history.last().unwrap_or(&f64::NAN),
            sol[0].1.iterations,
            t_table * threads as f64 / n as f64,
            peak_build.max(peak_table)
        );
        println!(
            "{level}: reverse mode: Jacobians (dV/dx, dR/dv_G, df/dq, df/dx) {t_rev:.2} s, {:.0} B a cell ({} + {} coloured evaluations); GAF reverse (every entry seeded; dR/dx recomputed by the node colours in it) {t_vjp:.1} s = {:.4} core-s per cell; peak memory: model {peak_build:.2} GB, GAF table {peak_table:.2} GB ({:.1} kB a cell), reverse {:.2} GB ({:.1} kB a cell)",
            rev.bytes() as f64 / n as f64,
            rev.motion.evaluations,
            rev.forces.evaluations,
            t_vjp * threads as f64 / n as f64,
            peak_table * 1e6 / n as f64,
            peak_gb(),
            peak_gb() * 1e6 / n as f64
        );
    }
    println!(
        "paper (FUN3D LFD, 219 555 nodes, 400 cores): function 70.5 min = {:.2} core-s per node, gradient 146.4 min = {:.2}",
        70.5 * 60.0 * 400.0 / 219_555.0,
        146.4 * 60.0 * 400.0 / 219_555.0
    );
}
