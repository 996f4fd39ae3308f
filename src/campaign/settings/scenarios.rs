//! Settings of a campaign over scenarios of the user's own: the `[campaign]` table with a
//! `scenarios` list (or `--sumocfg A,B`), overridden by flags, validated before any episode.
//!
//! ```toml
//! [campaign]
//! scenarios = ["game/A10KW.sumocfg", "game/ramp.sumocfg"]
//! planners = ["bk-pbs", "idm-mobil"]
//! alphas = [0.3, 0.6]
//! seeds = 3
//! # steps = 1500      # optional: shortens every scenario's own interval
//! ```
//!
//! The scenarios bring their demand and drivers, so `lambdas` and `hdv_profiles` have no
//! place here (`predictors`, the predictor axis, has, as on the paper's demand); each scenario runs its own `begin`–`end` unless `steps` shortens it. Every
//! scenario is read and its step length checked before the first episode starts.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::campaign::checks::{
    check_planners_and_alphas, check_seeds_and_steps, episode_timeout, origin, parse_list,
    read_doc, read_parts, shard_of, worker_count,
};

use crate::campaign::grid::{scenario_name, Cell, Grid};
use crate::campaign::settings::{CampaignTable, Overrides, Settings, SettingsError};
use crate::config::Config;
use crate::sumo::scenario_files;
use crate::sumo::sumocfg::SumoConfig;

/// What every cell of one scenario of a campaign runs with: its steps and the digests of its
/// files ([`crate::sumo::scenario_files::digests`]), which every cell's settings record carries.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioRecord {
    steps: u32,
    digests: BTreeMap<String, String>,
}

/// Is this campaign one over scenarios of the user's own: `--sumocfg` given, or a file whose
/// `[campaign]` table lists `scenarios`?
pub fn is_scenario_campaign(file: Option<&Path>, o: &Overrides) -> Result<bool, SettingsError> {
    if o.sumocfg.is_some() {
        return Ok(true);
    }
    let Some(path) = file else { return Ok(false) };
    let doc = read_doc(path)?;
    Ok(matches!(doc.get("campaign"), Some(toml::Value::Table(t)) if t.contains_key("scenarios")))
}

/// Refuses what the paper's demand has and a scenario brings itself.
fn refuse_demand_settings(
    doc: &toml::Table,
    o: &Overrides,
    file: Option<&Path>,
) -> Result<(), SettingsError> {
    let keys = match doc.get("campaign") {
        Some(toml::Value::Table(t)) => t.keys().cloned().collect(),
        _ => Vec::new(),
    };
    for (flag, key, set, what) in [
        ("--lambdas", "lambdas", o.lambdas.is_some(), "its demand"),
        (
            "--hdv-profiles",
            "hdv_profiles",
            o.hdv_profiles.is_some(),
            "its drivers",
        ),
    ] {
        if set || keys.iter().any(|k| k == key) {
            return Err(SettingsError::NotWithScenarios {
                origin: origin(set, flag, key, file),
                what,
            });
        }
    }
    Ok(())
}

fn apply_overrides(t: &mut CampaignTable, o: &Overrides) -> Result<(), SettingsError> {
    if let Some(text) = &o.sumocfg {
        t.scenarios = text
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(PathBuf::from)
            .collect();
    }
    if let Some(text) = &o.planners {
        t.planners = parse_list("--planners", text)?;
    }
    if let Some(text) = &o.alphas {
        t.alphas = parse_list("--alphas", text)?;
    }
    super::apply_predictors(t, o)?;
    t.seeds = o.seeds.unwrap_or(t.seeds);
    t.seed_base = o.seed_base.unwrap_or(t.seed_base);
    t.steps = o.steps.or(t.steps);
    // The paper demand's default rates: a scenario's routes are its demand.
    t.lambdas.clear();
    t.workers = o.workers.or(t.workers);
    t.episode_timeout = o.episode_timeout.or(t.episode_timeout);
    t.sumo_version = crate::sumo::version::BUILT.to_string();
    Ok(())
}

