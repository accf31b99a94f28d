//! `cargo bench --bench aero`: DLM influence matrices, factorizations, GAFs and their reverse mode
//! for the AGARD 445.6 study (400 boxes, 11 reduced frequencies, 6 modes).

fn main() -> anyhow::Result<()> {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm_analysis.json");
    let study = gustkit::study::Study::load(&file)?;
    let a = gustkit::runner::bench::bench_aero(&study, 3)?;
    println!(
        "aero/agard445 ({} boxes, {} k, {} modes): influence matrices {:.1} ms (all k), LU {:.1} ms (1 thread), GAFs {:.1} ms, reverse mode {:.1} ms",
        a.n_boxes,
        a.n_k,
        a.n_modes,
        1e3 * a.assembly_s,
        1e3 * a.factorization_s,
        1e3 * a.gafs_s,
        1e3 * a.gafs_vjp_s
    );
    Ok(())
}
