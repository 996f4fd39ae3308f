//! `bkpbs network FILE`: the merge regions bkpbs finds in a SUMO network, and whether an
//! episode would plan on it.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;

use bkpbs::sumo::frame::Regions;
use bkpbs::sumo::network::Net;

/// Needs no second stage: the library checks the file.
#[derive(Args)]
pub struct NetworkArgs {
    /// SUMO network file (.net.xml).
    file: PathBuf,
    /// The merge regions an episode would plan, by the edge an on-ramp joins (`!EDGE` leaves
    /// one out), as `--regions` of episode.
    #[arg(long, value_delimiter = ',', value_name = "EDGE,...")]
    regions: Vec<String>,
}

/// Prints every region (main carriageway, on-ramps with their acceleration lanes, off-ramps),
/// the junctions that are no merge and the edges left out; then fails exactly where an episode
/// on the file (with these regions) would.
pub fn run(a: NetworkArgs) -> Result<()> {
    let net = Net::read(&a.file)?;
    let regions = Regions::of(&net);
    let picked = regions.select(&a.regions).unwrap_or_default();
    for (k, (layout, road)) in regions.found.regions.iter().zip(&regions.roads).enumerate() {
        let merges: Vec<&str> = layout.merge_edges().collect();
        let mark = if picked.contains(&k) {
            ""
        } else {
            " (not selected)"
        };
        println!("region {} (merges at {}){mark}", k + 1, merges.join(", "));
        print!("{}", layout.describe());
        if let Err(why) = road {
            println!("cannot be planned on: {why}");
        }
    }
    print!("{}", regions.found.describe_left_out());
    println!(
        "internal junction lanes: {}",
        if net.internal.is_empty() { "no" } else { "yes" }
    );
    if let Err(why) = regions.planned(&a.regions) {
        bail!("network {}: {why}", a.file.display());
    }
    Ok(())
}
