//! The constant-speed predictor: every vehicle keeps its speed and its lane, except that a ramp
//! HDV on the acceleration lane merges when the scenario's stochastic rule makes it more likely
//! than not to have decided, executing the lane change as SUMO does (constant lateral speed over
//! the lane-change duration); a standing one only once the lane beside it is free
//! ([`super::blocked`]).

use super::blocked::Blocking;
use super::longitudinal::Longitudinal;
use super::Predictor;
use crate::config::Config;
use crate::model::scene::{Kind, Origin, Scene};
use crate::model::trajectory::Trajectory;

/// Keeps speed and lane; ramp HDVs merge at their median decision time.
#[derive(Debug, Clone)]
pub struct ConstantSpeed {
    dt: f64,
    lane_change_steps: usize,
    merge_exponent: f64,
    /// Hardest braking of an HDV (SUMO's emergencyDecel), carried by its predictions.
    hdv_brake: f64,
    /// How predicted HDVs move along their lane (the name's constant speed by default).
    longitudinal: Longitudinal,
    /// When a standing HDV can start its merge.
    blocking: Blocking,
}

impl ConstantSpeed {
    /// The predictor of `config`: its step length, lane-change duration, ramp merge rule and
    /// HDV emergency braking; HDVs at constant speed (see [`ConstantSpeed::with_longitudinal`]).
    pub fn new(config: &Config) -> Self {
        let s = &config.scenario;
        ConstantSpeed {
            dt: s.dt,
            lane_change_steps: s.lane_change_steps(),
            merge_exponent: config.ramp_merge.exponent,
            hdv_brake: config.idm.max_decel,
            longitudinal: Longitudinal::ConstantSpeed,
            blocking: Blocking::new(config),
        }
    }

    /// The same predictor with HDVs moving along their lane by `longitudinal`.
    pub fn with_longitudinal(mut self, longitudinal: Longitudinal) -> ConstantSpeed {
        self.longitudinal = longitudinal;
        self
    }

    /// Step at which a ramp HDV whose front is at `front`, driving `speed`, has decided to merge
    /// with probability at least ½ under the per-step hazard ξ^k; `None` beyond `horizon`.
    pub fn median_merge_step(
        &self,
        scene: &Scene,
        (lane, front): (i32, f64),
        speed: f64,
        horizon: usize,
    ) -> Option<usize> {
        let road = &scene.road;
        let merge = road.zone_for(lane, front);
        let zone = merge.end - merge.start;
        let mut undecided = 1.0;
        for k in 0..=horizon {
            let xi = ((front + speed * self.dt * k as f64 - merge.start) / zone).clamp(0.0, 1.0);
            undecided *= 1.0 - xi.powf(self.merge_exponent);
            if undecided <= 0.5 {
                return Some(k);
            }
        }
        None
    }
}

impl Predictor for ConstantSpeed {
    fn name(&self) -> &'static str {
        "constant"
    }

    fn predict(
        &self,
        scene: &Scene,
        i: usize,
        _conditioned_on: &[&Trajectory],
        horizon: usize,
    ) -> Trajectory {
        let v = &scene.vehicles[i];
        let w = scene.road.lane_width;
        let y0 = v.lane as f64 * w + v.lateral;
        let forward = v.speed;
        let road = &scene.road;
        let merging = v.kind == Kind::Hdv && v.origin == Origin::Ramp && !v.on_ramp;
        let merge_at = (merging && road.is_auxiliary(v.lane))
            .then(|| self.median_merge_step(scene, (v.lane, v.front()), forward, horizon))
            .flatten();
        let into = road.toward_main(v.lane);
        let merge_at = self.blocking.first_free(scene, i, into, merge_at, horizon);
        let inward = f64::from(into - v.lane);
        let lc = self.lane_change_steps as f64;
        let poses = self
            .longitudinal
            .poses(scene, i, horizon, self.dt, |k| match merge_at {
                Some(m) if k > m => y0 + inward * w * ((k - m) as f64 / lc).min(1.0),
                _ => y0,
            });
        Trajectory {
            poses,
            length: v.length,
            width: v.width,
            brake: (v.kind == Kind::Hdv).then_some(self.hdv_brake),
            committed: false,
        }
    }
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::model::road::Road;
    use crate::model::scene::VehicleState;

    fn vehicle(kind: Kind, origin: Origin, s: f64, lane: i32, speed: f64) -> VehicleState {
        VehicleState {
            desired_speed: speed,
            ..VehicleState::on_lane("v", kind, origin, s, lane, speed)
        }
    }

    #[test]
    fn keeps_speed_and_lane() {
        let scene =
            Scene::on_paper_road(0.0, vec![vehicle(Kind::Hdv, Origin::Main, 100.0, 2, 30.0)]);
        let t = ConstantSpeed::new(&Config::default()).predict(&scene, 0, &[], 15);
        assert_eq!(t.poses.len(), 16);
        assert!((t.poses[15].s - 190.0).abs() < 1e-9 && t.poses[15].y == 9.0);
    }

    #[test]
    fn ramp_hdv_merges_at_its_median_decision_step() {
        // Front at 40 % of the zone, 20 m/s: hazards 0.4, 0.422, … — after two steps the chance
        // of still being undecided is 0.6·0.578 = 0.347 ≤ ½; k = 0 counts as the first draw.
        let scene = Scene {
            time: 0.0,
            road: Road::paper_default(),
            vehicles: vec![vehicle(
                Kind::Hdv,
                Origin::Ramp,
                150.0 + 72.0 - 2.5,
                0,
                20.0,
            )],
        };
        let p = ConstantSpeed::new(&Config::default());
        assert_eq!(p.median_merge_step(&scene, (0, 222.0), 20.0, 15), Some(1));
        let t = p.predict(&scene, 0, &[], 15);
        assert_eq!(t.poses[1].y, 0.0);
        assert!((t.poses[2].y - 0.9).abs() < 1e-9);
        assert!((t.poses[6].y - 4.5).abs() < 1e-9 && (t.poses[15].y - 4.5).abs() < 1e-9);
        // A CAV on the same spot is not predicted to merge.
        let mut cav = scene.clone();
        cav.vehicles[0].kind = Kind::Cav;
        assert!(p.predict(&cav, 0, &[], 15).poses.iter().all(|q| q.y == 0.0));
    }
}
