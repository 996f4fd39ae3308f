//! M-A*'s tests: plans on hand-built scenes of the paper road.

use super::*;
use crate::config::{LowSpeedLaneChanges, PlannerSettings};
use crate::model::braking::{stays_clear, Braking};
use crate::model::road::Road;
use crate::model::scene::Scene;
use crate::model::scene::{Following, Limits};
use crate::planner::guard::{Guard, StartGuard};
use crate::planner::primitives::Primitive;

fn planner() -> Mastar {
    Mastar::on_paper_road()
}

/// A vehicle driving at constant speed on a lane centre.
fn other(s: f64, lane: i32, speed: f64) -> Trajectory {
    Trajectory::straight(s, lane as f64 * 4.5, speed, 20, 0.2)
}

fn request<'a>(
    m: &Mastar,
    s: f64,
    lane: i32,
    speed: f64,
    must_merge: bool,
    obstacles: &'a [&'a Trajectory],
) -> Request<'a> {
    Request {
        start: lane_state(&m.road, s, lane, speed),
        lane,
        ongoing: None,
        must_merge,
        length: 5.0,
        width: 2.0,
        max_speed: f64::INFINITY,
        limits: crate::model::scene::Limits::NONE,
        obstacles,
        guard: None,
        first_moves: None,
        merger: None,
    }
}

fn collision_free(plan: &Plan, obstacles: &[&Trajectory]) -> bool {
    (1..plan.trajectory.poses.len()).all(|k| {
        obstacles
            .iter()
            .all(|o| !crate::model::trajectory::bodies_overlap(&plan.trajectory, o, k, 0.2))
    })
}

#[test]
fn empty_road_reaches_the_phase1_goal_at_full_throttle() {
    let m = planner();
    let plan = m.plan(&request(&m, 20.0, 1, 28.0, false, &[])).unwrap();
    assert_eq!(plan.phase, Phase::Forward);
    assert_eq!(plan.first, FirstMove::Start(Primitive::Accelerate));
    let end = plan.trajectory.poses.last().unwrap();
    assert!(end.s - 20.0 >= 70.0 && end.y == 4.5, "{end:?}");
    assert!(plan.primitives.iter().all(|p| *p == Primitive::Accelerate));
    assert!(
        plan.expanded < 100,
        "A* should dive straight to the goal: {}",
        plan.expanded
    );
    assert!((plan.next_speed() - 28.4).abs() < 1e-9);
}

#[test]
fn slow_leader_makes_it_change_lane() {
    let m = planner();
    // 55 m ahead at 20 m/s: safe to follow for now, but slower than the CAV wants.
    let leader = other(80.0, 1, 20.0);
    let obs = [&leader];
    let plan = m.plan(&request(&m, 20.0, 1, 28.0, false, &obs)).unwrap();
    assert_eq!(plan.phase, Phase::Forward);
    let changes: Vec<_> = std::iter::once(plan.first)
        .filter_map(|f| match f {
            FirstMove::Start(p) => Some(p),
            FirstMove::Continue => None,
        })
        .chain(plan.primitives.iter().copied())
        .filter(|p| p.is_lane_change())
        .collect();
    assert_eq!(changes, vec![Primitive::LaneChangeLeft], "{plan:?}");
    assert!(collision_free(&plan, &obs));
    assert!(plan.trajectory.poses.last().unwrap().y == 9.0);
}

#[test]
fn a_lane_change_possible_now_is_not_put_off() {
    // The slow leader of `slow_leader_makes_it_change_lane`: changing now and a second later
    // reach the goal equally soon; only the deferral penalty makes the plan change now (the
    // first move, the one executed), instead of promising a change the next round may put
    // off again.
    let leader = other(80.0, 1, 20.0);
    let obs = [&leader];
    let first_move = |deferral: f64| {
        let settings = PlannerSettings {
            lane_change_deferral_penalty: deferral,
            ..PlannerSettings::default()
        };
        let m = Mastar::new(&settings, Road::paper_default(), 0.2, 1.0, 35.0);
        m.plan(&request(&m, 20.0, 1, 28.0, false, &obs))
            .unwrap()
            .first
    };
    assert_eq!(
        first_move(PlannerSettings::default().lane_change_deferral_penalty),
        FirstMove::Start(Primitive::LaneChangeLeft)
    );
    assert_ne!(first_move(0.0), FirstMove::Start(Primitive::LaneChangeLeft));
}

