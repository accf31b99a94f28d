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
    design_gradients(repeat)
}

/// A cantilever plate wing of 4 × 8 CQUAD4s, each its own PSHELL (32 thickness variables), 8
/// modes, one CAERO1 of 4 × 8 boxes on an infinite-plate spline, the bar wing's gust cards.
fn plate_deck() -> String {
    let mut d = String::from(
        "SOL 146\nCEND\nSPC = 1\nMETHOD = 1\nFREQ = 40\nRANDOM = 31\nGUST = 32\nSDAMP = 20\nBEGIN BULK\n",
    );
    d.push_str("EIGRL,1,,,8\nMAT1,1,7.0e10,,0.3,2700.\n");
    for iy in 0..9 {
        for ix in 0..5 {
            let (x, y) = (0.125 * ix as f64, 0.25 * iy as f64);
            d.push_str(&format!("GRID,{},,{x},{y},0.\n", 1 + ix + 5 * iy));
        }
    }
    for iy in 0..8 {
        for ix in 0..4 {
            let (e, g) = (1 + ix + 4 * iy, 1 + ix + 5 * iy);
            d.push_str(&format!("PSHELL,{e},1,{},1\n", 0.012 - 0.0008 * iy as f64));
            d.push_str(&format!(
                "CQUAD4,{e},{e},{g},{},{},{}\n",
                g + 1,
                g + 6,
                g + 5
            ));
        }
    }
    d.push_str("CONM2,201,45,,0.5\nSPC1,1,123456,1,THRU,5\n");
    d.push_str("AERO,0,100.,0.5,0.4\nPARAM,MACH,0.3\n");
    d.push_str("CAERO1,1001,1000,,8,4,,,1,+CA\n+CA,0.,0.,0.,0.5,0.,2.,0.,0.5\nPAERO1,1000\n");
    d.push_str("SPLINE1,100,1001,1001,1032,10\nSET1,10,1,THRU,45\n");
    d.push_str("MKAERO1,0.3,,,,,,,,+MK\n+MK,0.01,0.1,0.5,1.0\n");
    d.push_str("GUST,32,33,0.01,0.,100.\nRLOAD1,33,34,,,35\nDAREA,34,1,3,1.\n");
    d.push_str("TABLED1,35,,,,,,,,+TB\n+TB,0.,1.,1000.,1.,ENDT\n");
    d.push_str("FREQ1,40,0.1,0.25,79\nRANDPS,31,1,1,1.,,36\n");
    d.push_str("TABRND1,36,,,,,,,,+TR\n+TR,0.,1.,1000.,1.,ENDT\n");
    d.push_str("TABDMP1,20,CRIT,,,,,,,+TD\n+TD,0.,0.02,1000.,0.02,ENDT\nENDDATA\n");
    d
}

