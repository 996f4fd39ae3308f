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

use std::sync::OnceLock;

use crate::config::{LowSpeedLaneChanges, PlannerSettings};
use crate::model::kinematics::{free_flow_time, BicycleState};
use crate::model::math::Point;
use crate::model::road::{Road, MERGE_LANE};
use crate::model::scene::Scene;
use crate::model::trajectory::{Pose, Trajectory};
use crate::planner::primitives::{Library, Primitive, Throttle};
use crate::planner::safety::{Body, SafetyRule};
use crate::planner::search::{astar, Search, Stop};

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

/// A check every lane-change start must pass before the search may plan it. The controllers
/// pass the safety shield's, so that no plan counts on a start the shield would withdraw: other
/// CAVs are planned against that plan, so it must be what will be executed.
pub trait StartGuard: Sync {
    /// Whether scene vehicle `agent` may start a change of `lane_offset` lanes that has it at
    /// forward speed `first_speed` after the first step.
    fn admits(&self, scene: &Scene, agent: usize, lane_offset: i32, first_speed: f64) -> bool;
}

/// A [`StartGuard`] bound to one CAV of one scene.
#[derive(Clone, Copy)]
pub struct Guard<'a> {
    pub check: &'a dyn StartGuard,
    pub scene: &'a Scene,
    pub agent: usize,
}

impl Guard<'_> {
    fn admits(&self, lane_offset: i32, first_speed: f64) -> bool {
        self.check
            .admits(self.scene, self.agent, lane_offset, first_speed)
    }
}

impl std::fmt::Debug for Guard<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Guard(agent {})", self.agent)
    }
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
    /// The check a lane change started now must pass (none: every start the search finds free).
    pub guard: Option<Guard<'a>>,
    /// Where the moves from this start are kept between searches (none: worked out each time).
    /// It must belong to this start, guard and lane change under way.
    pub first_moves: Option<&'a FirstMoves>,
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

/// A move from a node: how it starts, the lane it ends in and its states at each step.
type Move = (FirstMove, i32, Vec<BicycleState>);

/// The moves from one CAV's start, per phase, worked out once and shared by every search from
/// that start. BK-PBS replans a CAV against one set of obstacles after another within a round;
/// its first moves (the primitives rolled out exactly from its state, the guard asked about
/// each lane change) do not depend on the obstacles, and were a sixth of a round's time.
#[derive(Debug, Default)]
pub struct FirstMoves {
    by_phase: [OnceLock<Vec<Move>>; 2],
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
    /// The default planner on the shipped network's road: for scenes built by hand (tests,
    /// planning without SUMO).
    pub fn on_paper_road() -> Self {
        Mastar::from_config(&crate::config::Config::default(), Road::paper_default())
    }