fn with_slides(slides: LowSpeedLaneChanges) -> Mastar {
    let settings = PlannerSettings {
        low_speed_lane_changes: slides,
        ..PlannerSettings::default()
    };
    Mastar::new(&settings, Road::paper_default(), 0.2, 1.0, 35.0)
}

fn starts_lane_change(plan: &Plan) -> bool {
    matches!(plan.first, FirstMove::Start(p) if p.is_lane_change())
}

#[test]
fn a_standing_ramp_cav_merges_by_a_slide_only_where_allowed() {
    // Standing 5 m before the lane end, the main lane free: below the bicycle's minimum
    // lane-change speed only a slide (as SUMO executes it) gets it out.
    for (slides, merges) in [
        (LowSpeedLaneChanges::Merge, true),
        (LowSpeedLaneChanges::All, true),
        (LowSpeedLaneChanges::Off, false),
    ] {
        let m = with_slides(slides);
        let plan = m.plan(&request(&m, 322.5, 0, 0.0, true, &[])).unwrap();
        assert_eq!(starts_lane_change(&plan), merges, "{slides:?}: {plan:?}");
    }
}

#[test]
fn a_standing_ramp_cav_merges_in_front_of_traffic_that_can_stop_for_it() {
    // Standing at the lane end; a car on the main lane at 25 m/s, predicted to keep its
    // speed. 80 m back it can stop behind the CAV braking at 5 m/s² (the cut-in rule takes
    // it to, as RSS does), so the CAV slides in now; 40 m back it cannot, so the CAV waits.
    let m = Mastar::from_config(&crate::config::Config::default(), Road::paper_default());
    for (back, merges) in [(80.0, true), (40.0, false)] {
        let follower = other(322.5 - back, 1, 25.0);
        let obs = [&follower];
        let plan = m.plan(&request(&m, 322.5, 0, 0.0, true, &obs)).unwrap();
        assert_eq!(starts_lane_change(&plan), merges, "{back} m: {plan:?}");
    }
}

#[test]
fn a_slow_main_road_cav_slides_only_when_all_slides_are_allowed() {
    // Standing 3 m behind a standing car, lane 2 free: only a slide gets it going.
    let queue = other(183.0, 1, 0.0);
    let obs = [&queue];
    for (slides, changes) in [
        (LowSpeedLaneChanges::Merge, false),
        (LowSpeedLaneChanges::All, true),
    ] {
        let m = with_slides(slides);
        let plan = m.plan(&request(&m, 175.0, 1, 0.0, false, &obs)).unwrap();
        assert_eq!(starts_lane_change(&plan), changes, "{slides:?}: {plan:?}");
    }
}

/// A guard that admits no lane-change start.
struct Closed;

impl StartGuard for Closed {
    fn admits(&self, _: &Scene, _: usize, lane_offset: i32, _: f64) -> bool {
        lane_offset == 0
    }
}

/// A guard that admits no first step faster than 25 m/s.
struct SpeedCap;

impl StartGuard for SpeedCap {
    fn admits(&self, _: &Scene, _: usize, _: i32, first_speed: f64) -> bool {
        first_speed <= 25.0
    }
}

#[test]
fn the_first_move_is_one_the_guard_admits() {
    // Free road at 26 m/s: the plan would hold or gain speed; capped, its first step slows.
    let m = planner();
    let free = request(&m, 20.0, 1, 26.0, false, &[]);
    let first = |p: &crate::planner::mastar::Plan| p.trajectory.poses[1].speed;
    assert!(first(&m.plan(&free).unwrap()) > 25.0);
    let scene = Scene::on_paper_road(0.0, Vec::new());
    let capped = Request {
        guard: Some(Guard {
            check: &SpeedCap,
            scene: &scene,
            agent: 0,
        }),
        ..free
    };
    assert!(first(&m.plan(&capped).unwrap()) <= 25.0);
}

