//! The start guard: a check every first move (a lane-change start, or the first step's speed in
//! lane) must pass before M-A* may plan it.
//!
//! It is a callback the planner layer defines so that the controller layer's safety shield can
//! veto a start without the planner importing upward: the controllers implement [`StartGuard`]
//! with the shield's rule and hand it down in each [`Request`](crate::planner::mastar::Request).
//! It exists because other CAVs are planned against a CAV's plan, so the plan must be what will
//! be executed: no plan may count on a start the shield would withdraw. Asked of lane-change
//! starts only, the shield still overrode a quarter of bk-pbs's steps in lane (258 overrides
//! per 1500-step episode, mostly main-road CAVs in lane 1 beside ramp HDVs the learned
//! predictor did not expect to merge yet); asked of every first move, 69, at the same delay
//! (system delay paired over 24 episodes: +0.29 s, 95 % interval [−0.13, +0.71]: none seen).

use crate::model::scene::Scene;

/// A check every first move must pass before the search may plan it. The controllers
/// pass the safety shield's, so that no plan counts on a start the shield would withdraw: other
/// CAVs are planned against that plan, so it must be what will be executed.
pub trait StartGuard: Sync {
    /// Whether scene vehicle `agent` may start a change of `lane_offset` lanes (0: keep its
    /// lane) that has it at forward speed `first_speed` after the first step.
    fn admits(&self, scene: &Scene, agent: usize, lane_offset: i32, first_speed: f64) -> bool;
}

/// A [`StartGuard`] bound to one CAV of one scene.
#[derive(Clone, Copy)]
pub struct Guard<'a> {
    /// The check (the controllers' safety shield).
    pub check: &'a dyn StartGuard,
    /// The scene the start is judged in.
    pub scene: &'a Scene,
    /// Scene index of the CAV.
    pub agent: usize,
}

impl Guard<'_> {
    /// Whether the bound CAV may start a change of `lane_offset` lanes that has it at forward
    /// speed `first_speed` after the first step.
    #[inline]
    pub fn admits(&self, lane_offset: i32, first_speed: f64) -> bool {
        self.check
            .admits(self.scene, self.agent, lane_offset, first_speed)
    }
}

impl std::fmt::Debug for Guard<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Guard(agent {})", self.agent)
    }
}