    /// The planner of a configuration on `road`.
    pub fn from_config(config: &crate::config::Config, road: Road) -> Self {
        let s = &config.scenario;
        let mut planner = Mastar::new(&config.planner, road, s.dt, s.lane_change_duration, s.v_max);
        planner.rule.follower_brake = config.idm.decel;
        planner
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
        library.slides_below_min_speed =
            settings.low_speed_lane_changes != LowSpeedLaneChanges::Off;
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

    /// Steps a plan is checked against obstacles up to: T plus a lane change.
    pub fn check_horizon(&self) -> usize {
        self.settings.horizon + self.library.lane_change_steps
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
            .filter(|t| (t.poses[0].s - req.start.pos.x).abs() < OBSTACLE_RANGE)
            .collect();
        let near = Obstacles::new(&near, self.check_horizon(), self.library.dt);
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

    /// One phase of M-A*: A* from the CAV's state to the phase's goal or horizon. Returns the
    /// nodes expanded when it finds no plan.
    fn search(&self, req: &Request, obstacles: &Obstacles, phase: Phase) -> Result<Plan, usize> {
        let spec = PhaseSpec::of(phase, &self.settings);
        let problem = PhaseSearch::new(self, req, obstacles, spec);
        let result = astar(
            problem.root(),
            |n| problem.successors(n),
            |n| problem.heuristic(n),
            |n| n.terminal || n.goal,
            |n| problem.key(n),
            spec.budget,
        );
        if result.stop != Stop::Found || result.path.len() < 2 {
            return Err(result.expanded);
        }
        Ok(assemble(req, phase, &result))
    }

    /// What the CAV of `req` does without a plan, over `horizon` steps: it brakes at the
    /// emergency deceleration while a lane change under way completes (SUMO keeps moving it
    /// sideways). The trajectory every other agent must be checked against, not a guess.
    pub fn fallback_trajectory(&self, req: &Request, horizon: usize) -> Trajectory {
        let y0 = req.start.pos.y;
        let (y1, total) = match req.ongoing {
            Some(lc) => (
                self.lane_y(lc.target_lane),
                lc.steps_left as f64 * self.library.dt,
            ),
            None => (y0, 0.0),
        };
        let brake = Throttle::Accel(-self.library.emergency_decel);
        let seg = self.library.track(&req.start, brake, horizon, |t| {
            if t < total {
                (y0 + (y1 - y0) * t / total, (y1 - y0) / total)
            } else {
                (y1, 0.0)
            }
        });
        let mut poses = vec![pose(&req.start)];
        poses.extend(seg.iter().map(pose));
        Trajectory {
            poses,
            length: req.length,
            width: req.width,
            brake: None,
        }
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
        if y_lo < -0.5 * w - EPS || y_hi > (f64::from(self.road.top_lane()) + 0.5) * w + EPS {
            return false;
        }
        let in_merge_lane = y_lo < 0.5 * w - EPS;
        if in_merge_lane {
            // Only ramp vehicles use it, and only until its zone ends.
            let zone = self.road.zone_ahead(s_lo);
            if !req.must_merge || s_hi > zone.end {
                return false;
            }
            // Crossing between it and the main road only beside the acceleration lane.
            let crossing = y_hi > 0.5 * w + EPS;
            if crossing && s_lo < zone.start {
                return false;
            }
            // Fully in the lane, the CAV must still be able to stop before its end, or the plan
            // could leave it in a state from which the crash is certain.
            let stop = st.speed * st.speed / (2.0 * self.library.emergency_decel);
            if !crossing && stop > zone.end - s_hi + 1e-9 {
                return false;
            }
        }
        true
    }

    /// Whether the CAV at `st` at `step` is clear of every obstacle (see [`SafetyRule`]).
    /// `me_now` is the CAV's body at the start.
    fn safe(&self, st: &BicycleState, step: usize, me_now: &Body, obstacles: &Obstacles) -> bool {
        let me = Body::new(pose(st), me_now.length, me_now.width, None);
        let t = step as f64 * self.library.dt;
        obstacles
            .at(step)
            .iter()
            .zip(obstacles.at(0))
            .all(|(other, other_now)| self.rule.clear(&me, me_now, other, other_now, t))
    }
}

/// The obstacles of one M-A* call, with their bodies at every step a search checks, built once:
/// every node checks every obstacle at every step of every primitive it rolls out, so reading a
/// pose (and its forward speed) off a trajectory each time would cost more than the checks.
///
/// A search checks no step past the check horizon T + one lane change: a node at T ends its
/// plan, a move from a node before T spans at most a lane change, and a plan's tail is checked
/// up to the check horizon.
struct Obstacles {
    /// `by_step[k][o]`: obstacle `o` at step `k`, for k up to the check horizon.
    by_step: Vec<Vec<Body>>,
}

impl Obstacles {
    fn new(trajectories: &[&Trajectory], check_horizon: usize, dt: f64) -> Self {
        let by_step = (0..=check_horizon)
            .map(|k| trajectories.iter().map(|t| Body::of(t, k, dt)).collect())
            .collect();
        Obstacles { by_step }
    }

    fn at(&self, step: usize) -> &[Body] {
        &self.by_step[step]
    }
}

/// Other vehicles farther than this along the road from the CAV now are left out of its search
/// (m). Every obstacle kept costs a safety check at every step of every rolled-out primitive, and
/// one this far away would have to close 80 m on the CAV within the 4 s checked (15 + 5 steps of
/// 0.2 s) just to come within the safety rule's [`REACH`](crate::planner::safety::REACH) of
/// 120 m, beyond which it never counts. A practical range, not a proven bound: changing it can
/// change plans.
const OBSTACLE_RANGE: f64 = 200.0;

/// Extra cost (steps) of a ramp CAV's plan that reaches the horizon still on the acceleration
/// lane. Such a plan still owes at least the lane change onto the main road (5 steps: 1 s at the
/// default 0.2 s steps), which the free-flow time of the distance it lacks does not count; without
/// it, a plan still on the ramp at the horizon could cost less than one that merges a few steps
/// later.
const UNMERGED_PENALTY: f64 = 5.0;

/// Phase 1's primitives: everything but the emergency brake.
const FORWARD_PRIMITIVES: [Primitive; 5] = [
    Primitive::Accelerate,
    Primitive::Idle,
    Primitive::Decelerate,
    Primitive::LaneChangeLeft,
    Primitive::LaneChangeRight,
];

/// Phase 2's primitives: slowing down, hard or not, and the lane changes.
const FALLBACK_PRIMITIVES: [Primitive; 4] = [
    Primitive::Decelerate,
    Primitive::EmergencyBrake,
    Primitive::LaneChangeLeft,
    Primitive::LaneChangeRight,
];

/// What one phase searches for: the primitives it may use, its goal distance, its expansion
/// budget and what a lane change costs on top of its steps. The two phases differ only in these.
#[derive(Debug, Clone, Copy)]
struct PhaseSpec {
    phase: Phase,
    primitives: &'static [Primitive],
    goal_distance: f64,
    budget: usize,
    lane_change_penalty: f64,
}

impl PhaseSpec {
    /// The spec of `phase` under `settings`.
    fn of(phase: Phase, settings: &PlannerSettings) -> Self {
        match phase {
            Phase::Forward => PhaseSpec {
                phase,
                primitives: &FORWARD_PRIMITIVES,
                goal_distance: settings.goal_distance,
                budget: settings.phase1_budget,
                lane_change_penalty: settings.phase1_lane_change_penalty,
            },
            Phase::Fallback => PhaseSpec {
                phase,
                primitives: &FALLBACK_PRIMITIVES,
                goal_distance: settings.fallback_goal_distance,
                budget: settings.phase2_budget,
                lane_change_penalty: settings.phase2_lane_change_penalty,
            },
        }
    }
}

/// The A* problem of one phase for one request: the successor, heuristic and goal functions
/// over [`Node`]s, with the planner, the request and its nearby obstacles borrowed for the
/// search. Keeping them together lets [`Mastar::search`] read as the algorithm.
struct PhaseSearch<'p> {
    planner: &'p Mastar,
    req: &'p Request<'p>,
    obstacles: &'p Obstacles,
    /// The CAV's body at the start.
    me_now: Body,
    spec: PhaseSpec,
    /// The CAV's start along the road: progress is measured from here.
    s0: f64,
    /// Step length (s).
    dt: f64,
    /// The planning horizon T (steps): a node at or past it ends its plan.
    horizon: usize,
    /// Steps a plan's end must stay safe up to when coasted on: T plus a lane change, the
    /// horizon other vehicles are predicted (and BK-PBS checks conflicts) over.
    check_horizon: usize,
}

impl<'p> PhaseSearch<'p> {
    /// The search of phase `spec` for `req` among `obstacles`.
    fn new(
        planner: &'p Mastar,
        req: &'p Request<'p>,
        obstacles: &'p Obstacles,
        spec: PhaseSpec,
    ) -> Self {
        let horizon = planner.settings.horizon;
        PhaseSearch {
            planner,
            req,
            obstacles,
            me_now: Body::new(pose(&req.start), req.length, req.width, None),
            spec,
            s0: req.start.pos.x,
            dt: planner.library.dt,
            horizon,
            check_horizon: planner.check_horizon(),
        }
    }

