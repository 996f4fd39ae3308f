//! One episode and what it needs: one entry point for either traffic ([`ran`]), the demand, SUMO's entry gate, the ramp HDVs' merge rule, the
//! runner that keeps SUMO and a controller in lock-step, the metrics and the CSV files it writes,
//! the side-by-side benchmark, the trace of what the planner saw and did (`trace.jsonl`), and
//! the trajectories of every vehicle (`trajectories.csv`).
//!
//! The runner composes parts, each in its own file: the `ledger` (who is where: every
//! vehicle's record, departures, arrivals, collisions), the `step_times` (how long SUMO and
//! the planner took) and the `recording` of trajectory rows. What can go wrong is in
//! [`error`]; what a caller may watch through is the [`Observer`] of [`observer`].

pub mod bench;
pub mod cells;
pub mod collisions;
pub mod control;
pub mod demand;
pub mod entry;
pub mod error;
pub mod gui;
mod ledger;
pub mod merge_rule;
pub mod metrics;
pub mod models_used;
pub mod observer;
pub mod output;
pub mod ran;
mod recording;
pub mod rows;
pub mod runner;
mod step_times;
pub mod summary;
pub mod sumocfg;
pub mod trace;
pub mod traffic;
pub mod trajectories;

pub use error::{sumo_errors, EpisodeError};
pub use observer::{NoObserver, Observer};
pub use ran::Ran;
pub use runner::{run, run_observed, run_with_demand, Driver, EpisodeResult};
