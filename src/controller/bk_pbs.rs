//! `bk-pbs`: all CAVs planned jointly each step by BK-PBS (see [`crate::planner::pbs`]); each CAV then
//! executes the first primitive of its plan. A CAV the chosen node leaves without a plan (no
//! plan even alone), or still in conflict after a fallback, is repaired: planned alone against
//! every other trajectory of that node, and if that fails too, it brakes at the emergency
//! deceleration. Every CAV always gets a maneuver. What it shares with `bk-mastar` lives in
//! [`crate::controller::search_planner`].

use std::sync::Arc;

use rayon::prelude::*;

use crate::config::Config;
use crate::controller::search_planner::{Round, RoundPlanner, SearchCore, SearchPlanner};
use crate::controller::{Command, PlanStats, Source};
use crate::model::road::Road;
use crate::model::scene::{Kind, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::lane_changes::SceneRequests;
use crate::planner::lane_end::merge_order;
use crate::planner::mastar::{NoPlan, Plan};
use crate::planner::pbs::{Budget, PbsStats, Problem, RequestFor, Solution};
use crate::predict::Predictor;

/// Centralised priority-based planner.
pub type BkPbs = SearchPlanner<Joint>;

impl BkPbs {
    /// With `predictor` for HDVs (conditioned on higher-priority CAVs when it can be), on `road`.
    pub fn new(config: &Config, predictor: Box<dyn Predictor>, road: &Road) -> Self {
        let rounds = Joint {
            commitments: Commitments::default(),
        };
        SearchPlanner::with_rounds(config, predictor, road, rounds)
    }
}

/// BK-PBS's round: every CAV planned jointly, the commitments of earlier rounds kept.
pub struct Joint {
    commitments: Commitments,
}

impl RoundPlanner for Joint {
    const NAME: &'static str = "bk-pbs";

    fn plan_round(
        &mut self,
        core: &SearchCore,
        scene: &Scene,
        round: &mut Round,
        out: &mut Vec<Command>,
    ) {
        let requests = SceneRequests::new(scene, &core.lane_changes, core.dt(), core.guard());
        let mut committed = self.commitments.in_scene(scene, scene.time);
        let idm = &core.config.idm;
        let lane_end = merge_order(scene, idm.min_gap, idm.decel);
        committed.extend(&lane_end);
        let problem = problem(core, scene, &requests, &committed);
        let solution = problem.solve();
        round.stats += search_stats(&solution.stats);
        let executed = executed_plans(&problem, &solution, &requests, &lane_end);
        for (i, executed) in executed.into_iter().enumerate() {
            let Some(executed) = executed else { continue };
            let (plan, planned_by) = match executed {
                Executed::Node(plan, source) => (Some(plan), source),
                Executed::Repair(result) => {
                    round.count_search(result.as_ref().map(|p| p.as_ref()));
                    (result.ok(), Source::Repair)
                }
            };
            let others = solution.trajectories.iter().map(|t| &**t).enumerate();
            out.push(round.command(core, scene, i, plan.as_deref(), planned_by, others));
        }
        let until = round.starts_end(core, scene);
        self.commitments
            .record(scene, &solution.edges, &round.starts, until);
    }
}

/// This step's BK-PBS problem: every CAV of `scene`, planned with M-A* and judged by the same
/// safety rule M-A* plans with, over the check horizon.
fn problem<'a>(
    core: &'a SearchCore,
    scene: &'a Scene,
    requests: &'a SceneRequests<'a>,
    committed: &'a [(usize, usize)],
) -> Problem<'a> {
    let pbs = &core.config.pbs;
    Problem {
        scene,
        planner: &core.planner,
        predictor: core.predictor.as_ref(),
        requests,
        committed,
        rule: &core.planner.rule,
        horizon: core.horizon(),
        dt: core.dt(),
        budget: Budget {
            nodes: pbs.node_budget,
            time_ms: (pbs.time_budget_ms > 0.0).then_some(pbs.time_budget_ms),
        },
        independent_groups: pbs.independent_groups.applies(scene.vehicles.len()),
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

/// What each agent executes (`None` for HDVs). After a fallback, the CAVs still in conflict
/// are repaired; repairs are independent of each other (each against the node's trajectories):
/// made in parallel, then used in order. `lane_end` is the round's merge order at the lane
/// ends ([`merge_order`]), which repairs keep too.
fn executed_plans(
    problem: &Problem<'_>,
    solution: &Solution,
    requests: &SceneRequests<'_>,
    lane_end: &[(usize, usize)],
) -> Vec<Option<Executed>> {
    let scene = problem.scene;
    let conflicted = solution
        .stats
        .fallback
        .then(|| problem.conflicted_agents(&solution.trajectories));
    (0..scene.vehicles.len())
        .into_par_iter()
        .map(|i| {
            let in_conflict = conflicted.as_ref().is_some_and(|c| c[i]);
            (scene.vehicles[i].kind == Kind::Cav).then(|| {
                let below: Vec<usize> = lane_end
                    .iter()
                    .filter(|&&(hi, _)| hi == i)
                    .map(|&(_, lo)| lo)
                    .collect();
                executed_plan(problem, solution, requests, (i, &below), in_conflict)
            })
        })
        .collect()
}

/// What CAV `i` executes: the chosen node's plan, or a repair when the node left it without
/// one or, after a fallback, `in_conflict`: planned alone against every other trajectory of
/// the node but those of the agents it goes before at a lane end (`below`), which wait for it:
/// repaired against a waiting merger's plan to merge, a lane-1 CAV braked to a stand beside it
/// and held it there.
fn executed_plan(
    problem: &Problem<'_>,
    solution: &Solution,
    requests: &SceneRequests<'_>,
    (i, below): (usize, &[usize]),
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
        .filter(|(j, _)| *j != i && !below.contains(j))
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
    use crate::controller::Controller;
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