/// The settings of a campaign over scenarios: reads the campaign file (if any), applies the
/// flags and checks every value, every scenario (readable, the planners' step length, an
/// interval) and every cell's configuration.
///
/// # Errors
/// The first problem found, naming its flag or key and file.
pub(crate) fn resolve(file: Option<&Path>, o: &Overrides) -> Result<Settings, SettingsError> {
    let doc = match file {
        Some(p) => read_doc(p)?,
        None => toml::Table::new(),
    };
    refuse_demand_settings(&doc, o, file)?;
    let (mut table, mut config): (CampaignTable, Config) = match file {
        Some(p) => read_parts(doc, p)?,
        None => Default::default(),
    };
    if let Some(format) = o.trajectories {
        config.output.trajectories = format;
    }
    apply_overrides(&mut table, o)?;
    let shard = shard_of(o)?;
    let workers = worker_count(table.workers, o.workers.is_some(), file)?;
    let timeout = episode_timeout(table.episode_timeout, o.episode_timeout.is_some(), file)?;
    let grid = checked_grid(&table, o, file)?;
    let steps = scenario_steps(&grid.scenarios, table.steps, config.scenario.dt)?;
    let scenario_records = (grid.scenarios.iter().zip(steps))
        .map(|(path, steps)| {
            let digests = scenario_files::digests(path)?;
            Ok(ScenarioRecord { steps, digests })
        })
        .collect::<Result<_, SettingsError>>()?;
    let settings = Settings {
        table,
        grid,
        shard,
        workers,
        episode_timeout: timeout,
        config,
        scenario_records,
    };
    for cell in settings.grid.cells() {
        settings.episode_config(&cell).validate()?;
    }
    Ok(settings)
}

/// A cell's whole configuration on its scenario: the shared settings with its scenario, α,
/// seed and steps (its predictor is the grid's, [`Settings::episode_config`]).
pub(crate) fn episode_config(settings: &Settings, cell: &Cell) -> Config {
    let mut c = settings.config.clone();
    let i = (settings.grid.scenarios.iter()).position(|s| Some(s) == cell.scenario.as_ref());
    c.scenario.sumocfg = cell.scenario.clone();
    c.scenario.alpha = cell.alpha;
    c.scenario.seed = cell.seed;
    if let Some(record) = i.map(|i| &settings.scenario_records[i]) {
        c.scenario.steps = record.steps;
        c.scenario.sumocfg_digests = record.digests.clone();
    }
    c
}

/// The grid, after checking planners, scenarios, α and seeds.
fn checked_grid(
    t: &CampaignTable,
    o: &Overrides,
    file: Option<&Path>,
) -> Result<Grid, SettingsError> {
    check_planners_and_alphas(&t.planners, &t.alphas, o, file)?;
    check_seeds_and_steps(t.seeds, t.steps, o, file)?;
    super::check_predictors(&t.predictors, o, file)?;
    let scenarios = unique_scenarios(&t.scenarios)?;
    if scenarios.is_empty() {
        return Err(SettingsError::Empty {
            origin: origin(o.sumocfg.is_some(), "--sumocfg", "scenarios", file),
        });
    }
    let grid = Grid::over_scenarios(&t.planners, scenarios, &t.alphas, t.seed_base, t.seeds);
    Ok(match t.predictors.is_empty() {
        true => grid,
        false => grid.with_predictors(&t.predictors),
    })
}

/// The scenarios each once, in order; two different files of one name are refused.
fn unique_scenarios(given: &[PathBuf]) -> Result<Vec<PathBuf>, SettingsError> {
    let mut out: Vec<PathBuf> = Vec::new();
    for s in given {
        if out.contains(s) {
            continue;
        }
        let name = scenario_name(s);
        if name.is_empty() || name == "." || name == ".." {
            return Err(SettingsError::BadName {
                path: s.clone(),
                name,
            });
        }
        if let Some(first) = out.iter().find(|o| scenario_name(o) == scenario_name(s)) {
            return Err(SettingsError::SameName {
                name: scenario_name(s),
                first: first.clone(),
                second: s.clone(),
            });
        }
        out.push(s.clone());
    }
    Ok(out)
}

/// Each scenario's steps: `steps` if given, else its own interval; each read, its step
/// length checked against the planners' `dt`, and one naming its own tripinfo output refused
/// (the campaign's episodes would share it).
fn scenario_steps(
    scenarios: &[PathBuf],
    steps: Option<u32>,
    dt: f64,
) -> Result<Vec<u32>, SettingsError> {
    scenarios
        .iter()
        .map(|path| {
            let cfg = SumoConfig::read(path)?;
            cfg.check_step(dt)?;
            crate::sumo::route_files::check_demand(&cfg)?;
            if let Some(file) = cfg.option(&["tripinfo-output", "tripinfo"]) {
                if !file.trim().is_empty() {
                    return Err(SettingsError::OwnTripinfo {
                        path: path.clone(),
                        file: file.to_string(),
                    });
                }
            }
            match (steps, cfg.steps(dt)?) {
                (Some(n), _) | (None, Some(n)) => Ok(n),
                (None, None) => Err(SettingsError::NoInterval { path: path.clone() }),
            }
        })
        .collect()
}
