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
//!
//! The rooms: this file is the public face (the planner, a request, a plan, and why there is
//! none) and runs the phases; `phase` is one phase's A* problem (its nodes, successors,
//! heuristic and goal) and the plan along the path found; `obstacles` holds what a search keeps
//! clear of (other vehicles' bodies per step, the road's edges); `gap_seeking` the vehicle a
//! ramp CAV on its acceleration lane keeps behind (`[planner] gap_seeking`); `first_moves` keeps a CAV's
//! moves from its start between the searches of a round. The check every lane-change start must
//! pass is a [`StartGuard`](crate::planner::guard::StartGuard), defined in
//! [`crate::planner::guard`] and implemented by the controllers' safety shield.

use crate::config::{LowSpeedLaneChanges, PlannerSettings};
use crate::model::kinematics::BicycleState;
use crate::model::math::Point;
use crate::model::road::Road;
use crate::model::scene::Limits;
use crate::model::trajectory::{Pose, Trajectory};
use crate::planner::guard::Guard;
use crate::planner::mastar::obstacles::Obstacles;
use crate::planner::mastar::phase::{assemble, PhaseSearch, PhaseSpec};
use crate::planner::primitives::{Library, Primitive, Throttle};
use crate::planner::safety::SafetyRule;
use crate::planner::search::{astar, Stop};

mod courtesy;
mod first_moves;
mod gap_seeking;
mod obstacles;
mod phase;
#[cfg(test)]
mod tests;

pub use crate::planner::mastar::courtesy::Merger;
pub use crate::planner::mastar::first_moves::FirstMoves;

/// Which phase produced a plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Phase 1: the goal d ahead, every primitive, biased to forward motion.
    Forward,
    /// Phase 2, when phase 1 failed: the shorter goal d', braking and lane changes only.
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
    /// The road-frame lane the change ends in.
    pub target_lane: i32,
    /// Planning steps until it ends there.
    pub steps_left: usize,
}

/// One planning problem.
#[derive(Debug, Clone)]
pub struct Request<'a> {
    /// Centre, heading and path speed in the road frame.
    pub start: BicycleState,
    /// The lane the CAV is in (its target lane when a change is under way).
    pub lane: i32,
    /// The lane change under way, which the plan must continue.
    pub ongoing: Option<OngoingLaneChange>,
    /// A ramp CAV that has not merged yet: its goal is the main road.
    pub must_merge: bool,
    /// The CAV's length (m).
    pub length: f64,
    /// The CAV's width (m).
    pub width: f64,
    /// The CAV's own top speed (m/s): no move accelerates it past this (infinite: only the
    /// planner's `v_max` limits it).
    pub max_speed: f64,
    /// The CAV's own accelerations: its moves ask no more of it than these and the library's.
    pub limits: Limits,
    /// Other vehicles' trajectories, step 0 = now.
    pub obstacles: &'a [&'a Trajectory],
    /// The check a lane change started now must pass (none: every start the search finds free).
    pub guard: Option<Guard<'a>>,
    /// Where the moves from this start are kept between searches (none: worked out each time).
    /// It must belong to this start, guard and lane change under way.
    pub first_moves: Option<&'a FirstMoves>,
    /// The ramp HDV ahead that merges into this CAV's lane, if any ([`courtesy`]).
    pub merger: Option<Merger>,
}

/// A plan found by M-A*.
#[derive(Debug, Clone)]
pub struct Plan {
    /// What the CAV does in the next step.
    pub first: FirstMove,
    /// The primitives after the first move.
    pub primitives: Vec<Primitive>,
    /// The CAV's planned poses, step 0 = now.
    pub trajectory: Trajectory,
    /// The phase that found it.
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
    /// Nodes expanded over both phases before giving up.
    pub expanded: usize,
}

