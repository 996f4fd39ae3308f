//! Courtesy toward a ramp HDV: a main-road CAV in the lane a ramp HDV ahead of it merges into
//! leaves it the gap SUMO's lane-change model asks of a merger's new follower (the follower's
//! own `minGap` and `tau` at the merger's speed: the CAV type's), as SUMO's own drivers do for it
//! (LC2013's cooperation), where it can by braking comfortably.

use crate::model::scene::Following;
use crate::model::trajectory::{Pose, Trajectory};
use crate::planner::mastar::{Mastar, Request};

/// A ramp HDV on an auxiliary lane ahead of a main-road CAV, merging into the CAV's lane: what
/// the request of that CAV carries of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Merger {
    /// Centre along the road (m).
    pub s: f64,
    /// Speed (m/s).
    pub speed: f64,
    /// Length (m).
    pub length: f64,
    /// Width (m).
    pub width: f64,
    /// Where its lane ends (m): it stops there at the latest.
    pub lane_end: f64,
}

impl Mastar {
    /// The merger of `req` as a vehicle in the CAV's own lane, its rear moved back so that the
    /// safety rule's gap behind it is the one SUMO's lane-change model asks of its new follower;
    /// `None` with courtesy off, without a merger, or where the CAV could not leave that gap
    /// braking at the planner's comfortable deceleration down to the merger's speed.
    pub(super) fn courtesy_leader(&self, req: &Request) -> Option<Trajectory> {
        let m = req.merger.filter(|_| self.courtesy && !req.must_merge)?;
        let front = req.start.pos.x + 0.5 * req.length;
        let gap = (m.s - 0.5 * m.length) - front;
        let v = req.start.speed;
        let closing = (v - m.speed).max(0.0);
        let slack = closing * closing / (2.0 * self.library.decel);
        // SUMO asks the follower's own `minGap` and `tau`: the CAV's type's, or SUMO's defaults.
        let following = req.limits.following.unwrap_or(Following::SUMO_DEFAULT);
        let wanted = following.gap_at(m.speed);
        if gap - slack < wanted {
            return None;
        }
        let own_gap = self.rule.safe_gap + self.rule.reaction_time * m.speed;
        let extra = (wanted - own_gap).max(0.0);
        let dt = self.library.dt;
        let y = self.lane_y(req.lane);
        let stop = m.lane_end - 0.5 * m.length;
        let poses = (0..=self.check_horizon())
            .map(|k| {
                let s = (m.s + m.speed * dt * k as f64).min(stop.max(m.s));
                let speed = if s >= stop { 0.0 } else { m.speed };
                Pose {
                    s: s - 0.5 * extra,
                    y,
                    heading: 0.0,
                    speed,
                }
            })
            .collect();
        Some(Trajectory {
            poses,
            length: m.length + extra,
            width: m.width,
            brake: None,
            committed: false,
        })
    }
}
