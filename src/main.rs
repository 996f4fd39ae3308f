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
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Help and version go to stdout with success; a usage error is one `error:` line (clap's own
/// first line, which names the culprit) and exit code 1, like every other error bkpbs reports
/// (clap's default is a multi-line message and code 2).
fn usage_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind::{
        DisplayHelp, DisplayHelpOnMissingArgumentOrSubcommand, DisplayVersion,
    };
    match e.kind() {
        DisplayHelp | DisplayVersion => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        // `bkpbs` alone: the help is the most useful answer, still an error.
        DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = e.print();
            return ExitCode::FAILURE;
        }
        _ => {}
    }
    // clap's first paragraph, on one line: a missing argument is named on the line after.
    let text = e.render().to_string();
    let paragraph: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let message = paragraph.join(" ");
    let message = message.strip_prefix("error: ").unwrap_or(&message);
    eprintln!("error: {message} (see bkpbs help)");
    ExitCode::FAILURE
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
