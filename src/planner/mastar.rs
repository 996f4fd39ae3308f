//! M-A*: multi-phase A* over motion primitives for one CAV among predicted other vehicles
//! (paper section IV.A).
//!
//! Nodes are CAV states at primitive boundaries; edges are primitives rolled out with the bicycle
//! model; other vehicles' trajectories are dynamic obstacles checked box against box at every
//! step; the road (lanes, the acceleration lane's end, the barrier between ramp and main road
//! before the merge zone) is a static obstacle. The closed set bins nodes by
//! (step, lane, s, v). The cost of a plan is its duration in steps until the goal; a plan that
//! reaches the horizon first is completed by the free-flow time of the distance it still lacks,
//! so faster plans win either way and the heuristic (the free-flow time, capped by the steps left
//! to the horizon) never overestimates.
//!
//! Phase 1 (forward): accelerate, idle, decelerate and the lane changes, goal distance d.
//! Phase 2 (fallback), if phase 1 fails: decelerate, emergency brake and the lane changes, goal
//! distance d', lane changes penalised so braking is preferred. Goals: a main-road CAV must get
//! d ahead on a main-road lane; a ramp CAV must reach a main-road lane (within the merge zone).

use crate::config::PlannerSettings;
use crate::model::kinematics::{free_flow_time, BicycleState};
use crate::model::math::Point;
use crate::model::road::{Road, MAIN_LANES, MERGE_LANE};
use crate::model::trajectory::{Pose, Trajectory};
use crate::planner::primitives::{Library, Primitive, Throttle};
use crate::planner::safety::{Body, SafetyRule};
use crate::planner::search::{astar, Stop};

/// Which phase produced a plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    Forward,
    Fallback,
}

/// What a plan's first step does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FirstMove {
    /// Start this primitive now.
    Start(Primitive),
    /// Go on with the lane change already under way (no new lateral command).
    Continue,
}

/// A lane change the CAV is executing: it reaches `target_lane` after `steps_left` more steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OngoingLaneChange {
    pub target_lane: i32,
    pub steps_left: usize,
}

/// One planning problem.
#[derive(Debug, Clone)]
pub struct Request<'a> {
    /// Centre, heading and path speed in the road frame.
    pub start: BicycleState,
    /// The lane the CAV is in (its target lane when a change is under way).
    pub lane: i32,
    pub ongoing: Option<OngoingLaneChange>,
    /// A ramp CAV that has not merged yet: its goal is the main road.
    pub must_merge: bool,
    pub length: f64,
    pub width: f64,
    /// Other vehicles' trajectories, step 0 = now.
    pub obstacles: &'a [&'a Trajectory],
}

/// A plan found by M-A*.
#[derive(Debug, Clone)]
pub struct Plan {
    pub first: FirstMove,
    /// The primitives after the first move.
    pub primitives: Vec<Primitive>,
    /// The CAV's planned poses, step 0 = now.
    pub trajectory: Trajectory,
    pub phase: Phase,
    /// Nodes expanded over both phases.
    pub expanded: usize,
    /// Cost in steps (with the terminal estimate).
    pub cost: f64,
}

impl Plan {
    /// Speed along the road at the end of the first step: the speed to command.
    pub fn next_speed(&self) -> f64 {
        let p = self
            .trajectory
            .poses
            .get(1)
            .unwrap_or(&self.trajectory.poses[0]);
        p.speed * p.heading.cos()
    }
}

/// No plan in either phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NoPlan {
    pub expanded: usize,
}

#[derive(Debug, Clone)]
struct Node {
    step: usize,
    lane: i32,
    state: BicycleState,
    /// The move that led here (`None` at the root).
    via: Option<FirstMove>,
    /// States at each step of that move.
    segment: Vec<BicycleState>,
    terminal: bool,
    /// The goal is reached here and coasting on from here stays safe to the check horizon.
    goal: bool,
}

/// The single-CAV planner: primitives, settings and the road.
#[derive(Debug, Clone)]
pub struct Mastar {
    pub library: Library,
    pub settings: PlannerSettings,
    pub road: Road,
    pub v_max: f64,
    pub rule: SafetyRule,
}

