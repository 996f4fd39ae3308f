//! One episode and what it needs: the demand, SUMO's entry gate, the ramp HDVs' merge rule, the
//! runner that keeps SUMO and a controller in lock-step, the metrics and the CSV files it writes,
//! and the side-by-side benchmark.

pub mod bench;
pub mod demand;
pub mod entry;
pub mod merge_rule;
pub mod metrics;
pub mod output;
pub mod runner;

pub use runner::{
    run, run_observed, run_with_demand, Driver, EpisodeError, EpisodeResult, NoObserver, Observer,
};