    /// The search's start: the CAV as it is now.
    fn root(&self) -> Node {
        Node {
            step: 0,
            lane: self.req.lane,
            state: self.req.start,
            via: None,
            segment: Vec::new(),
            terminal: false,
            goal: false,
        }
    }

    /// Steps to cover `remaining` metres from speed `v` at full throttle up to v_max.
    fn steps_for(&self, remaining: f64, v: f64) -> f64 {
        free_flow_time(remaining, v, self.planner.library.accel, self.planner.v_max) / self.dt
    }

    /// Steps the CAV at `n` still lacks to its goal distance, at free flow.
    fn lacking_steps(&self, n: &Node) -> f64 {
        self.steps_for(
            (self.spec.goal_distance - (n.state.pos.x - self.s0)).max(0.0),
            n.state.speed,
        )
    }

    /// Whether the CAV at `st` at `step` is on the road and clear of every obstacle.
    fn free(&self, st: &BicycleState, step: usize) -> bool {
        self.planner.on_road(st, self.req)
            && self.planner.safe(st, step, &self.me_now, self.obstacles)
    }

    /// Whether coasting on at constant speed from `st` at `step` stays free up to the check
    /// horizon, so a plan never ends right behind a slower vehicle.
    fn tail_safe(&self, st: &BicycleState, step: usize) -> bool {
        (step + 1..=self.check_horizon).all(|k| {
            let t = (k - step) as f64 * self.dt;
            let coast = BicycleState {
                pos: Point::new(st.pos.x + st.speed * t, st.pos.y),
                heading: 0.0,
                speed: st.speed,
            };
            self.free(&coast, k)
        })
    }

