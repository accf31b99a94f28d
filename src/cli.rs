//! The `gustkit` command line: argument parsing and dispatch to the runners (`crate::runner`).
//! Every study is loaded once here, through [`LoadedStudy::load`], which decides its kind.

use crate::runner;
use crate::runner::LoadedStudy;
use anyhow::Result;
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "gustkit",
    version,
    about = "Aeroelastic gust analysis and gust-constrained wing design"
)]
pub struct Cli {
    /// On an error, print its full debug form (with a backtrace where RUST_BACKTRACE asks for
    /// one) instead of the one-line message.
    #[arg(long, global = true)]
    pub debug: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Run a study: every analysis its file defines, with a report in reports/<study name>/.
    Run {
        study: PathBuf,
        /// Folder that holds the per-study report folders.
        #[arg(long, default_value = "reports")]
        reports: PathBuf,
        /// Continue an interrupted optimization from its checkpoint in the report folder.
        #[arg(long)]
        resume: bool,
        /// Analyse the final design of a run (its results.json) instead of the study's initial
        /// design, for an analysis study (no `optimization` section): another run's optimum with
        /// this study's fidelity, lattice, modes and gust. The report goes to
        /// reports/<study>_at_<run folder>/.
        #[arg(long, value_name = "RESULTS_JSON", conflicts_with = "resume")]
        design: Option<PathBuf>,
    },
    /// Run the study's `sweep` section: every case in parallel, then a table, CSV and figure in
    /// reports/<study>/sweep/.
    Sweep {
        study: PathBuf,
        /// Folder that holds the per-study report folders.
        #[arg(long, default_value = "reports")]
        reports: PathBuf,
        /// Reuse the results of cases that finished in an earlier, interrupted sweep.
        #[arg(long)]
        resume: bool,
    },
    /// Re-render every figure and summary.md of a run folder from its results.json alone.
    Report {
        /// A run folder written by `gustkit run` (holds results.json).
        run_dir: PathBuf,
    },
    /// One report across optimization runs and fidelities (convergence, thickness maps, PSDs,
    /// GAFs, cross-evaluation), from their results.json files alone.
    Compare {
        /// Run folders written by `gustkit run` of optimization studies.
        #[arg(required = true)]
        run_dirs: Vec<PathBuf>,
        /// Folder of the comparison report.
        #[arg(long, default_value = "reports/compare")]
        out: PathBuf,
    },
    /// Modal analysis of a study's wing: frequency table, mode-shape figures and a VTK file.
    Modes {
        study: PathBuf,
        /// Print a JSON object instead of the table.
        #[arg(long)]
        json: bool,
        /// Folder that holds the per-study report folders.
        #[arg(long, default_value = "reports")]
        reports: PathBuf,
    },
    /// Generalized aerodynamic forces of a study's modes at its reduced frequencies, as JSON.
    Gafs {
        study: PathBuf,
        /// Output file.
        #[arg(long)]
        out: PathBuf,
    },
    /// Box geometry and complex influence matrices of a study's DLM or of a surface file.
    Aic {
        /// A study file or a surface file {"b_ref", "symmetry", "surfaces": [...]} (SI).
        input: PathBuf,
        #[arg(long, allow_negative_numbers = true)]
        mach: f64,
        /// Reduced frequencies, comma separated.
        #[arg(
            long,
            value_delimiter = ',',
            required = true,
            allow_negative_numbers = true
        )]
        k: Vec<f64>,
        /// Output file.
        #[arg(long)]
        out: PathBuf,
    },
    /// p-k flutter sweep at the study's Mach number and density, with V-g and V-f figures.
    Flutter {
        study: PathBuf,
        /// Print JSON (flutter_speed_m_s, flutter_frequency_hz, per-mode curves).
        #[arg(long)]
        json: bool,
        /// Folder that holds the per-study report folders.
        #[arg(long, default_value = "reports")]
        reports: PathBuf,
        /// Skip the sweep at twice the modes and lattice (for a study already at a fine
        /// resolution, whose doubled lattice would need many times its memory).
        #[arg(long)]
        no_resolution_check: bool,
        /// Analyse the final design of a run (its results.json) instead of the study's initial
        /// design: another run's optimum with this study's fidelity, lattice and modes. The
        /// report goes to reports/<study>_at_<run folder>/.
        #[arg(long, value_name = "RESULTS_JSON")]
        design: Option<PathBuf>,
    },
    /// Adjoint gradient of the gust RMS against finite differences (like paper Table 4).
    CheckGradient {
        study: PathBuf,
        /// Design variables to check (t[i], span, sweep_c4, root_chord, tip_chord), one or more
        /// after one `--dv` or each after its own.
        #[arg(long = "dv", num_args = 1.., default_values_t = ["t[9]".to_string(), "sweep_c4".to_string()])]
        dv: Vec<String>,
        /// Print the rows as JSON (dv, adjoint, fd, fd_best, rel_error).
        #[arg(long)]
        json: bool,
    },
    /// The aerodynamic model's linearizations against their transposes and finite differences
    /// at steps 1e-8 … 1e-13 (like paper Table 3), at the study's initial design.
    CheckLinearization {
        study: PathBuf,
        /// Print the rows as JSON (name, forward, reverse, fd).
        #[arg(long)]
        json: bool,
    },
    /// The LFD analysis of the study's initial design (or of a run's optimum, `--design`) on
    /// the built-in mesh levels: RMS, GAF differences to the DLM of `aero.compare_with`,
    /// model-build and GAF-table times, peak memory, and over three levels the Richardson
    /// extrapolate (mesh_study.json, a figure and summary.md in reports/<study name>/; levels
    /// already in the file are kept, so each level can run on its own)
    MeshStudy {
        study: PathBuf,
        /// Comma-separated levels: coarse, medium, fine.
        #[arg(long, value_delimiter = ',', default_value = "coarse,medium,fine")]
        levels: Vec<String>,
        /// Folder that holds the per-study report folders (the study's is <reports>/<study name>).
        #[arg(long, default_value = "reports")]
        reports: PathBuf,
        /// Study the final design of a run (its results.json) instead of the study's initial
        /// design: another run's optimum on the mesh levels, against the study's DLM. The
        /// report goes to <reports>/<study>_at_<run folder>/.
        #[arg(long, value_name = "RESULTS_JSON")]
        design: Option<PathBuf>,
    },
    /// Benchmarks of a study (warm-up, repetitions, median/min/max, thread count): the
    /// structural chain (assembly, modes, all sensitivities), the aerodynamics, the gust
    /// response and its gradient; an LFD study's GAF table, gradient and warm starts.
    Bench {
        study: PathBuf,
        /// Timed repetitions of each line after one warm-up run (median, min and max are
        /// reported); default 20, and 1 for an LFD study (a GAF table takes a minute). 0, for an
        /// LFD study only: the first calls alone (the model, one GAF table, one reverse call and
        /// their peak memory), for a mesh level where a call takes hours.
        #[arg(long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(0..))]
        repeat: Option<usize>,
        /// Also time the study's whole optimization once (from scratch, no checkpoint).
        #[arg(long)]
        optimization: bool,
        /// An LFD study's built-in mesh level instead of its own (coarse, medium, fine): the
        /// per-level figures of the same study.
        #[arg(long)]
        mesh: Option<String>,
        /// With `--repeat 0`: the GAF table and reverse call at these reduced frequencies
        /// instead of the study's (comma separated): the cost and peak memory of one frequency
        /// of a level where the whole table takes hours.
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
        k: Vec<f64>,
    },
}

