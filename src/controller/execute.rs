//! Turning planner output into the maneuvers SUMO executes: shared by the search-based
//! controllers (`bk-mastar`, `bk-pbs`), so both execute a plan, and the lack of one, alike.

use super::{CavBelief, LaneChange, Maneuver, PlanStats, Source};
use crate::model::scene::Scene;
use crate::model::scene::VehicleState;
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::{FirstMove, NoPlan, Phase, Plan};

/// Counts one M-A* call and the nodes it expanded, whether or not it found a plan.
pub fn count_search(stats: &mut PlanStats, result: Result<&Plan, &NoPlan>) {
    stats.searches += 1;
    stats.nodes_expanded += match result {
        Ok(p) => p.expanded,
        Err(e) => e.expanded,
    } as u64;
}

/// What a CAV does next: its plan's first move (counting a phase-2 plan), or, without a plan,
/// braking at `emergency_decel` (counted as a fallback). Also returns the target lane of a lane
/// change the maneuver starts, which the controller must remember. `lane` is the lane the plan
/// started in.
pub fn maneuver_for(
    plan: Option<&Plan>,
    v: &VehicleState,
    lane: i32,
    emergency_decel: f64,
    dt: f64,
    stats: &mut PlanStats,
) -> (Maneuver, Option<i32>) {
    match plan {
        Some(plan) => {
            stats.phase2_plans += u64::from(plan.phase == Phase::Fallback);
            first_move(plan, lane)
        }
        None => {
            stats.fallbacks += 1;
            (emergency_brake(v, emergency_decel, dt), None)
        }
    }
}

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

/// The source a trace reports for a CAV's maneuver: braking without a plan, the continuation of
/// a lane change under way, else where the plan came from.
pub fn source_of(planned: Source, has_plan: bool, changing_lanes: bool) -> Source {
    match (has_plan, changing_lanes) {
        (false, _) => Source::Brake,
        (true, true) => Source::Continuation,
        (true, false) => planned,
    }
}

/// Range (m, along the road) within which a trace lists the trajectories a CAV was checked
/// against.
pub const BELIEF_RANGE: f64 = 60.0;

/// What the planner believed about CAV `i`: its planned trajectory and the trajectories of the
/// vehicles within [`BELIEF_RANGE`] of it.
pub fn belief<'a>(
    scene: &Scene,
    i: usize,
    planned: Option<&Trajectory>,
    others: impl Iterator<Item = (usize, &'a Trajectory)>,
) -> CavBelief {
    let s = scene.vehicles[i].s;
    CavBelief {
        vehicle: i,
        planned: planned.cloned(),
        others: others
            .filter(|&(j, _)| j != i && (scene.vehicles[j].s - s).abs() <= BELIEF_RANGE)
            .map(|(j, t)| (j, t.clone()))
            .collect(),
    }
}
