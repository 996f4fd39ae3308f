//! `bkpbs plot`: the figures of one episode directory.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bkpbs::report::episode_plots;

/// Needs no second stage: the library checks the directory.
#[derive(Args)]
pub struct PlotArgs {
    /// Episode directory written with `--trajectories` (by `bkpbs episode`, or a campaign
    /// cell); of an episode on a scenario of your own, each merge region's figures are drawn
    /// into its `trajectories/<region>/`.
    dir: PathBuf,
}

/// Draws the figures and says where they are.
pub fn run(a: PlotArgs) -> Result<()> {
    let plots = episode_plots::plot_dir(&a.dir)?;
    for f in &plots.files {
        println!("figure: {}", f.display());
    }
    if plots.collisions > 0 && !plots.close_ups {
        println!(
            "{} collision(s) marked; for close-ups rerun the episode with --trace",
            plots.collisions
        );
    }
    Ok(())
}
