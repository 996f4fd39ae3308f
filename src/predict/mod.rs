//! Predicting what HDVs (and, for BK-M-A*, other CAVs) will do over the planning horizon.
//!
//! A [`Predictor`] turns a scene vehicle into a trajectory, optionally conditioned on the planned
//! trajectories of higher-priority CAVs (BK-PBS); the learned model of `b_θ` plugs into the same
//! trait. [`ConstantSpeed`] is the first implementation.
//!
//! This folder is the runtime predictor only: what planning needs each step. Collecting data,
//! training and evaluating b_θ run whole episodes, so they sit above the episode runner, in
//! [`crate::train`].

mod constant;

// The learned lane-change model b_θ: features, network shape, inference, model file, predictor.
pub mod blocked;
pub mod calibration;
pub mod features;
pub mod gcn;
pub mod infer;
pub mod learned;
pub mod logistic;
pub mod longitudinal;
pub mod model_file;
pub mod training_record;

pub use constant::ConstantSpeed;
pub use learned::{configured, Learned, PredictorError};
pub use model_file::{LaneChangeModel, ModelError};

use crate::model::scene::Scene;
use crate::model::trajectory::Trajectory;

/// A model of other vehicles' motion.
pub trait Predictor: Send + Sync {
    /// The name shown in results.
    fn name(&self) -> &'static str;

    /// Predicted trajectory of `scene.vehicles[i]` over `horizon` steps (step 0 = now), given
    /// the planned trajectories of the CAVs that have priority over it (empty: unconditioned).
    fn predict(
        &self,
        scene: &Scene,
        i: usize,
        conditioned_on: &[&Trajectory],
        horizon: usize,
    ) -> Trajectory;
}
