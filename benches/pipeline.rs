//! `cargo bench --bench pipeline`: one function evaluation and one gradient of the AGARD 445.6 DLM
//! gust problem (104 variables, 11 reduced frequencies, 6 modes, 400 boxes).

fn main() -> anyhow::Result<()> {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm_analysis.json");
    let study = gustkit::study::Study::load(&file)?;
    let p = gustkit::runner::bench::bench_pipeline(&study, 3)?;
    println!(
        "pipeline/agard445 ({} threads):",
        rayon::current_num_threads()
    );
    println!("{}", p.function.line("function"));
    println!("{}", p.gradient.line("gradient"));
    Ok(())
}
