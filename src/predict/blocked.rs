//! When a standing HDV can start the lane change it is predicted to make: not while a vehicle in
//! the lane it changes into stands beside it.
//!
//! SUMO changes a vehicle's lane only into a gap: its new follower's minGap free behind it, its
//! own minGap free in front (even a merge the episode forces avoids immediate collisions). An
//! HDV standing at its lane's end beside a vehicle that stands too cannot move over until that
//! vehicle drives on; predicted to move over anyway, it lands on that vehicle whatever it does,
//! so a CAV standing beside it finds no plan, brakes, and both stand for good. Seen on the
//! left-lane drop layout under bk-mastar (α 0.6, seeds 16 and 21 of 11–40): a CAV came to a
//! stand in the middle lane overlapping an HDV that waited at the left lane's end, and the 21
//! and 28 vehicles behind them never arrived. Predicted to wait while the lane beside it is
//! blocked, the HDV no longer holds the CAV, which drives on; the HDV changes in behind it.
//!
//! Only a standing HDV is so predicted: one that moves may drop back or pull ahead into a gap
//! within the horizon, which SUMO's lane changer (and the CAV's own planning) decides as they go.

use crate::config::Config;
use crate::model::road::STANDING_SPEED;
use crate::model::scene::Scene;

/// The rule, with the step length and the gap it keeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blocking {
    /// Step length (s).
    dt: f64,
    /// The gap (m) SUMO keeps free before and behind a vehicle changing lanes: the CAVs'
    /// minGap (`idm.min_gap`), the follower's in the commonest case, a CAV beside the HDV.
    gap: f64,
}

impl Blocking {
    /// The rule of `config`.
    pub fn new(config: &Config) -> Blocking {
        Blocking {
            dt: config.scenario.dt,
            gap: config.idm.min_gap,
        }
    }

    /// The step, from `start` on and up to `horizon`, at which HDV `i` of `scene` can start its
    /// lane change into `target`: `start` for an HDV that moves; for a standing one the first
    /// step at which no vehicle in `target` (driving on at its speed) is within the gap of it,
    /// `None` if none comes within the horizon.
    pub fn first_free(
        &self,
        scene: &Scene,
        i: usize,
        target: i32,
        start: Option<usize>,
        horizon: usize,
    ) -> Option<usize> {
        let start = start?;
        if scene.vehicles[i].speed >= STANDING_SPEED {
            return Some(start);
        }
        (start..=horizon).find(|&k| !self.blocked_at(scene, i, target, k))
    }

    /// Whether a vehicle in `target` is within the gap of HDV `i` (its body, the gap before and
    /// behind) `k` steps from now, everyone at constant speed.
    fn blocked_at(&self, scene: &Scene, i: usize, target: i32, k: usize) -> bool {
        let v = &scene.vehicles[i];
        let t = self.dt * k as f64;
        let (rear, front) = (v.rear() + v.speed * t, v.front() + v.speed * t);
        scene.vehicles.iter().enumerate().any(|(j, o)| {
            let in_target = o.lane == target || o.other_lane() == Some(target);
            let moved = o.speed * t;
            j != i
                && in_target
                && o.front() + moved > rear - self.gap
                && o.rear() + moved < front + self.gap
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::{Kind, Origin, VehicleState};

    fn scene(hdv_speed: f64, cav_s: f64, cav_speed: f64) -> Scene {
        let hdv = VehicleState::on_lane("hdv", Kind::Hdv, Origin::Main, 200.0, 2, hdv_speed);
        let cav = VehicleState::on_lane("cav", Kind::Cav, Origin::Main, cav_s, 1, cav_speed);
        Scene::on_paper_road(0.0, vec![hdv, cav])
    }

    /// The left-lane drop's deadlock: a standing CAV overlapping the HDV, or standing with less
    /// than its minGap behind it, keeps the change from starting for the whole horizon; one
    /// minGap and more behind, or driving off, does not.
    #[test]
    fn a_standing_hdv_waits_while_a_standing_vehicle_blocks_the_lane_beside_it() {
        let b = Blocking::new(&Config::default());
        for cav_s in [199.6, 196.0, 191.0, 205.0] {
            assert_eq!(
                b.first_free(&scene(0.0, cav_s, 0.0), 0, 1, Some(0), 15),
                None
            );
        }
        assert_eq!(
            b.first_free(&scene(0.0, 189.0, 0.0), 0, 1, Some(3), 15),
            Some(3)
        );
        assert_eq!(
            b.first_free(&scene(0.0, 199.6, 0.0), 0, 2, Some(0), 15),
            Some(0)
        );
        // Driving on at 4 m/s from alongside, its rear is the gap (5 m) past the HDV's front
        // after 2.5 s: free from step 13.
        assert_eq!(
            b.first_free(&scene(0.0, 200.0, 4.0), 0, 1, Some(0), 15),
            Some(13)
        );
        // A moving HDV is left to the model and to SUMO.
        assert_eq!(
            b.first_free(&scene(3.0, 200.0, 0.0), 0, 1, Some(2), 15),
            Some(2)
        );
        assert_eq!(b.first_free(&scene(0.0, 200.0, 0.0), 0, 1, None, 15), None);
    }
}
