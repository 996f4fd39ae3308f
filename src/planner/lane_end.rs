//! Who goes first at the end of the acceleration lane: the merge order a planning round starts
//! from, so that a ramp CAV held up near the lane end and the main-road CAVs coming up beside
//! it never wait for each other.
//!
//! Left to the search, the two could deadlock: the ramp CAV's plan merges now, the lane-1 CAV
//! behind it cannot stay clear of that merge and brakes, and, braking, stops alongside the
//! ramp CAV, where neither can move (seen with bk-pbs, `paper` drivers, α 0.4, λ 3000: both
//! standing for the last 140 s of a 300 s run, 20 vehicles queued behind them). The order
//! settles it the way a zip merge does. Walking lane 1 back from the ramp CAV, each CAV that
//! can still stop at the comfortable deceleration with SUMO's minGap free behind the ramp CAV
//! yields to it (and the walk ends there: those behind follow the one that yields); each one
//! already too close for that passes first, and the ramp CAV plans around it. An HDV on lane 1
//! ends the walk: SUMO's drivers cooperate with a merger on their own. A CAV level with the ramp
//! CAV, its front already past the ramp CAV's, passes first as well.
//!
//! Liveness: the ramp CAV waits only for the CAVs that could not stop behind it when it came
//! to the lane end, a finite set that drives on past it, and then for HDVs that SUMO's
//! cooperation slows for it; the first CAV that can stop behind it yields. Once it yields, lane
//! 1 beside the ramp CAV clears as those ahead drive on, and the merge goes in.

use crate::model::scene::{Kind, Origin, Scene, VehicleState};
use crate::model::trajectory::Trajectory;

/// How far back from its lane's end (m) a slow ramp CAV counts as held up at the end.
pub const LANE_END_REACH: f64 = 30.0;
/// Slower than this (m/s), a ramp CAV near the lane end counts as held up there.
pub const HELD_UP_SPEED: f64 = 5.0;

/// The merge order at every lane end of `scene`: priority edges `(hi, lo)` (`lo` plans around
/// `hi`), by scene index. `yield_gap` is the bumper gap a yielding CAV keeps behind the merger
/// (SUMO's minGap of the CAV type), `decel` the comfortable deceleration it stops at.
pub fn merge_order(scene: &Scene, yield_gap: f64, decel: f64) -> Vec<(usize, usize)> {
    let mut edges = Vec::new();
    for (r, merger) in scene.vehicles.iter().enumerate() {
        if held_up_at_lane_end(scene, merger) {
            edges.extend(order_behind(scene, r, yield_gap, decel));
        }
    }
    edges
}

/// Ramp CAV `r` as the CAVs that yield to it must see it when they plan alone (bk-mastar,
/// where no plan of it is shared): standing in the lane it merges into where it waits, for
/// `horizon` steps of `dt`, so that they stop behind it with room for its merge.
pub fn standing_in_target_lane(scene: &Scene, r: usize, horizon: usize, dt: f64) -> Trajectory {
    let v = &scene.vehicles[r];
    let y = f64::from(scene.road.toward_main(v.lane)) * scene.road.lane_width;
    Trajectory {
        length: v.length,
        width: v.width,
        ..Trajectory::straight(v.s, y, 0.0, horizon, dt)
    }
}

/// Whether `v` is a ramp CAV on the acceleration lane, slow, near its end, not yet moving over.
pub fn held_up_at_lane_end(scene: &Scene, v: &VehicleState) -> bool {
    let Some(end) = scene.road.lane_end(v.lane, v.front()) else {
        return false;
    };
    v.kind == Kind::Cav
        && v.origin == Origin::Ramp
        && !v.on_ramp
        && v.other_lane().is_none()
        && v.speed < HELD_UP_SPEED
        && end - v.front() < LANE_END_REACH
}

/// The order between ramp CAV `r` and the lane-1 vehicles beside and behind it: those alongside
/// it with their front past its front go first, then the walk back from its front.
fn order_behind(scene: &Scene, r: usize, yield_gap: f64, decel: f64) -> Vec<(usize, usize)> {
    let mut edges = alongside_ahead(scene, r);
    edges.extend(walk_back(scene, r, yield_gap, decel));
    edges
}

