//! Campaign settings: the `[campaign]` table of a TOML file (next to any scenario settings of
//! [`Config`]), overridden by command-line flags, validated up front.
//!
//! A campaign file looks like `bkpbs config --print` plus one table:
//!
//! ```toml
//! [campaign]
//! planners = ["sumo", "idm-mobil"]
//! alphas = [0.4, 0.5, 0.6, 0.7, 0.8]
//! lambdas = [2500.0, 3000.0]
//! seeds = 5
//! seed_base = 0
//! steps = 400
//! workers = 2
//! episode_timeout = 600   # seconds; optional
//!
//! [idm]
//! time_headway = 1.2
//! ```
//!
//! `scenario.alpha`, `lambda`, `seed` and `steps` vary per cell or come from the campaign table,
//! so a campaign file must not set them.

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::{Deserialize, Serialize};

pub use super::checks::SettingsError;
use super::checks::{
    check_planners_and_alphas, check_seeds_and_steps, check_values, episode_timeout, names_a_cell,
    origin, parse_list, read_doc, read_parts, shard_of, worker_count, TOO_LONG,
};
use super::comparison::{campaign_file, run_difference};
use super::grid::{Cell, Grid, Shard};
pub use super::overrides::Overrides;
pub mod scenarios;

use crate::config::{Config, ConfigError, PredictorKind};
use crate::controller::PLANNERS;
pub use scenarios::{is_scenario_campaign, ScenarioRecord};

/// Steps of an episode of a campaign on the paper's demand, unless given.
pub const DEFAULT_STEPS: u32 = 400;

/// The `[campaign]` table, the one of every campaign: the grid and how to run it. A campaign
/// over scenarios of the user's own lists them (`scenarios`) and has no λ nor HDV profiles
/// (its routes and drivers are its own), nor steps unless given (each scenario's own interval);
/// a campaign on the paper's demand has no scenarios. Absent parts are no keys in
/// `campaign.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CampaignTable {
    /// The scenarios' configuration files (`.sumocfg`), a grid axis; empty: the paper's demand.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub scenarios: Vec<PathBuf>,
    /// Controllers to compare; default: every name in [`PLANNERS`].
    pub planners: Vec<String>,
    /// CAV penetrations α.
    pub alphas: Vec<f64>,
    /// Arrival rates λ (veh/h) of the paper's demand; none over scenarios.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub lambdas: Vec<f64>,
    /// Seeds per (planner, α, λ).
    pub seeds: u64,
    /// First seed; seeds run `seed_base .. seed_base + seeds`.
    pub seed_base: u64,
    /// Episode length in steps; default: [`DEFAULT_STEPS`] on the paper's demand, each
    /// scenario's own interval over scenarios.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steps: Option<u32>,
    /// Worker processes; default: the number of cores. Does not change results.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub workers: Option<usize>,
    /// Wall-clock limit of one episode in seconds; an episode that takes longer is stopped and
    /// recorded as failed. Default: none. Does not change the results of episodes that finish.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub episode_timeout: Option<f64>,
    /// HDV driver profiles, a grid axis; default: the one of `[hdv] profile`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hdv_profiles: Vec<String>,
    /// HDV predictors of the planners (`learned`, `constant`), a grid axis; default: none, every
    /// cell runs `[predictor] kind` (and cells keep the names and columns they had).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub predictors: Vec<String>,
    /// The SUMO version the campaign runs on: always the one bkpbs was built against (written
    /// into `campaign.toml`; a cell another SUMO ran runs again, and `report` merges campaigns
    /// of different versions only with `--allow-mixed`).
    pub sumo_version: String,
}

impl Default for CampaignTable {
    fn default() -> Self {
        CampaignTable {
            scenarios: Vec::new(),
            planners: PLANNERS.iter().map(|p| p.to_string()).collect(),
            alphas: vec![0.4, 0.5, 0.6, 0.7, 0.8],
            lambdas: vec![2500.0, 3000.0],
            seeds: 5,
            seed_base: 0,
            steps: None,
            workers: None,
            episode_timeout: None,
            hdv_profiles: Vec::new(),
            predictors: Vec::new(),
            sumo_version: crate::sumo::version::BUILT.to_string(),
        }
    }
}

/// Validated settings of one campaign run.
#[derive(Debug, Clone)]
pub struct Settings {
    /// The `[campaign]` table as resolved (file, then flags).
    pub table: CampaignTable,
    /// Every episode of the campaign, normalised.
    pub grid: Grid,
    /// The slice of the grid this run runs ([`Shard::ALL`] without `--shard`).
    pub shard: Shard,
    /// Worker processes, at least 1 (the table's, else one per core).
    pub workers: usize,
    /// Wall-clock limit of one episode, if any.
    pub episode_timeout: Option<Duration>,
    /// Scenario settings shared by all cells; `scenario.steps` already set (on the paper's
    /// demand).
    pub config: Config,
    /// Over scenarios of the user's own, each scenario's steps and file digests, in the order
    /// of `grid.scenarios`; empty on the paper's demand.
    pub scenario_records: Vec<ScenarioRecord>,
}

