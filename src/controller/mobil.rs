//! MOBIL lane-change decisions (Kesting, Treiber, Helbing 2007) on a scene, with IDM as the
//! car-following model, as highway-env uses them.
//!
//! A vehicle occupies its own lane and, while it is more than half a lane-width-minus-body off
//! centre (mid lane change), the neighbouring lane too, so vehicles cutting in are seen.

use super::idm::{self, Leader};
use crate::config::{Idm, Mobil};
use crate::model::scene::{Scene, VehicleState};

/// Whether `v` takes up space in `lane`.
pub fn occupies(v: &VehicleState, lane: i32, lane_width: f64) -> bool {
    if v.lane == lane {
        return true;
    }
    let spill = 0.5 * (lane_width - v.width);
    (lane == v.lane + 1 && v.lateral > spill) || (lane == v.lane - 1 && v.lateral < -spill)
}

/// Index of the nearest vehicle ahead of centre `s` occupying `lane`, skipping `skip`.
pub fn leader_index(scene: &Scene, lane: i32, s: f64, skip: usize) -> Option<usize> {
    nearest(scene, lane, skip, |o| o > s, |a, b| a < b)
}

/// Index of the nearest vehicle behind (or level with) centre `s` occupying `lane`.
pub fn follower_index(scene: &Scene, lane: i32, s: f64, skip: usize) -> Option<usize> {
    nearest(scene, lane, skip, |o| o <= s, |a, b| a > b)
}

fn nearest(
    scene: &Scene,
    lane: i32,
    skip: usize,
    side: impl Fn(f64) -> bool,
    closer: impl Fn(f64, f64) -> bool,
) -> Option<usize> {
    let w = scene.road.lane_width;
    let mut best: Option<usize> = None;
    for (i, v) in scene.vehicles.iter().enumerate() {
        if i == skip || !side(v.s) || !occupies(v, lane, w) {
            continue;
        }
        if best.is_none_or(|b| closer(v.s, scene.vehicles[b].s)) {
            best = Some(i);
        }
    }
    best
}

/// What `follower` sees ahead when `leader` is in front of it.
fn gap_to(follower: &VehicleState, leader: &VehicleState) -> Leader {
    Leader {
        gap: leader.rear() - follower.front(),
        speed: leader.speed,
    }
}

/// The binding constraint ahead of a vehicle with centre `s` in `lane`: the nearest leader, or,
/// on the merge lane, the lane's end, whichever is closer.
///
/// The lane end is a standing obstacle seen without IDM's time-headway term (a wall needs no
/// safety time gap, only a stopping distance): its gap is enlarged by v·T so that IDM's
/// s* = s0 + v·T + v²/(2√(ab)) reduces to s0 + v²/(2√(ab)) against it.
pub fn constraint_ahead(
    time_headway: f64,
    scene: &Scene,
    me: &VehicleState,
    lane: i32,
    skip: usize,
    new_leader: Option<usize>,
) -> Option<Leader> {
    let from_vehicle = new_leader
        .or_else(|| leader_index(scene, lane, me.s, skip))
        .map(|j| gap_to(me, &scene.vehicles[j]));
    let end = scene.road.lane_end(lane, me.front());
    let lane_end = end.filter(|&end| me.front() < end).map(|end| Leader {
        gap: end - me.front() + me.speed * time_headway,
        speed: 0.0,
    });
    match (from_vehicle, lane_end) {
        (Some(a), Some(b)) => Some(if a.gap <= b.gap { a } else { b }),
        (a, b) => a.or(b),
    }
}

/// IDM acceleration of scene vehicle `i` in `lane` behind its natural constraint.
pub fn idm_in_lane(p: &Idm, scene: &Scene, i: usize, lane: i32) -> f64 {
    let me = &scene.vehicles[i];
    idm::acceleration(
        p,
        me.speed,
        me.desired_speed,
        constraint_ahead(p.time_headway, scene, me, lane, i, None),
    )
}

