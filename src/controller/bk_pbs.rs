//! `bk-pbs`: all CAVs planned jointly each step by BK-PBS (see [`crate::planner::pbs`]); each CAV then
//! executes the first primitive of its plan. A CAV the chosen node leaves without a plan (no
//! plan even alone), or still in conflict after a fallback, is repaired: planned alone against
//! every other trajectory of that node, and if that fails too, it brakes at the emergency
//! deceleration. Every CAV always gets a maneuver.

use std::sync::Arc;

use rayon::prelude::*;

use super::shield::{self, Bounds};
use super::{execute, CavBelief, CavHandling, Command, Controller, PlanStats, Source};
use crate::config::Config;
use crate::model::road::Road;
use crate::model::scene::{Kind, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::guard::StartGuard;
use crate::planner::lane_changes::{LaneChanges, SceneRequests};
use crate::planner::mastar::{Mastar, NoPlan, Plan};
use crate::planner::pbs::{Budget, PbsStats, Problem, RequestFor, Solution};
use crate::predict::Predictor;

/// Centralised priority-based planner.
pub struct BkPbs {
    config: Config,
    predictor: Box<dyn Predictor>,
    planner: Mastar,
    lane_changes: LaneChanges,
    commitments: Commitments,
    /// The shield's check of lane-change starts, when the shield is on.
    guard: Option<Bounds>,
    stats: PlanStats,
    tracing: bool,
    beliefs: Vec<CavBelief>,
}

impl BkPbs {
    /// With `predictor` for HDVs (conditioned on higher-priority CAVs when it can be), on `road`.
    pub fn new(config: &Config, predictor: Box<dyn Predictor>, road: &Road) -> Self {
        BkPbs {
            config: config.clone(),
            predictor,
            planner: Mastar::from_config(config, road.clone()),
            lane_changes: LaneChanges::default(),
            guard: shield::start_guard(config),
            commitments: Commitments::default(),
            stats: PlanStats::default(),
            tracing: false,
            beliefs: Vec::new(),
        }
    }
}

impl Controller for BkPbs {
    fn name(&self) -> &'static str {
        "bk-pbs"
    }

    fn handling(&self) -> CavHandling {
        CavHandling::Commanded
    }

    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        let sc = &self.config.scenario;
        let (dt, lc_steps) = (sc.dt, sc.lane_change_steps());
        let decel = self.config.planner.emergency_decel;
        let now = scene.time;
        self.lane_changes.forget_finished(now);
        let guard = self.guard.as_ref().map(|g| g as &dyn StartGuard);
        let requests = SceneRequests::new(scene, &self.lane_changes, dt, guard);
        let committed = self.commitments.in_scene(scene, now);
        let problem = self.problem(scene, &requests, &committed);
        let solution = problem.solve();
        let mut stats = search_stats(&solution.stats);
        let mut starts = Vec::new();
        let mut beliefs = Vec::new();
        // After a fallback, the CAVs still in conflict are repaired.
        let conflicted = solution
            .stats
            .fallback
            .then(|| problem.conflicted_agents(&solution.trajectories));
        // Repairs are independent of each other (each against the node's trajectories): in
        // parallel, then used in order.
        let executed: Vec<Option<Executed>> = (0..scene.vehicles.len())
            .into_par_iter()
            .map(|i| {
                let in_conflict = conflicted.as_ref().is_some_and(|c| c[i]);
                (scene.vehicles[i].kind == Kind::Cav)
                    .then(|| executed_plan(&problem, &solution, &requests, i, in_conflict))
            })
            .collect();
        for ((i, v), executed) in scene.vehicles.iter().enumerate().zip(executed) {
            let (plan, planned_by) = match executed {
                None => continue,
                Some(Executed::Node(plan, source)) => (Some(plan), source),
                Some(Executed::Repair(result)) => {
                    execute::count_search(&mut stats, result.as_ref().map(|p| p.as_ref()));
                    (result.ok(), Source::Repair)
                }
            };
            let lane = self.lane_changes.planning_lane(scene, i, dt);
            let changing = self.lane_changes.ongoing(&v.id, now, dt).is_some();
            let source = execute::source_of(planned_by, plan.is_some(), changing);
            if self.tracing {
                let others = solution.trajectories.iter().map(|t| &**t).enumerate();
                let planned = plan.as_ref().map(|p| &p.trajectory);
                beliefs.push(execute::belief(scene, i, planned, others));
            }
            let (maneuver, target) =
                execute::maneuver_for(plan.as_deref(), v, lane, decel, dt, &mut stats);
            if let Some(target) = target {
                starts.push((i, v.id.clone(), target));
            }
            out.push(Command {
                vehicle: i,
                maneuver,
                source,
            });
        }
        self.beliefs = beliefs;
        let lc_duration = lc_steps as f64 * dt;
        self.commitments
            .record(scene, &solution.edges, &starts, now + lc_duration);
        // Recorded after the loop: `requests` reads the changes under way while CAVs are planned.
        for (_, id, target) in starts {
            self.lane_changes.start(&id, now, lc_duration, target);
        }
        self.stats = stats;
    }

    fn last_stats(&self) -> PlanStats {
        self.stats
    }

    fn set_tracing(&mut self, on: bool) {
        self.tracing = on;
    }

    fn beliefs(&self) -> Vec<CavBelief> {
        self.beliefs.clone()
    }

    fn lane_change_cancelled(&mut self, id: &str) {
        self.lane_changes.cancel(id);
    }
}