/// A campaign file split into its two parts; without a file, both parts' defaults.
#[derive(Default)]
struct FileParts {
    table: CampaignTable,
    config: Config,
}

fn read_file(path: &Path) -> Result<FileParts, SettingsError> {
    let (table, config) = read_parts(read_doc(path)?, path)?;
    Ok(FileParts { table, config })
}

/// The predictor axis `--predictors` gives, in place of the table's; an empty list refused.
fn apply_predictors(table: &mut CampaignTable, o: &Overrides) -> Result<(), SettingsError> {
    if let Some(text) = &o.predictors {
        table.predictors = parse_list("--predictors", text)?;
        if table.predictors.is_empty() {
            return Err(SettingsError::Empty {
                origin: "--predictors".into(),
            });
        }
    }
    Ok(())
}

/// Replaces the table's values by the flags that are set.
fn apply_overrides(table: &mut CampaignTable, o: &Overrides) -> Result<(), SettingsError> {
    if let Some(text) = &o.planners {
        table.planners = parse_list("--planners", text)?;
    }
    if let Some(text) = &o.alphas {
        table.alphas = parse_list("--alphas", text)?;
    }
    if let Some(text) = &o.lambdas {
        table.lambdas = parse_list("--lambdas", text)?;
    }
    if let Some(text) = &o.hdv_profiles {
        table.hdv_profiles = parse_list("--hdv-profiles", text)?;
    }
    apply_predictors(table, o)?;
    table.seeds = o.seeds.unwrap_or(table.seeds);
    table.seed_base = o.seed_base.unwrap_or(table.seed_base);
    table.steps = o.steps.or(table.steps);
    table.workers = o.workers.or(table.workers);
    table.episode_timeout = o.episode_timeout.or(table.episode_timeout);
    Ok(())
}

impl Settings {
    /// Reads the optional campaign file, applies the flags and validates everything, so that a
    /// bad setting stops the campaign before any episode runs.
    ///
    /// A campaign over scenarios of the user's own (`--sumocfg`, or a file whose table lists
    /// `scenarios`) resolves as [`scenarios`] says.
    pub fn resolve(file: Option<&Path>, o: &Overrides) -> Result<Settings, SettingsError> {
        if is_scenario_campaign(file, o)? {
            return scenarios::resolve(file, o);
        }
        let parts = match file {
            Some(p) => read_file(p)?,
            None => FileParts::default(),
        };
        Settings::from_parts(parts, file, o)
    }

    /// [`Settings::resolve`] of a file already read.
    fn from_parts(
        FileParts {
            mut table,
            mut config,
        }: FileParts,
        file: Option<&Path>,
        o: &Overrides,
    ) -> Result<Settings, SettingsError> {
        apply_overrides(&mut table, o)?;
        let steps = *table.steps.get_or_insert(DEFAULT_STEPS);
        // A record of the SUMO that runs, not a choice: a file written by another SUMO runs
        // on this one (and says so in the new campaign.toml).
        table.sumo_version = crate::sumo::version::BUILT.to_string();
        let shard = shard_of(o)?;
        check_table(&table, o, file)?;
        let workers = worker_count(table.workers, o.workers.is_some(), file)?;
        let episode_timeout =
            episode_timeout(table.episode_timeout, o.episode_timeout.is_some(), file)?;
        config.scenario.steps = steps;
        if let Some(format) = o.trajectories {
            config.output.trajectories = format;
        }
        let profiles = match table.hdv_profiles.is_empty() {
            true => vec![config.hdv.profile.clone()],
            false => table.hdv_profiles.clone(),
        };
        let grid = Grid::new(
            &table.planners,
            &table.alphas,
            &table.lambdas,
            table.seed_base,
            table.seeds,
        )
        .with_profiles(&profiles);
        let grid = match table.predictors.is_empty() {
            true => grid,
            false => grid.with_predictors(&table.predictors),
        };
        check_cells(&config, &grid)?;
        Ok(Settings {
            table,
            grid,
            shard,
            workers,
            episode_timeout,
            config,
            scenario_records: Vec::new(),
        })
    }

    /// Whether the campaign runs over scenarios of the user's own (else the paper's demand).
    pub fn is_over_scenarios(&self) -> bool {
        !self.grid.scenarios.is_empty()
    }

