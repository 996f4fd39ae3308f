//! The `bkpbs` command line: parses, dispatches to [`cli`], prints one error line on failure.

mod cli;

use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use cli::{Cli, Command};

fn main() -> ExitCode {
    // Die quietly on a closed pipe (`bkpbs … | head`), as command-line tools do.
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    match run(Cli::parse().command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Each subcommand in its two stages: the flags resolved into checked options, then the run.
fn run(command: Command) -> Result<()> {
    match command {
        Command::Episode(a) => cli::episode::run(a.resolve()?),
        Command::Explain(a) => cli::explain::run(a),
        Command::Config(a) => cli::config::run(a.resolve()?),
        Command::Bench(a) => cli::bench::run(a.resolve()?),
        Command::Demand(a) => cli::demand::run(a.resolve()?),
        Command::Campaign(a) => cli::campaign::run(a.resolve()?),
        Command::Report(a) => cli::report::run(a),
        Command::Collect(a) => cli::train::collect(a.resolve()?),
        Command::Train(a) => cli::train::train(a.resolve()),
        Command::EvalPredictor(a) => cli::train::eval_predictor(a.resolve()),
        Command::BenchPredictor(a) => cli::train::bench_predictor(a.resolve()?),
        Command::Worker => cli::campaign::worker(),
    }
}