#[test]
fn a_guard_that_refuses_the_start_keeps_the_lane_now() {
    // The slow leader of `slow_leader_makes_it_change_lane`: the plan changes lanes at once,
    // unless the guard (the shield, in the controllers) refuses; then it waits in lane.
    let m = planner();
    let leader = other(80.0, 1, 20.0);
    let obs = [&leader];
    let open = request(&m, 20.0, 1, 28.0, false, &obs);
    assert!(starts_lane_change(&m.plan(&open).unwrap()));
    let scene = Scene::on_paper_road(0.0, Vec::new());
    let closed = Request {
        guard: Some(Guard {
            check: &Closed,
            scene: &scene,
            agent: 0,
        }),
        ..open
    };
    let plan = m.plan(&closed).unwrap();
    assert!(!starts_lane_change(&plan), "{plan:?}");
    assert!(plan.primitives.iter().any(|p| p.is_lane_change()));
}

#[test]
fn both_lanes_blocked_falls_back_to_braking() {
    let m = planner();
    // Slow cars 70 m ahead in both lanes: at 2 m/s² the CAV cannot shed 15 m/s before the
    // safe gap is gone, at 6 m/s² it can.
    let (a, b) = (other(20.0 + 75.0, 1, 15.0), other(20.0 + 75.0, 2, 15.0));
    let obs = [&a, &b];
    let plan = m.plan(&request(&m, 20.0, 1, 30.0, false, &obs)).unwrap();
    assert_eq!(plan.phase, Phase::Fallback);
    assert!(
        plan.primitives.contains(&Primitive::EmergencyBrake)
            || plan.first == FirstMove::Start(Primitive::EmergencyBrake)
    );
    assert!(collision_free(&plan, &obs));
    assert!(plan.expanded > 0);
}

#[test]
fn unavoidable_crash_has_no_plan() {
    let m = planner();
    let (a, b) = (other(30.0, 1, 5.0), other(30.0, 2, 5.0));
    let obs = [&a, &b];
    assert!(m.plan(&request(&m, 20.0, 1, 30.0, false, &obs)).is_err());
}

#[test]
fn ramp_cav_merges_before_the_zone_ends() {
    let m = planner();
    // On the acceleration lane 60 m before its end, with a car in the main lane beside it.
    let beside = other(268.0, 1, 25.0);
    let obs = [&beside];
    let plan = m.plan(&request(&m, 270.0, 0, 25.0, true, &obs)).unwrap();
    assert!(collision_free(&plan, &obs));
    let end = plan.trajectory.poses.last().unwrap();
    assert!((end.y - 4.5).abs() < 1e-9, "ends merged: {end:?}");
    for p in &plan.trajectory.poses {
        if p.y < 2.25 - 1.0 {
            assert!(
                p.s + 2.5 <= 330.0,
                "still in the ending lane past its end: {p:?}"
            );
        }
    }
}

#[test]
fn ramp_cav_on_a_blocked_lane_end_brakes_instead_of_leaving_the_road() {
    let m = planner();
    // 20 m before the lane end at 15 m/s with the main lane beside it blocked by a queue.
    let queue: Vec<Trajectory> = (0..12)
        .map(|k| other(270.0 + 7.0 * k as f64, 1, 0.0))
        .collect();
    let obs: Vec<&Trajectory> = queue.iter().collect();
    let plan = m.plan(&request(&m, 302.5, 0, 15.0, true, &obs)).unwrap();
    assert!(
        plan.trajectory
            .poses
            .iter()
            .all(|p| p.s + 2.5 <= 330.0 + 1e-9 && p.y == 0.0),
        "{plan:?}"
    );
    // It can still stop before the end from where the plan leaves it.
    let last = plan.trajectory.poses.last().unwrap();
    assert!(
        last.speed * last.speed / 12.0 <= 330.0 - (last.s + 2.5) + 1e-9,
        "{last:?}"
    );
    assert!(collision_free(&plan, &obs));
}

