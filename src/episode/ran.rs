//! An episode of either traffic, run and written through one entry point: the paper's
//! generated demand ([`super::runner`]) or a SUMO scenario of the user's own
//! ([`super::sumocfg`], `scenario.sumocfg` set). The CLI, a campaign's worker, the benchmark and
//! the Python bindings run an episode here and need not ask which traffic it has.

use std::path::{Path, PathBuf};

use super::metrics::Timing;
use super::runner::EpisodeResult;
use super::summary::Summary;
use super::sumocfg::ScenarioResult;
use super::EpisodeError;
use crate::config::Config;
use crate::io::WriteError;

/// What an episode produced, by traffic (their files differ: a scenario's has its regions).
#[derive(Debug, Clone)]
pub enum Ran {
    /// On the paper's demand.
    Demand(Box<EpisodeResult>),
    /// On a scenario of the user's own.
    Scenario(Box<ScenarioResult>),
}

/// Runs one episode of `planner` with `config`: on the scenario `config.scenario.sumocfg`
/// names, else on the demand drawn from its (λ, α, seed).
///
/// # Errors
/// An invalid config, an unknown planner or unusable predictor, or SUMO failing.
pub fn run(config: &Config, planner: &str) -> Result<Ran, EpisodeError> {
    match config.scenario.sumocfg {
        Some(_) => super::sumocfg::run(config, planner).map(|r| Ran::Scenario(Box::new(r))),
        None => super::runner::run(config, planner).map(|r| Ran::Demand(Box::new(r))),
    }
}

impl Ran {
    /// The `episode.csv` row.
    pub fn summary(&self) -> &Summary {
        match self {
            Ran::Demand(r) => &r.summary,
            Ran::Scenario(r) => &r.summary,
        }
    }

    /// The wall-clock figures (`timing.csv`).
    pub fn timing(&self) -> &Timing {
        match self {
            Ran::Demand(r) => &r.timing,
            Ran::Scenario(r) => &r.timing,
        }
    }

    /// Vehicles in the planners' scenes per step (a scenario's: every region's together), on
    /// average.
    pub fn vehicles_per_step(&self) -> f64 {
        match self {
            Ran::Demand(r) => r.vehicles_per_step,
            Ran::Scenario(r) => r.vehicles_per_step,
        }
    }

    /// CAVs in those scenes per step, on average.
    pub fn cavs_per_step(&self) -> f64 {
        match self {
            Ran::Demand(r) => r.cavs_per_step,
            Ran::Scenario(r) => r.cavs_per_step,
        }
    }

    /// Writes the episode's files into `dir`, `episode.csv` last; the paths written.
    ///
    /// # Errors
    /// A file cannot be written (none of them is then half-written).
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, WriteError> {
        match self {
            Ran::Demand(r) => r.write(dir),
            Ran::Scenario(r) => super::sumocfg::write(r, dir),
        }
    }
}