impl BkPbs {
    /// This step's BK-PBS problem: every CAV of `scene`, planned with M-A* and judged by the
    /// same safety rule M-A* plans with.
    fn problem<'a>(
        &'a self,
        scene: &'a Scene,
        requests: &'a SceneRequests<'a>,
        committed: &'a [(usize, usize)],
    ) -> Problem<'a> {
        let pbs = &self.config.pbs;
        Problem {
            scene,
            planner: &self.planner,
            predictor: self.predictor.as_ref(),
            requests,
            committed,
            rule: &self.planner.rule,
            horizon: self.config.planner.horizon + self.config.scenario.lane_change_steps(),
            dt: self.config.scenario.dt,
            budget: Budget {
                nodes: pbs.node_budget,
                time_ms: (pbs.time_budget_ms > 0.0).then_some(pbs.time_budget_ms),
            },
            independent_groups: pbs.independent_groups.applies(scene.vehicles.len()),
        }
    }
}

/// The episode's plan statistics of one BK-PBS search.
fn search_stats(s: &PbsStats) -> PlanStats {
    PlanStats {
        searches: s.mastar_calls,
        nodes_expanded: s.mastar_nodes,
        pbs_nodes: s.nodes,
        pbs_depth: s.depth,
        predictions: s.predictions,
        pbs_fallbacks: u64::from(s.fallback),
        time_budget_hits: u64::from(s.timed_out),
        ..PlanStats::default()
    }
}

/// What a CAV executes: the chosen node's plan (and whether that node solved the round), or a
/// repair's answer (no plan: even the repair found none).
enum Executed {
    Node(Arc<Plan>, Source),
    Repair(Result<Arc<Plan>, NoPlan>),
}

/// What CAV `i` executes: the chosen node's plan, or a repair when the node left it without
/// one or, after a fallback, `in_conflict`: planned alone against every other trajectory of
/// the node.
fn executed_plan(
    problem: &Problem<'_>,
    solution: &Solution,
    requests: &SceneRequests<'_>,
    i: usize,
    in_conflict: bool,
) -> Executed {
    if let (false, Some(plan)) = (in_conflict, &solution.plans[i]) {
        let source = if solution.stats.fallback {
            Source::PbsBestNode
        } else {
            Source::PbsSolution
        };
        return Executed::Node(plan.clone(), source);
    }
    let others: Vec<&Trajectory> = solution
        .trajectories
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != i)
        .map(|(_, t)| &**t)
        .collect();
    Executed::Repair(requests.plan(problem.planner, i, &others).map(Arc::new))
}

