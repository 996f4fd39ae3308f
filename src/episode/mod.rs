//! One episode and what it needs: one entry point for either traffic ([`ran`]); the one loop
//! that keeps SUMO and the planners in lock-step over a source of traffic ([`lockstep`]), and
//! its planning side ([`planning`]: the merge [`region`]s, each with its scene, controller,
//! trajectories and trace, or a [`round`] over all of them); the paper's generated demand as a
//! source ([`runner`]: demand, SUMO's entry gate, the ramp HDVs' merge rule, the `ledger` of
//! who is where), a user's SUMO scenario as the other ([`sumocfg`]); the metrics and the CSV
//! files an episode writes, the side-by-side benchmark, the trace of what the planner saw and
//! did (`trace.jsonl`), and the trajectories of every vehicle (`trajectories.csv`). What can go
//! wrong is in [`error`]; what a caller may watch through is the [`Observer`] of [`observer`].

pub mod bench;
pub mod cells;
pub mod collisions;
pub mod control;
pub mod demand;
pub mod entry;
pub mod error;
pub mod gui;
mod ledger;
pub mod lockstep;
pub mod merge_rule;
pub mod metrics;
pub mod models_used;
pub mod nose;
pub mod observer;
pub mod output;
pub mod planning;
pub mod ran;
mod recording;
pub mod region;
pub mod round;
pub mod rows;
pub mod runner;
mod step_times;
pub mod summary;
pub mod sumocfg;
pub mod trace;
pub mod traffic;
pub mod trajectories;

pub use error::{sumo_errors, EpisodeError};
pub use observer::{NoObserver, Observer, PerRegion};
pub use ran::Ran;
pub use runner::{run, run_observed, run_with_demand, Driver, EpisodeResult};
