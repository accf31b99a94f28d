//! `cargo bench --bench structure`: assembly + modal analysis + all sensitivities of the AGARD
//! 445.6 plate model (10 × 10 elements, 104 design variables). Prints the median timings.

fn main() -> anyhow::Result<()> {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/agard445_dlm_analysis.json");
    let study = gustkit::study::Study::load(&file)?;
    let t = gustkit::runner::bench::bench_structure(&study, 50)?;
    println!(
        "structure/agard445 ({} dv, {} modes): assembly {:.2} ms, modes {:.2} ms, sensitivities {:.2} ms, total {:.2} ms",
        t.n_dv,
        t.n_modes,
        1e3 * t.assembly_s,
        1e3 * t.modes_s,
        1e3 * t.sensitivities_s,
        1e3 * t.total_s
    );
    Ok(())
}
