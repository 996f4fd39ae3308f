//! What can go wrong when talking to SUMO: one error type for every call of [`super::Simulation`].

/// What can go wrong when talking to SUMO.
#[derive(Debug, thiserror::Error)]
pub enum SumoError {
    /// SUMO itself refused or failed; `message` is SUMO's text.
    #[error("SUMO error in {call}: {message}")]
    Sumo {
        /// The libsumo call that failed.
        call: &'static str,
        /// SUMO's message, on one line.
        message: String,
    },
    /// This thread already holds the process's one libsumo simulation.
    #[error("a SUMO simulation is already open in this thread (libsumo allows one per process)")]
    AlreadyOpen,
    /// A string handed to SUMO contained a NUL byte.
    #[error("string passed to SUMO contains a NUL byte: {0:?}")]
    NulInString(String),
    /// The process talks to another SUMO than the one bkpbs was built against.
    #[error(
        "bkpbs was built against SUMO {built} but runs SUMO {loaded} ({from}): run it with the SUMO \
         it was built against, or rebuild it against this one (`make build`, with SUMO_HOME set to it)"
    )]
    VersionMismatch {
        /// [`super::version::BUILT`].
        built: &'static str,
        /// The version the loaded libsumo (or the connected sumo-gui) reports.
        loaded: String,
        /// The library file loaded, or `sumo-gui`.
        from: String,
    },
    /// A simulation step returned without advancing SUMO's clock.
    #[error("SUMO's simulation time did not advance in a step (still at {time} s)")]
    Stalled {
        /// SUMO's time before and after the step (s).
        time: f64,
    },
}
