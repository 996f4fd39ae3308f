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
    /// SUMO network file (.net.xml), or with --sumocfg the configuration whose net-file to read.
    file: PathBuf,
    /// FILE is a SUMO configuration (.sumocfg): check it as `episode --sumocfg` would (its
    /// step length; every selected region planned).
    #[arg(long)]
    sumocfg: bool,
    /// The merge regions an episode would plan, by the edge an on-ramp joins (`!EDGE` leaves
    /// one out), as `--regions` of episode.
    #[arg(long, value_delimiter = ',', value_name = "EDGE,...")]
    regions: Vec<String>,
}

/// Prints every region (main carriageway, on-ramps with their acceleration lanes, off-ramps),
/// the junctions that are no merge and the edges left out; then fails exactly where an episode
/// on the file (with these regions) would.
pub fn run(a: NetworkArgs) -> Result<()> {
    let scenario = a
        .sumocfg
        .then(|| bkpbs::sumo::sumocfg::SumoConfig::read(&a.file))
        .transpose()?;
    let net_file = scenario.as_ref().map_or(a.file.clone(), |c| c.net.clone());
    let net = Net::read(&net_file)?;
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
    let unplannable: Vec<usize> = (regions.roads.iter().enumerate())
        .filter_map(|(k, road)| road.is_err().then_some(k))
        .collect();
    print!("{}", regions.found.describe_left_out(&unplannable));
    println!(
        "internal junction lanes: {}",
        if net.internal.is_empty() { "no" } else { "yes" }
    );
    // As the episode would: a user's scenario plans every selected region, at the planners'
    // step; the paper's demand plans one region.
    if let Some(c) = &scenario {
        c.check_step(bkpbs::config::Scenario::default().dt)?;
        if let Err(why) = regions.all_planned(&a.regions) {
            bail!("network {}: {why}", net_file.display());
        }
    } else if let Err(why) = regions.planned(&a.regions) {
        bail!("network {}: {why}", net_file.display());
    }
    Ok(())
}
