//! Why an episode could not complete: [`EpisodeError`], and [`sumo_errors`], which reads SUMO's
//! own reason off its console.
//!
//! Apart from the runner because every caller of an episode (the CLI, training, campaigns, the
//! Python bindings) handles these errors without needing to know how the episode is stepped.

use crate::config::ConfigError;
use crate::controller::BuildError;
use crate::sumo::files::InputError;
use crate::sumo::frame::NetworkError;
use crate::sumo::sumocfg::SumoConfigError;
use crate::sumo::SumoError;

/// Why an episode could not complete.
#[derive(Debug, thiserror::Error)]
pub enum EpisodeError {
    /// The configuration is invalid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// SUMO's input (net, vehicle types, routes) could not be prepared.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The controller could not be built.
    #[error(transparent)]
    Controller(#[from] BuildError),
    /// SUMO did not start.
    #[error("cannot start SUMO on net {net}: {cause}")]
    Start {
        /// The network file SUMO was started on.
        net: std::path::PathBuf,
        /// SUMO's error.
        cause: SumoError,
    },
    /// The network cannot be read or is not a merge road to plan on.
    #[error(transparent)]
    Road(#[from] NetworkError),
    /// A simulation step failed.
    #[error("SUMO failed at step {step} (t = {time:.1} s): {cause}")]
    Step {
        /// Index of the failed step (0 the first).
        step: u32,
        /// Simulation time of that step: step × `scenario.dt` (s).
        time: f64,
        /// SUMO's error.
        cause: SumoError,
    },
    /// `sumo.gui` asked for sumo-gui where it cannot run.
    #[error("cannot show the episode: {0}")]
    NoGui(String),
    /// A stop signal (Ctrl-C, `kill`) arrived: the episode ended early, SUMO was closed and
    /// its input removed; nothing was written.
    #[error("interrupted by {} at step {step}; nothing written", crate::io::interrupt::name(*.signal))]
    Interrupted {
        /// Steps completed when the signal was seen (the index of the step not run).
        step: u32,
        /// The signal's number (2 for `SIGINT`, 15 for `SIGTERM`).
        signal: i32,
    },
    /// The user's SUMO configuration cannot be run.
    #[error(transparent)]
    Scenario(#[from] SumoConfigError),
    /// SUMO's own output of the episode could not be read back.
    #[error("{0}")]
    Output(String),
    /// A caller's own loop asked for a step out of order (before the start, past the last).
    #[error("{0}")]
    OutOfOrder(String),
    /// A failure with SUMO's own reason: libsumo reports only "Process Error", the reason goes
    /// to SUMO's (captured) console.
    #[error("{cause}; SUMO said: {said}")]
    Sumo {
        /// The failure as libsumo reported it.
        cause: Box<EpisodeError>,
        /// SUMO's `Error:` messages, on one line ([`sumo_errors`]).
        said: String,
        /// All SUMO printed, for `sumo.log`.
        log: String,
    },
}

impl EpisodeError {
    /// This error with SUMO's error messages from `log` (what it printed meanwhile), if any.
    pub fn with_sumo_log(self, log: String) -> EpisodeError {
        match sumo_errors(&log) {
            Some(said) => EpisodeError::Sumo {
                cause: Box::new(self),
                said,
                log,
            },
            None => self,
        }
    }

    /// What SUMO printed before the failure, when it said why.
    pub fn sumo_log(&self) -> Option<&str> {
        match self {
            EpisodeError::Sumo { log, .. } => Some(log),
            _ => None,
        }
    }
}

/// SUMO's `Error:` messages in `log`, with their indented continuation lines ("In file …"), on
/// one line.
pub fn sumo_errors(log: &str) -> Option<String> {
    let mut parts: Vec<&str> = Vec::new();
    let mut in_error = false;
    for line in log.lines() {
        if let Some(message) = line.strip_prefix("Error: ") {
            parts.push(message.trim());
            in_error = true;
        } else if in_error && line.starts_with(' ') && !line.trim().is_empty() {
            parts.push(line.trim());
        } else {
            in_error = false;
        }
    }
    (!parts.is_empty()).then(|| parts.join(" "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sumo_errors_are_read_off_sumo_s_console() {
        let log = "Warning: something\nError: invalid document structure\n In file 'x.net.xml'\n \
                   At line/column 2/1.\n\nQuitting (on error).\n";
        assert_eq!(
            sumo_errors(log).unwrap(),
            "invalid document structure In file 'x.net.xml' At line/column 2/1."
        );
        assert_eq!(sumo_errors("Warning: only this\n"), None);
    }
}
