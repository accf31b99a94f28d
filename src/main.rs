//! The `gustkit` command line (see `gustkit::cli`).

fn main() -> std::process::ExitCode {
    faer::set_global_parallelism(faer::Par::Seq);
    gustkit::cli::main()
}
