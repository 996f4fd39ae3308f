//! One phase of M-A*: the A* problem its search solves, and the plan along the path it finds.
//!
//! The two phases differ only in a [`PhaseSpec`] (their primitives, goal distance, budget and
//! lane-change penalty); a [`PhaseSearch`] is that spec applied to one request, giving
//! [`astar`](crate::planner::search::astar) its successor, heuristic, goal and closed-set key
//! functions over [`Node`]s. The traffic specifics all live here, so the search stays generic.

use crate::config::{LowSpeedLaneChanges, PlannerSettings};
use crate::model::kinematics::{free_flow_time, BicycleState};
use crate::model::math::Point;
use crate::model::trajectory::Trajectory;
use crate::planner::mastar::first_moves::Move;
use crate::planner::mastar::obstacles::Obstacles;
use crate::planner::mastar::{
    lateral_path, pose, FirstMove, Mastar, OngoingLaneChange, Phase, Plan, Request,
};
use crate::planner::primitives::{Library, Primitive, Throttle};
use crate::planner::safety::Body;
use crate::planner::search::Search;

/// A search node: the CAV at a primitive boundary.
#[derive(Debug, Clone)]
pub(super) struct Node {
    step: usize,
    lane: i32,
    state: BicycleState,
    /// The move that led here (`None` at the root).
    via: Option<FirstMove>,
    /// States at each step of that move.
    segment: Vec<BicycleState>,
    /// The plan reaches the horizon here, short of its goal.
    terminal: bool,
    /// The goal is reached here and coasting on from here stays safe to the check horizon.
    goal: bool,
}

impl Node {
    /// Whether the plan ends here: at its goal, or at the horizon short of it.
    #[inline]
    pub(super) fn ends_plan(&self) -> bool {
        self.terminal || self.goal
    }
}

/// Extra cost (steps) of a ramp CAV's plan that reaches the horizon still on an auxiliary lane,
/// per lane change it still owes the main road (5 steps: 1 s at the default 0.2 s steps), which
/// the free-flow time of the distance it lacks does not count; without it, a plan still on the
/// ramp at the horizon could cost less than one that merges a few steps later. Charged per lane
/// owed, a plan that moves from a two-lane ramp's outer lane to its inner one is worth its
/// lane change: charged once, such a CAV (bk-mastar on the two-lane gain layout) drove 800 m
/// on the outer lane and changed lanes twice from a stand at its end.
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
pub(super) struct PhaseSpec {
    phase: Phase,
    primitives: &'static [Primitive],
    goal_distance: f64,
    pub(super) budget: usize,
    lane_change_penalty: f64,
}

impl PhaseSpec {
    /// The spec of `phase` under `settings`.
    pub(super) fn of(phase: Phase, settings: &PlannerSettings) -> Self {
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
pub(super) struct PhaseSearch<'p> {
    planner: &'p Mastar,
    /// The primitives of this CAV: the planner's, within the CAV's own limits.
    library: &'p Library,
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
    /// Steps a plan's end must stay safe up to when coasted on: [`Mastar::check_horizon`], the
    /// horizon other vehicles are predicted (and BK-PBS checks conflicts) over.
    check_horizon: usize,
}

impl<'p> PhaseSearch<'p> {
    /// The search of phase `spec` for `req` among `obstacles`.
    pub(super) fn new(
        planner: &'p Mastar,
        library: &'p Library,
        req: &'p Request<'p>,
        obstacles: &'p Obstacles,
        spec: PhaseSpec,
    ) -> Self {
        let horizon = planner.settings.horizon;
        PhaseSearch {
            planner,
            library,
            req,
            obstacles,
            me_now: Body::new(pose(&req.start), req.length, req.width, None),
            spec,
            s0: req.start.pos.x,
            dt: library.dt,
            horizon,
            check_horizon: planner.check_horizon(),
        }
    }

    /// The search's start: the CAV as it is now.
    pub(super) fn root(&self) -> Node {
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
        free_flow_time(remaining, v, self.library.accel, self.planner.v_max) / self.dt
    }

    /// Steps the CAV at `n` still lacks to its goal distance, at free flow.
    fn lacking_steps(&self, n: &Node) -> f64 {
        self.steps_for(
            (self.spec.goal_distance - (n.state.pos.x - self.s0)).max(0.0),
            n.state.speed,
        )
    }

