//! Stochastic merging of ramp HDVs (the scenario of docs/src/scenarios.md), applied through TraCI.
//!
//! A ramp HDV on the acceleration lane that has not yet decided draws, each step, a decision with
//! probability ξ^k, where ξ ∈ [0, 1] is the share of the merge zone its front has driven and k is
//! `ramp_merge.exponent` (default 1: the probability grows linearly and is 1 at the zone's end).
//! Once decided, it asks SUMO every step to move to the main road's right lane; SUMO executes the
//! request only into a gap it deems safe (the vehicle adapts its speed to find one). Decisions use
//! their own random stream, so they are reproducible for a seed and independent of the demand.
//!
//! Under a gap-acceptance driver profile (`[hdv]`, e.g. `paper`) a decided HDV instead draws a
//! critical time gap and moves over, without SUMO's safety check, whenever the gaps to its new
//! follower and leader are at least that long (see [`accepts`]).
//!
//! A decided HDV standing at the very end of the acceleration lane forces its way in (SUMO then
//! only avoids immediate collisions), as a stuck human driver does. Without it SUMO deadlocks:
//! its main-lane follower stops to let the merger in (LC2013's cooperation) while the merger,
//! standing, waits for a safe gap that never opens (seen with bk-mastar, α = 0.4, λ = 2500,
//! seed 4: the right lane stood still for the last 50 s).

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::config::hdv::RampMergeStyle;
use crate::config::Config;
use crate::model::scene::{Kind, Origin, Scene};

/// Random stream of the merge decisions.
pub const MERGE_STREAM: u64 = 2;

/// A merge request of one ramp HDV this step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MergeRequest {
    /// Scene index of the HDV.
    pub vehicle: usize,
    /// Merge ignoring SUMO's safe gaps (avoiding only immediate collisions): stuck at the lane
    /// end, or a gap the driver accepted (gap-acceptance profiles).
    pub forced: bool,
}

/// Per-episode state of the ramp HDVs' merge decisions.
#[derive(Debug, Clone)]
pub struct RampMergeRule {
    exponent: f64,
    style: RampMergeStyle,
    rng: ChaCha8Rng,
    decided: HashSet<Arc<str>>,
    /// Each decided driver's critical time gap (s), gap-acceptance profiles only.
    critical_gap: HashMap<Arc<str>, f64>,
    /// Comfortable deceleration of the HDVs (`idm.decel`), for the gap to the new leader.
    decel: f64,
}

impl RampMergeRule {
    /// The rule for one episode: `config`'s merge exponent and HDV profile, random stream seeded
    /// from `scenario.seed`, no driver decided yet.
    pub fn new(config: &Config) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(config.scenario.seed);
        rng.set_stream(MERGE_STREAM);
        let style = config
            .hdv
            .resolved()
            .map_or(RampMergeStyle::Safe, |p| p.ramp_merge);
        RampMergeRule {
            exponent: config.ramp_merge.exponent,
            style,
            rng,
            decided: HashSet::new(),
            critical_gap: HashMap::new(),
            decel: config.idm.decel,
        }
    }

    /// Per-step decision probability at merge-zone progress `xi`.
    pub fn probability(&self, xi: f64) -> f64 {
        xi.clamp(0.0, 1.0).powf(self.exponent)
    }

    /// Whether the vehicle has decided to merge.
    pub fn has_decided(&self, id: &str) -> bool {
        self.decided.contains(id)
    }

    /// Draws this step's decisions; returns the HDVs that want to merge now.
    pub fn requests(&mut self, scene: &Scene) -> Vec<MergeRequest> {
        let road = &scene.road;
        let mut out = Vec::new();
        for (i, v) in scene.vehicles.iter().enumerate() {
            let Some(merge) = road.zone_on(v.lane, v.front()) else {
                continue;
            };
            if v.kind != Kind::Hdv || v.origin != Origin::Ramp || v.on_ramp {
                continue;
            }
            if !self.decided.contains(&v.id) {
                let xi = (v.front() - merge.start) / (merge.end - merge.start);
                let p = self.probability(xi);
                if self.rng.gen::<f64>() < p {
                    self.decide(&v.id);
                }
            }
            if !self.decided.contains(&v.id) {
                continue;
            }
            if road.forces_merge(v.lane, v.front(), v.speed) {
                out.push(MergeRequest {
                    vehicle: i,
                    forced: true,
                });
            } else if let Some(&gap) = self.critical_gap.get(&v.id) {
                if accepts(scene, i, gap, self.decel) {
                    out.push(MergeRequest {
                        vehicle: i,
                        forced: true,
                    });
                }
            } else {
                out.push(MergeRequest {
                    vehicle: i,
                    forced: false,
                });
            }
        }
        out
    }

    /// Records the decision and, with gap acceptance, draws the driver's critical gap.
    fn decide(&mut self, id: &Arc<str>) {
        self.decided.insert(id.clone());
        if let RampMergeStyle::GapAcceptance { median_s, log_sd } = self.style {
            let z = standard_normal(&mut self.rng);
            self.critical_gap
                .insert(id.clone(), median_s * (log_sd * z).exp());
        }
    }
}

/// A standard normal draw (Box–Muller).
fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.gen::<f64>();
    let u2: f64 = rng.gen();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Gap acceptance of the ramp HDV at scene index `i` into the lane to its left: the new
