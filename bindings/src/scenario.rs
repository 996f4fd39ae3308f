//! `bkpbs.run_episode(..., sumocfg=FILE)`: an episode on the user's own SUMO scenario in the
//! core's loop (SUMO in-process, GIL released), as `bkpbs episode --sumocfg` runs it.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bkpbs::episode::cells::cells;
use bkpbs::episode::sumocfg;
use bkpbs::sumo::sumocfg::SumoConfig;

use crate::errors::{bad_input, SumoError};
use crate::run_slot::{cell_table, cells_dict, run_detached};

/// What a scenario episode is run with besides the configuration.
pub struct ScenarioCall<'a, 'py> {
    pub planner: &'a str,
    pub alpha: f64,
    pub seed: i64,
    pub sumocfg: PathBuf,
    pub config: Option<&'a Bound<'py, PyAny>>,
    pub overrides: Option<&'a Bound<'py, PyDict>>,
    pub out: Option<PathBuf>,
}

/// Runs the scenario episode and returns its `episode.csv` row as a dict (the values it is
/// written from); `out` also writes its files there. The scenario's `begin`–`end` interval is
/// the episode's length unless `steps=` shortens it.
pub fn run<'py>(py: Python<'py>, call: ScenarioCall<'_, 'py>) -> PyResult<Bound<'py, PyDict>> {
    let table = cell_table(call.alpha, None, call.seed)?;
    let config = resolve_with(&call.sumocfg, call.config, call.overrides, table)?;
    let result = run_detached(py, call.planner, || sumocfg::run(&config, call.planner))?;
    if let Some(dir) = call.out {
        sumocfg::write(&result, &dir)
            .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))?;
    }
    summary_dict(py, &result)
}

/// A scenario episode's `episode.csv` row as a dict of its typed, full-precision values.
pub fn summary_dict<'py>(
    py: Python<'py>,
    result: &sumocfg::ScenarioResult,
) -> PyResult<Bound<'py, PyDict>> {
    let row = cells(&result.summary).map_err(|e| SumoError::new_err(e.to_string()))?;
    cells_dict(py, row)
}

/// The error for a paper-demand argument given with a scenario of the user's own.
pub fn lam_with_sumocfg(lam: f64) -> PyErr {
    bad_input(format!(
        "lam = {lam} was given with sumocfg: a scenario of your own brings its own demand"
    ))
}

/// The configuration of an episode on the scenario `sumocfg`: defaults ← `config` ←
/// `overrides`, the scenario's `begin`–`end` interval its length unless `steps` is given.
pub fn resolve(
    sumocfg: &std::path::Path,
    config: Option<&Bound<'_, PyAny>>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<bkpbs::config::Config> {
    resolve_with(sumocfg, config, overrides, toml::Table::new())
}

/// [`resolve`], with the scenario settings `table` (α, the seed) over the overrides.
pub fn resolve_with(
    sumocfg: &std::path::Path,
    config: Option<&Bound<'_, PyAny>>,
    overrides: Option<&Bound<'_, PyDict>>,
    mut table: toml::Table,
) -> PyResult<bkpbs::config::Config> {
    let path = sumocfg.display().to_string();
    table.insert("sumocfg".into(), toml::Value::String(path));
    let steps_given = overrides.is_some_and(|o| o.contains("steps").unwrap_or(false));
    let mut config = crate::config::resolve(config, overrides, table)?;
    // `steps=` or the scenario's interval; one without an end is refused as by the CLI.
    let given = steps_given.then_some(config.scenario.steps);
    config.scenario.steps = SumoConfig::episode_steps(sumocfg, config.scenario.dt, given)
        .map_err(|e| bad_input(e.to_string()))?;
    Ok(config)
}
