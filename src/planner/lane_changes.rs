//! Lane changes a planner commanded and SUMO is still executing.
//!
//! CAVs change lanes only when told (lane-change mode 0), so the planner knows exactly which
//! changes are under way: it must continue them (SUMO is moving the vehicle sideways), not
//! re-command or cancel them.
//!
//! This timer is not the lateral-offset test [`changing_lanes`] under another name: that reads
//! the offset SUMO reports and answers "is this vehicle off its lane centre now?" for any
//! vehicle. The timer answers "which change did the planner command, toward which lane, and for
//! how many more steps?" for its own CAVs: the offset points to the lane a vehicle comes from
//! once it has switched lanes at the midpoint, and tells no steps left, which the planner needs
//! to continue the change in its plan.
//!
//! [`changing_lanes`]: crate::model::scene::VehicleState::changing_lanes

use std::collections::HashMap;
use std::sync::Arc;

use crate::model::kinematics::BicycleState;
use crate::model::math::Point;
use crate::model::scene::{Kind, Origin, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::guard::{Guard, StartGuard};
use crate::planner::mastar::{
    FirstMoves, Mastar, Merger, NoPlan, OngoingLaneChange, Plan, Request,
};
use crate::planner::memo::SearchMemo;
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

    /// The M-A* request of scene vehicle `i` among `obstacles`, its lane-change starts passing
    /// `guard`.
    pub fn request<'a>(
        &self,
        scene: &'a Scene,
        i: usize,
        dt: f64,
        obstacles: &'a [&'a Trajectory],
        guard: Option<&'a dyn StartGuard>,
    ) -> Request<'a> {
        let v = &scene.vehicles[i];
        let w = scene.road.lane_width;
        let ongoing = self.ongoing(&v.id, scene.time, dt);
        let lane = ongoing.map_or(v.lane, |o| o.target_lane);
        // A merge under way is still a merge: the body overlaps the merge lane until it ends,
        // so the search must allow that (it once rejected every continuation, and the CAV
        // braked hard while SUMO kept moving it sideways).
        let road = &scene.road;
        let merging = ongoing.is_some_and(|o| {
            // Towards a lane an auxiliary lane merges into, still on the auxiliary lane or on
            // its side of a lane's centre.
            let from = road.zone_into(o.target_lane, v.s).map(|z| z.lane);
            let short = |from: i32| f64::from(o.target_lane - from) * v.lateral < 0.0;
            from.is_some_and(|from| v.lane == from || short(from))
        });
        let cos = v.heading.cos().max(0.5);
        Request {
            start: BicycleState {
                pos: Point::new(v.s, v.lane as f64 * w + v.lateral),
                heading: v.heading,
                speed: v.speed / cos,
            },
            lane,
            ongoing,
            must_merge: v.origin == Origin::Ramp && (road.is_auxiliary(lane) || merging),
            length: v.length,
            width: v.width,
            max_speed: v.max_speed,
            limits: v.limits,
            obstacles,
            guard: guard.map(|check| Guard {
                check,
                scene,
                agent: i,
            }),
            first_moves: None,
            merger: merger_ahead(scene, i, lane),
        }
    }
}

/// The ramp HDV nearest ahead of scene vehicle `i` (in `lane`, a main-road lane) on an
/// auxiliary lane merging into `lane`, past the start of its merge zone and not yet changing:
/// its scene index and where its lane ends. M-A*'s courtesy and IDM+MOBIL's yield to it.
pub fn ramp_hdv_merging_ahead(scene: &Scene, i: usize, lane: i32) -> Option<(usize, f64)> {
    let road = &scene.road;
    let me = &scene.vehicles[i];
    if road.is_auxiliary(lane) {
        return None;
    }
    (scene.vehicles.iter().enumerate())
        .filter(|(_, o)| o.kind == Kind::Hdv && o.origin == Origin::Ramp && !o.changing_lanes())
        .filter(|(_, o)| road.is_auxiliary(o.lane) && road.toward_main(o.lane) == lane)
        .filter(|(_, o)| o.rear() > me.front())
        .filter_map(|(j, o)| {
            let zone = road.zone_on(o.lane, o.front())?;
            (o.front() >= zone.start && o.front() <= zone.end).then_some((j, zone.end))
        })
        .min_by(|&(a, _), &(b, _)| scene.vehicles[a].s.total_cmp(&scene.vehicles[b].s))
}

/// [`ramp_hdv_merging_ahead`] as the M-A* request carries it.
fn merger_ahead(scene: &Scene, i: usize, lane: i32) -> Option<Merger> {
    let (m, lane_end) = ramp_hdv_merging_ahead(scene, i, lane)?;
    let o = &scene.vehicles[m];
    Some(Merger {
        s: o.s,
        speed: o.speed,
        length: o.length,
        width: o.width,
        lane_end,
    })
}

/// How BK-PBS plans each agent of a scene: the M-A* request of its current state, continuing
/// the lane change it has under way, its starts passing `guard`. Each agent's first moves are
/// kept for the round (every search of it starts from the same state), and so is every answer
/// (the same search asked again is looked up: [`SearchMemo`]).
pub struct SceneRequests<'a> {
    scene: &'a Scene,
    lane_changes: &'a LaneChanges,
    dt: f64,
    guard: Option<&'a dyn StartGuard>,
    first_moves: Vec<FirstMoves>,
    memo: SearchMemo,
}

