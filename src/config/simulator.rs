//! How SUMO runs an episode and what an episode writes besides its results.
//!
//! Apart from the scenario because it says how the simulator is run rather than what it
//! simulates: the same scenario runs in-process or in sumo-gui, with or without trajectories
//! written.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// How long one SUMO call (start, a step, close) may take before the watchdog ends the run,
/// unless `sumo.stall_timeout_s` says otherwise: far beyond any step, or the load of a large
/// network, seen here.
pub const DEFAULT_STALL_LIMIT: std::time::Duration = std::time::Duration::from_secs(120);

/// How SUMO is run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SumoSettings {
    /// Let SUMO print its warnings and step log.
    pub verbose: bool,
    /// Additional SUMO files (detectors, extra vehicles, …) loaded with the vehicle types.
    pub additional_files: Vec<PathBuf>,
    /// Extra SUMO command-line options, appended last.
    pub extra_args: Vec<String>,
    /// Run the episode in SUMO's own sumo-gui (through libtraci) instead of in-process
    /// libsumo; the results are the same. Needs a display.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub gui: bool,
    /// Pause of sumo-gui per step (ms); default: real time (one step length).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gui_delay_ms: Option<f64>,
    /// How long one SUMO call (its start, one step) may take before the run is ended as stuck
    /// (s); default [`DEFAULT_STALL_LIMIT`]. A guard against a SUMO that loops
    /// inside a call, where nothing else could stop it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stall_timeout_s: Option<f64>,
}

impl SumoSettings {
    /// The bound on one SUMO call (checked by the configuration's validation).
    pub fn stall_limit(&self) -> std::time::Duration {
        self.stall_timeout_s
            .map_or(DEFAULT_STALL_LIMIT, std::time::Duration::from_secs_f64)
    }
}

/// Optional outputs of an episode. A campaign does not record them in its settings: they do
/// not change results, so runs with and without them may share a directory.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSettings {
    /// One row per vehicle and step (columns in docs/src/metrics.md).
    pub trajectories: TrajectoryFormat,
    /// The episode's progress on stderr (`bkpbs episode`: a bar on a terminal, a line a
    /// minute elsewhere); never in a file, nor in a campaign's workers, whose campaign shows
    /// its own.
    #[serde(skip)]
    pub progress: bool,
    /// `trace.jsonl` of every planning round (`bkpbs episode --trace`): on a scenario of your
    /// own each region's beside its trajectories; never in a file, nor in a campaign.
    #[serde(skip)]
    pub trace: bool,
}

/// Whether and how an episode writes its trajectories.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum TrajectoryFormat {
    /// None written.
    #[default]
    None,
    /// `trajectories.csv`: SUMO's and the road frame's view, and the maneuvers sent.
    Csv,
    /// `trajectories.fcd.xml`: SUMO's floating-car-data format.
    Fcd,
}