    /// The configuration of one cell's episode.
    pub fn episode_config(&self, cell: &Cell) -> Config {
        let mut c = match cell.scenario {
            Some(_) => scenarios::episode_config(self, cell),
            None => {
                let mut c = self.config.clone();
                c.scenario.alpha = cell.alpha;
                c.scenario.lambda = cell.lambda;
                c.scenario.seed = cell.seed;
                c.hdv.profile = cell.hdv_profile.clone();
                c
            }
        };
        if let Some(p) = &cell.predictor {
            c.predictor.kind = predictor_kind(p).expect("checked when the settings resolved");
        }
        c
    }

    /// The settings as a campaign file (`<out>/campaign.toml`): the grid and the scenario, not
    /// the worker count or shard, which do not change results. Feeding it back with `--config`
    /// reproduces the campaign.
    pub fn to_toml(&self) -> String {
        let table = CampaignTable {
            workers: None,
            episode_timeout: None,
            ..self.table.clone()
        };
        let header = match self.is_over_scenarios() {
            true => "# bkpbs campaign over scenarios; rerun with: bkpbs campaign --config campaign.toml --out DIR",
            false => "# bkpbs campaign settings; rerun with: bkpbs campaign --config campaign.toml --out DIR",
        };
        campaign_file(header, &table, &self.config)
    }

    /// Reads the settings a campaign directory was made with (its `campaign.toml`).
    /// The file's `sumo_version` is kept: it records which SUMO ran the campaign.
    pub fn from_campaign_file(path: &Path) -> Result<Settings, SettingsError> {
        let recorded = read_parts::<CampaignTable>(read_doc(path)?, path)?
            .0
            .sumo_version;
        let mut settings = Settings::resolve(Some(path), &Overrides::default())?;
        settings.table.sumo_version = recorded;
        Ok(settings)
    }

    /// The first scenario setting (dotted key) in which two campaigns' episodes differ, if any:
    /// campaigns that agree here may share a results directory.
    pub fn scenario_difference(&self, other: &Settings) -> Option<String> {
        if self.grid.has_predictor_axis() != other.grid.has_predictor_axis() {
            // One names a predictor per cell in its collected files, the other not.
            return Some("campaign.predictors".into());
        }
        run_difference((&self.config, &self.table), (&other.config, &other.table))
    }
}

/// The predictor a name of the predictor axis selects.
fn predictor_kind(name: &str) -> Option<PredictorKind> {
    <PredictorKind as clap::ValueEnum>::from_str(name, false).ok()
}

/// Every entry of the predictor axis must name a predictor.
fn check_predictors(
    predictors: &[String],
    o: &Overrides,
    file: Option<&Path>,
) -> Result<(), SettingsError> {
    match predictors.iter().find(|p| predictor_kind(p).is_none()) {
        None => Ok(()),
        Some(p) => Err(SettingsError::UnknownPredictor {
            origin: origin(o.predictors.is_some(), "--predictors", "predictors", file),
            name: p.clone(),
        }),
    }
}

/// Checks the resolved table's lists and counts; an error names the flag or file key the bad
/// value came from.
fn check_table(
    table: &CampaignTable,
    o: &Overrides,
    file: Option<&Path>,
) -> Result<(), SettingsError> {
    check_planners_and_alphas(&table.planners, &table.alphas, o, file)?;
    check_predictors(&table.predictors, o, file)?;
    check_values(
        &origin(o.lambdas.is_some(), "--lambdas", "lambdas", file),
        "λ",
        &table.lambdas,
        |l| l > 0.0 && l.is_finite(),
        "must be a positive rate in veh/h",
    )?;
    check_values(
        &origin(o.lambdas.is_some(), "--lambdas", "lambdas", file),
        "λ",
        &table.lambdas,
        names_a_cell,
        TOO_LONG,
    )?;
    check_seeds_and_steps(table.seeds, table.steps, o, file)
}

