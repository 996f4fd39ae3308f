//! The episode's window for onlookers: an [`Observer`] sees each step's scenes, what the
//! controller decided on it and which vehicles collided, without touching the loop.
//!
//! It exists so that recording data (the predictor's training set, `trace.jsonl`, benchmarks,
//! the RL environment) is a caller's business: the lock-step loop stays one loop, and each
//! recorder is written against this trait alone.

use crate::controller::{Command, Controller};
use crate::model::scene::Scene;

/// Sees the scene of every step, before the controller plans: for recording data (e.g. the
/// predictor's training set) without touching the loop.
pub trait Observer {
    /// Sees the scene of one step, as the controller is about to plan on it.
    fn observe(&mut self, scene: &Scene);

    /// Sees the scene of merge region `region` (numbered from 0 in the episode's order) in one
    /// step: on a user's scenario each region's scene in turn, on the paper's merge its one.
    /// By default the same as [`Observer::observe`].
    fn observe_region(&mut self, _region: usize, scene: &Scene) {
        self.observe(scene);
    }

    /// Sees what the controller decided in the step whose scene was just observed, and what it
    /// believed (when tracing; see [`Controller::set_tracing`]).
    fn planned(&mut self, _scene: &Scene, _commands: &[Command], _controller: &dyn Controller) {}

    /// Hears of each vehicle removed in a collision, in the step it happened (before the
    /// scene of that step is observed).
    fn removed_in_collision(&mut self, _id: &str) {}

    /// Whether [`Observer::planned`] needs the controller's beliefs (turns its tracing on).
    fn wants_beliefs(&self) -> bool {
        false
    }
}

/// An observer the caller keeps, lent to an episode: it is the observer it borrows.
impl<O: Observer + ?Sized> Observer for &mut O {
    fn observe(&mut self, scene: &Scene) {
        (**self).observe(scene);
    }
    fn observe_region(&mut self, region: usize, scene: &Scene) {
        (**self).observe_region(region, scene);
    }
    fn planned(&mut self, scene: &Scene, commands: &[Command], controller: &dyn Controller) {
        (**self).planned(scene, commands, controller);
    }
    fn removed_in_collision(&mut self, id: &str) {
        (**self).removed_in_collision(id);
    }
    fn wants_beliefs(&self) -> bool {
        (**self).wants_beliefs()
    }
}

/// An observer that looks away.
pub struct NoObserver;

impl Observer for NoObserver {
    fn observe(&mut self, _scene: &Scene) {}
}