impl Mastar {
    /// The planner of a configuration on `road`.
    pub fn from_config(config: &crate::config::Config, road: Road) -> Self {
        let s = &config.scenario;
        Mastar::new(&config.planner, road, s.dt, s.lane_change_duration, s.v_max)
    }

    /// A planner for steps of `dt` on `road`, lane changes taking `lane_change_duration`.
    pub fn new(
        settings: &PlannerSettings,
        road: Road,
        dt: f64,
        lane_change_duration: f64,
        v_max: f64,
    ) -> Self {
        let mut library = Library::new(dt, road.lane_width, lane_change_duration, v_max);
        library.accel = settings.accel;
        library.decel = settings.decel;
        library.emergency_decel = settings.emergency_decel;
        library.min_lane_change_speed = settings.min_lane_change_speed;
        let library = Library::rebuilt(library);
        let rule = SafetyRule::new(settings, road.lane_width);
        Mastar {
            library,
            settings: settings.clone(),
            road,
            v_max,
            rule,
        }
    }

    fn lane_y(&self, lane: i32) -> f64 {
        lane as f64 * self.road.lane_width
    }

    /// Phase 1, then phase 2 if needed.
    pub fn plan(&self, req: &Request) -> Result<Plan, NoPlan> {
        let near: Vec<&Trajectory> = req
            .obstacles
            .iter()
            .copied()
            .filter(|t| (t.poses[0].s - req.start.pos.x).abs() < 200.0)
            .collect();
        let mut expanded = 0;
        for phase in [Phase::Forward, Phase::Fallback] {
            match self.search(req, &near, phase) {
                Ok(mut plan) => {
                    plan.expanded += expanded;
                    return Ok(plan);
                }
                Err(n) => expanded += n,
            }
        }
        Err(NoPlan { expanded })
    }

