//! Python bindings of bkpbs: the native module `bkpbs._bkpbs`, re-exported by the `bkpbs`
//! package. Thin wrappers, one module per core concept; the logic stays in the core crate.

mod campaign;
mod config;
mod controller;
mod episode;
mod errors;
mod gym;
mod own_loop;
mod predict;
mod run_slot;
mod scenario;
mod scene;
mod traci_client;

use pyo3::prelude::*;

#[pymodule]
fn _bkpbs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("SUMO_VERSION", bkpbs::sumo::version::BUILT)?;
    m.add("PLANNERS", controller::planners(m.py())?)?;
    m.add("COMMANDED_MODES", bkpbs::episode::control::COMMANDED_MODES)?;
    m.add_class::<controller::PyController>()?;
    m.add_class::<controller::PyManeuver>()?;
    m.add_class::<campaign::PyCampaign>()?;
    m.add_class::<campaign::PyCampaignTask>()?;
    m.add_class::<predict::PyPredictor>()?;
    m.add_class::<gym::PyMergeEnv>()?;
    m.add_function(wrap_pyfunction!(episode::run_episode, m)?)?;
    m.add_function(wrap_pyfunction!(episode::write_demand, m)?)?;
    m.add_function(wrap_pyfunction!(episode::write_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(episode::config_toml, m)?)?;
    m.add_function(wrap_pyfunction!(campaign::report, m)?)?;
    m.add_function(wrap_pyfunction!(predict::load_predictor, m)?)?;
    Ok(())
}