impl<'a> SceneRequests<'a> {
    /// The requests of `scene`'s agents, with the changes under way in `lane_changes`, planning
    /// steps of `dt` (s) and lane-change starts checked by `guard` (none: unchecked).
    pub fn new(
        scene: &'a Scene,
        lane_changes: &'a LaneChanges,
        dt: f64,
        guard: Option<&'a dyn StartGuard>,
    ) -> Self {
        let first_moves = scene
            .vehicles
            .iter()
            .map(|_| FirstMoves::default())
            .collect();
        SceneRequests {
            scene,
            lane_changes,
            dt,
            guard,
            first_moves,
            memo: SearchMemo::default(),
        }
    }
}

impl RequestFor for SceneRequests<'_> {
    fn plan(
        &self,
        planner: &Mastar,
        agent: usize,
        obstacles: &[&Trajectory],
    ) -> Result<Plan, NoPlan> {
        self.memo.answer(agent, obstacles, || {
            let req = self
                .lane_changes
                .request(self.scene, agent, self.dt, obstacles, self.guard);
            planner.plan(&Request {
                first_moves: Some(&self.first_moves[agent]),
                ..req
            })
        })
    }

    fn fallback(&self, planner: &Mastar, agent: usize, horizon: usize) -> Trajectory {
        let req = self
            .lane_changes
            .request(self.scene, agent, self.dt, &[], self.guard);
        planner.fallback_trajectory(&req, horizon)
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

    use crate::model::scene::{Kind, VehicleState};
    use crate::planner::mastar::{FirstMove, Mastar};
    use crate::planner::pbs::RequestFor;

    fn planner() -> Mastar {
        Mastar::on_paper_road()
    }

    fn ramp_cav(s: f64, lane: i32, lateral: f64, speed: f64) -> VehicleState {
        VehicleState {
            lateral,
            ..VehicleState::on_lane("ramp.1", Kind::Cav, Origin::Ramp, s, lane, speed)
        }
    }

    #[test]
    fn a_merge_under_way_keeps_a_continuation_plan() {
        // R1 regression: a ramp CAV two steps into its merge (still on the merge lane, moving
        // left) had no plan at all, because the search took the merge for finished and refused
        // every state overlapping the merge lane; it braked while SUMO moved it sideways.
        let scene = Scene::on_paper_road(10.0, vec![ramp_cav(250.0, 0, 1.8, 25.0)]);
        let mut lc = LaneChanges::default();
        lc.start(&scene.vehicles[0].id, 9.6, 1.0, 1);
        let req = lc.request(&scene, 0, 0.2, &[], None);
        assert!(req.must_merge && req.ongoing.is_some());
        let plan = planner().plan(&req).expect("the merge continues");
        assert_eq!(plan.first, FirstMove::Continue);
        // Past the lane's centre line SUMO reports the target lane with a negative offset.
        let scene = Scene::on_paper_road(10.0, vec![ramp_cav(250.0, 1, -1.5, 25.0)]);
        let req = lc.request(&scene, 0, 0.2, &[], None);
        assert!(req.must_merge);
        assert!(planner().plan(&req).is_ok());
    }

    #[test]
    fn no_lane_change_starts_on_the_ramp_edge() {
        // R3 regression: a change started while the front was still on SUMO's one-lane ramp
        // edge was never sent, yet the controller continued it for four steps of braking.
        let m = planner();
        let lc = LaneChanges::default();
        for front in [140.0, 146.0, 149.9] {
            let scene = Scene::on_paper_road(0.0, vec![ramp_cav(front - 2.5, 0, 0.0, 30.0)]);
            let plan = m.plan(&lc.request(&scene, 0, 0.2, &[], None)).unwrap();
            assert!(
                !matches!(plan.first, FirstMove::Start(p) if p.is_lane_change()),
                "front at {front}: {:?}",
                plan.first
            );
        }
        // On the acceleration lane with the main road free, the merge starts at once.
        let scene = Scene::on_paper_road(0.0, vec![ramp_cav(200.0, 0, 0.0, 30.0)]);
        let plan = m.plan(&lc.request(&scene, 0, 0.2, &[], None)).unwrap();
        assert!(matches!(plan.first, FirstMove::Start(p) if p.is_lane_change()));
    }

    #[test]
    fn without_a_plan_others_see_the_brake_and_the_lane_change_completing() {
        // What PBS checks the other agents against when a CAV has no plan is what it will do:
        // brake at the emergency deceleration while SUMO completes its merge (it once was a
        // constant-speed, fixed-lateral guess).
        let scene = Scene::on_paper_road(10.0, vec![ramp_cav(250.0, 0, 1.8, 25.0)]);
        let mut lc = LaneChanges::default();
        lc.start(&scene.vehicles[0].id, 9.6, 1.0, 1);
        let requests = SceneRequests::new(&scene, &lc, 0.2, None);
        let m = planner();
        let t = requests.fallback(&m, 0, 20);
        assert_eq!(t.poses.len(), 21);
        assert!(
            (t.poses[1].speed - (25.0 - 6.0 * 0.2)).abs() < 0.05,
            "{:?}",
            t.poses[1]
        );
        assert!(
            t.poses[20].speed < 25.0 - 6.0 * 4.0 + 0.05,
            "braked for 4 s"
        );
        let y = |k: usize| t.poses[k].y;
        // Sideways on SUMO's schedule (3 steps left), tracked by the bicycle model's steering.
        assert!(
            y(1) > y(0) && y(3) > 4.0 && (y(20) - 4.5).abs() < 0.05,
            "{:?}",
            t.poses
        );
    }
}