/// Every (predictor, profile, α, λ) of the grid must make a valid episode configuration, so
/// that no cell fails on its settings halfway through the campaign.
fn check_cells(config: &Config, grid: &Grid) -> Result<(), ConfigError> {
    for predictor in &grid.predictors {
        for profile in &grid.profiles {
            for &alpha in &grid.alphas {
                for &lambda in &grid.lambdas {
                    let mut c = config.clone();
                    c.scenario.alpha = alpha;
                    c.scenario.lambda = lambda;
                    c.hdv.profile = profile.clone();
                    if let Some(kind) = predictor.as_deref().and_then(predictor_kind) {
                        c.predictor.kind = kind;
                    }
                    c.validate()?;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error text of resolving `flags` with no campaign file.
    fn flag_error(flags: Overrides) -> String {
        Settings::resolve(None, &flags).unwrap_err().to_string()
    }

    /// The error text of resolving a campaign file holding `text`, and the file's path.
    fn file_error(text: &str) -> (String, String) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("campaign.toml");
        std::fs::write(&path, text).unwrap();
        let e = Settings::resolve(Some(&path), &Overrides::default()).unwrap_err();
        (e.to_string(), path.display().to_string())
    }

    #[test]
    fn defaults_resolve() {
        let s = Settings::resolve(None, &Overrides::default()).unwrap();
        let steps = Some(DEFAULT_STEPS);
        assert_eq!(
            s.table,
            CampaignTable {
                steps,
                ..CampaignTable::default()
            }
        );
        assert_eq!(s.config.scenario.steps, 400);
        assert!(s.workers >= 1);
    }

    #[test]
    fn list_flags_are_trimmed_and_skip_empty_entries() {
        let s = Settings::resolve(
            None,
            &Overrides {
                planners: Some(" sumo , idm-mobil,,".into()),
                alphas: Some("0.4, 0.6,".into()),
                lambdas: Some(" 2500 ".into()),
                ..Overrides::default()
            },
        )
        .unwrap();
        assert_eq!(s.table.planners, ["sumo", "idm-mobil"]);
        assert_eq!(s.table.alphas, [0.4, 0.6]);
        assert_eq!(s.table.lambdas, [2500.0]);
    }

    #[test]
    fn bad_flags_name_the_flag() {
        let cases = [
            (
                Overrides {
                    planners: Some(" , ".into()),
                    ..Overrides::default()
                },
                "--planners: the list is empty".to_string(),
            ),
            (
                Overrides {
                    planners: Some("sumo,bk-pbz".into()),
                    ..Overrides::default()
                },
                format!(
                    "--planners: unknown planner 'bk-pbz' (known: {})",
                    PLANNERS.join(", ")
                ),
            ),
            (
                Overrides {
                    alphas: Some("0.4,abc".into()),
                    ..Overrides::default()
                },
                "--alphas: 'abc' is not a number".into(),
            ),
            (
                Overrides {
                    alphas: Some("0.4,1.5".into()),
                    ..Overrides::default()
                },
                "--alphas: α 1.5 must lie in [0, 1]".into(),
            ),
            (
                Overrides {
                    lambdas: Some("2500,-5".into()),
                    ..Overrides::default()
                },
                "--lambdas: λ -5 must be a positive rate in veh/h".into(),
            ),
            (
                Overrides {
                    lambdas: Some("x".into()),
                    ..Overrides::default()
                },
                "--lambdas: 'x' is not a number".into(),
            ),
            (
                Overrides {
                    seeds: Some(0),
                    ..Overrides::default()
                },
                "--seeds: seed count 0 must be at least 1".into(),
            ),
            (
                Overrides {
                    steps: Some(0),
                    ..Overrides::default()
                },
                "--steps: steps 0 must be at least 1".into(),
            ),
            (
                Overrides {
                    workers: Some(0),
                    ..Overrides::default()
                },
                "--workers: workers 0 must be at least 1".into(),
            ),
        ];
        for (flags, expected) in cases {
            assert_eq!(flag_error(flags), expected);
        }
    }

    #[test]
    fn errors_come_in_order_parsing_shard_table_cells() {
        let bad_everything = Overrides {
            planners: Some("nope".into()),
            alphas: Some("abc".into()),
            lambdas: Some("x".into()),
            seeds: Some(0),
            shard: Some("3/2".into()),
            ..Overrides::default()
        };
        assert_eq!(
            flag_error(bad_everything.clone()),
            "--alphas: 'abc' is not a number"
        );
        let e = flag_error(Overrides {
            alphas: None,
            lambdas: None,
            ..bad_everything.clone()
        });
        assert!(e.contains("3/2"), "{e}");
        let e = flag_error(Overrides {
            alphas: Some("2".into()),
            lambdas: None,
            shard: None,
            ..bad_everything
        });
        assert!(e.starts_with("--planners: unknown planner 'nope'"), "{e}");
    }

    #[test]
    fn bad_file_values_name_the_key_and_file() {
        let (e, path) = file_error("[campaign]\nalphas = []\n");
        assert_eq!(e, format!("campaign.alphas in {path}: the list is empty"));
        let (e, path) = file_error("[campaign]\nseeds = 0\n");
        assert_eq!(
            e,
            format!("campaign.seeds in {path}: seed count 0 must be at least 1")
        );
        let (e, path) = file_error("[scenario]\nalpha = 0.5\n");
        assert_eq!(
            e,
            format!("scenario.alpha in {path} is set by the campaign (use campaign.alphas)")
        );
    }

    #[test]
    fn every_cell_must_make_a_valid_episode() {
        let (e, _) = file_error("[idm]\naccel = 0.0\n");
        assert_eq!(e, "invalid setting idm.accel = 0: must be positive");
    }
}
