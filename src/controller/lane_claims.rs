//! The lanes vehicles are moving into, so that IDM+MOBIL does not send a CAV into a lane
//! another vehicle is entering from the other side, or one of its own CAVs entering it in the
//! same step. MOBIL sees a vehicle in the lane it changes into only once it is half across
//! (`mobil::occupies`): main-road CAVs moving right into lane 1 ran into ramp vehicles merging
//! into it from the acceleration lane (13 of 33 controllable collisions on the tuning seeds of
//! the two ramps alongside, `results/layouts/README.md`).

use super::mobil;
use crate::config::Mobil;
use crate::model::scene::Scene;

/// Lanes claimed: (lane, scene vehicle moving into it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaneClaims {
    claims: Vec<(i32, usize)>,
}

impl LaneClaims {
    /// The claims of `scene`'s vehicles changing lanes: each claims the lane its lateral offset
    /// points to (past the middle, the lane it comes from: a claim still, until it is across).
    pub fn of_scene(scene: &Scene) -> Self {
        let claims = (scene.vehicles.iter().enumerate())
            .filter(|(_, v)| v.changing_lanes())
            .map(|(j, v)| (v.lane + v.lateral.signum() as i32, j))
            .collect();
        LaneClaims { claims }
    }

    /// Whether scene vehicle `i` may move into `target`: each other vehicle claiming it is clear
    /// of `i` by the merge's gap acceptance, whichever of the two is ahead.
    pub fn admit(&self, mobil: &Mobil, scene: &Scene, i: usize, target: i32) -> bool {
        let me = &scene.vehicles[i];
        (self.claims.iter())
            .filter(|&&(lane, j)| lane == target && j != i)
            .all(|&(_, j)| {
                let other = &scene.vehicles[j];
                match other.s > me.s {
                    true => mobil::gap_is_safe(mobil, me, other),
                    false => mobil::gap_is_safe(mobil, other, me),
                }
            })
    }

    /// Notes that scene vehicle `i` moves into `lane`.
    pub fn claim(&mut self, i: usize, lane: i32) {
        self.claims.push((lane, i));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::{Kind, Origin, VehicleState};

    fn car(id: &str, s: f64, lane: i32, speed: f64) -> VehicleState {
        VehicleState::on_lane(id, Kind::Cav, Origin::Main, s, lane, speed)
    }

    /// A ramp vehicle 1 m into its change from lane 0 to lane 1 claims lane 1: a main-road CAV
    /// 11 m behind it at 30 m/s against its 14 m/s (room 3.5 m, 42.7 m needed at 3 m/s²) may not
    /// move right into lane 1; 60 m behind it may; a CAV that claimed lane 1 in this step
    /// blocks another level with it on the other side.
    #[test]
    fn a_lane_another_vehicle_moves_into_is_admitted_only_clear_of_it() {
        let mut merger = car("m", 400.0, 0, 14.0);
        merger.lateral = 1.0;
        let near = car("n", 389.0, 2, 30.0);
        let far = car("f", 340.0, 2, 30.0);
        let scene = Scene::on_paper_road(0.0, vec![merger, near, far]);
        let claims = LaneClaims::of_scene(&scene);
        let m = Mobil::default();
        assert!(!claims.admit(&m, &scene, 1, 1));
        assert!(claims.admit(&m, &scene, 2, 1));
        assert!(claims.admit(&m, &scene, 1, 3), "no claim on lane 3");
        let level = Scene::on_paper_road(
            0.0,
            vec![car("a", 300.0, 0, 25.0), car("b", 301.0, 2, 25.0)],
        );
        let mut claims = LaneClaims::of_scene(&level);
        assert!(claims.admit(&m, &level, 0, 1));
        claims.claim(0, 1);
        assert!(!claims.admit(&m, &level, 1, 1));
    }
}
