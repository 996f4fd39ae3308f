//! `bkpbs demand`: an episode's vehicles as a SUMO route file.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bkpbs::config::Config;
use bkpbs::episode::{demand, output};

use super::scenario::ScenarioArgs;

#[derive(Args)]
pub struct DemandArgs {
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Route file to write.
    #[arg(long)]
    out: PathBuf,
}

/// A checked demand request.
pub struct Demand {
    config: Config,
    out: PathBuf,
}

impl DemandArgs {
    /// Checks the configuration before the route file is written.
    pub fn resolve(self) -> Result<Demand> {
        Ok(Demand {
            config: self.scenario.resolve()?,
            out: self.out,
        })
    }
}

/// Generates the demand and writes it atomically, so a failed run leaves no half file.
pub fn run(d: Demand) -> Result<()> {
    let road = bkpbs::sumo::frame::scenario_road(&d.config.scenario)?;
    demand::check_entries(&d.config, &road)?;
    let planned = demand::generate(&d.config, &road);
    output::write_atomic(&d.out, demand::route_file(&road, &planned).as_bytes())?;
    println!("{} vehicles written to {}", planned.len(), d.out.display());
    Ok(())
}
