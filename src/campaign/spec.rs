//! What the one campaign runner asks of a campaign's settings ([`super::Settings`]), whatever
//! traffic its cells run: the paper's generated demand or scenarios of the user's own. The
//! claim, the resume check, the preparation of the requests, the run and the collection are
//! written once, over this trait; where the two traffics' files differ, it says which.

use std::path::Path;
use std::time::Duration;

use super::cell::CellState;
use super::grid::{Cell, Shard};
use super::{CampaignError, SettingsError};
use crate::config::Config;

/// Where a cell of a campaign directory stands, for the resume check: a [`CellState`] without
/// the finished cell's files, which the check does not need.
pub type Readiness = CellState<()>;

/// How many rows a collection gathered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Collected {
    /// Rows of the collected `episodes.csv`.
    pub episodes: usize,
    /// Rows of the collected `failures.csv`.
    pub failures: usize,
}

/// A campaign's validated settings, as the one runner uses them.
pub trait CampaignSpec {
    /// Every cell, in grid order (the order of every collected file).
    fn cells(&self) -> Vec<Cell>;
    /// The slice of the grid this run runs.
    fn shard(&self) -> Shard;
    /// Worker processes, at least 1.
    fn workers(&self) -> usize;
    /// Wall-clock limit of one episode, if any.
    fn episode_timeout(&self) -> Option<Duration>;
    /// The axes as the status line names them (`2 planners × 3 α × 2 λ × 5 seeds`).
    fn axes(&self) -> String;
    /// The settings as `campaign.toml` records them.
    fn to_toml(&self) -> String;
    /// The first setting (dotted) in which the campaign recorded in `file` runs a cell
    /// differently, if any: campaigns that agree may share a directory.
    ///
    /// # Errors
    /// The recorded file is unreadable or invalid.
    fn difference_from_file(&self, file: &Path) -> Result<Option<String>, SettingsError>;
    /// The episodes `out`'s collected `episodes.csv` records outside this grid, as cells are
    /// displayed.
    fn recorded_outside(&self, out: &Path) -> Vec<String>;
    /// Where `cell` stands in `out`.
    fn readiness(&self, out: &Path, cell: &Cell) -> Readiness;
    /// The full configuration `cell`'s episode runs with.
    fn episode_config(&self, cell: &Cell) -> Config;
    /// Gathers the finished cells found in `out` into its collected files.
    ///
    /// # Errors
    /// A cell's files are unreadable or belong to another cell, or the collected files cannot
    /// be written.
    fn collect(&self, out: &Path) -> Result<Collected, CampaignError>;
}

impl CampaignSpec for super::Settings {
    fn cells(&self) -> Vec<Cell> {
        self.grid.cells()
    }
    fn shard(&self) -> Shard {
        self.shard
    }
    fn workers(&self) -> usize {
        self.workers
    }
    fn episode_timeout(&self) -> Option<Duration> {
        self.episode_timeout
    }
    fn axes(&self) -> String {
        let g = &self.grid;
        let predictors = match g.has_predictor_axis() {
            false => String::new(),
            true => format!(" × {} predictors", g.predictors.len()),
        };
        if self.is_over_scenarios() {
            return format!(
                "{} planners{predictors} × {} scenarios × {} α × {} seeds",
                g.planners.len(),
                g.scenarios.len(),
                g.alphas.len(),
                g.seeds.len(),
            );
        }
        let profiles = match g.profiles.len() {
            1 => String::new(),
            n => format!(" × {n} HDV profiles"),
        };
        format!(
            "{} planners{predictors}{profiles} × {} α × {} λ × {} seeds",
            g.planners.len(),
            g.alphas.len(),
            g.lambdas.len(),
            g.seeds.len(),
        )
    }
    fn to_toml(&self) -> String {
        super::Settings::to_toml(self)
    }
    fn difference_from_file(&self, file: &Path) -> Result<Option<String>, SettingsError> {
        let earlier = super::Settings::from_campaign_file(file)?;
        Ok(self.scenario_difference(&earlier))
    }
    fn recorded_outside(&self, out: &Path) -> Vec<String> {
        let cells = super::collect::recorded_outside(out, &self.grid);
        cells.iter().map(ToString::to_string).collect()
    }
    fn readiness(&self, out: &Path, cell: &Cell) -> Readiness {
        super::collect::cell_state(out, self, cell).without_files()
    }
    fn episode_config(&self, cell: &Cell) -> Config {
        super::Settings::episode_config(self, cell)
    }
    fn collect(&self, out: &Path) -> Result<Collected, CampaignError> {
        let results = super::collect::collect(out, self)?;
        results.write(out)?;
        Ok(Collected {
            episodes: results.episodes.rows.len(),
            failures: results.failures.rows.len(),
        })
    }
}
