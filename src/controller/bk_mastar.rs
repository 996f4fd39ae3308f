//! `bk-mastar`: every CAV planned on its own by M-A* against the predicted trajectories of all
//! other vehicles (HDVs by the predictor, other CAVs at constant speed in their lane), with no
//! conflict resolution between CAVs (paper section V.C). The first primitive of each plan is
//! executed; a CAV without a plan in either phase brakes at the emergency deceleration, and the
//! step records a fallback.

use std::collections::HashMap;
use std::sync::Arc;

use super::{CavHandling, Command, Controller, LaneChange, Maneuver, PlanStats};
use crate::config::Config;
use crate::kinematics::BicycleState;
use crate::mastar::{FirstMove, Mastar, OngoingLaneChange, Phase, Request};
use crate::math::Point;
use crate::predict::{ConstantSpeed, Predictor};
use crate::road::MERGE_LANE;
use crate::scene::{Kind, Origin, Scene};
use crate::trajectory::Trajectory;

/// Decentralised M-A* planner.
pub struct BkMastar {
    config: Config,
    predictor: Box<dyn Predictor>,
    others: ConstantSpeed,
    planner: Option<Mastar>,
    /// Lane changes commanded and not yet finished: (time they end, target lane).
    ongoing: HashMap<Arc<str>, (f64, i32)>,
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
            ongoing: HashMap::new(),
            stats: PlanStats::default(),
        }
    }

    fn lane_change_steps(&self) -> usize {
        let s = &self.config.scenario;
        (s.lane_change_duration / s.dt).round().max(1.0) as usize
    }
}

/// The M-A* request of scene vehicle `i`, given the lane change it is executing, if any.
pub fn request_for<'a>(
    scene: &Scene,
    i: usize,
    ongoing: Option<(f64, i32)>,
    dt: f64,
    obstacles: &'a [&'a Trajectory],
) -> Request<'a> {
    let v = &scene.vehicles[i];
    let w = scene.road.lane_width;
    let ongoing = ongoing.and_then(|(end, target)| {
        let steps_left = ((end - scene.time) / dt).round();
        (steps_left >= 1.0).then_some(OngoingLaneChange {
            target_lane: target,
            steps_left: steps_left as usize,
        })
    });
    let lane = ongoing.map_or(v.lane, |o| o.target_lane);
    let cos = v.heading.cos().max(0.5);
    Request {
        start: BicycleState {
            pos: Point::new(v.s, v.lane as f64 * w + v.lateral),
            heading: v.heading,
            speed: v.speed / cos,
        },
        lane,
        ongoing,
        must_merge: v.origin == Origin::Ramp && lane == MERGE_LANE,
        length: v.length,
        width: v.width,
        obstacles,
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
        self.ongoing.retain(|_, (end, _)| *end > now + 1e-6);
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
            let req = request_for(scene, i, self.ongoing.get(&v.id).copied(), dt, &obstacles);
            stats.searches += 1;
            let maneuver = match planner.plan(&req) {
                Ok(plan) => {
                    stats.nodes_expanded += plan.expanded as u64;
                    stats.phase2_plans += (plan.phase == Phase::Fallback) as u64;
                    let lane_change = match plan.first {
                        FirstMove::Start(p) if p.is_lane_change() => {
                            let target = req.lane + p.lane_offset();
                            self.ongoing
                                .insert(v.id.clone(), (now + lc_steps as f64 * dt, target));
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