    /// Whether the move along `seg` from `n` ends faster than the CAV's own top speed and faster
    /// than it started (a CAV above it may hold its speed or brake).
    fn past_top_speed(&self, n: &Node, seg: &[BicycleState]) -> bool {
        let cap = self.req.max_speed.max(n.state.speed) + 1e-9;
        seg.last()
            .is_some_and(|st| st.speed * st.heading.cos() > cap)
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
    pub(super) fn heuristic(&self, n: &Node) -> f64 {
        if n.ends_plan() {
            return 0.0;
        }
        let to_horizon = self.horizon.saturating_sub(n.step) as f64;
        let to_goal = if self.req.must_merge {
            let road = &self.planner.road;
            let rear = n.state.pos.x - 0.5 * self.req.length;
            let approach = (road.zone_for(n.lane, rear).start - rear).max(0.0);
            approach / (self.planner.v_max * self.dt) + self.library.lane_change_steps as f64
        } else {
            self.lacking_steps(n)
        };
        to_goal.min(to_horizon)
    }

    /// Cost charged when a plan reaches the horizon short of its goal.
    fn terminal_cost(&self, n: &Node) -> f64 {
        let lacking = self.lacking_steps(n);
        if self.req.must_merge {
            let owed = self.planner.road.lanes_to_main(n.lane);
            lacking + UNMERGED_PENALTY * owed as f64
        } else {
            lacking
        }
    }

    /// The closed-set key: nodes alike in step, lane, s bin, v bin and terminality are one.
    #[inline]
    pub(super) fn key(&self, n: &Node) -> (usize, i32, i64, i64, bool) {
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
    pub(super) fn successors(&self, n: &Node) -> Vec<(Node, f64)> {
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
            Some(kept) if n.step == 0 => kept.of_phase(self.spec.phase, || self.work_out_moves(n)),
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
                let library = self.library;
                let mut moves = Vec::new();
                for &p in self.spec.primitives {
                    if !library.available(p, &n.state) {
                        continue;
                    }
                    let lane = n.lane + p.lane_offset();
                    let road = &self.planner.road;
                    if !road.lanes().contains(&lane) || !self.can_start(p, n) {
                        continue;
                    }
                    // From an auxiliary lane only towards the carriageway.
                    if p.is_lane_change() && road.is_auxiliary(n.lane) {
                        let admitted = || {
                            let me = (&n.state, self.req.length);
                            (self.planner).merge_start_admitted(me, lane, n.step, self.obstacles)
                        };
                        if !road.is_merge(n.lane, lane) || !admitted() {
                            continue;
                        }
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
            LowSpeedLaneChanges::Merge => self.planner.road.is_auxiliary(n.lane),
            LowSpeedLaneChanges::All => true,
        };
        let zone = self.planner.road.zone_on(n.lane, front);
        let before_zone = zone.is_some_and(|z| front < z.start);
        !before_zone && (!slow || slide_allowed)
    }

    /// Whether the request's guard lets primitive `p`, rolled out as `seg` from the root, start.
    fn guard_admits(&self, p: Primitive, seg: &[BicycleState]) -> bool {
        match (self.req.guard, seg.first()) {
            (Some(g), Some(first)) => g.admits(p.lane_offset(), first.speed * first.heading.cos()),
            _ => true,
        }
    }

    /// The rest of the lane change under way from `st`: forward speed held, lateral position
    /// linear to the target lane's centre over the steps left.
    fn continue_lane_change(&self, st: &BicycleState, lc: OngoingLaneChange) -> Vec<BicycleState> {
        let y0 = st.pos.y;
        let y1 = self.planner.lane_y(lc.target_lane);
        let total = lc.steps_left as f64 * self.dt;
        self.library.track(
            st,
            Throttle::HoldForwardSpeed(st.speed * st.heading.cos()),
            lc.steps_left,
            lateral_path(y0, y1, total),
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
        if !ok || self.past_top_speed(n, &seg) {
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
pub(super) fn assemble(req: &Request, phase: Phase, result: &Search<Node>) -> Plan {
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
            committed: true,
        },
        phase,
        expanded: result.expanded,
        cost: result.cost,
    }
}
