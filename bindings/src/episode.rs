//! `bkpbs.run_episode` (the core's episode loop, GIL released) and the scenario files a Python
//! TraCI loop needs (`write_scenario`, `write_demand`).

use std::path::{Path, PathBuf};

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bkpbs::controller::{UnknownPlanner, PLANNERS};
use bkpbs::episode::demand;
use bkpbs::episode::output;
use bkpbs::episode::summary::Summary;
use bkpbs::episode::{self};
use bkpbs::model::road::EMBEDDED_NET;
use bkpbs::sumo::files;

use crate::errors::bad_input;
use crate::run_slot::{cell_table, cells_dict, run_detached};

/// The `episode.csv` row as a dict: the values the row is written from, typed and at full
/// precision (a float is the `f64` itself, not its CSV text; empty cells are `None`).
pub(crate) fn summary_dict<'py>(
    py: Python<'py>,
    summary: &Summary,
) -> PyResult<Bound<'py, PyDict>> {
    cells_dict(py, summary.cells())
}

/// Runs one episode of `planner` at penetration `alpha`, arrival rate `lam` (veh/h) and
/// `seed` in the core's episode loop (SUMO in-process) and returns its summary: the values
/// `episode.csv` is written from, at full precision. `config` (dict, TOML text or file) and
/// keyword overrides (`steps=100`, `idm={"accel": 2.0}`) set the rest; `out` also writes the
/// episode's CSV files there. With `sumocfg` the episode runs the user's own SUMO scenario
/// instead of the paper's demand (no `lam`), as `bkpbs episode --sumocfg` does, and returns
/// that `episode.csv` row.
#[pyfunction]
#[pyo3(signature = (planner, alpha, lam = None, seed = 0, *, config = None, out = None, sumocfg = None, **overrides))]
#[allow(clippy::too_many_arguments)]
pub fn run_episode<'py>(
    py: Python<'py>,
    planner: &str,
    alpha: f64,
    lam: Option<f64>,
    seed: i64,
    config: Option<&Bound<'py, PyAny>>,
    out: Option<PathBuf>,
    sumocfg: Option<PathBuf>,
    overrides: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    if !PLANNERS.contains(&planner) {
        return Err(bad_input(UnknownPlanner(planner.to_string())));
    }
    let config = match sumocfg {
        Some(sumocfg) => {
            if let Some(lam) = lam {
                return Err(crate::scenario::lam_with_sumocfg(lam));
            }
            let table = cell_table(alpha, None, seed)?;
            crate::scenario::resolve_with(&sumocfg, config, overrides, table)?
        }
        None => crate::config::resolve(config, overrides, cell_table(alpha, lam, seed)?)?,
    };
    let ran = run_detached(py, planner, || episode::ran::run(&config, planner))?;
    if let Some(dir) = out {
        ran.write(&dir)
            .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))?;
    }
    summary_dict(py, ran.summary())
}

fn write(path: &Path, text: &str) -> PyResult<()> {
    output::write_atomic(path, text.as_bytes())
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))
}

/// Writes an episode's demand (α, λ, seed and the configuration) as a SUMO route file, the
/// same as `bkpbs demand --out`, and returns the number of vehicles.
#[pyfunction]
#[pyo3(signature = (out, alpha = 0.5, lam = 3000.0, seed = 0, *, config = None, **overrides))]
pub fn write_demand(
    out: PathBuf,
    alpha: f64,
    lam: f64,
    seed: i64,
    config: Option<&Bound<'_, PyAny>>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<usize> {
    let config = crate::config::resolve(config, overrides, cell_table(alpha, Some(lam), seed)?)?;
    let road = bkpbs::sumo::frame::scenario_road(&config.scenario).map_err(bad_input)?;
    demand::check_entries(&config, &road).map_err(bad_input)?;
    let planned = demand::generate(&config, &road);
    write(&out, &demand::route_file(&road, &planned))?;
    Ok(planned.len())
}

/// Writes what SUMO needs to run an episode from a TraCI or libsumo loop into `dir`: the merge
/// network (unless the configuration names one), the vehicle types and the demand as a route
/// file. Returns their paths, the SUMO command line the episode runner uses (`sumo_args`:
/// step length, collision options, lane-change duration, …; collisions are only reported, so
/// the loop removes the vehicles involved), the step length `dt`, `steps` and the number of
/// vehicles.
#[pyfunction]
#[pyo3(signature = (dir, alpha = 0.5, lam = 3000.0, seed = 0, *, config = None, **overrides))]
pub fn write_scenario<'py>(
    py: Python<'py>,
    dir: PathBuf,
    alpha: f64,
    lam: f64,
    seed: i64,
    config: Option<&Bound<'py, PyAny>>,
    overrides: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let config = crate::config::resolve(config, overrides, cell_table(alpha, Some(lam), seed)?)?;
    let net = match &config.scenario.net_file {
        Some(p) => p.clone(),
        None => {
            let p = dir.join("merge.net.xml");
            write(&p, EMBEDDED_NET)?;
            p
        }
    };
    let road = bkpbs::sumo::frame::scenario_road(&config.scenario).map_err(bad_input)?;
    let vtypes = dir.join("vtypes.add.xml");
    write(&vtypes, &files::vehicle_types(&config, road.lane_width))?;
    let routes = dir.join("demand.rou.xml");
    demand::check_entries(&config, &road).map_err(bad_input)?;
    let planned = demand::generate(&config, &road);
    write(&routes, &demand::route_file(&road, &planned))?;
    let d = PyDict::new(py);
    d.set_item(
        "sumo_args",
        files::command_line(&config, &net, &vtypes, &routes),
    )?;
    d.set_item("net", net)?;
    d.set_item("vtypes", vtypes)?;
    d.set_item("routes", routes)?;
    d.set_item("dt", config.scenario.dt)?;
    d.set_item("steps", config.scenario.steps)?;
    d.set_item("vehicles", planned.len())?;
    Ok(d)
}

/// The whole configuration as TOML (as `bkpbs config --print` shows it), after `config` and
/// keyword overrides.
#[pyfunction]
#[pyo3(signature = (config = None, **overrides))]
pub fn config_toml(
    config: Option<&Bound<'_, PyAny>>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    Ok(crate::config::resolve(config, overrides, toml::Table::new())?.to_toml())
}
