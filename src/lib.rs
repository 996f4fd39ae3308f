//! bkpbs: coordinating connected automated vehicles (CAVs) among human-driven vehicles (HDVs) at
//! a highway on-ramp merge, co-simulated in-process with SUMO.
//!
//! # The front door
//! The names a library user needs are re-exported here: the settings ([`Config`]), the planners
//! ([`PlannerKind`], each a [`Controller`] that turns a [`Scene`] into one [`Command`] per CAV),
//! the HDV [`Predictor`]s, and one episode of SUMO and a controller in lock-step
//! ([`run_episode`], giving an [`EpisodeResult`] whose [`Summary`] is the `episode.csv` row).
//! Campaigns (grids of episodes over worker processes) start at [`campaign::run`].
//!
//! ```
//! use bkpbs::{run_episode, Config, PlannerKind};
//!
//! let mut config = Config::default(); // the paper's merge, α 0.5, λ 3000, 400 steps of 0.2 s
//! config.scenario.seed = 7;
//! config.scenario.steps = 100;
//! let result = run_episode(&config, PlannerKind::BkPbs.name())?;
//! let s = &result.summary;
//! let delay = s.travel().mean_delay_s; // the paper demand's part of the summary
//! println!("arrived {} of {}, mean delay {delay:?} s", s.arrived, s.inserted);
//! assert!(s.inserted > 0 && s.arrived <= s.inserted);
//! let out = tempfile::tempdir()?;
//! result.write(out.path())?; // episode.csv, vehicles.csv, collisions.csv, timing.csv
//! assert!(out.path().join("episode.csv").is_file());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//! (An episode starts SUMO in-process: one simulation per process at a time.)
//!
//! # The layers
//! The library does the work; the `bkpbs` binary only parses arguments and dispatches.
//! The folders are layers, lowest first; each imports only from the ones above it in this list:
//! [`io`] and [`config`] (plain files and settings), [`model`] (the road frame), [`sumo`]
//! (libsumo and the frame <-> SUMO translation), [`predict`] (HDV prediction), [`planner`]
//! (M-A*, PBS), [`policy`] (the RL-PPO policy), [`controller`] (one maneuver per CAV),
//! [`episode`] (SUMO and a controller in lock-step), [`train`] (offline training of the
//! predictor and the policy), [`campaign`] (grids of episodes), [`report`] (tables and
//! figures). The guide (`docs/`) tells the algorithm, the metrics and the files.

#![warn(missing_docs)]

pub use config::{Config, ConfigError};
pub use controller::{Command, Controller, LaneChange, Maneuver, PlannerKind};
pub use episode::summary::Summary;
pub use episode::{run as run_episode, EpisodeError, EpisodeResult, Observer};
pub use model::road::Road;
pub use model::scene::{Kind, Scene, VehicleState};
pub use predict::{ConstantSpeed, Learned, Predictor};

pub mod io;

pub mod config;

pub mod model;

pub mod sumo;

pub mod predict;

pub mod planner;

pub mod policy;

pub mod controller;

pub mod episode;

pub mod train;

pub mod campaign;

pub mod report;