#[test]
fn main_road_cav_never_enters_the_acceleration_lane() {
    let m = planner();
    let leader = other(55.0 + 150.0, 1, 15.0);
    let left = other(30.0 + 150.0, 2, 28.0);
    let obs = [&leader, &left];
    // Boxed in (a slower leader ahead, a car beside on the left) the CAV must brake rather
    // than dodge right into the acceleration lane. A plan must exist: with the leader 10 m
    // closer and slower no plan does, and the assertion below would check nothing.
    let plan = m
        .plan(&request(&m, 170.0, 1, 28.0, false, &obs))
        .expect("braking in lane is always available here");
    assert!(plan.trajectory.poses.iter().all(|p| p.y > 2.25));
    assert!(
        plan.trajectory.poses.last().unwrap().s < 170.0 + 28.0 * 4.0,
        "it slowed down"
    );
}

#[test]
fn the_check_horizon_is_the_horizon_plus_one_lane_change() {
    // What the controllers predicted over before asking `check_horizon`: it must not change.
    let config = crate::config::Config::default();
    let m = Mastar::from_config(&config, Road::paper_default());
    let lane_change = config.scenario.lane_change_steps();
    assert_eq!(m.check_horizon(), config.planner.horizon + lane_change);
    assert_eq!(m.check_horizon(), 20);
}

/// A truck's own top speed bounds its plan: it never accelerates past it, and one above it
/// (as it entered) may hold its speed.
#[test]
fn a_cav_is_planned_within_its_own_top_speed() {
    let m = Mastar::on_paper_road();
    let free = request(&m, 100.0, 2, 20.0, false, &[]);
    let fast = m.plan(&free).unwrap();
    assert!(fast.trajectory.poses.iter().any(|p| p.speed > 22.5));
    let truck = Request {
        max_speed: 22.22,
        ..free.clone()
    };
    let plan = m.plan(&truck).unwrap();
    assert!(plan
        .trajectory
        .poses
        .iter()
        .all(|p| p.speed <= 22.22 + 1e-6));
    let above = Request {
        start: lane_state(&m.road, 100.0, 2, 25.0),
        ..truck
    };
    let plan = m.plan(&above).unwrap();
    assert!(plan.trajectory.poses.iter().all(|p| p.speed <= 25.0 + 1e-6));
}

/// A CAV's own accelerations are what its plan accelerates at, `[planner] accel` unset: the
/// paper's 2 m/s² for a vehicle with no limit of its own (the paper's demand), a car type's
/// 2.6 and a truck type's 1.3 for theirs (a user's scenario). Set, it caps them: 2 leaves the
/// car at 2 and the truck at 1.3.
#[test]
fn a_cav_is_planned_within_its_own_accelerations() {
    let rate = |plan: &Plan| {
        let poses = &plan.trajectory.poses;
        poses
            .windows(2)
            .map(|w| (w[1].speed - w[0].speed) / 0.2)
            .fold(f64::MIN, f64::max)
    };
    let limits = |accel| crate::model::scene::Limits {
        accel,
        decel: 4.0,
        emergency_decel: 7.0,
        following: None,
    };
    let mut capped = crate::config::Config::default();
    capped.planner.accel = Some(2.0);
    for (m, car_rate) in [
        (Mastar::on_paper_road(), 2.6),
        (Mastar::from_config(&capped, Road::paper_default()), 2.0),
    ] {
        let free = request(&m, 100.0, 2, 20.0, false, &[]);
        let paper = m.plan(&free).unwrap();
        assert!((rate(&paper) - 2.0).abs() < 1e-9, "{}", rate(&paper));
        let as_car = Request {
            limits: limits(2.6),
            ..free.clone()
        };
        let car = m.plan(&as_car).unwrap();
        assert!((rate(&car) - car_rate).abs() < 1e-9, "{}", rate(&car));
        let as_truck = Request {
            limits: limits(1.3),
            ..free.clone()
        };
        let truck = m.plan(&as_truck).unwrap();
        assert!((rate(&truck) - 1.3).abs() < 1e-9, "{}", rate(&truck));
    }
}

