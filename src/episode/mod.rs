//! One episode and what it needs: the demand, SUMO's entry gate, the ramp HDVs' merge rule, the
//! runner that keeps SUMO and a controller in lock-step, the metrics and the CSV files it writes,
//! the side-by-side benchmark, the trace of what the planner saw and did (`trace.jsonl`), and
//! the trajectories of every vehicle (`trajectories.csv`).

pub mod bench;
pub mod demand;
pub mod entry;
pub mod gui;
pub mod merge_rule;
pub mod metrics;
pub mod output;
pub mod record;
pub mod runner;
pub mod trace;
pub mod trajectories;

pub use runner::{
    run, run_observed, run_with_demand, Driver, EpisodeError, EpisodeResult, NoObserver, Observer,
};
