//! Ramps that join at the nose, without an acceleration lane: SUMO has no lane beside the
//! ramp's to change into, and its vehicles move over by driving on, into the lane their lane
//! and a carriageway lane lead into where the ramp joins. A lane change a controller sends a
//! CAV on such a ramp's last stretch (its zone, [`MergeZone::nose`]) is therefore a commitment,
//! not a command SUMO could carry out: from then until the nose (where its junction lane, on
//! the target lane, begins) the CAV counts as changing lanes, its frame position moving from
//! the ramp's lane towards the target lane with its distance or time since it committed
//! ([`NoseCommitments::apply`]). Planners, the shield and the merge rule see a change under
//! way, as on an acceleration lane: never cancelled, occupying both lanes.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::controller::Command;
use crate::model::road::{MergeZone, Road};
use crate::model::scene::{Scene, VehicleState, CHANGING_LATERAL};
use crate::sumo::frame::SumoScene;

/// The least lateral offset a committed vehicle is given (m): past [`CHANGING_LATERAL`], so it
/// counts as changing lanes from the step after it committed, before it has moved.
const COMMITTED: f64 = 2.0 * CHANGING_LATERAL;

/// The CAVs committed to merging at a nose, each with the front `s` and the time where and
/// when it committed.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NoseCommitments {
    from: BTreeMap<Arc<str>, (f64, f64)>,
}

/// The nose zone of the lane vehicle `v` drives on, if it drives on one.
fn nose_zone<'r>(road: &'r Road, v: &VehicleState) -> Option<&'r MergeZone> {
    road.nose_zone_at(v.lane, v.front())
}

impl NoseCommitments {
    /// Notes the commitments `commands` make in `framed`: a lane change of a vehicle on a nose
    /// zone, past its start, into its target lane, where SUMO has no lane to change into.
    pub fn note(&mut self, framed: &SumoScene, commands: &[Command]) {
        let road = &framed.scene.road;
        for c in commands {
            let v = &framed.scene.vehicles[c.vehicle];
            let Some(dir) = c.maneuver.lane_change else {
                continue;
            };
            let target = v.lane + dir.offset();
            let Some(z) = nose_zone(road, v) else {
                continue;
            };
            let no_lane = framed.sumo_lane_index(c.vehicle, target).is_none();
            let first = first_on_its_lane(&framed.scene, v, z);
            if no_lane && first && z.target() == target && v.front() >= z.start {
                let when = framed.scene.time;
                self.from.entry(v.id.clone()).or_insert((v.front(), when));
            }
        }
    }

    /// Puts each committed vehicle of `scene` between its lane and the target lane, by how far
    /// it has come since it committed towards the end of its lane (where its junction lane,
    /// on the target lane, begins) or, if further, by the time since then in a lane change's
    /// `duration`: a CAV that committed standing at the end of its lane (a slide) is nearly
    /// across a lane change later, as on an acceleration lane, and drives on from there
    /// (measured by distance alone, it stayed committed where it stood, and the planner found
    /// no plan for it). Until the nose it is never quite across: it still occupies its own
    /// lane, and a ramp CAV behind it keeps its distance (put on the target lane, a committed
    /// CAV queued on a ramp was driven into by the one behind). Forgets those that passed the
    /// end or left the scene.
    pub fn apply(&mut self, scene: &mut Scene, duration: f64) {
        let width = scene.road.lane_width;
        let mut still = BTreeMap::new();
        for v in &mut scene.vehicles {
            let Some(&(from, when)) = self.from.get(&v.id) else {
                continue;
            };
            let Some(z) = nose_zone(&scene.road, v).copied() else {
                continue;
            };
            let by_distance = (v.front() - from) / (z.end - from).max(0.5);
            let by_time = (scene.time - when) / duration;
            // Short of the nose it is still on its own lane too: never quite across.
            let progress = by_distance.max(by_time).clamp(0.0, 1.0);
            let lateral = (width * progress).clamp(COMMITTED, width - COMMITTED);
            move_over(v, &z, (lateral, width));
            still.insert(v.id.clone(), (from, when));
        }
        self.from = still;
    }
}

