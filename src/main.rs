//! The `gustkit` command line (see `gustkit::cli`).

fn main() -> anyhow::Result<()> {
    gustkit::cli::main()
}
