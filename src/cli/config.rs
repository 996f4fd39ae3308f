//! `bkpbs config`: the configuration as TOML, or the SUMO vehicle types it implies.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bkpbs::config::Config;
use bkpbs::sumo::files;

use super::scenario::load_config;

#[derive(Args)]
pub struct ConfigArgs {
    /// Print the full configuration as TOML.
    #[arg(long, conflicts_with = "vtypes")]
    print: bool,
    /// Print the SUMO vehicle-type file the configuration implies.
    #[arg(long)]
    vtypes: bool,
    /// Start from this file instead of the defaults.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Use this HDV driver profile; `--print` then also shows its resolved settings (under
    /// [hdv.profiles.NAME], ready to copy and edit).
    #[arg(long, value_name = "NAME")]
    hdv_profile: Option<String>,
}

/// What `config` prints: the TOML (`--print`, also without a flag) or the vehicle types.
pub enum ShowConfig {
    Toml(Config),
    VehicleTypes(Config),
}

impl ConfigArgs {
    /// Loads (and so checks) the configuration to show.
    pub fn resolve(self) -> Result<ShowConfig> {
        let profile = self.hdv_profile;
        let mut config = load_config(self.config.as_deref(), |c| {
            if let Some(p) = &profile {
                c.hdv.profile = p.clone();
            }
        })?;
        if profile.is_some() {
            let resolved = config.hdv.resolved()?;
            config
                .hdv
                .profiles
                .insert(config.hdv.profile.clone(), resolved);
        }
        Ok(if self.vtypes {
            ShowConfig::VehicleTypes(config)
        } else {
            ShowConfig::Toml(config)
        })
    }
}

/// Prints the chosen view on stdout.
pub fn run(show: ShowConfig) -> Result<()> {
    match show {
        ShowConfig::Toml(c) => print!("{}", c.to_toml()),
        ShowConfig::VehicleTypes(c) => {
            let road = bkpbs::sumo::frame::scenario_road(&c.scenario)?;
            print!("{}", files::vehicle_types(&c, road.lane_width))
        }
    }
    Ok(())
}
