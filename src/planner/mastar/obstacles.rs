//! What an M-A* search keeps clear of: other vehicles, whose predicted trajectories are dynamic
//! obstacles checked body against body under the safety rule at every step, and the road, a
//! static obstacle (its lanes, the acceleration lane's end, the barrier between ramp and main
//! road before the merge zone).
//!
//! Both checks run at every step of every primitive a search rolls out, so they live apart from
//! the search that calls them and the obstacles' bodies are worked out once per call.

use crate::model::kinematics::BicycleState;
use crate::model::road::MergeZone;
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::{pose, Mastar, Request};
use crate::planner::safety::Body;

/// The obstacles of one M-A* call, with their bodies at every step a search checks, built once:
/// every node checks every obstacle at every step of every primitive it rolls out, so reading a
/// pose (and its forward speed) off a trajectory each time would cost more than the checks.
///
/// A search checks no step past the check horizon T + one lane change: a node at T ends its
/// plan, a move from a node before T spans at most a lane change, and a plan's tail is checked
/// up to the check horizon.
pub(super) struct Obstacles {
    /// `by_step[k][o]`: obstacle `o` at step `k`, for k up to the check horizon.
    by_step: Vec<Vec<Body>>,
}

impl Obstacles {
    /// The trajectories of `all` that start within [`OBSTACLE_RANGE`] of `s` along the road,
    /// with their bodies up to `check_horizon`.
    pub(super) fn near(all: &[&Trajectory], s: f64, check_horizon: usize, dt: f64) -> Self {
        let near: Vec<&Trajectory> = all
            .iter()
            .copied()
            .filter(|t| (t.poses[0].s - s).abs() < OBSTACLE_RANGE)
            .collect();
        Obstacles::new(&near, check_horizon, dt)
    }

    /// `trajectories` with their bodies at every step up to `check_horizon`.
    fn new(trajectories: &[&Trajectory], check_horizon: usize, dt: f64) -> Self {
        let by_step = (0..=check_horizon)
            .map(|k| trajectories.iter().map(|t| Body::of(t, k, dt)).collect())
            .collect();
        Obstacles { by_step }
    }

    /// The obstacles' bodies at `step`.
    #[inline]
    pub(super) fn at(&self, step: usize) -> &[Body] {
        &self.by_step[step]
    }
}

/// Other vehicles farther than this along the road from the CAV now are left out of its search
/// (m). Every obstacle kept costs a safety check at every step of every rolled-out primitive, and
/// one this far away would have to close 80 m on the CAV within the 4 s checked (15 + 5 steps of
/// 0.2 s) just to come within the safety rule's [`REACH`](crate::planner::safety::REACH) of
/// 120 m, beyond which it never counts. A practical range, not a proven bound: changing it can
/// change plans.
const OBSTACLE_RANGE: f64 = 200.0;

/// How far before a weaving section's end a ramp CAV on its lane plans to be able to stop (m),
/// while it still can: the room a vehicle bound for the off-ramp needs to move into the lane in
/// front of it. Planned to stop right at the end, a ramp CAV once stood there side by side
/// with a CAV bound for the exit (left to SUMO), each needing the other's lane, until SUMO
/// teleported one (the cloverleaf, seed 1009, `tests/lane_roles.rs`). A car's length and a
/// half and the gap SUMO's drivers accept in front; a practical value, not a proven bound.
pub(super) const WEAVING_ROOM: f64 = 20.0;

