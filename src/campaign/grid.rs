//! The experiment grid, the one for every campaign: planners × predictors × HDV profiles ×
//! scenarios × α × λ × seeds, its fixed order, and how it splits into shards.
//!
//! A campaign on the paper's demand has no scenario axis (its cells run the generated demand at
//! each λ); a campaign over scenarios of the user's own (`--sumocfg`) has one, and no λ axis
//! (a scenario's routes are its demand) nor HDV profiles (its drivers are its own).
//!
//! Grid order is planner, predictor, HDV profile and scenario (in the order given), then α, λ
//! and seed, each ascending. Every output of a campaign follows it, so results never depend on
//! which worker ran which episode.

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::config::hdv::DEFAULT_PROFILE;

/// One episode of the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// The controller's name as the CLI spells it (`bk-pbs`, `idm-mobil`, …).
    pub planner: String,
    /// CAV penetration α (share of CAVs, 0 to 1).
    pub alpha: f64,
    /// Total arrival rate λ (veh/h) of the paper's demand; 0 on a scenario of the user's own,
    /// whose routes are its demand.
    pub lambda: f64,
    /// The episode's seed (`scenario.seed`).
    pub seed: u64,
    /// The HDV driver profile SUMO runs (the default on a scenario of the user's own, whose
    /// drivers are its own).
    pub hdv_profile: String,
    /// The HDV predictor of the planners (`learned`, `constant`) when the campaign has the
    /// predictor axis (`--predictors`); `None`: the configuration's `[predictor] kind`.
    pub predictor: Option<String>,
    /// The user's SUMO scenario the cell runs (its configuration file, as given); `None`: the
    /// paper's demand.
    pub scenario: Option<PathBuf>,
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

impl Cell {
    /// The name the report compares the cell's episodes under: the planner, or on a
    /// campaign with the predictor axis the planner and its predictor (`bk-pbs+constant`).
    pub fn arm(&self) -> String {
        match &self.predictor {
            None => self.planner.clone(),
            Some(p) => format!("{}+{p}", self.planner),
        }
    }
}

impl Cell {
    /// The scenario's name ([`scenario_name`]), on a scenario of the user's own.
    pub fn scenario_name(&self) -> Option<String> {
        self.scenario.as_deref().map(scenario_name)
    }

    /// The cell's directory below `<out>/episodes/`: `<planner>/a<α>_l<λ>_s<seed>` for the
    /// default drivers, `<planner>/hdv-<profile>/a<α>_l<λ>_s<seed>` for others, with
    /// `predictor-<name>/` after the planner on a campaign with the predictor axis; on a
    /// scenario of the user's own `<planner>/<scenario>/a<α>_s<seed>`.
    ///
    /// α and λ use Rust's shortest round-trip formatting, the same as `episode.csv`, so the name
    /// is stable and reads like the values (`a0.4_l2500_s3`).
    pub fn dir_name(&self) -> PathBuf {
        let mut dir = PathBuf::from(&self.planner);
        if let Some(p) = &self.predictor {
            dir.push(format!("predictor-{p}"));
        }
        if let Some(name) = self.scenario_name() {
            return dir
                .join(name)
                .join(format!("a{}_s{}", self.alpha, self.seed));
        }
        if self.hdv_profile != DEFAULT_PROFILE {
            dir.push(format!("hdv-{}", self.hdv_profile));
        }
        dir.join(format!("a{}_l{}_s{}", self.alpha, self.lambda, self.seed))
    }
}

impl fmt::Display for Cell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.scenario_name() {
            Some(name) => write!(
                f,
                "{} {name} α={} seed={}",
                self.planner, self.alpha, self.seed
            )?,
            None => write!(
                f,
                "{} α={} λ={} seed={}",
                self.planner, self.alpha, self.lambda, self.seed
            )?,
        }
        if let Some(p) = &self.predictor {
            write!(f, " predictor={p}")?;
        }
        if self.hdv_profile != DEFAULT_PROFILE {
            write!(f, " hdv={}", self.hdv_profile)?;
        }
        Ok(())
    }
}

