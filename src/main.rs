//! The `gustkit` command line (see `gustkit::cli`).

fn main() -> std::process::ExitCode {
    gustkit::cli::main()
}