/// The gradients of a design study's mass and two RMS limits with respect to 32 PSHELL
/// thicknesses: the forward mode (a sweep a variable) against the reverse mode (a sweep a
/// limit), with the analysis beside them.
fn design_gradients(repeat: usize) -> anyhow::Result<()> {
    use gustkit::nastran::design::{parse_output, DesignModel, PropertyRelation};
    let dir = std::env::temp_dir().join(format!("gustkit-bench-design-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let file = dir.join("plate32.bdf");
    std::fs::write(&file, plate_deck())?;
    let (base, sub) = load(&file)?;
    let relations = (0..32)
        .map(|e| PropertyRelation::new(&base, "PSHELL", e + 1, "T", 0.0, vec![(e as usize, 1.0)]))
        .collect::<Result<Vec<_>, _>>()?;
    let (_, modes) = subcase_modes(&base, &sub)?;
    let x0: Vec<f64> = relations.iter().map(|r| r.current(&base)).collect();
    let model = DesignModel {
        n_modes: modes.lambda.len(),
        base,
        sub,
        relations,
        requests: ["45T3", "SPCF 3R1"]
            .iter()
            .map(|l| parse_output(l).expect("a label"))
            .collect(),
        interpolation: KInterpolation::Dense((0..=40).map(|i| 0.35 * i as f64 / 40.0).collect()),
        n_variables: 32,
        lfd: None,
    };
    let p = model.analyse(&x0)?;
    println!(
        "design gradients (plate wing: 32 CQUAD4s, 32 PSHELL thickness variables, {} modes, 32 boxes, 2 outputs):",
        model.n_modes
    );
    let analysis = measure(repeat, || {
        let t0 = Instant::now();
        model.analyse(&x0)?;
        Ok(t0.elapsed().as_secs_f64())
    })?;
    println!("{}", analysis.line("analysis (modes, mass, response)"));
    let forward = measure(3, || {
        let t0 = Instant::now();
        model.gradients(&p)?;
        Ok(t0.elapsed().as_secs_f64())
    })?;
    println!("{}", forward.line("forward mode: 32 variables"));
    let functionals = vec![vec![(1.0, 0.0), (0.0, 0.0)], vec![(0.0, 0.0), (1.0, 0.0)]];
    let reverse = measure(repeat, || {
        let t0 = Instant::now();
        model.gradients_reverse(&p, &functionals)?;
        Ok(t0.elapsed().as_secs_f64())
    })?;
    println!("{}", reverse.line("reverse mode: 2 limits"));
    let _ = std::fs::remove_dir_all(&dir);
    splines()?;
    Ok(())
}

/// SPLINE1 over every grid of an n × n plate (square, 1 m) to the 16 × 16 boxes of a CAERO1
/// on it: the spline's dense (n² + 3)² system, factored once, is O(n⁶); the model's dense
/// structure (6 000 components, 1 000 grids) bounds a spline's grids before it does.
fn splines() -> anyhow::Result<()> {
    use gustkit::nastran::aero::{lifting_surfaces, spline_rows};
    use gustkit::nastran::structure::Structure;
    println!("SPLINE1 over every grid of a plate, to 16 × 16 boxes (1 warm-up, 5 repetitions):");
    for n in [10usize, 20, 30] {
        let mut d = String::from(
            "SOL 145\nCEND\nBEGIN BULK\nMAT1,1,7.0e10,,0.3,2700.\nPSHELL,1,1,0.01,1\n",
        );
        for j in 0..=n {
            for i in 0..=n {
                d.push_str(&format!(
                    "GRID,{},,{},{},0.\n",
                    1 + i + (n + 1) * j,
                    i as f64 / n as f64,
                    j as f64 / n as f64
                ));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let g = 1 + i + (n + 1) * j;
                d.push_str(&format!(
                    "CQUAD4,{},1,{g},{},{},{}\n",
                    1 + i + n * j,
                    g + 1,
                    g + n + 2,
                    g + n + 1
                ));
            }
        }
        let grids = (n + 1) * (n + 1);
        d.push_str("AERO,0,100.,1.,1.2\nCAERO1,100001,1000,,16,16,,,1,+CA\n+CA,0.,0.,0.,1.,0.,1.,0.,1.\nPAERO1,1000\n");
        d.push_str(&format!(
            "SPLINE1,100,100001,100001,100256,10\nSET1,10,1,THRU,{grids}\nENDDATA\n"
        ));
        let file = std::env::temp_dir().join(format!("gustkit-bench-spline-{n}.bdf"));
        std::fs::write(&file, d)?;
        let (b, _) = load(&file)?;
        let _ = std::fs::remove_file(&file);
        let s = Structure::assemble(&b, None)?;
        let surf = lifting_surfaces(&b, &s)?;
        let t = measure(5, || {
            let t0 = Instant::now();
            spline_rows(&b, &s, &surf)?;
            Ok(t0.elapsed().as_secs_f64())
        })?;
        println!("{}", t.line(&format!("{grids} grids ({n} × {n} elements)")));
    }
    Ok(())
}
