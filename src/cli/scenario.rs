//! The scenario flags shared by the subcommands that run SUMO, and the one way every subcommand
//! builds its configuration: the file (or the paper's defaults), then the flags, then one
//! validation of the result.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;

use bkpbs::config::{Config, TrajectoryFormat};

/// The configuration from `file` (the paper's defaults without one) with `flags` applied, then
/// validated. One helper, so that a config file is read, overridden and checked the same way
/// by every subcommand.
pub fn load_config(file: Option<&Path>, flags: impl FnOnce(&mut Config)) -> Result<Config> {
    let mut config = match file {
        Some(p) => Config::from_file(p)?,
        None => Config::default(),
    };
    flags(&mut config);
    config.validate()?;
    Ok(config)
}

/// Checks the scenario of the user's own that `config` runs, if any, before any episode: its
/// configuration and every file it names can be read, and its network has a region to plan.
///
/// # Errors
/// A file that cannot be read or a network without a region, naming the file.
pub fn check_own_scenario(config: &Config) -> Result<()> {
    if config.scenario.sumocfg.is_some() {
        bkpbs::sumo::frame::scenario_roads(&config.scenario)?;
        bkpbs::sumo::scenario_record::scenario_record(&config.scenario)?;
    }
    Ok(())
}

/// Scenario flags shared by the subcommands that run SUMO; each overrides the config file.
#[derive(Args)]
pub struct ScenarioArgs {
    /// TOML file with settings; unset fields keep the paper's defaults.
    #[arg(long)]
    config: Option<PathBuf>,
    /// CAV penetration α in [0, 1].
    #[arg(long, allow_negative_numbers = true)]
    alpha: Option<f64>,
    /// Arrival rate λ (veh/h).
    #[arg(long = "lambda", allow_negative_numbers = true)]
    lambda: Option<f64>,
    /// Seed of the demand and of the HDVs' merge decisions.
    #[arg(long, allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Episode length in steps (default 400 of 0.2 s).
    #[arg(long, allow_negative_numbers = true)]
    steps: Option<u32>,
    /// Network file to use instead of the embedded merge network.
    #[arg(long)]
    net: Option<PathBuf>,
    /// The network's merge regions to plan, by the edge an on-ramp joins (`!EDGE` leaves one
    /// out); `bkpbs network FILE` lists them.
    #[arg(long, value_delimiter = ',', value_name = "EDGE,...")]
    regions: Option<Vec<String>>,
    /// A SUMO configuration of your own (.sumocfg: its net, routes, flows, vehicle types):
    /// run instead of the paper's demand, α of its vehicles CAVs; --steps defaults to its
    /// begin–end interval.
    #[arg(long, value_name = "FILE")]
    sumocfg: Option<PathBuf>,
    /// With --sumocfg: the vehicle types whose vehicles are the CAVs (all of them, no other),
    /// instead of the share α.
    #[arg(long, value_delimiter = ',', value_name = "TYPE,...")]
    cav_types: Option<Vec<String>>,
    /// HDV driver profile: sumo-safe (default), paper, heterogeneous, krauss, eidm, or one
    /// the config file defines under [hdv.profiles.NAME].
    #[arg(long, value_name = "NAME")]
    hdv_profile: Option<String>,
    /// Let SUMO print its warnings.
    #[arg(long)]
    verbose: bool,
}

impl ScenarioArgs {
    /// The validated configuration: file (or defaults), then these flags.
    pub fn resolve(&self) -> Result<Config> {
        self.resolve_with(|_| {})
    }

    /// Like [`Self::resolve`], with a subcommand's own overrides applied after these flags and
    /// before validation, so the configuration that runs is the one that was checked.
    pub fn resolve_with(&self, more: impl FnOnce(&mut Config)) -> Result<Config> {
        let config = load_config(self.config.as_deref(), |c| {
            self.apply(c);
            more(c);
        })?;
        self.with_scenario_steps(config)
    }

    /// `config` running a scenario of the user's own for `--steps`, else for the scenario's
    /// `begin`–`end` interval; one without an end and no `--steps` is refused (SUMO would run
    /// it until every vehicle has arrived; an episode runs a number of steps).
    fn with_scenario_steps(&self, mut config: Config) -> Result<Config> {
        let Some(cfg) = config.scenario.sumocfg.clone() else {
            return Ok(config);
        };
        // The paper's demand and drivers: a scenario brings its own, and the flags would be
        // ignored without a word.
        for (flag, given, what) in [
            ("--lambda", self.lambda.is_some(), "its own demand"),
            (
                "--hdv-profile",
                self.hdv_profile.is_some(),
                "its own drivers",
            ),
        ] {
            if given {
                anyhow::bail!(
                    "{flag}: a scenario of your own ({}) brings {what}; leave {flag} out",
                    cfg.display()
                );
            }
        }
        let dt = config.scenario.dt;
        config.scenario.steps =
            bkpbs::sumo::sumocfg::SumoConfig::episode_steps(&cfg, dt, self.steps)?;
        config.validate()?;
        Ok(config)
    }

    /// Writes the flags that were given over the file's values.
    fn apply(&self, c: &mut Config) {
        let s = &mut c.scenario;
        if let Some(a) = self.alpha {
            s.alpha = a;
        }
        if let Some(l) = self.lambda {
            s.lambda = l;
        }
        if let Some(seed) = self.seed {
            s.seed = seed;
        }
        if let Some(n) = self.steps {
            s.steps = n;
        }
        if let Some(n) = &self.net {
            s.net_file = Some(n.clone());
        }
        if let Some(r) = &self.regions {
            s.regions = r.clone();
        }
        if let Some(cfg) = &self.sumocfg {
            s.sumocfg = Some(cfg.clone());
        }
        if let Some(t) = &self.cav_types {
            s.cav_types = t.clone();
        }
        if let Some(p) = &self.hdv_profile {
            c.hdv.profile = p.clone();
        }
        c.sumo.verbose |= self.verbose;
    }
}

/// The trajectory flags of `episode` and `campaign`.
#[derive(Args)]
pub struct TrajectoryArgs {
    /// Also write the trajectories: one row per vehicle and step (trajectories.csv).
    #[arg(long)]
    trajectories: bool,
    /// Their format: csv (bkpbs's columns, maneuvers included) or fcd (SUMO's FCD XML);
    /// implies --trajectories.
    #[arg(long, value_enum, value_name = "FORMAT")]
    trajectories_format: Option<TrajectoryFormat>,
}

impl TrajectoryArgs {
    /// The format asked for, if any (the config file's `output.trajectories` otherwise).
    pub fn format(&self) -> Option<TrajectoryFormat> {
        match (self.trajectories_format, self.trajectories) {
            (Some(f), _) => Some(f),
            (None, true) => Some(TrajectoryFormat::Csv),
            (None, false) => None,
        }
    }
}
