//! Scenario and driver-model settings: one serde struct whose defaults are the paper's.
//!
//! A TOML file may set any subset of fields; the rest keep their defaults. Unknown fields are an
//! error, so a misspelt key never silently leaves a default in place.
//!
//! This module holds the whole [`Config`], how it is read and validated, and its errors; the
//! sections live by concept, each struct with its defaults, and are re-exported here so every
//! setting is named `crate::config::X`:
//! - `scenario`: the episode's world, demand and metrics;
//! - `drivers`: IDM, MOBIL and the ramp HDVs' merge decision;
//! - [`hdv`]: the HDV driver profiles;
//! - `planning`: planner, BK-PBS, predictor, safety shield and RL-PPO;
//! - `simulator`: how SUMO runs and the optional outputs;
//! - `rules`: what every number must satisfy, with its error text;
//! - [`trained_on`]: what a model or policy file was trained on (not a setting: the record
//!   both file formats share).

mod drivers;
pub mod hdv;
mod planning;
mod rules;
mod scenario;
mod simulator;
#[cfg(test)]
mod tests;
pub mod trained_on;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use drivers::{Idm, Mobil, RampMerge};
pub use hdv::{HdvProfile, HdvSettings};
pub use planning::{
    Grouping, LowSpeedLaneChanges, PbsSettings, PlannerSettings, PredictorKind, PredictorSettings,
    RlSettings, SafetySettings, AUTO_GROUPING_ABOVE, PAPER_ACCEL,
};
pub use rules::MAX_RATE;
use rules::{
    check_demand, check_idm, check_mobil, check_pbs, check_planner, check_predictor,
    check_ramp_merge, check_scenario, check_sumo,
};
pub use scenario::{CavShare, Demand, MetricsSettings, Scenario, TStarSpeed, MAX_STEPS};
pub use simulator::{OutputSettings, SumoSettings, TrajectoryFormat};
pub use trained_on::{TrainedOn, TrainingScenario};

/// Why a configuration could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The config file could not be read.
    #[error("cannot read config file {path}: {cause}")]
    Read {
        /// The file asked for.
        path: PathBuf,
        /// What the file system said.
        cause: std::io::Error,
    },
    /// The file is not TOML of the [`Config`] shape (syntax, wrong type, unknown key).
    #[error("malformed config file {path}: {message}")]
    Parse {
        /// The file read.
        path: PathBuf,
        /// The TOML parser's message, with the byte offset where known.
        message: String,
    },
    /// A setting holds a value no episode can run with.
    #[error("invalid setting {field} = {value}: {reason}")]
    Invalid {
        /// The setting as written in TOML (`section.key`).
        field: &'static str,
        /// The offending value, as text.
        value: String,
        /// The rule it breaks.
        reason: &'static str,
    },
    /// `hdv.profile` names neither a built-in nor a user-defined profile.
    #[error("unknown HDV profile '{name}' (hdv.profile); known: {known}")]
    UnknownProfile {
        /// The name asked for.
        name: String,
        /// Every known profile name, comma-separated.
        known: String,
    },
    /// A SUMO vType attribute of the HDV profile that SUMO cannot be given.
    #[error("invalid setting hdv.profiles.{profile}.attributes.{key} = {value:?}: {reason}")]
    InvalidAttribute {
        /// The profile.
        profile: String,
        /// The attribute's name.
        key: String,
        /// Its value, as given.
        value: String,
        /// The rule it breaks.
        reason: &'static str,
    },
    /// A per-driver draw range of the HDV profile is not a positive `[low, high]`.
    #[error("invalid setting hdv draw {key} = [{low}, {high}]: must be positive and low ≤ high")]
    InvalidDraw {
        /// The SUMO vType attribute drawn (e.g. `tau`).
        key: String,
        /// Lower end of the range, in the attribute's unit.
        low: f64,
        /// Upper end of the range, in the attribute's unit.
        high: f64,
    },
}

/// Everything an episode needs besides the controller.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    /// The episode's world: α, λ, seed, length, step, road and vehicle size.
    pub scenario: Scenario,
    /// How vehicles are generated: λ's split over the roads, speed ranges, how α picks CAVs.
    pub demand: Demand,
    /// Longitudinal model of HDVs (SUMO's IDM) and of idm-mobil CAVs (the Rust IDM).
    pub idm: Idm,
    /// Lane-change model of idm-mobil CAVs (HDVs on the main road use SUMO's LC2013).
    pub mobil: Mobil,
    /// Stochastic merge decision of HDVs on the ramp.
    pub ramp_merge: RampMerge,
    /// Who the human drivers are (the guide's scenarios chapter, docs/src/scenarios.md).
    pub hdv: HdvSettings,
    /// Motion primitives and M-A* (BK-M-A*, BK-PBS).
    pub planner: PlannerSettings,
    /// The high-level search of BK-PBS.
    pub pbs: PbsSettings,
    /// How the planners predict HDVs (BK-M-A*, BK-PBS).
    pub predictor: PredictorSettings,
    /// How SUMO runs (verbosity, extra files and options, sumo-gui).
    pub sumo: SumoSettings,
    /// Choices in how the episode metrics are computed.
    pub metrics: MetricsSettings,
    /// The safety shield in front of the search-based planners.
    pub safety: SafetySettings,
    /// The RL-PPO baseline (`rl-ppo`): which policy, shielded or not.
    #[serde(skip_serializing_if = "RlSettings::is_default")]
    pub rl: RlSettings,
    /// Optional per-episode outputs; they do not change any result.
    pub output: OutputSettings,
}

impl Config {
    /// Reads a TOML file; missing fields keep the defaults.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Config)
            .map_err(|cause| ConfigError::Read {
                path: path.to_path_buf(),
                cause,
            })?;
        let config: Config = toml::from_str(&text).map_err(|e| ConfigError::Parse {
            path: path.to_path_buf(),
            message: e.message().to_string()
                + &e.span()
                    .map(|s| format!(" (at byte {})", s.start))
                    .unwrap_or_default(),
        })?;
        config.validate()?;
        Ok(config)
    }

    /// The whole configuration as TOML, as `bkpbs config --print` shows it.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("config always serialises")
    }

    /// Rejects values no episode can run with, section by section; the first failing rule is
    /// the one reported. Of `sumo` only sumo-gui's pause is checked: SUMO checks its own files and
    /// options.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_scenario(&self.scenario)?;
        check_demand(&self.demand, self.scenario.v_max)?;
        check_idm(&self.idm)?;
        check_mobil(&self.mobil)?;
        check_pbs(&self.pbs)?;
        check_planner(&self.planner)?;
        check_ramp_merge(&self.ramp_merge)?;
        check_predictor(&self.predictor)?;
        check_sumo(&self.sumo)?;
        self.hdv.validate()
    }
}