/// The road and the other vehicles, as a search checks them.
impl Mastar {
    /// Whether the (un-inflated) body stays on drivable road.
    #[inline]
    pub(super) fn on_road(&self, st: &BicycleState, req: &Request) -> bool {
        let w = self.road.lane_width;
        let (sin, cos) = st.heading.sin_cos();
        let half_across = 0.5 * req.width * cos.abs() + 0.5 * req.length * sin.abs();
        let half_along = 0.5 * req.length * cos.abs() + 0.5 * req.width * sin.abs();
        let (y_lo, y_hi) = (st.pos.y - half_across, st.pos.y + half_across);
        let (s_lo, s_hi) = (st.pos.x - half_along, st.pos.x + half_along);
        const EPS: f64 = 0.05;
        let (bottom, top) = (self.road.bottom_lane(), self.road.top_lane());
        let edge = |lane: i32, side: f64| (f64::from(lane) + 0.5 * side) * w;
        if y_lo < edge(bottom, -1.0) - EPS || y_hi > edge(top, 1.0) + EPS {
            return false;
        }
        let stop = self.stopping_distance(st.speed);
        let auxiliary = (bottom..=top).filter(|&l| self.road.is_auxiliary(l));
        auxiliary.into_iter().all(|lane| {
            // The lane's line towards the carriageway and its outer one; the body overlaps the
            // lane, and crosses its line towards the carriageway, or not.
            let right = lane < self.road.toward_main(lane);
            let (overlaps, crossing) = if right {
                let (near, far) = (edge(lane, 1.0), edge(lane, -1.0));
                (y_lo < near - EPS && y_hi > far + EPS, y_hi > near + EPS)
            } else {
                let (near, far) = (edge(lane, -1.0), edge(lane, 1.0));
                (y_hi > near + EPS && y_lo < far - EPS, y_lo < near - EPS)
            };
            !overlaps || self.fits_auxiliary_lane(lane, (s_lo, s_hi), crossing, stop, req)
        })
    }

    /// Whether a body spanning `s_lo..s_hi` on auxiliary lane `lane`, `crossing` its line
    /// towards the carriageway or not, needing `stop` metres to stop, may be there: only a ramp
    /// vehicle, only until the lane's zone ends, crossing only beside the acceleration lane.
    fn fits_auxiliary_lane(
        &self,
        lane: i32,
        (s_lo, s_hi): (f64, f64),
        crossing: bool,
        stop: f64,
        req: &Request,
    ) -> bool {
        let Some(zone) = self.road.zone_on(lane, s_lo) else {
            return false;
        };
        if !req.must_merge || s_hi > zone.end {
            return false;
        }
        if crossing && s_lo < zone.start {
            return false;
        }
        // Fully in the lane, the CAV must still be able to stop before its end, or the plan
        // could leave it in a state from which the crash is certain.
        crossing || stop <= zone.end - self.weaving_room(zone, req) - s_hi + 1e-9
    }

    /// The room a ramp CAV leaves before the end of `zone`'s lane when it plans to stop:
    /// [`WEAVING_ROOM`] on a weaving section's lane if it can still stop that far before the
    /// end from where it starts, none otherwise (then it may stop at the end, as on any lane).
    fn weaving_room(&self, zone: &MergeZone, req: &Request) -> f64 {
        if !zone.weaving {
            return 0.0;
        }
        let start = &req.start;
        let front = start.pos.x + 0.5 * req.length;
        let stop = self.stopping_distance(start.speed);
        if front + stop + WEAVING_ROOM <= zone.end {
            WEAVING_ROOM
        } else {
            0.0
        }
    }

    /// Metres the CAV needs to stop from `speed` at the emergency deceleration.
    fn stopping_distance(&self, speed: f64) -> f64 {
        speed * speed / (2.0 * self.library.emergency_decel)
    }

    /// Whether the CAV at `st` at `step` is clear of every obstacle (see [`SafetyRule`](crate::planner::safety::SafetyRule)).
    /// `me_now` is the CAV's body at the start.
    #[inline]
    pub(super) fn safe(
        &self,
        st: &BicycleState,
        step: usize,
        me_now: &Body,
        obstacles: &Obstacles,
    ) -> bool {
        let me = Body::new(pose(st), me_now.length, me_now.width, None);
        let t = step as f64 * self.library.dt;
        obstacles
            .at(step)
            .iter()
            .zip(obstacles.at(0))
            .all(|(other, other_now)| self.rule.clear(&me, me_now, other, other_now, t))
    }
}
