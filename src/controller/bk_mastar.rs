//! `bk-mastar`: every CAV planned on its own by M-A* against the predicted trajectories of all
//! other vehicles (HDVs by the predictor, other CAVs at constant speed in their lane), with no
//! conflict resolution between CAVs (paper section V.C). The first primitive of each plan is
//! executed; a CAV without a plan in either phase brakes at the emergency deceleration, and the
//! step records a fallback.

use super::shield::{self, Bounds};
use super::{execute, CavBelief, CavHandling, Command, Controller, PlanStats, Source};
use crate::config::Config;
use crate::model::road::Road;
use crate::model::scene::{Kind, Scene};
use crate::model::trajectory::Trajectory;
use crate::planner::guard::StartGuard;
use crate::planner::lane_changes::LaneChanges;
use crate::planner::mastar::Mastar;
use crate::predict::{ConstantSpeed, Predictor};

/// Decentralised M-A* planner.
pub struct BkMastar {
    config: Config,
    predictor: Box<dyn Predictor>,
    others: ConstantSpeed,
    planner: Mastar,
    lane_changes: LaneChanges,
    /// The shield's check of lane-change starts, when the shield is on.
    guard: Option<Bounds>,
    stats: PlanStats,
    tracing: bool,
    beliefs: Vec<CavBelief>,
}

impl BkMastar {
    /// With `predictor` for HDVs, on `road`.
    pub fn new(config: &Config, predictor: Box<dyn Predictor>, road: &Road) -> Self {
        BkMastar {
            config: config.clone(),
            predictor,
            others: ConstantSpeed::new(config),
            planner: Mastar::from_config(config, road.clone()),
            lane_changes: LaneChanges::default(),
            guard: shield::start_guard(config),
            stats: PlanStats::default(),
            tracing: false,
            beliefs: Vec::new(),
        }
    }
}

impl Controller for BkMastar {
    fn name(&self) -> &'static str {
        "bk-mastar"
    }

    fn handling(&self) -> CavHandling {
        CavHandling::Commanded
    }

    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        let sc = &self.config.scenario;
        let dt = sc.dt;
        let lc_steps = sc.lane_change_steps();
        let horizon = self.config.planner.horizon + lc_steps;
        let planner = &self.planner;
        let predictions: Vec<Trajectory> = scene
            .vehicles
            .iter()
            .enumerate()
            .map(|(j, v)| match v.kind {
                Kind::Hdv => self.predictor.predict(scene, j, &[], horizon),
                Kind::Cav => self.others.predict(scene, j, &[], horizon),
            })
            .collect();
        let now = scene.time;
        self.lane_changes.forget_finished(now);
        self.beliefs.clear();
        let mut stats = PlanStats::default();
        for (i, v) in scene.vehicles.iter().enumerate() {
            if v.kind != Kind::Cav {
                continue;
            }
            let obstacles: Vec<&Trajectory> = predictions
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, t)| t)
                .collect();
            let guard = self.guard.as_ref().map(|g| g as &dyn StartGuard);
            let req = self.lane_changes.request(scene, i, dt, &obstacles, guard);
            let result = planner.plan(&req);
            execute::count_search(&mut stats, result.as_ref());
            let decel = self.config.planner.emergency_decel;
            let (maneuver, target) =
                execute::maneuver_for(result.as_ref().ok(), v, req.lane, decel, dt, &mut stats);
            if let Some(target) = target {
                self.lane_changes
                    .start(&v.id, now, lc_steps as f64 * dt, target);
            }
            let changing = req.ongoing.is_some();
            let source = execute::source_of(Source::Plan, result.is_ok(), changing);
            if self.tracing {
                let others = predictions.iter().enumerate();
                let planned = result.as_ref().ok().map(|p| &p.trajectory);
                self.beliefs
                    .push(execute::belief(scene, i, planned, others));
            }
            out.push(Command {
                vehicle: i,
                maneuver,
                source,
            });
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