    /// The goal test: a ramp CAV on a main-road lane; a main-road CAV the goal distance ahead on
    /// a main-road lane.
    fn reached(&self, n: &Node) -> bool {
        if self.req.must_merge {
            self.on_main(n) && n.step > 0
        } else {
            n.state.pos.x - self.s0 >= self.spec.goal_distance && self.on_main(n)
        }
    }

    fn on_main(&self, n: &Node) -> bool {
        self.planner.road.main_lane_range().contains(&n.lane)
    }

    /// Remaining cost, estimated from below: the time to the goal at free flow (for a ramp CAV,
    /// for its rear to reach the merge zone at v_max, plus a lane change), capped by the steps
    /// left to the horizon.
    fn heuristic(&self, n: &Node) -> f64 {
        if n.terminal || n.goal {
            return 0.0;
        }
        let to_horizon = self.horizon.saturating_sub(n.step) as f64;
        let to_goal = if self.req.must_merge {
            let road = &self.planner.road;
            let rear = n.state.pos.x - 0.5 * self.req.length;
            let approach = (road.zone_ahead(rear).start - rear).max(0.0);
            approach / (self.planner.v_max * self.dt)
                + self.planner.library.lane_change_steps as f64
        } else {
            self.lacking_steps(n)
        };
        to_goal.min(to_horizon)
    }

    /// Cost charged when a plan reaches the horizon short of its goal.
    fn terminal_cost(&self, n: &Node) -> f64 {
        let lacking = self.lacking_steps(n);
        if self.req.must_merge && !self.on_main(n) {
            lacking + UNMERGED_PENALTY
        } else {
            lacking
        }
    }