/// Priority edges carried across rounds: recursive feasibility of cut-ins.
///
/// A CAV that starts a lane change in front of another CAV may rely on that CAV yielding (the
/// round's priority `hi ≺ lo`). Only the first step of the plan is executed and the next round
/// starts afresh, so without memory nothing would hold `lo` to it while the change, which
/// cannot be undone, is under way. The invariant kept: while a lane change started in a round
/// is under way, every CAV that had to yield to it in that round keeps yielding in later rounds,
/// as long as it can plan so (else the commitment is dropped and PBS resolves the conflict
/// afresh, the repair and braking still apply).
#[derive(Debug, Clone, Default)]
struct Commitments {
    /// (higher id, lower id, until time).
    edges: Vec<(Arc<str>, Arc<str>, f64)>,
}

impl Commitments {
    /// The commitments still running at `now` between CAVs of `scene`, as scene indices.
    fn in_scene(&mut self, scene: &Scene, now: f64) -> Vec<(usize, usize)> {
        self.edges.retain(|(_, _, until)| *until > now + 1e-6);
        let index = |id: &Arc<str>| {
            scene
                .vehicles
                .iter()
                .position(|v| v.id == *id && v.kind == Kind::Cav)
        };
        self.edges
            .iter()
            .filter_map(|(hi, lo, _)| Some((index(hi)?, index(lo)?)))
            .collect()
    }

    /// Records, for each CAV that starts a lane change now, the CAVs the round made yield to it,
    /// until the change ends.
    fn record(
        &mut self,
        scene: &Scene,
        edges: &[(usize, usize)],
        starts: &[(usize, Arc<str>, i32)],
        until: f64,
    ) {
        for &(i, _, _) in starts {
            for &(hi, lo) in edges.iter().filter(|&&(hi, _)| hi == i) {
                if scene.vehicles[lo].kind != Kind::Cav {
                    continue;
                }
                let (h, l) = (&scene.vehicles[hi].id, &scene.vehicles[lo].id);
                if !self.edges.iter().any(|(a, b, _)| a == h && b == l) {
                    self.edges.push((h.clone(), l.clone(), until));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::model::road::Road;
    use crate::model::scene::{Origin, VehicleState};
    use crate::predict::ConstantSpeed;

    #[test]
    fn every_cav_gets_a_maneuver_even_when_nothing_is_safe() {
        let config = Config::default();
        let road = Road::paper_default();
        let v = |id: &str, kind, s, lane, speed| {
            VehicleState::on_lane(id, kind, Origin::Main, s, lane, speed)
        };
        let scene = Scene {
            time: 3.0,
            road: road.clone(),
            vehicles: vec![
                v("main.1", Kind::Cav, 100.0, 1, 35.0),
                v("main.2", Kind::Hdv, 106.0, 1, 0.0),
                v("main.3", Kind::Hdv, 106.0, 2, 0.0),
                v("main.4", Kind::Cav, 300.0, 2, 30.0),
            ],
        };
        let mut ctl = BkPbs::new(&config, Box::new(ConstantSpeed::new(&config)), &road);
        let mut out = Vec::new();
        ctl.plan(&scene, &mut out);
        let cavs: Vec<usize> = out.iter().map(|c| c.vehicle).collect();
        assert_eq!(cavs, vec![0, 3]);
        let stuck = out[0].maneuver;
        assert!(
            stuck.speed < 35.0 - 1.0,
            "the doomed CAV brakes hard: {stuck:?}"
        );
        assert!(ctl.last_stats().pbs_fallbacks == 1);
    }
}
