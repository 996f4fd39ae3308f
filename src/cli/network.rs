//! `bkpbs network FILE`: the merge layout bkpbs finds in a SUMO network.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bkpbs::sumo::network::{Layout, Net};

/// Needs no second stage: the library checks the file.
#[derive(Args)]
pub struct NetworkArgs {
    /// SUMO network file (.net.xml).
    file: PathBuf,
}

/// Prints the main carriageway, the on-ramps with their acceleration lanes, the off-ramps.
pub fn run(a: NetworkArgs) -> Result<()> {
    let net = Net::read(&a.file)?;
    let layout = Layout::discover(&net, &a.file)?;
    print!("{}", layout.describe());
    println!(
        "internal junction lanes: {}",
        if net.internal.is_empty() { "no" } else { "yes" }
    );
    Ok(())
}