/// A ramp CAV on the outer lane of a two-lane ramp (frame lane −1 beside the acceleration lane,
/// both ending at 330 m), the main road's lane 1 a solid platoon beside it: it cannot merge
/// within the horizon, but it moves to the inner lane, one lane change fewer still owed. With
/// a plan left unmerged charged once whatever it still owes, it stayed, and a bk-mastar CAV on
/// the two-lane gain layout drove 800 m on the outer lane and changed twice from a stand.
#[test]
fn an_outer_ramp_lane_cav_moves_inward_when_it_cannot_merge_yet() {
    let mut road = Road::paper_default();
    let mut outer = road.zones[0];
    outer.lane = -1;
    road.zones.push(outer);
    let m = Mastar::from_config(&crate::config::Config::default(), road);
    let platoon: Vec<Trajectory> = (0..40)
        .map(|k| other(100.0 + 7.0 * k as f64, 1, 25.0))
        .collect();
    let obs: Vec<&Trajectory> = platoon.iter().collect();
    let plan = m.plan(&request(&m, 160.0, -1, 25.0, true, &obs)).unwrap();
    assert!(collision_free(&plan, &obs));
    let end = plan.trajectory.poses.last().unwrap();
    assert!(end.y.abs() < 1e-9, "ends on the inner lane: {end:?}");
    assert_eq!(m.road.lanes_to_main(-1), 2);
    assert_eq!(m.road.lanes_to_main(0), 1);
    assert_eq!(m.road.lanes_to_main(2), 0);
}

/// A ramp CAV at 8 m/s on the acceleration lane beside a lane 1 packed at 5 m/s: without gap
/// seeking its plan runs on past the slow lane (no gap to merge into at its speed); with it the
/// plan keeps behind the nearest lane-1 vehicle ahead of it, as if that one drove in its lane.
#[test]
fn gap_seeking_keeps_a_ramp_cav_behind_the_target_lane_vehicle_ahead() {
    let zone = Road::paper_default().zones[0];
    let s = zone.start + 20.0;
    // Lane 1: a car every 11 m (6 m gaps) from 30 m behind the CAV to the lane's end.
    let lane_1: Vec<Trajectory> = (0..)
        .map(|k| s - 30.0 + 11.0 * f64::from(k))
        .take_while(|&x| x < zone.end)
        .map(|x| other(x, 1, 5.0))
        .collect();
    let obs: Vec<&Trajectory> = lane_1.iter().collect();
    let leader = (lane_1.iter())
        .find(|t| t.poses[0].s - 2.5 > s + 2.5)
        .unwrap();
    let plan_with = |gap_seeking: bool| {
        let settings = PlannerSettings {
            gap_seeking: Some(gap_seeking),
            ..PlannerSettings::default()
        };
        let m = Mastar::new(&settings, Road::paper_default(), 0.2, 1.0, 35.0);
        m.plan(&request(&m, s, 0, 8.0, true, &obs)).unwrap()
    };
    let behind_leader = |plan: &Plan| {
        (plan.trajectory.poses.iter().enumerate())
            .all(|(k, p)| p.s + 2.5 <= leader.poses[k].s - 2.5)
    };
    assert!(!behind_leader(&plan_with(false)));
    let seeking = plan_with(true);
    assert!(behind_leader(&seeking), "{seeking:?}");
    assert!(collision_free(&seeking, &obs));
}