/// The axes of a campaign, normalised: planners, predictors and HDV profiles keep their order
/// (duplicates dropped), α and λ are sorted ascending without duplicates, seeds are
/// `seed_base .. seed_base + seeds`.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Controller names, in the order given.
    pub planners: Vec<String>,
    /// HDV predictors, in the order given; `[None]` without the predictor axis (every cell
    /// runs the configuration's predictor).
    pub predictors: Vec<Option<String>>,
    /// HDV driver profiles, in the order given.
    pub profiles: Vec<String>,
    /// The user's scenarios (configuration files), in the order given, each once; empty for
    /// the paper's demand.
    pub scenarios: Vec<PathBuf>,
    /// CAV penetrations α (0 to 1), ascending.
    pub alphas: Vec<f64>,
    /// Total arrival rates λ (veh/h), ascending; `[0]` over scenarios of the user's own.
    pub lambdas: Vec<f64>,
    /// Episode seeds, ascending and consecutive.
    pub seeds: Vec<u64>,
}

/// The names in their first-seen order, each once.
pub(super) fn unique(names: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for n in names {
        if !out.contains(n) {
            out.push(n.clone());
        }
    }
    out
}

/// The values ascending, each once.
pub(super) fn sorted_unique(mut xs: Vec<f64>) -> Vec<f64> {
    xs.sort_by(f64::total_cmp);
    xs.dedup_by(|a, b| a == b);
    xs
}

/// `seeds` consecutive seeds from `seed_base` (saturating at the largest seed).
pub(super) fn seed_range(seed_base: u64, seeds: u64) -> Vec<u64> {
    (0..seeds).map(|i| seed_base.saturating_add(i)).collect()
}

impl Grid {
    /// Builds the normalised grid for the default drivers (validation of the values is the
    /// caller's job).
    pub fn new(
        planners: &[String],
        alphas: &[f64],
        lambdas: &[f64],
        seed_base: u64,
        seeds: u64,
    ) -> Grid {
        Grid {
            planners: unique(planners),
            predictors: vec![None],
            profiles: vec![DEFAULT_PROFILE.to_string()],
            scenarios: Vec::new(),
            alphas: sorted_unique(alphas.to_vec()),
            lambdas: sorted_unique(lambdas.to_vec()),
            seeds: seed_range(seed_base, seeds),
        }
    }

    /// The grid over scenarios of the user's own (`scenarios` as given: the caller keeps each
    /// once): no λ axis, the default drivers' profile (a scenario's drivers are its own).
    pub fn over_scenarios(
        planners: &[String],
        scenarios: Vec<PathBuf>,
        alphas: &[f64],
        seed_base: u64,
        seeds: u64,
    ) -> Grid {
        Grid {
            scenarios,
            ..Grid::new(planners, alphas, &[0.0], seed_base, seeds)
        }
    }

    /// The same grid over these HDV profiles (duplicates dropped, order kept).
    pub fn with_profiles(mut self, profiles: &[String]) -> Grid {
        self.profiles = unique(profiles);
        self
    }

    /// The same grid with the predictor axis over these predictors (duplicates dropped, order
    /// kept).
    pub fn with_predictors(mut self, predictors: &[String]) -> Grid {
        self.predictors = unique(predictors).into_iter().map(Some).collect();
        self
    }

    /// Whether the grid has the predictor axis (`--predictors`): its cells' directories and
    /// its collected files' lead columns then name the predictor.
    pub fn has_predictor_axis(&self) -> bool {
        self.predictors.iter().any(Option::is_some)
    }

    /// The scenario axis: each scenario, or the paper's demand alone (`None`).
    fn scenario_axis(&self) -> Vec<Option<PathBuf>> {
        if self.scenarios.is_empty() {
            return vec![None];
        }
        self.scenarios.iter().cloned().map(Some).collect()
    }

