//! What the two search-based controllers (`bk-mastar`, `bk-pbs`) share: the HDV predictor, the
//! M-A* planner, the lane changes under way, the shield's check of lane-change starts, tracing,
//! and how a CAV's plan (or the lack of one: braking) becomes its command.
//!
//! They differ only in how a round is planned (each CAV alone, or all jointly by BK-PBS): that
//! part is a [`RoundPlanner`], and [`SearchPlanner`] wraps it into a [`Controller`] once, so the
//! two cannot drift apart in what they execute, count or trace.

use std::sync::Arc;

use crate::config::Config;
use crate::controller::shield::{self, WorstCase};
use crate::controller::{execute, CavBelief, CavHandling, Command, Controller, PlanStats, Source};
use crate::model::road::Road;
use crate::model::scene::Scene;
use crate::model::trajectory::Trajectory;
use crate::planner::guard::StartGuard;
use crate::planner::lane_changes::LaneChanges;
use crate::planner::mastar::{Mastar, NoPlan, Plan};
use crate::predict::Predictor;

/// How a search-based controller plans one round: a command per CAV of `scene` into `out`,
/// each made by [`Round::command`].
pub trait RoundPlanner: Send {
    /// The controller's name on the command line and in CSV files.
    const NAME: &'static str;

    /// Plans one round for `scene`: one command per CAV into `out` (which arrives empty), each
    /// made by [`Round::command`]; the round's effort and lane-change starts go into `round`.
    fn plan_round(
        &mut self,
        core: &SearchCore,
        scene: &Scene,
        round: &mut Round,
        out: &mut Vec<Command>,
    );
}

/// What every round reads: the configuration, the predictor, the planner, the lane changes
/// under way and the shield's check of starts.
pub struct SearchCore {
    /// The configuration the controller was built with.
    pub config: Config,
    /// The HDV predictor: the trajectories the CAVs are planned against.
    pub predictor: Box<dyn Predictor>,
    /// The single-CAV M-A* planner.
    pub planner: Mastar,
    /// The lane changes under way (continued, not re-planned, until they end).
    pub lane_changes: LaneChanges,
    /// The shield's check of lane-change starts, when the shield is on.
    guard: Option<WorstCase>,
}

impl SearchCore {
    /// Step length (s).
    pub fn dt(&self) -> f64 {
        self.config.scenario.dt
    }

    /// Steps predicted and checked: the planner's horizon plus one lane change.
    pub fn horizon(&self) -> usize {
        self.planner.check_horizon()
    }

    /// How long a lane change takes (s), on the step grid.
    fn lane_change_duration(&self) -> f64 {
        self.config.scenario.lane_change_steps() as f64 * self.dt()
    }

    /// The check lane-change starts must pass, if the shield is on.
    pub fn guard(&self) -> Option<&dyn StartGuard> {
        self.guard.as_ref().map(|g| g as &dyn StartGuard)
    }
}

/// A lane change a round starts: (scene index, vehicle id, target lane).
pub type Start = (usize, Arc<str>, i32);

/// What one round produces besides its commands: its effort, the beliefs (while tracing) and
/// the lane changes it starts (recorded after the round, as the round reads those under way).
pub struct Round {
    /// The round's search effort, counted as it plans.
    pub stats: PlanStats,
    tracing: bool,
    beliefs: Vec<CavBelief>,
    /// The lane changes the round starts, recorded into [`SearchCore::lane_changes`] after it.
    pub starts: Vec<Start>,
}

impl Round {
    /// Counts one M-A* call (see [`execute::count_search`]).
    pub fn count_search(&mut self, result: Result<&Plan, &NoPlan>) {
        execute::count_search(&mut self.stats, result);
    }

    /// The command of CAV `i` that executes `plan` (braking without one), which `planned_by`
    /// made; the vehicles it was checked against, `others`, go into its belief while tracing.
    pub fn command<'t>(
        &mut self,
        core: &SearchCore,
        scene: &Scene,
        i: usize,
        plan: Option<&Plan>,
        planned_by: Source,
        others: impl Iterator<Item = (usize, &'t Trajectory)>,
    ) -> Command {
        let v = &scene.vehicles[i];
        let dt = core.dt();
        let lane = core.lane_changes.planning_lane(scene, i, dt);
        let changing = core.lane_changes.ongoing(&v.id, scene.time, dt).is_some();
        let source = execute::source_of(planned_by, plan.is_some(), changing);
        if self.tracing {
            let planned = plan.map(|p| &p.trajectory);
            self.beliefs
                .push(execute::belief(scene, i, planned, others));
        }
        let decel = core.config.planner.emergency_decel;
        let (maneuver, target) = execute::maneuver_for(plan, v, lane, decel, dt, &mut self.stats);
        if let Some(target) = target {
            self.starts.push((i, v.id.clone(), target));
        }
        Command {
            vehicle: i,
            maneuver,
            source,
        }
    }

    /// When the lane changes started now end.
    pub fn starts_end(&self, core: &SearchCore, scene: &Scene) -> f64 {
        scene.time + core.lane_change_duration()
    }
}

/// Every trajectory of `ts` but agent `i`'s: what a CAV planned alone is checked against.
pub fn all_but<'t>(ts: impl IntoIterator<Item = &'t Trajectory>, i: usize) -> Vec<&'t Trajectory> {
    ts.into_iter()
        .enumerate()
        .filter(|(j, _)| *j != i)
        .map(|(_, t)| t)
        .collect()
}

/// A search-based controller: the shared core around the round planner `R`.
pub struct SearchPlanner<R> {
    core: SearchCore,
    rounds: R,
    stats: PlanStats,
    tracing: bool,
    beliefs: Vec<CavBelief>,
}

impl<R: RoundPlanner> SearchPlanner<R> {
    /// `rounds` with `predictor` for HDVs, on `road`.
    pub fn with_rounds(
        config: &Config,
        predictor: Box<dyn Predictor>,
        road: &Road,
        rounds: R,
    ) -> Self {
        SearchPlanner {
            core: SearchCore {
                config: config.clone(),
                predictor,
                planner: Mastar::from_config(config, road.clone()),
                lane_changes: LaneChanges::default(),
                guard: shield::start_guard(config),
            },
            rounds,
            stats: PlanStats::default(),
            tracing: false,
            beliefs: Vec::new(),
        }
    }
}

impl<R: RoundPlanner> Controller for SearchPlanner<R> {
    fn name(&self) -> &'static str {
        R::NAME
    }

    fn handling(&self) -> CavHandling {
        CavHandling::Commanded
    }

    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        let now = scene.time;
        self.core.lane_changes.forget_finished(now);
        let mut round = Round {
            stats: PlanStats::default(),
            tracing: self.tracing,
            beliefs: Vec::new(),
            starts: Vec::new(),
        };
        self.rounds.plan_round(&self.core, scene, &mut round, out);
        let duration = self.core.lane_change_duration();
        for (_, id, target) in &round.starts {
            self.core.lane_changes.start(id, now, duration, *target);
        }
        self.stats = round.stats;
        self.beliefs = round.beliefs;
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
        self.core.lane_changes.cancel(id);
    }
}
