//! `bkpbs explain`: the last seconds before each collision of a traced episode.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bkpbs::report::explain;

/// Needs no second stage: the library checks the directory.
#[derive(Args)]
pub struct ExplainArgs {
    /// Episode directory written by `bkpbs episode --trace` (on a scenario of your own, each
    /// merge region's trace is read from its `trajectories/<region>/`).
    dir: PathBuf,
    /// Also draw each collision: DIR/explain_<n>.png and .svg (s and lateral position over
    /// time, planned vs actual, per vehicle).
    #[arg(long)]
    plot: bool,
}

/// Prints the story of every collision and, with `--plot`, where its figure is: of an
/// episode on a scenario of your own, region by region.
pub fn run(a: ExplainArgs) -> Result<()> {
    let regions = explain::traced_regions(&a.dir);
    if regions.is_empty() {
        return tell(&a.dir, explain::explain_dir(&a.dir)?, a.plot);
    }
    for (k, region) in regions.iter().enumerate() {
        if k > 0 {
            println!();
        }
        let name = region.file_name().unwrap_or_default().to_string_lossy();
        println!("region {}:", name.replace('+', " "));
        tell(region, explain::explain_region_dir(region)?, a.plot)?;
    }
    Ok(())
}

/// Prints `explanations` of the collisions traced in `dir`, drawing them there with `plot`.
fn tell(dir: &std::path::Path, explanations: Vec<explain::Explanation>, plot: bool) -> Result<()> {
    if explanations.is_empty() {
        println!("no collision in {}", dir.display());
        return Ok(());
    }
    for (k, e) in explanations.iter().enumerate() {
        if k > 0 {
            println!();
        }
        print!("{}", explain::format(e));
    }
    if plot {
        println!();
        for p in explain::write_plots(dir, &explanations)? {
            println!("figure: {}", p.display());
        }
    }
    Ok(())
}
