//! `cargo bench -p gustkit-dlm --bench kernel`: cost of one incremental-kernel evaluation and of
//! one influence-matrix entry.
use gustkit_dlm::kernel::{incremental_numerators, integrals};
use std::time::Instant;

fn main() {
    let n = 2_000_000;
    let t = Instant::now();
    let mut acc = 0.0;
    for i in 0..n {
        let u = -3.0 + 6.0 * (i as f64) / n as f64;
        let (a, b) = integrals::<f64>(u, 0.7);
        acc += a.re + b.im;
    }
    let ti = t.elapsed().as_secs_f64() / n as f64;
    let t = Instant::now();
    for i in 0..n {
        let x = 0.1 + (i as f64) / n as f64;
        let (a, b) = incremental_numerators::<f64>(x, 0.3 - x * 0.2, 0.0, 1.0, 0.0, 2.0, 0.5);
        acc += a.re + b.im;
    }
    let tk = t.elapsed().as_secs_f64() / n as f64;
    println!(
        "integrals I1, I2: {:.1} ns; kernel numerators P1, P2: {:.1} ns ({acc:.3})",
        ti * 1e9,
        tk * 1e9
    );
}
