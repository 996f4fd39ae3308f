//! Courtesy toward a ramp HDV: a main-road CAV in the lane a ramp HDV ahead of it merges into
//! leaves it the gap SUMO's lane-change model asks of a merger's new follower, as SUMO's own
//! drivers do for it (LC2013's cooperation), where it can by braking comfortably.

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

/// The gap SUMO's lane-change model asks of a merger's new follower at equal speeds: the
/// follower's minGap and its time headway `tau` (SUMO's defaults: 2.5 m, 1 s).
const SUMO_MIN_GAP: f64 = 2.5;
const SUMO_TAU: f64 = 1.0;

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
        let wanted = SUMO_MIN_GAP + SUMO_TAU * m.speed;
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
