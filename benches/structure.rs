//! `cargo bench --bench structure`: assembly + modal analysis + all sensitivities of the AGARD
//! 445.6 plate model (10 × 10 elements, 104 design variables). Prints the median timings.

fn main() -> anyhow::Result<()> {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm_analysis.json");
    let study = gustkit::study::Study::load(&file)?;
    let t = gustkit::runner::bench::bench_structure(&study, 50)?;
    println!(
        "structure/agard445 ({} dv, {} modes, {} threads):",
        t.n_dv,
        t.n_modes,
        rayon::current_num_threads()
    );
    println!("{}", t.assembly.line("assembly"));
    println!("{}", t.modes.line("modes"));
    println!("{}", t.sensitivities.line("sensitivities"));
    println!("{}", t.total.line("total"));
    Ok(())
}
