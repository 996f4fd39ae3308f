//! The configuration of an episode on the user's own SUMO scenario, as Python gives it
//! (`bkpbs.run_episode(..., sumocfg=FILE)`, `Controller(sumocfg=…)`, the Gymnasium
//! environment), resolved as `bkpbs episode --sumocfg` resolves it.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bkpbs::sumo::sumocfg::SumoConfig;

use crate::errors::bad_input;

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
