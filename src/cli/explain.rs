//! `bkpbs explain`: the last seconds before each collision of a traced episode.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bkpbs::report::explain;

/// Needs no second stage: the library checks the directory.
#[derive(Args)]
pub struct ExplainArgs {
    /// Episode directory written by `bkpbs episode --trace`.
    dir: PathBuf,
    /// Also draw each collision: DIR/explain_<n>.png and .svg (s and lateral position over
    /// time, planned vs actual, per vehicle).
    #[arg(long)]
    plot: bool,
}

/// Prints the story of every collision and, with `--plot`, where its figure is.
pub fn run(a: ExplainArgs) -> Result<()> {
    let explanations = explain::explain_dir(&a.dir)?;
    if explanations.is_empty() {
        println!("no collision in {}", a.dir.display());
        return Ok(());
    }
    for (k, e) in explanations.iter().enumerate() {
        if k > 0 {
            println!();
        }
        print!("{}", explain::format(e));
    }
    if a.plot {
        println!();
        for p in explain::write_plots(&a.dir, &explanations)? {
            println!("figure: {}", p.display());
        }
    }
    Ok(())
}
