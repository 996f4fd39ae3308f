//! Python exception classes for the core's errors: bad input is a `ValueError`, a failing or
//! busy SUMO a `RuntimeError`, so callers can catch what they can fix apart from what they
//! cannot. Messages are the core's own, unchanged.

use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use bkpbs::episode::EpisodeError;
use bkpbs::sumo::files::InputError;

pyo3::create_exception!(
    bkpbs,
    BkpbsError,
    PyValueError,
    "Bad input: an unknown planner, α outside [0, 1], an unknown or invalid configuration key, a malformed vehicle, a bad campaign grid."
);
pyo3::create_exception!(
    bkpbs,
    SumoError,
    PyRuntimeError,
    "SUMO failed to start or failed during an episode; the message is SUMO's."
);
pyo3::create_exception!(
    bkpbs,
    SimulationBusyError,
    SumoError,
    "An episode is already running in this process: libsumo allows one simulation per process."
);

/// A [`BkpbsError`] with `message`.
pub fn bad_input(message: impl std::fmt::Display) -> PyErr {
    BkpbsError::new_err(message.to_string())
}

/// The Python exception of an episode's error (one with SUMO's own reason is classed by its
/// cause, and says what SUMO said).
pub fn episode_error(e: &EpisodeError) -> PyErr {
    let message = e.to_string();
    let e = match e {
        EpisodeError::Sumo { cause, .. } => cause.as_ref(),
        other => other,
    };
    match e {
        EpisodeError::Config(_)
        | EpisodeError::NoGui(_)
        | EpisodeError::Controller(_)
        | EpisodeError::Input(InputError::MissingNet(_))
        | EpisodeError::Scenario(_)
        | EpisodeError::OutOfOrder(_)
        | EpisodeError::Road(_) => BkpbsError::new_err(message),
        EpisodeError::Input(InputError::Write { .. }) => PyOSError::new_err(message),
        // Only the bkpbs binary takes stop signals as requests; kept exhaustive all the same.
        EpisodeError::Interrupted { .. } => PyKeyboardInterrupt::new_err(message),
        EpisodeError::Start { .. }
        | EpisodeError::Step { .. }
        | EpisodeError::Sumo { .. }
        | EpisodeError::Output(_) => SumoError::new_err(message),
    }
}

/// Registers the exception classes on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("BkpbsError", py.get_type::<BkpbsError>())?;
    m.add("SumoError", py.get_type::<SumoError>())?;
    m.add("SimulationBusyError", py.get_type::<SimulationBusyError>())?;
    Ok(())
}
