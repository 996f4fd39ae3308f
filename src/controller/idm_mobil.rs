//! The `idm-mobil` baseline: IDM + MOBIL computed in Rust for every CAV (desired speed v_max),
//! with the HDV model's parameters, commanded through SUMO with SUMO's own checks off. On a
//! scenario of one's own each CAV follows with its type's parameters, leaves a merging ramp HDV
//! room, drops back behind a car that blocks its merge (`super::merging`) and changes into no
//! lane another vehicle is moving into nearby (`super::lane_claims`).

use std::collections::HashMap;
use std::sync::Arc;

use super::lane_claims::LaneClaims;
use super::merging::{self, nose_zone};
use super::{mobil, CavHandling, Command, Controller, LaneChange, Maneuver, Source};
use crate::config::{Config, Idm, Mobil};
use crate::model::scene::{Kind, Scene, VehicleState};

/// Slack of time comparisons on the step grid (s).
const TIME_EPSILON: f64 = 1e-6;

/// Rule-based CAV controller.
#[derive(Debug, Clone)]
pub struct IdmMobil {
    idm: Idm,
    mobil: Mobil,
    dt: f64,
    v_max: f64,
    /// Each CAV follows with its SUMO type's parameters ([`Mobil::follows_type`]).
    type_following: bool,
    /// CAVs let others merge and merge into gaps ([`Mobil::cooperates`]).
    cooperative: bool,
    last_change: HashMap<Arc<str>, f64>,
}

impl IdmMobil {
    /// The controller with `config`'s IDM and MOBIL parameters, step length and desired speed
    /// (`scenario.v_max`).
    pub fn new(config: &Config) -> Self {
        let own_scenario = config.scenario.sumocfg.is_some();
        IdmMobil {
            idm: config.idm.clone(),
            mobil: config.mobil.clone(),
            dt: config.scenario.dt,
            v_max: config.scenario.v_max,
            type_following: config.mobil.follows_type(own_scenario),
            cooperative: config.mobil.cooperates(own_scenario),
            last_change: HashMap::new(),
        }
    }

    /// The IDM parameters `v` follows with: `[idm]`'s, or with type following, where SUMO gave
    /// them, its type's `accel`, `decel`, `tau` and `minGap` as a, b, T and s0 (as SUMO's own
    /// IDM reads them).
    fn idm_of(&self, v: &VehicleState) -> Idm {
        match v.limits.following.filter(|_| self.type_following) {
            Some(f) => Idm {
                accel: v.limits.accel,
                decel: v.limits.decel,
                time_headway: f.tau,
                min_gap: f.min_gap,
                ..self.idm.clone()
            },
            None => self.idm.clone(),
        }
    }

    /// IDM's acceleration of scene vehicle `i`, lining up for its merge and leaving a merging
    /// ramp HDV room where it does either.
    fn acceleration(&self, scene: &Scene, i: usize) -> f64 {
        let v = &scene.vehicles[i];
        let p = self.idm_of(v);
        let committed = v.changing_lanes() && nose_zone(scene, v).is_some();
        let mut a = match committed {
            true => merging::committed_acceleration(&p, scene, i),
            false => mobil::idm_in_lane(&p, scene, i, v.lane),
        };
        if let Some(target) = merging::merge_target(scene, v) {
            let pm = (&p, &self.mobil);
            if let Some(seeking) =
                merging::seeking_acceleration(pm, scene, i, target, self.cooperative)
            {
                a = a.min(seeking);
            }
        }
        if self.cooperative {
            if let Some(yielding) = merging::courtesy_acceleration((&p, &self.mobil), scene, i) {
                a = a.min(yielding);
            }
        }
        a
    }

    fn lane_change(&self, scene: &Scene, i: usize) -> Option<LaneChange> {
        let me = &scene.vehicles[i];
        if me.changing_lanes() {
            return None;
        }
        let road = &scene.road;
        if me.on_ramp {
            // At a nose the merge is a commitment to drive into the target lane there.
            let target = nose_zone(scene, me)?.target();
            return mobil::merge_is_safe(&self.mobil, scene, i, target)
                .then(|| LaneChange::between(me.lane, target))
                .flatten();
        }
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
        let mut claims = LaneClaims::of_scene(scene);
        for (i, v) in scene.vehicles.iter().enumerate() {
            if v.kind != Kind::Cav {
                continue;
            }
            let a = self.acceleration(scene, i);
            // No more than the vehicle can (a truck's type accelerates at 1.3 m/s², below IDM's).
            let a = a.clamp(-v.limits.emergency_decel, v.limits.accel);
            let mut lane_change = self.lane_change(scene, i);
            if let Some(d) = lane_change.filter(|_| self.cooperative) {
                let target = v.lane + d.offset();
                match claims.admit(&self.mobil, scene, i, target) {
                    true => claims.claim(i, target),
                    false => lane_change = None,
                }
            }
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
