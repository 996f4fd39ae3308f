//! bkpbs: coordinating connected automated vehicles (CAVs) among human-driven vehicles (HDVs) at
//! a highway on-ramp merge, co-simulated in-process with SUMO.
//!
//! The library does the work; the `bkpbs` binary only parses arguments and dispatches.
//! The folders are layers, lowest first; each imports only from the ones above it in this list:
//! [`io`] and [`config`] (plain files and settings), [`model`] (the road frame), [`sumo`] (libsumo
//! and the frame <-> SUMO translation), [`predict`] (HDV prediction), [`planner`] (M-A*, PBS),
//! [`policy`] (the RL-PPO policy), [`controller`] (one maneuver per CAV), [`episode`] (SUMO and a controller in lock-step),
//! [`train`] (offline training of the predictor), [`campaign`] (grids of episodes), [`report`]
//! (tables and figures). Start at [`episode::run`].

#![warn(missing_docs)]

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
