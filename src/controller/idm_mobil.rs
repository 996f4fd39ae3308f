//! The `idm-mobil` baseline: IDM + MOBIL computed in Rust for every CAV (desired speed v_max),
//! with the HDV model's parameters, commanded through SUMO with SUMO's own checks off.

use std::collections::HashMap;
use std::sync::Arc;

use super::{idm, mobil, CavHandling, Command, Controller, LaneChange, Maneuver, Source};
use crate::config::{Config, Idm, Mobil};
use crate::model::scene::{Kind, Scene};

/// Slack of time comparisons on the step grid (s).
const TIME_EPSILON: f64 = 1e-6;

/// Rule-based CAV controller.
#[derive(Debug, Clone)]
pub struct IdmMobil {
    idm: Idm,
    mobil: Mobil,
    dt: f64,
    v_max: f64,
    last_change: HashMap<Arc<str>, f64>,
}

impl IdmMobil {
    /// The controller with `config`'s IDM and MOBIL parameters, step length and desired speed
    /// (`scenario.v_max`).
    pub fn new(config: &Config) -> Self {
        IdmMobil {
            idm: config.idm.clone(),
            mobil: config.mobil.clone(),
            dt: config.scenario.dt,
            v_max: config.scenario.v_max,
            last_change: HashMap::new(),
        }
    }

    fn lane_change(&self, scene: &Scene, i: usize) -> Option<LaneChange> {
        let me = &scene.vehicles[i];
        if me.on_ramp || me.changing_lanes() {
            return None;
        }
        let road = &scene.road;
        if road.is_auxiliary(me.lane) {
            // The merge is mandatory: only its safety matters.
            let target = road.toward_main(me.lane);
            return mobil::merge_is_safe(&self.mobil, scene, i, target)
                .then(|| LaneChange::between(me.lane, target))
                .flatten();
        }
        if let Some(t) = self.last_change.get(&me.id) {
            // Times lie on the step grid but are not exact in binary: compare with a margin
            // far below a step, so a change exactly one interval ago counts as one interval.
            if scene.time - t < self.mobil.decision_interval - TIME_EPSILON {
                return None;
            }
        }
        let mut best: Option<(f64, LaneChange)> = None;
        for dir in [LaneChange::Left, LaneChange::Right] {
            let target = me.lane + dir.offset();
            if road.is_auxiliary(target) {
                continue; // main-road vehicles never enter the acceleration lane
            }
            if let Some(g) = mobil::evaluate(&self.idm, &self.mobil, scene, i, target) {
                if best.is_none_or(|(bg, _)| g > bg) {
                    best = Some((g, dir));
                }
            }
        }
        best.map(|(_, d)| d)
    }
}

impl Controller for IdmMobil {
    fn name(&self) -> &'static str {
        "idm-mobil"
    }

    fn handling(&self) -> CavHandling {
        CavHandling::Commanded
    }

    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        for (i, v) in scene.vehicles.iter().enumerate() {
            if v.kind != Kind::Cav {
                continue;
            }
            let mut a = mobil::idm_in_lane(&self.idm, scene, i, v.lane);
            if scene.road.is_auxiliary(v.lane) && !v.on_ramp {
                // Gap seeking: on the acceleration lane also follow the nearest vehicle ahead on
                // the main road, so the CAV lines up behind a gap instead of racing past it.
                let target = scene.road.toward_main(v.lane);
                if let Some(j) = mobil::leader_index(scene, target, v.s, i) {
                    let l = &scene.vehicles[j];
                    let gap = l.rear() - v.front();
                    if gap > 0.0 {
                        let leader = idm::Leader {
                            gap,
                            speed: l.speed,
                        };
                        a = a.min(idm::acceleration(
                            &self.idm,
                            v.speed,
                            v.desired_speed,
                            Some(leader),
                        ));
                    }
                }
            }
            // No more than the vehicle can (a truck's type accelerates at 1.3 m/s², below IDM's).
            let a = a.clamp(-v.limits.emergency_decel, v.limits.accel);
            let lane_change = self.lane_change(scene, i);
            if lane_change.is_some() {
                self.last_change.insert(v.id.clone(), scene.time);
            }
            out.push(Command {
                vehicle: i,
                maneuver: Maneuver {
                    speed: (v.speed + a * self.dt).clamp(0.0, self.v_max),
                    lane_change,
                },
                source: Source::Rule,
            });
        }
        if self.last_change.len() > 4 * scene.vehicles.len() + 64 {
            let horizon = scene.time - self.mobil.decision_interval;
            self.last_change.retain(|_, t| *t >= horizon);
        }
    }
}