/// Unset, gap seeking is on for a scenario of the user's own (`scenario.sumocfg`) and off on
/// the paper's demand; set, it holds on both.
#[test]
fn gap_seeking_unset_follows_the_scenario() {
    let seeks = |gap_seeking: Option<bool>, sumocfg: Option<&str>| {
        let mut config = crate::config::Config::default();
        config.planner.gap_seeking = gap_seeking;
        config.scenario.sumocfg = sumocfg.map(Into::into);
        Mastar::from_config(&config, Road::paper_default()).seeks_gaps
    };
    assert!(seeks(None, Some("ramp.sumocfg")));
    assert!(!seeks(None, None));
    assert!(!seeks(Some(false), Some("ramp.sumocfg")));
    assert!(seeks(Some(true), None));
    assert!(!Mastar::on_paper_road().seeks_gaps);
}

/// A ramp CAV at 20 m/s on the acceleration lane, a car 40 m behind it in lane 1 at 27.7 m/s,
/// the start guard refusing a merge now. The safety rule alone has that car braking from the
/// plan's start, so a merge in front of it a few steps on passes; the safety shield, when that
/// step comes, has it brake only then (at 5 m/s² while the CAV may brake at 6) and refuses. With
/// gap seeking every merge the plan starts later is one the shield's check admits when it comes.
#[test]
fn gap_seeking_plans_no_later_merge_the_shield_would_refuse() {
    let zone = Road::paper_default().zones[0];
    let s = zone.start + 10.0;
    let follower = other(s - 40.0, 1, 27.7);
    let obs = [&follower];
    let scene = Scene::on_paper_road(0.0, Vec::new());
    let plan_with = |gap_seeking: bool| {
        let mut config = crate::config::Config::default();
        config.planner.gap_seeking = Some(gap_seeking);
        let m = Mastar::from_config(&config, Road::paper_default());
        let req = Request {
            guard: Some(Guard {
                check: &Closed,
                scene: &scene,
                agent: 0,
            }),
            ..request(&m, s, 0, 20.0, true, &obs)
        };
        (m.plan(&req).unwrap(), m)
    };
    // The step the merge starts at: the last one still on the acceleration lane's centre.
    let merge_start = |plan: &Plan| (plan.trajectory.poses.iter()).position(|p| p.y.abs() > 1e-6);
    let shield_admits = |plan: &Plan, m: &Mastar, k: usize| {
        let (me, f) = (&plan.trajectory.poses[k], follower.at(k, 0.2));
        let back = Braking {
            speed: f.speed,
            first: None,
            decel: m.rule.follower_brake,
            reach: f64::INFINITY,
        };
        let front = Braking {
            speed: me.speed,
            first: Some(me.speed),
            decel: m.rule.brake,
            reach: f64::INFINITY,
        };
        let gap = (me.s - 2.5) - (f.s + 2.5);
        f.s > me.s || stays_clear(back, front, gap, m.rule.margin_long, 0.2)
    };
    let (without, m) = plan_with(false);
    let k = merge_start(&without).expect("without gap seeking the plan merges");
    assert!(without.trajectory.poses[k].s > follower.at(k, 0.2).s);
    assert!(!shield_admits(&without, &m, k - 1), "{without:?}");
    let (with, m) = plan_with(true);
    // It speeds up first, shrinking the braking distances' difference, and moves over in
    // front of the car once the shield will let it.
    let k = merge_start(&with).expect("with gap seeking the plan merges too");
    assert!(with.trajectory.poses[k].s > follower.at(k, 0.2).s);
    assert!(shield_admits(&with, &m, k - 1), "{with:?}");
}

/// The bumper gap from a planned 5 m CAV to `merger` (5 m, driving on at its speed and stopping
/// at its lane's end) at each step of `plan`.
fn gaps_behind(plan: &Plan, merger: Merger) -> Vec<f64> {
    let stop = merger.lane_end - 0.5 * merger.length;
    (plan.trajectory.poses.iter().enumerate())
        .map(|(k, p)| (merger.s + merger.speed * 0.2 * k as f64).min(stop) - 2.5 - (p.s + 2.5))
        .collect()
}

