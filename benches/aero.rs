//! `cargo bench --bench aero`: DLM influence matrices, factorizations, GAFs and their reverse mode
//! for the AGARD 445.6 study (400 boxes, 11 reduced frequencies, 6 modes).

fn main() -> anyhow::Result<()> {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm_analysis.json");
    let study = gustkit::study::Study::load(&file)?;
    let a = gustkit::runner::bench::bench_aero(&study, 3)?;
    println!(
        "aero/agard445 ({} boxes, {} k, {} modes, {} threads):",
        a.n_boxes,
        a.n_k,
        a.n_modes,
        rayon::current_num_threads()
    );
    println!("{}", a.assembly.line("influence matrices (all k)"));
    println!("{}", a.factorization.line("LU (all k, 1 thread)"));
    println!("{}", a.gafs.line("GAFs"));
    println!("{}", a.gafs_vjp.line("reverse mode"));
    Ok(())
}