    fn search(
        &self,
        req: &Request,
        obstacles: &[&Trajectory],
        phase: Phase,
    ) -> Result<Plan, usize> {
        let set = &self.settings;
        let (primitives, goal_distance, budget, lc_penalty): (&[Primitive], f64, usize, f64) =
            match phase {
                Phase::Forward => (
                    &[
                        Primitive::Accelerate,
                        Primitive::Idle,
                        Primitive::Decelerate,
                        Primitive::LaneChangeLeft,
                        Primitive::LaneChangeRight,
                    ],
                    set.goal_distance,
                    set.phase1_budget,
                    set.phase1_lane_change_penalty,
                ),
                Phase::Fallback => (
                    &[
                        Primitive::Decelerate,
                        Primitive::EmergencyBrake,
                        Primitive::LaneChangeLeft,
                        Primitive::LaneChangeRight,
                    ],
                    set.fallback_goal_distance,
                    set.phase2_budget,
                    set.phase2_lane_change_penalty,
                ),
            };
        let s0 = req.start.pos.x;
        let horizon = set.horizon;
        let dt = self.library.dt;
        let steps_for = |remaining: f64, v: f64| -> f64 {
            free_flow_time(remaining, v, self.library.accel, self.v_max) / dt
        };
        let check_horizon = horizon + self.library.lane_change_steps;
        // Coasting on at constant speed from a goal or horizon node must stay safe up to the
        // horizon other vehicles are predicted (and BK-PBS checks conflicts) over, so a plan
        // never ends right behind a slower vehicle.
        let tail_safe = |st: &BicycleState, step: usize| -> bool {
            (step + 1..=check_horizon).all(|k| {
                let t = (k - step) as f64 * dt;
                let coast = BicycleState {
                    pos: Point::new(st.pos.x + st.speed * t, st.pos.y),
                    heading: 0.0,
                    speed: st.speed,
                };
                self.on_road(&coast, req) && self.safe(&coast, k, req, obstacles)
            })
        };
        let reached = |n: &Node| -> bool {
            if req.must_merge {
                MAIN_LANES.contains(&n.lane) && n.step > 0
            } else {
                n.state.pos.x - s0 >= goal_distance && MAIN_LANES.contains(&n.lane)
            }
        };
        // Remaining cost, estimated from below.
        let heuristic = |n: &Node| -> f64 {
            if n.terminal || n.goal {
                return 0.0;
            }
            let to_horizon = horizon.saturating_sub(n.step) as f64;
            let to_goal = if req.must_merge {
                let approach =
                    (self.road.merge_start - (n.state.pos.x - 0.5 * req.length)).max(0.0);
                approach / (self.v_max * dt) + self.library.lane_change_steps as f64
            } else {
                steps_for(
                    (goal_distance - (n.state.pos.x - s0)).max(0.0),
                    n.state.speed,
                )
            };
            to_goal.min(to_horizon)
        };
        // Cost charged when a plan reaches the horizon short of its goal.
        let terminal_cost = |n: &Node| -> f64 {
            let lacking = steps_for(
                (goal_distance - (n.state.pos.x - s0)).max(0.0),
                n.state.speed,
            );
            if req.must_merge && !MAIN_LANES.contains(&n.lane) {
                lacking + 5.0
            } else {
                lacking
            }
        };
        let root = Node {
            step: 0,
            lane: req.lane,
            state: req.start,
            via: None,
            segment: Vec::new(),
            terminal: false,
            goal: false,
        };
        let successors = |n: &Node| -> Vec<(Node, f64)> {
            let mut out = Vec::new();
            if n.terminal {
                return out;
            }
            let mut moves: Vec<(FirstMove, i32, Vec<BicycleState>)> = Vec::new();
            match (n.step, req.ongoing) {
                (0, Some(lc)) if lc.steps_left > 0 => {
                    let y0 = n.state.pos.y;
                    let y1 = self.lane_y(lc.target_lane);
                    let total = lc.steps_left as f64 * dt;
                    let seg = self.library.track(
                        &n.state,
                        Throttle::HoldForwardSpeed(n.state.speed * n.state.heading.cos()),
                        lc.steps_left,
                        |t| {
                            if t < total {
                                (y0 + (y1 - y0) * t / total, (y1 - y0) / total)
                            } else {
                                (y1, 0.0)
                            }
                        },
                    );
                    moves.push((FirstMove::Continue, lc.target_lane, seg));
                }
                _ => {
                    for &p in primitives {
                        if !self.library.available(p, &n.state) {
                            continue;
                        }
                        let lane = n.lane + p.lane_offset();
                        if !(MERGE_LANE..=MAIN_LANES[1]).contains(&lane) {
                            continue;
                        }
                        let seg = if n.step == 0 {
                            self.library.rollout(p, &n.state, self.lane_y(n.lane))
                        } else {
                            self.library.rollout_settled(p, &n.state)
                        };
                        moves.push((FirstMove::Start(p), lane, seg));
                    }
                }
            }
            for (mv, lane, seg) in moves {
                let ok = seg.iter().enumerate().all(|(k, st)| {
                    let step = n.step + k + 1;
                    self.on_road(st, req) && self.safe(st, step, req, obstacles)
                });
                if !ok {
                    continue;
                }
                let steps = seg.len();
                let mut state = *seg.last().expect("moves span at least one step");
                // Inside the search every node is settled on its lane (see rollout_settled); the
                // first move, which is what gets executed, is rolled out exactly.
                state.pos.y = self.lane_y(lane);
                state.speed *= state.heading.cos();
                state.heading = 0.0;
                let step = n.step + steps;
                let mut cost = steps as f64;
                if matches!(mv, FirstMove::Start(p) if p.is_lane_change()) {
                    cost += lc_penalty;
                }
                let mut next = Node {
                    step,
                    lane,
                    state,
                    via: Some(mv),
                    segment: seg,
                    terminal: false,
                    goal: false,
                };
                let ends = reached(&next) || step >= horizon;
                let tail_ok = ends && tail_safe(&next.state, step);
                if reached(&next) && tail_ok {
                    next.goal = true;
                    if !req.must_merge && state.speed > 0.0 {
                        // Charge the time the goal distance was actually passed, not the whole
                        // step.
                        let over = next.state.pos.x - s0 - goal_distance;
                        cost -= (over / (state.speed * dt)).clamp(0.0, 1.0 - 1e-9);
                    }
                } else if step >= horizon {
                    if !tail_ok {
                        continue;
                    }
                    next.terminal = true;
                    cost += terminal_cost(&next);
                }
                out.push((next, cost));
            }
            out
        };
        let (s_bin, v_bin) = (set.s_bin, set.v_bin);
        let key = |n: &Node| {
            (
                n.step,
                n.lane,
                (n.state.pos.x / s_bin).round() as i64,
                (n.state.speed / v_bin).round() as i64,
                n.terminal,
            )
        };
        let result = astar(
            root,
            successors,
            heuristic,
            |n| n.terminal || n.goal,
            key,
            budget,
        );
        if result.stop != Stop::Found || result.path.len() < 2 {
            return Err(result.expanded);
        }
        let mut poses = vec![pose(&req.start)];
        let mut prims = Vec::new();
        for n in &result.path[1..] {
            poses.extend(n.segment.iter().map(pose));
            if let Some(FirstMove::Start(p)) = n.via {
                prims.push(p);
            }
        }
        let first = result.path[1].via.expect("non-root nodes have a move");
        if matches!(first, FirstMove::Start(_)) {
            prims.remove(0);
        }
        Ok(Plan {
            first,
            primitives: prims,
            trajectory: Trajectory {
                poses,
                length: req.length,
                width: req.width,
            },
            phase,
            expanded: result.expanded,
            cost: result.cost,
        })
    }

