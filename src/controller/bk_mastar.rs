//! `bk-mastar`: every CAV planned on its own by M-A* against the predicted trajectories of all
//! other vehicles (HDVs by the predictor, other CAVs at constant speed in their lane), with no
//! conflict resolution between CAVs (paper section V.C). The first primitive of each plan is
//! executed; a CAV without a plan in either phase brakes at the emergency deceleration, and the
//! step records a fallback.

use super::lane_changes::LaneChanges;
use super::{CavHandling, Command, Controller, LaneChange, Maneuver, PlanStats};
use crate::config::Config;
use crate::mastar::{FirstMove, Mastar, Phase};
use crate::predict::{ConstantSpeed, Predictor};
use crate::scene::{Kind, Scene};
use crate::trajectory::Trajectory;

/// Decentralised M-A* planner.
pub struct BkMastar {
    config: Config,
    predictor: Box<dyn Predictor>,
    others: ConstantSpeed,
    planner: Option<Mastar>,
    lane_changes: LaneChanges,
    stats: PlanStats,
}

impl BkMastar {
    /// With `predictor` for HDVs.
    pub fn new(config: &Config, predictor: Box<dyn Predictor>) -> Self {
        BkMastar {
            config: config.clone(),
            predictor,
            others: ConstantSpeed::new(config),
            planner: None,
            lane_changes: LaneChanges::default(),
            stats: PlanStats::default(),
        }
    }

    fn lane_change_steps(&self) -> usize {
        let s = &self.config.scenario;
        (s.lane_change_duration / s.dt).round().max(1.0) as usize
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
        let (dt, v_max) = (sc.dt, sc.v_max);
        let lc_steps = self.lane_change_steps();
        let horizon = self.config.planner.horizon + lc_steps;
        let planner = self.planner.get_or_insert_with(|| {
            Mastar::new(
                &self.config.planner,
                scene.road.clone(),
                dt,
                sc.lane_change_duration,
                v_max,
            )
        });
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
            let req = self.lane_changes.request(scene, i, dt, &obstacles);
            stats.searches += 1;
            let maneuver = match planner.plan(&req) {
                Ok(plan) => {
                    stats.nodes_expanded += plan.expanded as u64;
                    stats.phase2_plans += (plan.phase == Phase::Fallback) as u64;
                    let lane_change = match plan.first {
                        FirstMove::Start(p) if p.is_lane_change() => {
                            let target = req.lane + p.lane_offset();
                            self.lane_changes
                                .start(&v.id, now, lc_steps as f64 * dt, target);
                            Some(if p.lane_offset() > 0 {
                                LaneChange::Left
                            } else {
                                LaneChange::Right
                            })
                        }
                        _ => None,
                    };
                    Maneuver {
                        speed: plan.next_speed().clamp(0.0, v_max),
                        lane_change,
                    }
                }
                Err(e) => {
                    stats.nodes_expanded += e.expanded as u64;
                    stats.fallbacks += 1;
                    let brake = self.config.planner.emergency_decel * dt;
                    Maneuver {
                        speed: (v.speed - brake).max(0.0),
                        lane_change: None,
                    }
                }
            };
            out.push(Command {
                vehicle: i,
                maneuver,
            });
        }
        self.stats = stats;
    }

    fn last_stats(&self) -> PlanStats {
        self.stats
    }
}
