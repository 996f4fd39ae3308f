//! bkpbs: coordinating connected automated vehicles (CAVs) among human-driven vehicles (HDVs) at
//! a highway on-ramp merge, co-simulated in-process with SUMO.
//!
//! The library does the work; the `bkpbs` binary only parses arguments and dispatches.
//! Start at [`episode::run`]: it builds the demand ([`demand`]), starts SUMO ([`sumo`]) on the
//! merge network ([`road`]), and lets a [`controller::Controller`] command the CAVs each step,
//! recording [`metrics`].

pub mod bench;
pub mod campaign;
pub mod config;
pub mod controller;
pub mod demand;
pub mod entry;
pub mod episode;
pub mod geometry;
pub mod kinematics;
pub mod mastar;
pub mod math;
pub mod merge_rule;
pub mod metrics;
pub mod output;
pub mod pbs;
pub mod plot;
pub mod predict;
pub mod primitives;
pub mod priority;
pub mod report;
pub mod road;
pub mod safety;
pub mod scene;
pub mod search;
pub mod sumo;
pub mod sumo_files;
pub mod sumo_scene;
pub mod trajectory;
