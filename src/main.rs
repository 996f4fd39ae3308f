//! The `bkpbs` command line: parses, dispatches to [`cli`], prints one error line on failure.

mod cli;

use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use bkpbs::io::interrupt;

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
    let result = run(cli.command);
    if let Err(e) = &result {
        eprintln!("error: {e:#}");
    }
    // A run stopped by a signal exits as the shell expects of one (130 for Ctrl-C), after it
    // tidied up; otherwise 1 for any error.
    match (result, interrupt::requested()) {
        (_, Some(signal)) => ExitCode::from(interrupt::exit_code(signal)),
        (Ok(()), None) => ExitCode::SUCCESS,
        (Err(_), None) => ExitCode::FAILURE,
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
/// The commands that run SUMO take stop signals as requests, so that they tidy up (SUMO's
/// input directory, a campaign's workers and collected files); the others keep the default.
fn run(command: Command) -> Result<()> {
    match command {
        Command::Episode(a) => {
            let episode = a.resolve()?;
            interrupt::install(true);
            cli::episode::run(episode)
        }
        Command::Explain(a) => cli::explain::run(a),
        Command::Plot(a) => cli::plot::run(a),
        Command::Network(a) => cli::network::run(a),
        Command::Config(a) => cli::config::run(a.resolve()?),
        Command::Bench(a) => cli::bench::run(a.resolve()?),
        Command::Demand(a) => cli::demand::run(a.resolve()?),
        Command::Campaign(a) => {
            let campaign = a.resolve()?;
            interrupt::install(true);
            cli::campaign::run(campaign)
        }
        Command::Report(a) => cli::report::run(a),
        Command::Collect(a) => cli::train::collect(a.resolve()?),
        Command::Train(a) => cli::train::train(a.resolve()?),
        Command::EvalPredictor(a) => cli::train::eval_predictor(a.resolve()?),
        Command::BenchPredictor(a) => cli::train::bench_predictor(a.resolve()?),
        Command::Calibrate(a) => cli::calibrate::run(a.resolve()?),
        Command::TrainRl(a) => {
            let training = a.resolve()?;
            interrupt::install(true);
            cli::train_rl::run(training)
        }
        Command::RlWorker => {
            interrupt::install(false);
            Ok(bkpbs::train::ppo::workers::serve_stdio()?)
        }
        Command::Worker => {
            interrupt::install(false);
            cli::campaign::worker()
        }
    }
}