/// The lane-1 CAVs alongside ramp CAV `r`, their fronts past its front and their rears behind
/// it: each passes first. The walk back from the merger's front does not reach them, and left
/// to the search a 12 m CAV truck crawling level with a ramp CAV at the lane end stood with it
/// for good: the merger's plan merged into the truck's body, the truck found no plan clear of
/// it and braked, and neither could move (SUMO's `ramp` game, bk-pbs, α 0.5, seed 2: both
/// standing for the last 280 s, lane 1 closed behind them).
fn alongside_ahead(scene: &Scene, r: usize) -> Vec<(usize, usize)> {
    let merger = &scene.vehicles[r];
    let target = scene.road.toward_main(merger.lane);
    scene
        .vehicles
        .iter()
        .enumerate()
        .filter(|(_, v)| {
            v.kind == Kind::Cav
                && v.lane == target
                && v.front() >= merger.front()
                && v.rear() < merger.front()
        })
        .map(|(f, _)| (f, r))
        .collect()
}

/// The walk back along lane 1 from ramp CAV `r`'s front: each CAV too close to stop behind it
/// passes first, the first that can stop yields and ends the walk, as does an HDV.
fn walk_back(scene: &Scene, r: usize, yield_gap: f64, decel: f64) -> Vec<(usize, usize)> {
    let merger = &scene.vehicles[r];
    let target = scene.road.toward_main(merger.lane);
    let mut behind: Vec<(usize, &VehicleState)> = scene
        .vehicles
        .iter()
        .enumerate()
        .filter(|(_, v)| v.lane == target && v.front() < merger.front())
        .collect();
    behind.sort_by(|a, b| b.1.s.total_cmp(&a.1.s));
    let mut edges = Vec::new();
    for (f, follower) in behind {
        if follower.kind != Kind::Cav {
            break;
        }
        let room = merger.rear() - follower.front() - yield_gap;
        let stopping = follower.speed * follower.speed / (2.0 * decel);
        if room >= stopping {
            edges.push((r, f));
            break;
        }
        edges.push((f, r));
    }
    edges
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::road::Road;

    fn scene(vehicles: Vec<VehicleState>) -> Scene {
        Scene {
            time: 0.0,
            road: Road::paper_default(),
            vehicles,
        }
    }

    fn at_lane_end(speed: f64) -> VehicleState {
        let end = Road::paper_default().zones[0].end;
        VehicleState::on_lane("ramp.1", Kind::Cav, Origin::Ramp, end - 3.0, 0, speed)
    }

    fn on_lane_1(id: &str, kind: Kind, s: f64, speed: f64) -> VehicleState {
        VehicleState::on_lane(id, kind, Origin::Main, s, 1, speed)
    }

    #[test]
    fn a_cav_that_can_stop_behind_yields_and_those_too_close_pass() {
        let r = at_lane_end(0.0);
        let s = r.s;
        let sc = scene(vec![
            r,
            on_lane_1("alongside", Kind::Cav, s - 3.0, 1.0),
            on_lane_1("close", Kind::Cav, s - 12.0, 15.0),
            on_lane_1("far", Kind::Cav, s - 80.0, 20.0),
            on_lane_1("farther", Kind::Cav, s - 120.0, 20.0),
        ]);
        // 15 m/s needs 15²/4 = 56 m at 2 m/s²: too close; 20 m/s needs 100 m of 80 − 5 − 5: too
        // close as well; 120 m back it can stop: it yields, and the walk ends there.
        assert_eq!(
            merge_order(&sc, 5.0, 2.0),
            vec![(1, 0), (2, 0), (3, 0), (0, 4)]
        );
    }

    #[test]
    fn an_hdv_behind_ends_the_walk_and_a_moving_merger_is_left_to_the_search() {
        let r = at_lane_end(0.0);
        let s = r.s;
        let sc = scene(vec![
            r.clone(),
            on_lane_1("hdv", Kind::Hdv, s - 20.0, 10.0),
            on_lane_1("cav", Kind::Cav, s - 60.0, 10.0),
        ]);
        assert!(merge_order(&sc, 5.0, 2.0).is_empty());
        let moving = scene(vec![
            at_lane_end(HELD_UP_SPEED + 1.0),
            on_lane_1("cav", Kind::Cav, s - 60.0, 10.0),
        ]);
        assert!(merge_order(&moving, 5.0, 2.0).is_empty());
    }

    #[test]
    fn a_cav_level_with_the_merger_and_ahead_of_its_front_passes_first() {
        let r = at_lane_end(0.0);
        let front = r.front();
        let truck = |id: &str, kind: Kind, front_at: f64| VehicleState {
            length: 12.0,
            ..on_lane_1(id, kind, front_at - 6.0, 0.4)
        };
        let sc = scene(vec![
            r,
            truck("level", Kind::Cav, front + 0.3),
            truck("beyond", Kind::Cav, front + 20.0),
            truck("hdv level", Kind::Hdv, front + 0.5),
        ]);
        // The CAV wholly past the merger is no obstacle to it; an HDV level with it is left to
        // SUMO's cooperation.
        assert_eq!(merge_order(&sc, 5.0, 2.0), vec![(1, 0)]);
    }
}
