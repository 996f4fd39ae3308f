//! The RL-PPO policy's actions: the six motion primitives of the planners' library, in
//! [`Primitive::ALL`]'s order, under the lane-change rules the planners obey. An action the
//! rules forbid is masked out of the policy's distribution, so the policy never picks it.

use crate::config::{Config, LowSpeedLaneChanges};
use crate::model::scene::Scene;
use crate::planner::primitives::Primitive;

/// Number of actions.
pub const ACTIONS: usize = Primitive::ALL.len();

/// Which actions may start now.
pub type Mask = [bool; ACTIONS];

/// The rules, from the configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Rules {
    /// Step length (s): how long an action's acceleration is held.
    pub dt: f64,
    /// Speed limit (m/s): no action takes the speed above it.
    pub v_max: f64,
    /// Acceleration of the `accelerate` primitive (m/s²).
    pub accel: f64,
    /// Deceleration of the `decelerate` primitive (m/s², positive).
    pub decel: f64,
    /// Deceleration of the `emergency-brake` primitive (m/s², positive).
    pub emergency_decel: f64,
    /// Slowest speed from which the bicycle model steers a lane change (m/s); below it a lane
    /// change is allowed only where `low_speed` lets SUMO slide the vehicle across.
    pub min_lane_change_speed: f64,
    /// Which lane changes a CAV slower than `min_lane_change_speed` may still make.
    pub low_speed: LowSpeedLaneChanges,
}

impl Rules {
    /// The rules of `config`: its step length and speed limit, and the planners' primitive
    /// accelerations and lane-change settings, so the policy acts under the planners' rules.
    pub fn from_config(config: &Config) -> Rules {
        let p = &config.planner;
        Rules {
            dt: config.scenario.dt,
            v_max: config.scenario.v_max,
            accel: p.accel_or_paper(),
            decel: p.decel,
            emergency_decel: p.emergency_decel,
            min_lane_change_speed: p.min_lane_change_speed,
            low_speed: p.low_speed_lane_changes,
        }
    }

    /// The actions scene vehicle `i` may start: every longitudinal one; a lane change only off
    /// the ramp edge, onto a lane that exists there and is not the merge lane (main-road CAVs
    /// never enter it), out of the merge lane only once past the merge start, and below the
    /// bicycle's lane-change speed only where `low_speed_lane_changes` lets SUMO slide it.
    pub fn mask(&self, scene: &Scene, i: usize) -> Mask {
        let v = &scene.vehicles[i];
        let road = &scene.road;
        Primitive::ALL.map(|p| {
            if !p.is_lane_change() {
                return true;
            }
            let target = v.lane + p.lane_offset();
            let slow = v.speed < self.min_lane_change_speed;
            let slide_ok = match self.low_speed {
                LowSpeedLaneChanges::Off => false,
                LowSpeedLaneChanges::Merge => road.is_auxiliary(v.lane),
                LowSpeedLaneChanges::All => true,
            };
            let zone = road.zone_on(v.lane, v.front());
            !v.on_ramp
                && (!road.is_auxiliary(target) || road.is_merge(v.lane, target))
                && road.lane_exists(target, v.s)
                && !zone.is_some_and(|z| v.front() < z.start)
                && (!slow || slide_ok)
        })
    }

    /// The speed at the end of the next step under primitive `action` (an index into
    /// [`Primitive::ALL`]) from `speed`: its acceleration held for one step, within
    /// [0, v_max]. Lane changes keep the speed, as the planners' lane-change primitive does.
    pub fn next_speed(&self, action: usize, speed: f64) -> f64 {
        let accel =
            Primitive::ALL[action].acceleration(self.accel, self.decel, self.emergency_decel);
        (speed + accel * self.dt).clamp(0.0, self.v_max)
    }
}

/// Index of the idle primitive (keep speed and lane).
pub const IDLE: usize = 1;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::{Kind, Origin, VehicleState};

    fn rules() -> Rules {
        Rules::from_config(&Config::default())
    }

    #[test]
    fn lane_rules() {
        let main_right = VehicleState::on_lane("a", Kind::Cav, Origin::Main, 200.0, 1, 30.0);
        let main_left = VehicleState::on_lane("b", Kind::Cav, Origin::Main, 100.0, 2, 30.0);
        let mut merging = VehicleState::on_lane("c", Kind::Cav, Origin::Ramp, 250.0, 0, 5.0);
        let mut on_ramp = merging.clone();
        on_ramp.on_ramp = true;
        on_ramp.s = 100.0;
        merging.id = "c".into();
        let scene = Scene::on_paper_road(0.0, vec![main_right, main_left, merging, on_ramp]);
        let r = rules();
        // accelerate, idle, decelerate, left, right, emergency
        assert_eq!(r.mask(&scene, 0), [true, true, true, true, false, true]);
        assert_eq!(r.mask(&scene, 1), [true, true, true, false, true, true]);
        assert_eq!(r.mask(&scene, 2), [true, true, true, true, false, true]);
        assert_eq!(r.mask(&scene, 3), [true, true, true, false, false, true]);
    }

    #[test]
    fn speeds() {
        let r = rules();
        assert_eq!(r.next_speed(0, 34.8), 35.0);
        assert!((r.next_speed(2, 20.0) - 19.6).abs() < 1e-12);
        assert_eq!(r.next_speed(5, 0.5), 0.0);
        assert_eq!(r.next_speed(3, 20.0), 20.0);
        assert_eq!(r.next_speed(IDLE, 20.0), 20.0);
    }
}
