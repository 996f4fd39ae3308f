//! Turning planner output into the maneuvers SUMO executes: shared by the search-based
//! controllers (`bk-mastar`, `bk-pbs`).

use super::{LaneChange, Maneuver};
use crate::model::scene::VehicleState;
use crate::planner::mastar::{FirstMove, Plan};

/// The maneuver that executes a plan's first move, and the target lane of a lane change it
/// starts (which the controller must remember, to continue the change in the next steps).
/// `lane` is the lane the plan started in.
pub fn first_move(plan: &Plan, lane: i32) -> (Maneuver, Option<i32>) {
    let (lane_change, target) = match plan.first {
        FirstMove::Start(p) if p.is_lane_change() => {
            let dir = if p.lane_offset() > 0 {
                LaneChange::Left
            } else {
                LaneChange::Right
            };
            (Some(dir), Some(lane + p.lane_offset()))
        }
        _ => (None, None),
    };
    let maneuver = Maneuver {
        speed: plan.next_speed(),
        lane_change,
    };
    (maneuver, target)
}

/// Braking at `decel` for one step of `dt`: the answer when no plan exists.
pub fn emergency_brake(v: &VehicleState, decel: f64, dt: f64) -> Maneuver {
    Maneuver {
        speed: (v.speed - decel * dt).max(0.0),
        lane_change: None,
    }
}