/// The single-CAV planner: primitives, settings and the road.
#[derive(Debug, Clone)]
pub struct Mastar {
    /// The motion primitives, rolled out on the kinematic bicycle model.
    pub library: Library,
    /// Horizon, goal distances, node budgets and bins (`[planner]`).
    pub settings: PlannerSettings,
    /// The road the CAVs plan on.
    pub road: Road,
    /// Speed limit of the plans (m/s).
    pub v_max: f64,
    /// The safety rule a plan keeps to other vehicles' trajectories.
    pub rule: SafetyRule,
    /// Whether ramp CAVs seek gaps ([`PlannerSettings::seeks_gaps`], `gap_seeking`).
    pub seeks_gaps: bool,
    /// Whether main-road CAVs leave a ramp HDV ahead the gap SUMO asks of its new follower
    /// ([`PlannerSettings::is_courteous`], `courtesy`).
    pub courtesy: bool,
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
        planner.seeks_gaps = config.planner.seeks_gaps(s.sumocfg.is_some());
        planner.courtesy = config.planner.is_courteous(s.sumocfg.is_some());
        planner
    }

    /// A planner for steps of `dt` on `road`, lane changes taking `lane_change_duration`;
    /// ramp CAVs seek gaps only where `settings` says so.
    pub fn new(
        settings: &PlannerSettings,
        road: Road,
        dt: f64,
        lane_change_duration: f64,
        v_max: f64,
    ) -> Self {
        let mut library = Library::new(dt, road.lane_width, lane_change_duration, v_max);
        library.accel = settings.accel_or_paper();
        library.accel_own = settings.accel.is_none();
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
            seeks_gaps: settings.seeks_gaps(false),
            courtesy: settings.is_courteous(false),
        }
    }

    /// The check horizon (steps): the planning horizon T plus one lane change. A plan is checked
    /// against obstacles up to it (a node at T ends its plan, and its tail is coasted on to here),
    /// so it is also the horizon every other vehicle must be predicted over and BK-PBS checks
    /// conflicts over. The one definition: callers ask here (`self.planner.check_horizon()` in
    /// the controllers) rather than adding the two.
    pub fn check_horizon(&self) -> usize {
        self.settings.horizon + self.library.lane_change_steps
    }

    /// The centre line of lane `lane` (road frame y).
    #[inline]
    fn lane_y(&self, lane: i32) -> f64 {
        lane as f64 * self.road.lane_width
    }

    /// Phase 1, then phase 2 if needed.
    pub fn plan(&self, req: &Request) -> Result<Plan, NoPlan> {
        let virtual_leaders: Vec<Trajectory> = [self.gap_leader(req), self.courtesy_leader(req)]
            .into_iter()
            .flatten()
            .collect();
        let with_leaders: Vec<&Trajectory>;
        let obstacles = if virtual_leaders.is_empty() {
            req.obstacles
        } else {
            with_leaders = req
                .obstacles
                .iter()
                .copied()
                .chain(&virtual_leaders)
                .collect();
            &with_leaders[..]
        };
        let near = Obstacles::near(
            obstacles,
            req.start.pos.x,
            self.check_horizon(),
            self.library.dt,
        );
        let own = self.library.limited(&req.limits);
        let library = own.as_ref().unwrap_or(&self.library);
        let mut expanded = 0;
        for phase in [Phase::Forward, Phase::Fallback] {
            match self.search(req, library, &near, phase) {
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
    fn search(
        &self,
        req: &Request,
        library: &Library,
        obstacles: &Obstacles,
        phase: Phase,
    ) -> Result<Plan, usize> {
        let spec = PhaseSpec::of(phase, &self.settings);
        let problem = PhaseSearch::new(self, library, req, obstacles, spec);
        let result = astar(
            problem.root(),
            |n| problem.successors(n),
            |n| problem.heuristic(n),
            |n| n.ends_plan(),
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
        let brake = Throttle::Accel(-self.library.emergency_decel.min(req.limits.emergency_decel));
        let seg = self
            .library
            .track(&req.start, brake, horizon, lateral_path(y0, y1, total));
        let mut poses = vec![pose(&req.start)];
        poses.extend(seg.iter().map(pose));
        Trajectory {
            poses,
            length: req.length,
            width: req.width,
            brake: None,
            committed: true,
        }
    }
}

/// The lateral reference (position, lateral speed) at time `t` of a lane change under way from
/// `y0` to `y1` that ends after `total` seconds: linear, as SUMO moves a changing vehicle
/// sideways, then on `y1`. Both the plans that continue such a change and the fallback follow it.
fn lateral_path(y0: f64, y1: f64, total: f64) -> impl Fn(f64) -> (f64, f64) {
    move |t| {
        if t < total {
            (y0 + (y1 - y0) * t / total, (y1 - y0) / total)
        } else {
            (y1, 0.0)
        }
    }
}

/// The pose of state `st`.
#[inline]
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