/// follower at least `critical_gap` seconds behind (at the follower's speed); ahead, room to
/// brake behind the new leader at the comfortable `decel` plus half the critical gap at its own
/// speed. Nothing alongside. The driver risks the follower's safety, not its own: a merger
/// accepting a short gap behind a standing car drove into it.
pub fn accepts(scene: &Scene, i: usize, critical_gap: f64, decel: f64) -> bool {
    let v = &scene.vehicles[i];
    let target = scene.road.toward_main(v.lane);
    scene.vehicles.iter().filter(|u| u.lane == target).all(|u| {
        if u.front() <= v.rear() {
            v.rear() - u.front() >= critical_gap * u.speed.max(0.1)
        } else if u.rear() >= v.front() {
            let braking = (v.speed.powi(2) - u.speed.powi(2)).max(0.0) / (2.0 * decel);
            u.rear() - v.front() >= 0.5 * critical_gap * v.speed.max(0.1) + braking
        } else {
            false
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::road::Road;
    use crate::model::scene::VehicleState;

    fn ramp_hdv(s: f64) -> VehicleState {
        VehicleState {
            desired_speed: 30.0,
            ..VehicleState::on_lane("ramp.1", Kind::Hdv, Origin::Ramp, s, 0, 20.0)
        }
    }

    #[test]
    fn probability_grows_to_one_at_the_zone_end() {
        let r = RampMergeRule::new(&Config::default());
        assert_eq!(r.probability(0.0), 0.0);
        assert_eq!(r.probability(0.5), 0.5);
        assert_eq!(r.probability(1.0), 1.0);
        assert_eq!(r.probability(1.7), 1.0);
    }

    #[test]
    fn at_the_zone_end_the_decision_is_certain_and_sticks() {
        let mut r = RampMergeRule::new(&Config::default());
        let road = Road::paper_default();
        let scene = Scene {
            time: 0.0,
            road: road.clone(),
            vehicles: vec![ramp_hdv(road.zones[0].end - 2.5)],
        };
        assert_eq!(
            r.requests(&scene)
                .iter()
                .map(|m| m.vehicle)
                .collect::<Vec<_>>(),
            vec![0]
        );
        let back = Scene {
            time: 0.2,
            road,
            vehicles: vec![ramp_hdv(160.0)],
        };
        assert_eq!(r.requests(&back).len(), 1, "a decided vehicle keeps asking");
    }

    #[test]
    fn standing_at_the_lane_end_forces_the_merge() {
        let mut r = RampMergeRule::new(&Config::default());
        let road = Road::paper_default();
        let mut v = ramp_hdv(road.zones[0].end - 2.5 - 1.0);
        v.speed = 0.1;
        let scene = Scene {
            time: 0.0,
            road: road.clone(),
            vehicles: vec![v.clone()],
        };
        assert!(r.requests(&scene)[0].forced);
        v.speed = 5.0;
        let scene = Scene {
            time: 0.2,
            road,
            vehicles: vec![v],
        };
        assert!(!r.requests(&scene)[0].forced);
    }

    #[test]
    fn empirical_decision_rate_matches_probability() {
        let road = Road::paper_default();
        let mut decided = 0;
        let n = 4000;
        for seed in 0..n {
            let mut c = Config::default();
            c.scenario.seed = seed;
            let mut r = RampMergeRule::new(&c);
            // front at 25 % of the zone
            let s = road.zones[0].start + 0.25 * 180.0 - 2.5;
            let scene = Scene {
                time: 0.0,
                road: road.clone(),
                vehicles: vec![ramp_hdv(s)],
            };
            decided += (!r.requests(&scene).is_empty()) as usize;
        }
        let rate = decided as f64 / n as f64;
        assert!((rate - 0.25).abs() < 0.025, "{rate}");
    }

    #[test]
    fn gap_acceptance_wants_the_critical_gap_behind_and_room_to_brake_ahead() {
        let road = Road::paper_default();
        let with = |follower_s: f64, leader_s: f64| Scene {
            time: 0.0,
            road: road.clone(),
            vehicles: vec![
                ramp_hdv(150.0),
                VehicleState::on_lane("f", Kind::Cav, Origin::Main, follower_s, 1, 25.0),
                VehicleState::on_lane("l", Kind::Hdv, Origin::Main, leader_s, 1, 25.0),
            ],
        };
        // Critical gap 1 s: 25 m behind (at the follower's 25 m/s), 10 m ahead (at 20 m/s; the
        // leader is faster, so no braking room).
        let ok = |follower: f64, leader: f64| accepts(&with(follower, leader), 0, 1.0, 5.0);
        assert!(ok(150.0 - 5.0 - 25.5, 150.0 + 5.0 + 10.5));
        assert!(!ok(150.0 - 5.0 - 24.5, 150.0 + 5.0 + 10.5));
        assert!(!ok(150.0 - 5.0 - 25.5, 150.0 + 5.0 + 9.5));
        assert!(!ok(152.0, 300.0), "a car alongside");
        // Behind a standing car it also wants room to brake: 20²/(2·5) = 40 m more.
        let mut standing = with(100.0, 150.0 + 2.5 + 45.0);
        standing.vehicles[2].speed = 0.0;
        assert!(!accepts(&standing, 0, 1.0, 5.0));
        standing.vehicles[2].s += 10.0;
        assert!(accepts(&standing, 0, 1.0, 5.0));
    }
}
