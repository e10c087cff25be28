//! The `grasp` command line. Thin: parse, dispatch to `cli::*`, print errors.

mod cli;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    cli::init_logging(&args.global);
    if let Err(err) = cli::dispatch(args) {
        eprintln!("error: {err:#}");
        std::process::exit(1);
    }
}
