//! `bkpbs.Controller(sumocfg=…)` stepped by the caller's own TraCI loop: the core's episode on
//! a user's scenario ([`OwnLoop`]) answered through the caller's module, so that the loop gets
//! the rows and files of `bkpbs episode --sumocfg`.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bkpbs::episode::cells::cells;
use bkpbs::episode::sumocfg::{self, OwnLoop};

use crate::errors::{bad_input, episode_error, SumoError};
use crate::run_slot::cells_dict;
use crate::traci_client::TraciClient;

/// The error of a scenario call on a controller of one merge road.
pub fn not_a_scenario() -> PyErr {
    bad_input("start, step, finish, steps and sumo_command are for a Controller(sumocfg=...)")
}

/// The episode, unless it has been finished.
pub fn episode(e: &Option<Box<OwnLoop>>) -> PyResult<&OwnLoop> {
    e.as_deref().ok_or_else(finished)
}

fn finished() -> PyErr {
    bad_input("the episode is finished: build a new Controller for another")
}

/// See `Controller.start`.
pub fn start(e: &mut Option<Box<OwnLoop>>, traci: &Bound<'_, PyAny>) -> PyResult<()> {
    let episode = e.as_mut().ok_or_else(finished)?;
    let mut client = TraciClient::new(traci.clone(), &episode.edge_names());
    episode.start(&mut client).map_err(|e| episode_error(&e))
}

/// See `Controller.step`.
pub fn step(e: &mut Option<Box<OwnLoop>>, traci: &Bound<'_, PyAny>) -> PyResult<()> {
    let episode = e.as_mut().ok_or_else(finished)?;
    let mut client = TraciClient::new(traci.clone(), &episode.edge_names());
    episode.step(&mut client).map_err(|e| episode_error(&e))
}

/// See `Controller.finish`.
pub fn finish<'py>(
    py: Python<'py>,
    e: &mut Option<Box<OwnLoop>>,
    out: Option<std::path::PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    episode(e)?.sumo_closed().map_err(|e| episode_error(&e))?;
    let episode = e.take().ok_or_else(finished)?;
    let result = episode.finish().map_err(|e| episode_error(&e))?;
    if let Some(dir) = out {
        sumocfg::write(&result, &dir)
            .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))?;
    }
    let row = cells(&result.summary).map_err(|e| SumoError::new_err(e.to_string()))?;
    cells_dict(py, row)
}