/// A main-road CAV at 25 m/s in lane 1, a ramp HDV at 20 m/s ahead of it on the acceleration
/// lane. With courtesy the CAV keeps the gap SUMO asks of the merger's new follower behind it
/// (2.5 m + 1 s at its speed), as if it drove in lane 1 already; too close to leave it by
/// braking comfortably, it plans as without.
#[test]
fn courtesy_leaves_a_ramp_hdv_ahead_the_gap_sumo_asks_for() {
    let zone = Road::paper_default().zones[0];
    let s = zone.start + 10.0;
    let plan_with = |courtesy: bool, gap: f64| {
        let settings = PlannerSettings {
            courtesy: Some(courtesy),
            ..PlannerSettings::default()
        };
        let m = Mastar::new(&settings, Road::paper_default(), 0.2, 1.0, 35.0);
        let merger = Merger {
            s: s + 5.0 + gap,
            speed: 20.0,
            length: 5.0,
            width: 2.0,
            lane_end: zone.end,
        };
        let req = Request {
            merger: Some(merger),
            ..request(&m, s, 1, 25.0, false, &[])
        };
        (m.plan(&req).unwrap(), merger)
    };
    let gaps = |plan: &Plan, merger: Merger| gaps_behind(plan, merger);
    let sumo_gap = 2.5 + 20.0;
    let (polite, merger) = plan_with(true, 40.0);
    let (rude, _) = plan_with(false, 40.0);
    assert!(
        gaps(&polite, merger).iter().all(|&g| g >= sumo_gap - 0.5),
        "{polite:?}"
    );
    assert!(
        gaps(&rude, merger).iter().any(|&g| g < sumo_gap - 0.5),
        "{rude:?}"
    );
    // 12 m behind at 5 m/s faster: braking at 2 m/s² to 20 m/s costs 6.25 m, so no.
    let (close, _) = plan_with(true, 12.0);
    let (close_rude, _) = plan_with(false, 12.0);
    assert_eq!(close.trajectory.poses, close_rude.trajectory.poses);
}

/// The courtesy gap is the CAV type's own (`tau`, `minGap`, read from SUMO), SUMO's defaults
/// only where the CAV has none: 50 m behind a merger 5 m/s slower, with `tau` 2 s it keeps
/// 2.5 m + 2 s behind it at 20 m/s; with SUMO's 1 s it closes in to about 35 m.
#[test]
fn courtesy_keeps_the_cav_types_own_following_gap() {
    let zone = Road::paper_default().zones[0];
    let s = zone.start + 10.0;
    let settings = PlannerSettings {
        courtesy: Some(true),
        ..PlannerSettings::default()
    };
    let m = Mastar::new(&settings, Road::paper_default(), 0.2, 1.0, 35.0);
    let merger = Merger {
        s: s + 5.0 + 50.0,
        speed: 20.0,
        length: 5.0,
        width: 2.0,
        lane_end: zone.end,
    };
    // A car beside it in lane 2 keeps it in lane 1.
    let beside = other(s, 2, 25.0);
    let obs = [&beside];
    let plan = |following: Option<Following>| {
        let base = request(&m, s, 1, 25.0, false, &obs);
        let limits = Limits {
            following,
            ..base.limits
        };
        let req = Request {
            merger: Some(merger),
            limits,
            ..base
        };
        m.plan(&req).unwrap()
    };
    let least_gap = |plan: &Plan| {
        gaps_behind(plan, merger)
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    };
    let patient = Following {
        tau: 2.0,
        min_gap: 2.5,
    };
    let (own, default) = (plan(Some(patient)), plan(None));
    assert!(least_gap(&own) >= patient.gap_at(20.0) - 0.5, "{own:?}");
    assert!(
        least_gap(&default) < patient.gap_at(20.0) - 0.5,
        "{default:?}"
    );
    assert!(least_gap(&default) >= Following::SUMO_DEFAULT.gap_at(20.0) - 0.5);
}
