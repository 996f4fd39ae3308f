//! How an IDM+MOBIL CAV merges and lets others merge: lining up with a gap on its acceleration
//! lane (gap seeking), committing to a merge at a nose, and leaving a merging ramp HDV the
//! room it needs (courtesy). The planners' counterparts are `planner::mastar::gap_seeking`,
//! `episode::nose` and `planner::mastar::courtesy`.

use super::idm::{self, Leader};
use super::mobil;
use crate::config::{Idm, Mobil};
use crate::model::road::MergeZone;
use crate::model::scene::{Scene, VehicleState};
use crate::planner::lane_changes::ramp_hdv_merging_ahead;

/// The nose zone `v`'s front is on, past its start: where a ramp that joins without an
/// acceleration lane lets its vehicles commit to the merge.
pub fn nose_zone<'s>(scene: &'s Scene, v: &VehicleState) -> Option<&'s MergeZone> {
    let z = scene.road.nose_zone_at(v.lane, v.front())?;
    (v.front() >= z.start).then_some(z)
}

/// The lane vehicle `v` must merge into and lines up for: from an acceleration lane (on the ramp
/// before it: `None`), or from a nose zone until it has committed.
pub fn merge_target(scene: &Scene, v: &VehicleState) -> Option<i32> {
    if let Some(z) = nose_zone(scene, v) {
        return (!v.changing_lanes()).then(|| z.target());
    }
    let road = &scene.road;
    (road.is_auxiliary(v.lane) && !v.on_ramp).then(|| road.toward_main(v.lane))
}

/// IDM's acceleration of `v` behind `leader`, or `None` if `leader` is not ahead of it.
fn behind(p: &Idm, v: &VehicleState, leader: &VehicleState, margin: f64) -> Option<f64> {
    let gap = leader.rear() - v.front() - margin;
    (gap > 0.0).then(|| {
        let l = Leader {
            gap,
            speed: leader.speed,
        };
        idm::acceleration(p, v.speed, v.desired_speed, Some(l))
    })
}

/// Gap seeking: scene vehicle `i`, lining up to merge into `target`, also follows the nearest
/// vehicle ahead there, so that it lines up behind a gap instead of racing past it. With
/// `drops_back`, while the merge is not yet safe, the vehicle it lines up behind is the nearest
/// one whose front is past its rear less `merge_min_gap`, so one alongside too: it brakes
/// comfortably (`p.decel`) to drop behind that one (while faster than half its speed) instead
/// of keeping level with it until its lane ends.
pub fn seeking_acceleration(
    (p, m): (&Idm, &Mobil),
    scene: &Scene,
    i: usize,
    target: i32,
    drops_back: bool,
) -> Option<f64> {
    let v = &scene.vehicles[i];
    let blocked = drops_back && !mobil::merge_is_safe(m, scene, i, target);
    let ahead = if blocked {
        let w = scene.road.lane_width;
        (scene.vehicles.iter().enumerate())
            .filter(|&(j, o)| j != i && mobil::occupies(o, target, w))
            .filter(|(_, o)| o.front() > v.rear() - m.merge_min_gap)
            .min_by(|(_, a), (_, b)| a.s.total_cmp(&b.s))
            .map(|(j, _)| j)
    } else {
        mobil::leader_index(scene, target, v.s, i)
    };
    let l = &scene.vehicles[ahead?];
    match behind(p, v, l, 0.0) {
        Some(a) => Some(a),
        None if blocked && v.speed > 0.5 * l.speed => Some(-p.decel),
        None => None,
    }
}

/// IDM's acceleration of a CAV committed to merging at a nose (`episode::nose`): behind the
/// nearest vehicle ahead in its frame lane, with no wall at its lane's end, which it drives past
/// into the target lane.
pub fn committed_acceleration(p: &Idm, scene: &Scene, i: usize) -> f64 {
    let v = &scene.vehicles[i];
    let leader = mobil::leader_index(scene, v.lane, v.s, i).map(|j| {
        let l = &scene.vehicles[j];
        Leader {
            gap: l.rear() - v.front(),
            speed: l.speed,
        }
    });
    idm::acceleration(p, v.speed, v.desired_speed, leader)
}

/// Courtesy: main-road CAV `i` follows the ramp HDV whose new follower it would be (merging into
/// its lane from an auxiliary lane, past its zone's start, not yet changing lanes, `i` the
/// nearest vehicle behind it there) as if it drove in its lane, keeping its own `s0` more than
/// IDM would behind a leader and braking for it no harder than `merge_safe_braking` (the most
/// the merge's gap acceptance asks of a new follower). `None` where it yields to no one.
///
/// The extra `s0`: stopped `s0` behind a waiting merger, a CAV with its type's `minGap` as `s0`
/// left it exactly the gap SUMO's merger asks at a stand, which it did not take (standoffs of
/// minutes on the tuning seeds, `results/layouts/README.md`). Yielding only where comfortable
/// braking did (as M-A*'s courtesy) left nearly every merger that came level with a CAV
/// without room.
pub fn courtesy_acceleration((p, m): (&Idm, &Mobil), scene: &Scene, i: usize) -> Option<f64> {
    let v = &scene.vehicles[i];
    let merger = merger_yielded_to(scene, i)?;
    let a = behind(p, v, &scene.vehicles[merger], p.min_gap)?;
    Some(a.max(-m.merge_safe_braking))
}

