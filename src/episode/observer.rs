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

/// One observer per merge region, each made by `new` from its region's number as the region is
/// first seen: for a recorder that reads the scenes it is shown as those of one road, which on
/// a user's scenario of several regions must see each region's apart. The paper's merge is
/// region 0, so there it is the one observer `new(0)`. It sees scenes only.
pub struct PerRegion<O, F> {
    new: F,
    regions: Vec<O>,
}

impl<O, F: Fn(usize) -> O> PerRegion<O, F> {
    /// No region seen yet; `new(k)` makes region `k`'s observer.
    pub fn new(new: F) -> Self {
        PerRegion {
            new,
            regions: Vec::new(),
        }
    }

    /// The regions' observers so far, in region order.
    pub fn regions(&self) -> &[O] {
        &self.regions
    }

    /// The regions' observers in region order; region 0's (made now if no scene came) at least.
    pub fn into_regions(mut self) -> Vec<O> {
        if self.regions.is_empty() {
            self.regions.push((self.new)(0));
        }
        self.regions
    }
}

impl<O: Observer, F: Fn(usize) -> O> Observer for PerRegion<O, F> {
    fn observe(&mut self, scene: &Scene) {
        self.observe_region(0, scene);
    }

    fn observe_region(&mut self, region: usize, scene: &Scene) {
        while self.regions.len() <= region {
            let next = (self.new)(self.regions.len());
            self.regions.push(next);
        }
        self.regions[region].observe(scene);
    }
}

/// An observer that looks away.
pub struct NoObserver;

impl Observer for NoObserver {
    fn observe(&mut self, _scene: &Scene) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Region `.0`'s observer, counting the scenes it saw.
    struct Count(usize, usize);

    impl Observer for Count {
        fn observe(&mut self, _scene: &Scene) {
            self.1 += 1;
        }
    }

    #[test]
    fn each_region_has_its_own_observer_made_as_the_region_is_first_seen() {
        let none = PerRegion::new(|k| Count(k, 0)).into_regions();
        assert_eq!(
            none.iter().map(|c| (c.0, c.1)).collect::<Vec<_>>(),
            [(0, 0)]
        );
        let mut p = PerRegion::new(|k| Count(k, 0));
        let scene = Scene::on_paper_road(0.0, Vec::new());
        p.observe_region(2, &scene);
        p.observe(&scene);
        p.observe_region(2, &scene);
        let seen: Vec<(usize, usize)> = p.regions().iter().map(|c| (c.0, c.1)).collect();
        assert_eq!(seen, [(0, 1), (1, 0), (2, 2)]);
    }
}
