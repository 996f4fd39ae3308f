//! Offline work on the HDV models: the learned predictor b_θ (collecting lane-change data from
//! SUMO episodes, the data set, training with Adam and the network's backward pass, evaluation,
//! the predictor's benchmark) and the longitudinal calibration against SUMO's drivers
//! ([`longitudinal`]). It runs whole episodes, so it sits above the episode runner; the runtime
//! predictor it produces is [`crate::predict`].

pub mod adam;
pub mod bench;
pub mod collect;
pub mod commands;
pub mod dataset;
pub mod eval;
pub mod fit;
pub mod gcn;
pub mod logistic;
pub mod longitudinal;
pub mod ppo;
pub mod provenance;
pub mod training_loop;