    /// The closed-set key: nodes alike in step, lane, s bin, v bin and terminality are one.
    fn key(&self, n: &Node) -> (usize, i32, i64, i64, bool) {
        let (s_bin, v_bin) = (self.planner.settings.s_bin, self.planner.settings.v_bin);
        (
            n.step,
            n.lane,
            (n.state.pos.x / s_bin).round() as i64,
            (n.state.speed / v_bin).round() as i64,
            n.terminal,
        )
    }

    /// The children of `n` with their edge costs: every move that stays free, settled on its
    /// lane, and marked goal or terminal where it ends the plan.
    fn successors(&self, n: &Node) -> Vec<(Node, f64)> {
        if n.terminal {
            return Vec::new();
        }
        self.moves(n)
            .into_iter()
            .filter_map(|(mv, lane, seg)| self.successor(n, mv, lane, seg))
            .collect()
    }

    /// The moves from `n`; from the root, kept in the request's [`FirstMoves`] if it has one.
    fn moves(&self, n: &Node) -> Vec<Move> {
        match self.req.first_moves {
            Some(kept) if n.step == 0 => kept.by_phase[self.spec.phase as usize]
                .get_or_init(|| self.work_out_moves(n))
                .clone(),
            _ => self.work_out_moves(n),
        }
    }

    /// The moves from `n`, each with the lane it ends in and its states at each step: at the
    /// root the lane change under way, if any, is continued; otherwise every primitive of the
    /// phase that is available and keeps to the road's lanes.
    fn work_out_moves(&self, n: &Node) -> Vec<Move> {
        match (n.step, self.req.ongoing) {
            (0, Some(lc)) if lc.steps_left > 0 => {
                let seg = self.continue_lane_change(&n.state, lc);
                vec![(FirstMove::Continue, lc.target_lane, seg)]
            }
            _ => {
                let library = &self.planner.library;
                let mut moves = Vec::new();
                for &p in self.spec.primitives {
                    if !library.available(p, &n.state) {
                        continue;
                    }
                    let lane = n.lane + p.lane_offset();
                    if !self.planner.road.lanes().contains(&lane) || !self.can_start(p, n) {
                        continue;
                    }
                    let seg = if n.step == 0 {
                        library.rollout(p, &n.state, self.planner.lane_y(n.lane))
                    } else {
                        library.rollout_settled(p, &n.state)
                    };
                    if n.step == 0 && !self.guard_admits(p, &seg) {
                        continue;
                    }
                    moves.push((FirstMove::Start(p), lane, seg));
                }
                moves
            }
        }
    }

    /// Whether primitive `p` may start at `n`: a lane change out of the merge lane only once the
    /// front is on the acceleration lane (on SUMO's ramp edge there is no lane to change to, so
    /// a change started there would not be executed while the plan counted on it), and a slow
    /// one (a slide) only where `low_speed_lane_changes` allows it.
    fn can_start(&self, p: Primitive, n: &Node) -> bool {
        if !p.is_lane_change() {
            return true;
        }
        let settings = &self.planner.settings;
        let front = n.state.pos.x + 0.5 * self.req.length;
        let slow = n.state.speed < settings.min_lane_change_speed;
        let slide_allowed = match settings.low_speed_lane_changes {
            LowSpeedLaneChanges::Off => false,
            LowSpeedLaneChanges::Merge => n.lane == MERGE_LANE,
            LowSpeedLaneChanges::All => true,
        };
        let before_zone = front < self.planner.road.zone_ahead(front).start;
        !(n.lane == MERGE_LANE && before_zone) && (!slow || slide_allowed)
    }

    /// Whether the request's guard lets primitive `p`, rolled out as `seg` from the root, start.
    fn guard_admits(&self, p: Primitive, seg: &[BicycleState]) -> bool {
        match (self.req.guard, seg.first()) {
            (Some(g), Some(first)) if p.is_lane_change() => {
                g.admits(p.lane_offset(), first.speed * first.heading.cos())
            }
            _ => true,
        }
    }