/// Whether no vehicle drives ahead of `v` on its nose zone `z`'s lane before the nose: only
/// then can it go to the target lane, which it reaches through the junction. A CAV committed
/// behind a ramp HDV waiting at a priority junction's nose was put on the target lane beside
/// it and drove into it.
fn first_on_its_lane(scene: &Scene, v: &VehicleState, z: &MergeZone) -> bool {
    !(scene.vehicles.iter()).any(|o| o.lane == z.lane && o.s > v.s && o.rear() < z.end)
}

/// Sets `v` `lateral` metres across from its zone's lane towards the target lane (`width`
/// apart), in the frame lane its centre is then on.
fn move_over(v: &mut VehicleState, z: &MergeZone, (lateral, width): (f64, f64)) {
    let toward = f64::from(z.target() - z.lane);
    if lateral > 0.5 * width {
        v.lane = z.target();
        v.lateral = toward * (lateral - width);
    } else {
        v.lateral = toward * lateral;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::{Kind, Origin};

    /// The paper road with its ramp joining at the nose at 330 m, its zone from 270 m.
    fn nose_road() -> Road {
        let mut road = Road::paper_default();
        road.zones[0].nose = true;
        road.zones[0].start = 270.0;
        road
    }

    fn ramp_cav(id: &str, s: f64, speed: f64) -> VehicleState {
        VehicleState::on_lane(id, Kind::Cav, Origin::Ramp, s, 0, speed)
    }

    /// Committed 40 m before the nose at speed, a CAV moves over with its distance: half-way
    /// across 20 m on; a lane change's duration later, standing where it committed, it is
    /// nearly across; never quite across before the nose, so it still occupies its own lane.
    #[test]
    fn a_committed_cav_moves_over_by_distance_or_time_never_quite_across() {
        let road = nose_road();
        let width = road.lane_width;
        let at = |s: f64, time: f64, from: f64| {
            let mut c = NoseCommitments::default();
            c.from.insert(Arc::from("cav"), (from, 0.0));
            let mut scene = Scene {
                time,
                road: road.clone(),
                vehicles: vec![ramp_cav("cav", s, 20.0)],
            };
            c.apply(&mut scene, 1.0);
            (scene.vehicles[0].lane, scene.vehicles[0].lateral)
        };
        let (lane, lateral) = at(307.5, 0.2, 290.0);
        assert_eq!(lane, 0);
        assert!((lateral - 0.5 * width).abs() < 0.25, "{lateral}");
        assert_eq!(at(326.0, 0.0, 328.5), (0, COMMITTED));
        let (lane, lateral) = at(326.0, 1.0, 328.5);
        assert_eq!(lane, 1);
        assert!((lateral + COMMITTED).abs() < 1e-9, "{lateral}");
        let (lane, lateral) = at(326.0, 0.4, 290.0);
        assert_eq!(lane, 1);
        assert!(lateral <= -COMMITTED + 1e-9, "{lateral}");
    }

    /// Only the first vehicle on the ramp's lane before the nose may commit: one behind a ramp
    /// HDV waiting at a priority junction's nose may not.
    #[test]
    fn only_the_first_on_the_ramp_commits() {
        let road = nose_road();
        let waiting = VehicleState::on_lane("hdv", Kind::Hdv, Origin::Ramp, 327.0, 0, 0.0);
        let me = ramp_cav("cav", 300.0, 10.0);
        let scene = |vehicles| Scene {
            time: 0.0,
            road: road.clone(),
            vehicles,
        };
        let z = road.zones[0];
        assert!(!first_on_its_lane(
            &scene(vec![me.clone(), waiting]),
            &me,
            &z
        ));
        let main = VehicleState::on_lane("m", Kind::Hdv, Origin::Main, 320.0, 1, 30.0);
        assert!(first_on_its_lane(&scene(vec![me.clone(), main]), &me, &z));
    }
}