/// Gap acceptance for the mandatory merge from the acceleration lane: a kinematic check, since
/// MOBIL's IDM-based safety criterion rejects every gap once the merging vehicle has had to slow
/// down (it then reads a standing car as an emergency), which jams the lane for good.
///
/// Accepted when both gaps are at least `merge_min_gap` and neither the merging vehicle (behind
/// its new leader) nor its new follower (behind it) needs to brake harder than
/// `merge_safe_braking` to cancel the speed difference before the gap shrinks to `merge_min_gap`.
pub fn merge_is_safe(mobil: &Mobil, scene: &Scene, i: usize, target: i32) -> bool {
    let me = &scene.vehicles[i];
    let ok = |back: &VehicleState, front: &VehicleState| gap_is_safe(mobil, back, front);
    let leader_ok = leader_index(scene, target, me.s, i).is_none_or(|l| ok(me, &scene.vehicles[l]));
    let follower_ok =
        follower_index(scene, target, me.s, i).is_none_or(|f| ok(&scene.vehicles[f], me));
    leader_ok && follower_ok
}

/// The merge's gap acceptance between two vehicles in one lane: the gap from `back` to `front`
/// at least `merge_min_gap`, and `back` need brake no harder than `merge_safe_braking` to
/// cancel the speed difference before it shrinks to that.
pub fn gap_is_safe(mobil: &Mobil, back: &VehicleState, front: &VehicleState) -> bool {
    let gap = front.rear() - back.front();
    let room = gap - mobil.merge_min_gap;
    let closing = (back.speed - front.speed).max(0.0);
    room >= 0.0 && closing * closing <= 2.0 * mobil.merge_safe_braking * room
}