    /// Whether the (un-inflated) body stays on drivable road.
    fn on_road(&self, st: &BicycleState, req: &Request) -> bool {
        let w = self.road.lane_width;
        let (sin, cos) = st.heading.sin_cos();
        let half_across = 0.5 * req.width * cos.abs() + 0.5 * req.length * sin.abs();
        let half_along = 0.5 * req.length * cos.abs() + 0.5 * req.width * sin.abs();
        let (y_lo, y_hi) = (st.pos.y - half_across, st.pos.y + half_across);
        let (s_lo, s_hi) = (st.pos.x - half_along, st.pos.x + half_along);
        const EPS: f64 = 0.05;
        if y_lo < -0.5 * w - EPS || y_hi > 2.5 * w + EPS {
            return false;
        }
        let in_merge_lane = y_lo < 0.5 * w - EPS;
        if in_merge_lane {
            // Only ramp vehicles use it, and only until it ends.
            if !req.must_merge || s_hi > self.road.merge_end {
                return false;
            }
            // Crossing between it and the main road only beside the acceleration lane.
            let crossing = y_hi > 0.5 * w + EPS;
            if crossing && s_lo < self.road.merge_start {
                return false;
            }
            // Fully in the lane, the CAV must still be able to stop before its end, or the plan
            // could leave it in a state from which the crash is certain.
            let stop = st.speed * st.speed / (2.0 * self.library.emergency_decel);
            if !crossing && stop > self.road.merge_end - s_hi + 1e-9 {
                return false;
            }
        }
        true
    }

    /// Whether the CAV at `st` at `step` is clear of every obstacle (see [`SafetyRule`]).
    fn safe(
        &self,
        st: &BicycleState,
        step: usize,
        req: &Request,
        obstacles: &[&Trajectory],
    ) -> bool {
        let dt = self.library.dt;
        let body = |st: &BicycleState| Body {
            pose: pose(st),
            length: req.length,
            width: req.width,
        };
        let (me, me_now) = (body(st), body(&req.start));
        obstacles.iter().all(|t| {
            let (other, other_now) = (Body::of(t, step, dt), Body::of(t, 0, dt));
            self.rule
                .clear(&me, &me_now, &other, &other_now, step as f64 * dt)
        })
    }
}

fn pose(st: &BicycleState) -> Pose {
    Pose {
        s: st.pos.x,
        y: st.pos.y,
        heading: st.heading,
        speed: st.speed,
    }
}

/// A state at the centre of lane `lane` (road frame), heading along the road.
pub fn lane_state(road: &Road, s: f64, lane: i32, speed: f64) -> BicycleState {
    BicycleState {
        pos: Point::new(s, lane as f64 * road.lane_width),
        heading: 0.0,
        speed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planner() -> Mastar {
        Mastar::new(
            &PlannerSettings::default(),
            Road::paper_default(),
            0.2,
            1.0,
            35.0,
        )
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
            obstacles,
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
        let leader = other(45.0 + 150.0, 1, 10.0);
        let left = other(30.0 + 150.0, 2, 28.0);
        let obs = [&leader, &left];
        if let Ok(plan) = m.plan(&request(&m, 170.0, 1, 28.0, false, &obs)) {
            assert!(plan.trajectory.poses.iter().all(|p| p.y > 2.25));
        }
    }
}
