//! Lane changes a planner commanded and SUMO is still executing.
//!
//! CAVs change lanes only when told (lane-change mode 0), so the planner knows exactly which
//! changes are under way: it must continue them (SUMO is moving the vehicle sideways), not
//! re-command or cancel them.

use std::collections::HashMap;
use std::sync::Arc;

use crate::model::kinematics::BicycleState;
use crate::model::math::Point;
use crate::model::road::MERGE_LANE;
use crate::model::scene::{Origin, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::{Mastar, NoPlan, OngoingLaneChange, Plan, Request};
use crate::planner::pbs::RequestFor;

/// Commanded lane changes: vehicle → (time the change ends, target lane).
#[derive(Debug, Clone, Default)]
pub struct LaneChanges {
    under_way: HashMap<Arc<str>, (f64, i32)>,
}

impl LaneChanges {
    /// Records a change of `id` to `target` starting at `now` and lasting `duration` seconds.
    pub fn start(&mut self, id: &Arc<str>, now: f64, duration: f64, target: i32) {
        self.under_way.insert(id.clone(), (now + duration, target));
    }

    /// Forgets the change of `id`, which was withdrawn before SUMO started it.
    pub fn cancel(&mut self, id: &str) {
        self.under_way.remove(id);
    }

    /// Forgets the changes that have ended by `now`.
    pub fn forget_finished(&mut self, now: f64) {
        self.under_way.retain(|_, (end, _)| *end > now + 1e-6);
    }

    /// The change of `id` still under way at `now`, in planner terms.
    pub fn ongoing(&self, id: &str, now: f64, dt: f64) -> Option<OngoingLaneChange> {
        let (end, target) = *self.under_way.get(id)?;
        let steps_left = ((end - now) / dt).round();
        (steps_left >= 1.0).then_some(OngoingLaneChange {
            target_lane: target,
            steps_left: steps_left as usize,
        })
    }

    /// The lane scene vehicle `i` plans from: the target of its change under way, else its lane.
    pub fn planning_lane(&self, scene: &Scene, i: usize, dt: f64) -> i32 {
        let v = &scene.vehicles[i];
        self.ongoing(&v.id, scene.time, dt)
            .map_or(v.lane, |o| o.target_lane)
    }

    /// The M-A* request of scene vehicle `i` among `obstacles`.
    pub fn request<'a>(
        &self,
        scene: &Scene,
        i: usize,
        dt: f64,
        obstacles: &'a [&'a Trajectory],
    ) -> Request<'a> {
        let v = &scene.vehicles[i];
        let w = scene.road.lane_width;
        let ongoing = self.ongoing(&v.id, scene.time, dt);
        let lane = ongoing.map_or(v.lane, |o| o.target_lane);
        let cos = v.heading.cos().max(0.5);
        Request {
            start: BicycleState {
                pos: Point::new(v.s, v.lane as f64 * w + v.lateral),
                heading: v.heading,
                speed: v.speed / cos,
            },
            lane,
            ongoing,
            must_merge: v.origin == Origin::Ramp && lane == MERGE_LANE,
            length: v.length,
            width: v.width,
            obstacles,
        }
    }
}

/// How BK-PBS plans each agent of a scene: the M-A* request of its current state, continuing
/// the lane change it has under way.
pub struct SceneRequests<'a> {
    pub scene: &'a Scene,
    pub lane_changes: &'a LaneChanges,
    pub dt: f64,
}

impl RequestFor for SceneRequests<'_> {
    fn plan(
        &self,
        planner: &Mastar,
        agent: usize,
        obstacles: &[&Trajectory],
    ) -> Result<Plan, NoPlan> {
        planner.plan(
            &self
                .lane_changes
                .request(self.scene, agent, self.dt, obstacles),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_is_continued_until_it_ends() {
        let mut lc = LaneChanges::default();
        let id: Arc<str> = Arc::from("cav.1");
        lc.start(&id, 10.0, 1.0, 2);
        let o = lc.ongoing("cav.1", 10.2, 0.2).unwrap();
        assert_eq!((o.target_lane, o.steps_left), (2, 4));
        assert!(lc.ongoing("cav.1", 11.0, 0.2).is_none());
        lc.forget_finished(11.0);
        assert!(lc.under_way.is_empty());
    }
}