    /// The rest of the lane change under way from `st`: forward speed held, lateral position
    /// linear to the target lane's centre over the steps left.
    fn continue_lane_change(&self, st: &BicycleState, lc: OngoingLaneChange) -> Vec<BicycleState> {
        let y0 = st.pos.y;
        let y1 = self.planner.lane_y(lc.target_lane);
        let total = lc.steps_left as f64 * self.dt;
        self.planner.library.track(
            st,
            Throttle::HoldForwardSpeed(st.speed * st.heading.cos()),
            lc.steps_left,
            |t| {
                if t < total {
                    (y0 + (y1 - y0) * t / total, (y1 - y0) / total)
                } else {
                    (y1, 0.0)
                }
            },
        )
    }

    /// The child of `n` reached by `mv` along `seg` into `lane`, with its edge cost, unless a
    /// state of `seg` is not free or the child reaches the horizon with an unsafe tail.
    fn successor(
        &self,
        n: &Node,
        mv: FirstMove,
        lane: i32,
        seg: Vec<BicycleState>,
    ) -> Option<(Node, f64)> {
        let ok = seg
            .iter()
            .enumerate()
            .all(|(k, st)| self.free(st, n.step + k + 1));
        if !ok {
            return None;
        }
        let steps = seg.len();
        let mut state = *seg.last().expect("moves span at least one step");
        // Inside the search every node is settled on its lane (see rollout_settled); the first
        // move, which is what gets executed, is rolled out exactly.
        state.pos.y = self.planner.lane_y(lane);
        state.speed *= state.heading.cos();
        state.heading = 0.0;
        let mut cost = steps as f64;
        if matches!(mv, FirstMove::Start(p) if p.is_lane_change()) {
            let deferral = self.planner.settings.lane_change_deferral_penalty;
            cost += self.spec.lane_change_penalty + deferral * n.step as f64;
        }
        let next = Node {
            step: n.step + steps,
            lane,
            state,
            via: Some(mv),
            segment: seg,
            terminal: false,
            goal: false,
        };
        self.mark_end(next, cost)
    }

    /// Marks `next` as a goal if it reached the goal with a safe tail (charging only the part of
    /// its last step before the goal distance was passed), else, at the horizon, as terminal
    /// (charging the terminal cost), or drops it there if its tail is unsafe. A goal node with an
    /// unsafe tail short of the horizon stays an ordinary node, searched on.
    fn mark_end(&self, mut next: Node, mut cost: f64) -> Option<(Node, f64)> {
        let (step, state) = (next.step, next.state);
        let ends = self.reached(&next) || step >= self.horizon;
        let tail_ok = ends && self.tail_safe(&next.state, step);
        if self.reached(&next) && tail_ok {
            next.goal = true;
            if !self.req.must_merge && state.speed > 0.0 {
                // Charge the time the goal distance was actually passed, not the whole step.
                let over = next.state.pos.x - self.s0 - self.spec.goal_distance;
                cost -= (over / (state.speed * self.dt)).clamp(0.0, 1.0 - 1e-9);
            }
        } else if step >= self.horizon {
            if !tail_ok {
                return None;
            }
            next.terminal = true;
            cost += self.terminal_cost(&next);
        }
        Some((next, cost))
    }
}

/// The plan along a found path (root first): its poses, the first move and the primitives after
/// it.
fn assemble(req: &Request, phase: Phase, result: &Search<Node>) -> Plan {
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
    Plan {
        first,
        primitives: prims,
        trajectory: Trajectory {
            poses,
            length: req.length,
            width: req.width,
            brake: None,
        },
        phase,
        expanded: result.expanded,
        cost: result.cost,
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
            obstacles,
            guard: None,
            first_moves: None,
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
        fn admits(&self, _: &Scene, _: usize, _: i32, _: f64) -> bool {
            false
        }
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
}
