//! What every run of the core's episode loop from Python shares: the process's one simulation
//! slot (libsumo holds one simulation per process), the message of a caught panic, the
//! `scenario` table of a call's α, λ and seed, and a CSV row as a dict.

use std::panic::{self, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bkpbs::episode::cells::{Cell, Value};
use bkpbs::episode::EpisodeError;

use crate::errors::{bad_input, episode_error, SimulationBusyError, SumoError};

/// Set while an episode runs in this process: libsumo holds one simulation per process.
static RUNNING: AtomicBool = AtomicBool::new(false);

/// Holds [`RUNNING`] until dropped.
pub struct Slot(());

impl Slot {
    /// Claims the process's simulation slot.
    ///
    /// # Errors
    /// [`SimulationBusyError`] while another episode runs in this process.
    pub fn claim() -> PyResult<Slot> {
        RUNNING
            .compare_exchange(false, true, Ordering::SeqCst, Ordering::SeqCst)
            .map(|_| Slot(()))
            .map_err(|_| {
                SimulationBusyError::new_err(
                    "an episode is already running in this process (libsumo allows one \
                     simulation per process): run episodes one after another, or in separate \
                     processes (python -m bkpbs.campaign)",
                )
            })
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        RUNNING.store(false, Ordering::SeqCst);
    }
}

/// The message of a caught panic.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic payload".into())
}

/// The α, λ (unless left to the configuration) and seed of an episode as a `scenario` table.
pub(crate) fn cell_table(alpha: f64, lam: Option<f64>, seed: i64) -> PyResult<toml::Table> {
    if seed < 0 {
        return Err(bad_input(format!(
            "invalid setting scenario.seed = {seed}: must not be negative"
        )));
    }
    let mut table = toml::Table::from_iter([
        ("alpha".to_string(), toml::Value::Float(alpha)),
        ("seed".to_string(), toml::Value::Integer(seed)),
    ]);
    if let Some(lam) = lam {
        table.insert("lambda".to_string(), toml::Value::Float(lam));
    }
    Ok(table)
}

/// A CSV row's cells as a dict of their typed, full-precision values.
pub(crate) fn cells_dict(py: Python<'_>, row: Vec<Cell>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for Cell { column, value } in row {
        match value {
            Value::Text(s) => d.set_item(column, s)?,
            Value::Int(i) => d.set_item(column, i)?,
            Value::UInt(u) => d.set_item(column, u)?,
            Value::Bool(b) => d.set_item(column, b)?,
            Value::Float { value, .. } => d.set_item(column, value)?,
            Value::Empty => d.set_item(column, py.None())?,
        }
    }
    Ok(d)
}

/// Runs `episode` (of `planner`) in this thread in the process's simulation slot with the GIL
/// released; `Err` carries the Python exception, a panic included.
pub(crate) fn run_detached<T: Send>(
    py: Python<'_>,
    planner: &str,
    episode: impl FnOnce() -> Result<T, EpisodeError> + Send,
) -> PyResult<T> {
    let _slot = Slot::claim()?;
    let outcome = py.detach(|| panic::catch_unwind(AssertUnwindSafe(episode)));
    match outcome {
        Ok(Ok(result)) => Ok(result),
        Ok(Err(e)) => Err(episode_error(&e)),
        Err(payload) => Err(SumoError::new_err(format!(
            "planner {planner} panicked: {}",
            panic_message(payload.as_ref())
        ))),
    }
}
