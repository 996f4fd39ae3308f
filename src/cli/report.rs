//! `bkpbs report`: tables and figures from campaign directories.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;

use bkpbs::report;

/// Needs no second stage: clap already requires a directory, and the library checks them.
#[derive(Args)]
pub struct ReportArgs {
    /// Campaign directories (several are merged).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Where to write [default: the first directory].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Merge directories whose campaigns ran with different settings (refused otherwise).
    #[arg(long)]
    allow_mixed: bool,
    /// Compare every planner with these reference planners, seed by seed (paired differences,
    /// Wilcoxon and Fisher tests): report/paired.csv, report/paired_collisions.csv.
    #[arg(long, value_delimiter = ',', value_name = "PLANNERS")]
    versus: Vec<String>,
}

/// Writes the report of the directories.
pub fn run(a: ReportArgs) -> Result<()> {
    print_report(&a.dirs, a.out.as_deref(), a.allow_mixed, &a.versus)
}

/// Writes a report and prints its tables and where the files are; `campaign` ends with it too.
pub fn print_report(
    dirs: &[PathBuf],
    out: Option<&Path>,
    allow_mixed: bool,
    versus: &[String],
) -> Result<()> {
    let r = report::run_versus(dirs, out, allow_mixed, versus)?;
    print!("{}", r.markdown);
    let collected: Vec<&str> = [
        "episodes.csv",
        "regions.csv",
        "entries.csv",
        "vehicles.csv",
        "timings.csv",
        "failures.csv",
    ]
    .into_iter()
    .filter(|f| r.out.join(f).is_file())
    .collect();
    println!("results in {}: {}", r.out.display(), collected.join(", "));
    println!("tables and figures:");
    for p in report::highlights(&r) {
        println!("  {}", p.display());
    }
    Ok(())
}
