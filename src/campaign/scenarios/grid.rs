//! The grid of a campaign over scenarios of the user's own: planners × scenarios × α × seeds,
//! in that order (planners and scenarios as given, α ascending, seeds ascending). Every
//! collected file follows it, so results never depend on which worker ran which episode.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::campaign::cell::GridCell;

/// One episode of the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioCell {
    /// The controller's name as the CLI spells it.
    pub planner: String,
    /// The scenario's configuration file, as given.
    pub sumocfg: PathBuf,
    /// CAV share α of the scenario's vehicles.
    pub alpha: f64,
    /// The episode's seed (SUMO's and the CAV draw's).
    pub seed: u64,
}

/// A scenario's name in directories and tables: its file name without `.sumocfg`.
pub fn scenario_name(sumocfg: &Path) -> String {
    let file = sumocfg.file_name().unwrap_or(sumocfg.as_os_str());
    let file = file.to_string_lossy();
    file.strip_suffix(".sumocfg").unwrap_or(&file).to_string()
}

/// A configuration's file name, as `episode.csv` names its scenario (`A10KW.sumocfg`).
pub fn file_name_of(sumocfg: &Path) -> String {
    sumocfg
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_default()
}

impl ScenarioCell {
    /// The scenario's name ([`scenario_name`]).
    pub fn scenario(&self) -> String {
        scenario_name(&self.sumocfg)
    }
}

impl GridCell for ScenarioCell {
    /// The cell's directory below `<out>/episodes/`: `<planner>/<scenario>/a<α>_s<seed>` (α in
    /// Rust's shortest round-trip form, as `episode.csv` writes it).
    fn dir_name(&self) -> PathBuf {
        PathBuf::from(&self.planner)
            .join(self.scenario())
            .join(format!("a{}_s{}", self.alpha, self.seed))
    }

    fn planner(&self) -> &str {
        &self.planner
    }
}

impl fmt::Display for ScenarioCell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {} α={} seed={}",
            self.planner,
            self.scenario(),
            self.alpha,
            self.seed
        )
    }
}

/// The four axes, normalised.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioGrid {
    /// Controller names, in the order given, each once.
    pub planners: Vec<String>,
    /// Configuration files, in the order given, each once.
    pub scenarios: Vec<PathBuf>,
    /// CAV shares α, ascending, each once.
    pub alphas: Vec<f64>,
    /// Seeds, ascending and consecutive.
    pub seeds: Vec<u64>,
}

impl ScenarioGrid {
    /// Number of episodes.
    pub fn len(&self) -> usize {
        self.planners.len() * self.scenarios.len() * self.alphas.len() * self.seeds.len()
    }

    /// True for a grid without episodes.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// All cells in grid order: planner, scenario, α, seed.
    pub fn cells(&self) -> Vec<ScenarioCell> {
        let mut out = Vec::with_capacity(self.len());
        for planner in &self.planners {
            for sumocfg in &self.scenarios {
                for &alpha in &self.alphas {
                    out.extend(self.seeds.iter().map(|&seed| ScenarioCell {
                        planner: planner.clone(),
                        sumocfg: sumocfg.clone(),
                        alpha,
                        seed,
                    }));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_run_in_grid_order_and_name_their_directories() {
        let grid = ScenarioGrid {
            planners: vec!["bk-pbs".into(), "sumo".into()],
            scenarios: vec!["game/A10KW.sumocfg".into(), "ramp.sumocfg".into()],
            alphas: vec![0.3, 0.6],
            seeds: vec![4, 5],
        };
        let cells = grid.cells();
        assert_eq!(cells.len(), 16);
        assert_eq!(cells[0].dir_name(), Path::new("bk-pbs/A10KW/a0.3_s4"));
        assert_eq!(cells[3].dir_name(), Path::new("bk-pbs/A10KW/a0.6_s5"));
        assert_eq!(cells[4].dir_name(), Path::new("bk-pbs/ramp/a0.3_s4"));
        assert_eq!(cells[8].to_string(), "sumo A10KW α=0.3 seed=4");
    }
}
