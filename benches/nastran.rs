//! `cargo bench --bench nastran`: the published NASTRAN-95 decks through gustkit's Nastran path —
//! reading, modes, and the gust responses (random D11-03-1A, transient D11-03-2A: 42 boxes, 12
//! modes, 40 frequencies) — with warm-up, repetitions and the thread count.

use gustkit::nastran::bulk::BulkData;
use gustkit::nastran::random::{random_response, KInterpolation, Quantity};
use gustkit::nastran::structure::subcase_modes;
use gustkit::nastran::transient::transient_response;
use gustkit::nastran::{Input, Subcase};
use gustkit::runner::bench::measure;
use std::path::Path;
use std::time::Instant;

/// A deck's bulk data and its first subcase.
fn load(deck: &Path) -> anyhow::Result<(BulkData, Subcase)> {
    let input = Input::read(deck)?;
    let b = BulkData::from_cards(&input.deck.bulk)?;
    let sub = input
        .case_control
        .subcase(1)
        .ok_or_else(|| anyhow::anyhow!("{}: no subcase 1", deck.display()))?;
    Ok((b, sub))
}

fn main() -> anyhow::Result<()> {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/nastran");
    let repeat = 20;
    println!(
        "nastran (NASTRAN-95 D11-03-1A/2A: 42 boxes, 12 modes, 40 frequencies; {} threads):",
        rayon::current_num_threads()
    );
    let read = measure(repeat, || {
        let t0 = Instant::now();
        load(&data.join("d11031a.inp"))?;
        Ok(t0.elapsed().as_secs_f64())
    })?;
    println!("{}", read.line("read the deck (cards, case control)"));
    let (b, sub) = load(&data.join("d11031a.inp"))?;
    let modes = measure(repeat, || {
        let t0 = Instant::now();
        subcase_modes(&b, &sub)?;
        Ok(t0.elapsed().as_secs_f64())
    })?;
    println!("{}", modes.line("assembly, reduction, 12 modes"));
    let (s, m) = subcase_modes(&b, &sub)?;
    let k: Vec<f64> = (0..=40).map(|i| 0.5 * i as f64 / 40.0).collect();
    let requests = [
        (11, 3, Quantity::Displacement),
        (9, 3, Quantity::Displacement),
        (11, 6, Quantity::SpcForce),
    ];
    let random = measure(repeat, || {
        let t0 = Instant::now();
        random_response(
            &b,
            &sub,
            &s,
            &m,
            &requests,
            &KInterpolation::Dense(k.clone()),
        )?;
        Ok(t0.elapsed().as_secs_f64())
    })?;
    println!(
        "{}",
        random.line("random response (DLM on 41 k, 3 outputs)")
    );
    let (b, sub) = load(&data.join("d11032a.inp"))?;
    let (s, m) = subcase_modes(&b, &sub)?;
    let transient = measure(repeat, || {
        let t0 = Instant::now();
        transient_response(
            &b,
            &sub,
            &s,
            &m,
            &requests,
            &KInterpolation::Dense(k.clone()),
        )?;
        Ok(t0.elapsed().as_secs_f64())
    })?;
    println!(
        "{}",
        transient.line("transient response (41 times, 3 outputs)")
    );
    Ok(())
}