    /// Number of episodes.
    pub fn len(&self) -> usize {
        self.planners.len()
            * self.predictors.len()
            * self.profiles.len()
            * self.scenario_axis().len()
            * self.alphas.len()
            * self.lambdas.len()
            * self.seeds.len()
    }

    /// True for a grid without episodes.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// All cells in grid order: planner, predictor, profile, scenario, α, λ, seed.
    pub fn cells(&self) -> Vec<Cell> {
        let mut out = Vec::with_capacity(self.len());
        for p in &self.planners {
            for predictor in &self.predictors {
                for h in &self.profiles {
                    for scenario in self.scenario_axis() {
                        let cell = Cell {
                            planner: p.clone(),
                            alpha: 0.0,
                            lambda: 0.0,
                            seed: 0,
                            hdv_profile: h.clone(),
                            predictor: predictor.clone(),
                            scenario,
                        };
                        out.extend(self.points(&cell));
                    }
                }
            }
        }
        out
    }

    /// The cells of `like`'s planner, predictor, profile and scenario at every α, λ and seed.
    fn points<'a>(&'a self, like: &'a Cell) -> impl Iterator<Item = Cell> + 'a {
        self.alphas.iter().flat_map(move |&alpha| {
            self.lambdas.iter().flat_map(move |&lambda| {
                self.seeds.iter().map(move |&seed| Cell {
                    alpha,
                    lambda,
                    seed,
                    ..like.clone()
                })
            })
        })
    }
}

/// The k-th of n disjoint slices of a grid (k is 1-based).
///
/// Slices are interleaved: the cell at grid position i (0-based) belongs to slice
/// `i mod n + 1`. Interleaving gives every slice a similar mix of planners and traffic levels,
/// so slices take about the same time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which slice, k (1-based, at most `count`).
    pub index: usize,
    /// How many slices the grid is cut into, n.
    pub count: usize,
}

/// A `--shard` value that is not `k/n` with 1 ≤ k ≤ n.
#[derive(Debug, thiserror::Error)]
#[error("invalid shard '{spec}': {reason} (expected k/n with 1 <= k <= n, e.g. 2/4)")]
pub struct ShardError {
    /// The `--shard` value as given.
    pub spec: String,
    /// What is wrong with it.
    pub reason: &'static str,
}

impl Shard {
    /// The whole grid.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Does the cell at grid position `position` (0-based) belong to this slice?
    pub fn contains(&self, position: usize) -> bool {
        position % self.count == self.index - 1
    }
}

impl FromStr for Shard {
    type Err = ShardError;

    fn from_str(spec: &str) -> Result<Self, Self::Err> {
        let err = |reason| ShardError {
            spec: spec.to_string(),
            reason,
        };
        let (k, n) = spec.split_once('/').ok_or_else(|| err("no '/'"))?;
        let k: usize = k.trim().parse().map_err(|_| err("k is not a number"))?;
        let n: usize = n.trim().parse().map_err(|_| err("n is not a number"))?;
        if n == 0 {
            return Err(err("n must be at least 1"));
        }
        if k == 0 || k > n {
            return Err(err("k must lie in 1..=n"));
        }
        Ok(Shard { index: k, count: n })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenario_cells_run_in_grid_order_and_name_their_directories() {
        let grid = Grid::over_scenarios(
            &["bk-pbs".into(), "sumo".into()],
            vec!["game/A10KW.sumocfg".into(), "ramp.sumocfg".into()],
            &[0.6, 0.3],
            4,
            2,
        );
        let cells = grid.cells();
        assert_eq!((cells.len(), grid.len()), (16, 16));
        assert_eq!(cells[0].dir_name(), Path::new("bk-pbs/A10KW/a0.3_s4"));
        assert_eq!(cells[3].dir_name(), Path::new("bk-pbs/A10KW/a0.6_s5"));
        assert_eq!(cells[4].dir_name(), Path::new("bk-pbs/ramp/a0.3_s4"));
        assert_eq!(cells[8].to_string(), "sumo A10KW α=0.3 seed=4");
    }
}
