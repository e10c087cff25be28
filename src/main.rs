//! The `grasp` command line. Thin: parse, dispatch to `cli::*`, print errors.

mod cli;

use clap::Parser;

fn main() {
    cli::configure_candle_threads();
    cli::quiet_broken_pipe();
    let args = cli::Cli::parse();
    cli::init_logging(&args.global);
    if let Err(err) = cli::dispatch(args) {
        if cli::is_broken_pipe(&err) {
            // The reader went away (`grasp ... | head`): nothing left to tell anyone.
            std::process::exit(0);
        }
        eprintln!("error: {}", cli::error_text(&err));
        std::process::exit(1);
    }
}