/// Loads a study that must be a wing study (`command` names the subcommand in the error).
fn wing(file: &Path, command: &str) -> Result<crate::study::Study> {
    LoadedStudy::load(file)?.into_wing(file, command)
}

/// The wing study of `file`, at the final design of the run whose results.json is `design`
/// where one is given (`--design` of `flutter` and `mesh-study`).
fn wing_at(file: &Path, command: &str, design: Option<&Path>) -> Result<crate::study::Study> {
    let study = wing(file, command)?;
    Ok(match design {
        Some(d) => study.at_final_design(d)?,
        None => study,
    })
}

/// Runs the parsed command line.
pub fn dispatch(cli: Cli) -> Result<runner::Outcome> {
    let done = |r: Result<()>| r.map(|()| runner::Outcome::Done);
    match cli.command {
        Command::Run {
            study,
            reports,
            resume,
            design: None,
        } => runner::run(&study, &reports, resume),
        Command::Run {
            study,
            reports,
            design: Some(design),
            ..
        } => runner::run_design(&study, &reports, &design),
        Command::Report { run_dir } => done(runner::report(&run_dir)),
        Command::Compare { run_dirs, out } => {
            done(crate::report::compare::compare(&run_dirs, &out))
        }
        Command::Sweep {
            study,
            reports,
            resume,
        } => runner::sweep::sweep(&wing(&study, "sweep")?, &reports, resume),
        Command::Modes {
            study,
            json,
            reports,
        } => done(runner::wing::modes(&wing(&study, "modes")?, json, &reports)),
        Command::Gafs { study, out } => done(runner::export::gafs(&wing(&study, "gafs")?, &out)),
        Command::Aic {
            input,
            mach,
            k,
            out,
        } => done(runner::export::aic(&input, mach, &k, &out)),
        Command::Flutter {
            study,
            json,
            reports,
            no_resolution_check,
            design,
        } => done(runner::wing::flutter::flutter(
            &wing_at(&study, "flutter", design.as_deref())?,
            json,
            &reports,
            !no_resolution_check,
        )),
        Command::CheckGradient { study, dv, json } => done(runner::wing::gradient::check_gradient(
            &wing(&study, "check-gradient")?,
            &dv,
            json,
        )),
        Command::CheckLinearization { study, json } => {
            done(runner::wing::gradient::check_linearization(
                &wing(&study, "check-linearization")?,
                json,
            ))
        }
        Command::MeshStudy {
            study,
            levels,
            reports,
            design,
        } => {
            let study = wing_at(&study, "mesh-study", design.as_deref())?;
            let dir = reports.join(&study.spec.name);
            done(runner::wing::mesh_study::mesh_study(
                &study,
                &levels,
                &dir,
                design.as_deref(),
            ))
        }
        Command::Bench {
            study,
            repeat,
            optimization,
            mesh,
            k,
        } => {
            let mut study = wing(&study, "bench")?;
            if let Some(level) = mesh {
                runner::wing::mesh_study::set_level(&mut study, &level)?;
            }
            if !k.is_empty() {
                runner::bench::set_frequencies(&mut study, &k, repeat)?;
            }
            done(runner::bench::bench(&study, repeat, optimization))
        }
    }
}

/// Parses the process arguments, runs them and prints an error the way a user reads it: one
/// line with its chain of causes (`error: file: field: reason`), no backtrace unless `--debug`.
/// Exit status: 0 success; 1 an error (bad input, a failed solve: nothing new written); 2 a
/// command-line usage error (clap's); 3 a run that wrote its results without reaching its goal
/// (an optimization that did not converge, sweep cases that failed or did not converge).
pub fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let debug = cli.debug;
    match dispatch(cli) {
        Ok(runner::Outcome::Done) => std::process::ExitCode::SUCCESS,
        Ok(runner::Outcome::GoalNotReached(why)) => {
            eprintln!("gustkit: {why} (the results are written)");
            std::process::ExitCode::from(runner::EXIT_GOAL_NOT_REACHED)
        }
        Err(e) => {
            if debug {
                eprintln!("error: {e:?}");
            } else {
                eprintln!("error: {e:#}");
            }
            std::process::ExitCode::FAILURE
        }
    }
}