/// The ramp HDV whose new follower scene vehicle `i` (on a main-road lane) would be.
fn merger_yielded_to(scene: &Scene, i: usize) -> Option<usize> {
    let me = &scene.vehicles[i];
    let (m, _) = ramp_hdv_merging_ahead(scene, i, me.lane)?;
    let s = scene.vehicles[m].s;
    (mobil::follower_index(scene, me.lane, s, m) == Some(i)).then_some(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::road::Road;
    use crate::model::scene::{Kind, Origin};

    fn car(id: &str, kind: Kind, origin: Origin, s: f64, lane: i32, speed: f64) -> VehicleState {
        VehicleState {
            desired_speed: 30.0,
            ..VehicleState::on_lane(id, kind, origin, s, lane, speed)
        }
    }

    fn nose_road() -> Road {
        let mut road = Road::paper_default();
        road.zones[0].nose = true;
        road.zones[0].start = 270.0;
        road
    }

    /// A ramp HDV on the acceleration lane ahead of a main-road CAV, with nobody between: the
    /// CAV yields, keeping s0 more than IDM's gap, braking no harder than `merge_safe_braking`;
    /// with another car between them it does not.
    #[test]
    fn courtesy_yields_as_the_mergers_new_follower_braking_at_most_the_merges_limit() {
        let zone = Road::paper_default().zones[0];
        let at = zone.start + 30.0;
        let merger = car("m", Kind::Hdv, Origin::Ramp, at, 0, 20.0);
        let cav = car("c", Kind::Cav, Origin::Main, at - 60.0, 1, 20.0);
        let pm = (&Idm::default(), &Mobil::default());
        let scene = Scene::on_paper_road(0.0, vec![cav.clone(), merger.clone()]);
        let a = courtesy_acceleration(pm, &scene, 0).expect("yields");
        // Gap 55 m less s0 5 m = 50 m; s* = 5 + 20·1.5 = 35 m: a = 3(1 − (20/30)^4 − (35/50)²).
        let want = 3.0 * (1.0 - (20.0f64 / 30.0).powi(4) - 0.7f64.powi(2));
        assert!((a - want).abs() < 1e-9, "{a} {want}");
        let between = car("b", Kind::Hdv, Origin::Main, at - 20.0, 1, 20.0);
        let scene = Scene::on_paper_road(0.0, vec![cav.clone(), merger.clone(), between]);
        assert_eq!(courtesy_acceleration(pm, &scene, 0), None);
        let close = car("c", Kind::Cav, Origin::Main, at - 12.0, 1, 25.0);
        let scene = Scene::on_paper_road(0.0, vec![close, merger]);
        assert_eq!(courtesy_acceleration(pm, &scene, 0), Some(-3.0));
    }

    /// Blocked by a car alongside in the target lane, a CAV on its acceleration lane brakes
    /// comfortably to drop behind it when dropping back is on, and keeps its speed otherwise.
    #[test]
    fn a_blocked_merger_drops_back_behind_the_car_alongside() {
        let zone = Road::paper_default().zones[0];
        let at = zone.start + 40.0;
        let me = car("c", Kind::Cav, Origin::Ramp, at, 0, 25.0);
        let alongside = car("a", Kind::Hdv, Origin::Main, at - 1.0, 1, 25.0);
        let scene = Scene::on_paper_road(0.0, vec![me, alongside]);
        let pm = (&Idm::default(), &Mobil::default());
        assert_eq!(seeking_acceleration(pm, &scene, 0, 1, true), Some(-5.0));
        assert_eq!(seeking_acceleration(pm, &scene, 0, 1, false), None);
    }

    /// On a nose zone past its start a ramp CAV lines up for the target lane; before the zone, or
    /// once committed (changing lanes), it does not; and committed, it sees no wall at the nose.
    #[test]
    fn a_nose_zone_lines_up_and_a_committed_cav_drives_past_the_nose() {
        let road = nose_road();
        // On a nose ramp's edge every vehicle is on the ramp, its zone too.
        let on_ramp = |s: f64| VehicleState {
            on_ramp: true,
            ..car("c", Kind::Cav, Origin::Ramp, s, 0, 20.0)
        };
        let on_zone = on_ramp(300.0);
        let scene = Scene {
            road: road.clone(),
            ..Scene::on_paper_road(0.0, vec![on_zone.clone()])
        };
        assert_eq!(merge_target(&scene, &scene.vehicles[0]), Some(1));
        let before = on_ramp(200.0);
        let scene_before = Scene {
            road: road.clone(),
            ..Scene::on_paper_road(0.0, vec![before])
        };
        assert_eq!(merge_target(&scene_before, &scene_before.vehicles[0]), None);
        let mut committed = on_zone;
        committed.lateral = 1.0;
        let scene = Scene {
            road,
            ..Scene::on_paper_road(0.0, vec![committed])
        };
        assert_eq!(merge_target(&scene, &scene.vehicles[0]), None);
        let free = idm::acceleration(&Idm::default(), 20.0, 30.0, None);
        assert_eq!(committed_acceleration(&Idm::default(), &scene, 0), free);
    }
}