/// The MOBIL verdict for vehicle `i` moving to lane `target`: `Some(gain)` if the change is
/// safe (the new follower brakes at most `safe_braking`, no body overlaps) and its incentive
/// exceeds the threshold.
pub fn evaluate(idm_p: &Idm, mobil: &Mobil, scene: &Scene, i: usize, target: i32) -> Option<f64> {
    let me = &scene.vehicles[i];
    if !scene.road.lane_exists(target, me.front()) {
        return None;
    }
    let new_leader = leader_index(scene, target, me.s, i);
    let new_follower = follower_index(scene, target, me.s, i);
    if let Some(l) = new_leader {
        if scene.vehicles[l].rear() <= me.front() {
            return None;
        }
    }
    let (nf_before, nf_after) = match new_follower {
        Some(f) => {
            let fv = &scene.vehicles[f];
            if fv.front() >= me.rear() {
                return None;
            }
            let after = idm::acceleration(idm_p, fv.speed, fv.desired_speed, Some(gap_to(fv, me)));
            if after < -mobil.safe_braking {
                return None;
            }
            (idm_in_lane(idm_p, scene, f, target), after)
        }
        None => (0.0, 0.0),
    };
    let me_after = idm::acceleration(
        idm_p,
        me.speed,
        me.desired_speed,
        constraint_ahead(idm_p.time_headway, scene, me, target, i, new_leader),
    );
    let me_before = idm_in_lane(idm_p, scene, i, me.lane);
    let mut gain = me_after - me_before;
    if mobil.politeness > 0.0 {
        gain += mobil.politeness * (nf_after - nf_before);
        if let Some(f) = follower_index(scene, me.lane, me.s, i) {
            let fv = &scene.vehicles[f];
            let before = idm::acceleration(idm_p, fv.speed, fv.desired_speed, Some(gap_to(fv, me)));
            let after = idm::acceleration(
                idm_p,
                fv.speed,
                fv.desired_speed,
                leader_index(scene, me.lane, me.s, i).map(|l| gap_to(fv, &scene.vehicles[l])),
            );
            gain += mobil.politeness * (after - before);
        }
    }
    (gain > mobil.gain_threshold).then_some(gain)
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::model::scene::{Kind, Origin};

    fn car(s: f64, lane: i32, speed: f64, desired: f64) -> VehicleState {
        let id = format!("v{s}-{lane}");
        VehicleState {
            desired_speed: desired,
            ..VehicleState::on_lane(&id, Kind::Hdv, Origin::Main, s, lane, speed)
        }
    }

    #[test]
    fn overtakes_a_slow_leader_into_a_free_lane_hand_computed() {
        // Ego at s=100 lane 1, 30 m/s wanting 35; slow leader 40 m ahead (gap 35 m) at 25 m/s.
        // Before: s* = 5 + 45 + 30·5/(2√15) = 69.364917; a = 3(1 − 0.539775 − (69.364917/35)²)
        //       = 3(0.460225 − 3.927832) = −10.40 -> clamped to −9.
        // After (free lane 2): a = 3·0.460225 = 1.380675. Gain = 10.380675 > 0.2.
        let sc = Scene::on_paper_road(
            0.0,
            vec![car(100.0, 1, 30.0, 35.0), car(140.0, 1, 25.0, 25.0)],
        );
        let p = Mobil::default();
        let g = evaluate(&Idm::default(), &p, &sc, 0, 2).unwrap();
        assert!((g - 10.380_675).abs() < 1e-4, "{g}");
        // Moving right, into the merge lane, is not allowed past its end and is not a main lane
        // choice here (s=100 is before the merge zone but lane 0 there is the ramp side).
    }

    #[test]
    fn unsafe_when_new_follower_must_brake_hard() {
        // New follower in lane 2 just 8 m behind at 35 m/s vs ego 30: it would brake < −2.
        let sc = Scene::on_paper_road(
            0.0,
            vec![
                car(100.0, 1, 30.0, 35.0),
                car(140.0, 1, 25.0, 25.0),
                car(87.0, 2, 35.0, 35.0),
            ],
        );
        assert!(evaluate(&Idm::default(), &Mobil::default(), &sc, 0, 2).is_none());
    }

    #[test]
    fn overlapping_target_slot_is_refused_by_both_criteria() {
        let sc = Scene::on_paper_road(
            0.0,
            vec![car(200.0, 0, 25.0, 35.0), car(202.0, 1, 25.0, 35.0)],
        );
        assert!(evaluate(&Idm::default(), &Mobil::default(), &sc, 0, 1).is_none());
        assert!(!merge_is_safe(&Mobil::default(), &sc, 0, 1));
    }

    #[test]
    fn merge_gap_acceptance_hand_computed() {
        // Standing merger at s=300 (front 302.5); follower on lane 1 at 20 m/s.
        // Room needed: 20² / (2·3) = 66.67 m beyond the 2.5 m minimum gap.
        let m = Mobil::default();
        let far = Scene::on_paper_road(
            0.0,
            vec![
                car(300.0, 0, 0.0, 35.0),
                car(300.0 - 5.0 - 70.0, 1, 20.0, 35.0),
            ],
        );
        assert!(merge_is_safe(&m, &far, 0, 1)); // gap 70 -> room 67.5 >= 66.67
        let near = Scene::on_paper_road(
            0.0,
            vec![
                car(300.0, 0, 0.0, 35.0),
                car(300.0 - 5.0 - 68.0, 1, 20.0, 35.0),
            ],
        );
        assert!(!merge_is_safe(&m, &near, 0, 1)); // room 65.5 < 66.67
                                                  // A slower leader ahead of a moving merger counts the same way.
        let lead = Scene::on_paper_road(
            0.0,
            vec![
                car(200.0, 0, 25.0, 35.0),
                car(200.0 + 5.0 + 10.0, 1, 15.0, 35.0),
            ],
        );
        assert!(!merge_is_safe(&m, &lead, 0, 1)); // 10² / (2·3) = 16.7 > 7.5
    }

    #[test]
    fn lane_end_acts_as_standing_obstacle() {
        let sc = Scene::on_paper_road(0.0, vec![car(300.0, 0, 20.0, 35.0)]);
        // Front at 302.5, end at 330: 27.5 m, plus v·T = 20·1.5 = 30 m.
        let c = constraint_ahead(1.5, &sc, &sc.vehicles[0], 0, 0, None).unwrap();
        assert!((c.gap - 57.5).abs() < 1e-9 && c.speed == 0.0);
        assert!(constraint_ahead(1.5, &sc, &sc.vehicles[0], 1, 0, None).is_none());
    }

    #[test]
    fn mid_change_vehicle_occupies_both_lanes() {
        let mut v = car(100.0, 1, 30.0, 35.0);
        v.lateral = 1.5; // drifting left, 1.5 > (4.5 − 2)/2
        assert!(occupies(&v, 1, 4.5) && occupies(&v, 2, 4.5) && !occupies(&v, 0, 4.5));
    }
}
