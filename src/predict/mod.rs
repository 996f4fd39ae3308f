//! Predicting what HDVs (and, for BK-M-A*, other CAVs) will do over the planning horizon.
//!
//! A [`Predictor`] turns a scene vehicle into a trajectory, optionally conditioned on the planned
//! trajectories of higher-priority CAVs (BK-PBS); the learned model of `b_θ` plugs into the same
//! trait. [`ConstantSpeed`] is the first implementation.

mod constant;

pub use constant::ConstantSpeed;

use crate::scene::Scene;
use crate::trajectory::Trajectory;

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
