//! Entry control: admits scheduled vehicles into SUMO when their entry lane has room.
//!
//! SUMO 1.15 cannot be given the demand as a plain route file: a vehicle whose numeric
//! `departSpeed` is unsafe because of slow traffic further down its lane is silently dropped
//! ("will not be able to depart ... slow lane ahead"), so vehicles would vanish exactly when the
//! road is congested, and `departSpeed="max"` inserts at any speed down to zero as soon as there
//! is a car length free, leaving stopped cars at the entry. Instead each entry lane keeps a FIFO
//! queue of its scheduled vehicles; its head is added (`Vehicle::add`, depart now) once its
//! scheduled time has come and the nearest vehicle ahead in the same road-frame lane leaves room
//! by SUMO's own IDM insertion rule: gap − s0 ≥ v·T + v·(v − v_l)/(2√(ab)). The vehicle enters
//! at its drawn speed, or at the highest speed the rule allows if that is lower but still at
//! least the leader's; otherwise it waits. The leader's speed is taken after one step of its
//! current deceleration, since SUMO inserts at the end of the coming step. A vehicle still queued
//! at the end counts as never inserted (`never_inserted`); the time it waited is its entry delay.

use std::collections::VecDeque;

use crate::config::Config;
use crate::episode::demand::PlannedVehicle;
use crate::model::road::Road;
use crate::model::scene::{Origin, Scene};

/// A vehicle cleared to enter now.
#[derive(Debug, Clone, PartialEq)]
pub struct Admission {
    /// The vehicle as the demand scheduled it.
    pub vehicle: PlannedVehicle,
    /// Insertion speed (m/s).
    pub speed: f64,
}

/// The entry queues: one per main lane (by SUMO lane index on the first edge), then one per
/// on-ramp.
#[derive(Debug, Clone)]
pub struct EntryControl {
    queues: Vec<VecDeque<PlannedVehicle>>,
    main_lanes: usize,
    idm: crate::config::Idm,
    dt: f64,
    length: f64,
}

impl EntryControl {
    /// Queues `planned` (sorted by depart time) by entry on `road`.
    pub fn new(config: &Config, road: &Road, planned: &[PlannedVehicle]) -> Self {
        let main_lanes = road.main_lanes as usize;
        let mut queues = vec![VecDeque::new(); main_lanes + road.ramp_zones().count()];
        for p in planned {
            queues[Self::queue_of(main_lanes, p)].push_back(p.clone());
        }
        EntryControl {
            queues,
            main_lanes,
            idm: config.idm.clone(),
            dt: config.scenario.dt,
            length: config.scenario.vehicle_length,
        }
    }

    fn queue_of(main_lanes: usize, p: &PlannedVehicle) -> usize {
        match p.origin {
            Origin::Main => (p.depart_lane as usize).min(main_lanes - 1),
            Origin::Ramp => main_lanes + p.entry - 1,
        }
    }

    /// Road-frame lane and front position of a vehicle just inserted by queue `queue`.
    fn entry_point(&self, road: &Road, queue: usize) -> (i32, f64) {
        match queue.checked_sub(self.main_lanes) {
            Some(ramp) => {
                let zone = road.ramp_zones().nth(ramp).expect("a queue per on-ramp");
                (zone.lane, zone.ramp_start + self.length)
            }
            None => {
                let first = road.edges[0].lanes[queue + road.first_through_lane()]
                    .as_ref()
                    .expect("main lanes are in the frame");
                (first.lane, first.s0 + self.length)
            }
        }
    }

    /// Vehicles still waiting.
    pub fn pending(&self) -> usize {
        self.queues.iter().map(VecDeque::len).sum()
    }

    /// Pops the queue heads that may enter at time `now` given the current `scene`.
    pub fn admit(&mut self, now: f64, scene: &Scene) -> Vec<Admission> {
        let mut out = Vec::new();
        for entry in 0..self.queues.len() {
            let Some(head) = self.queues[entry].front() else {
                continue;
            };
            if head.depart > now + 1e-9 {
                continue;
            }
            let (lane, front) = self.entry_point(&scene.road, entry);
            // Not above the entry's speed limit, where SUMO would refuse the vehicle.
            let wanted = head
                .depart_speed
                .min(scene.road.entries[head.entry].speed_limit);
            if let Some(speed) = self.entry_speed(scene, lane, front, wanted) {
                let vehicle = self.queues[entry].pop_front().expect("head exists");
                out.push(Admission { vehicle, speed });
            }
        }
        out
    }

    /// The speed a vehicle with front at `front` in `lane` may enter with, if any. Its leader
    /// may be a vehicle changing into or out of `lane`
    /// ([`other_lane`](crate::model::scene::VehicleState::other_lane)).
    fn entry_speed(&self, scene: &Scene, lane: i32, front: f64, wanted: f64) -> Option<f64> {
        let leader = scene
            .vehicles
            .iter()
            .filter(|v| v.lane == lane || v.other_lane() == Some(lane))
            .filter(|v| v.front() > front - self.length)
            .min_by(|a, b| a.rear().total_cmp(&b.rear()));
        let Some(l) = leader else {
            return Some(wanted);
        };
        let room = l.rear() - front - self.idm.min_gap;
        if room <= 0.0 {
            return None;
        }
        let leader_speed = (l.speed + l.accel.min(0.0) * self.dt).max(0.0);
        // Largest v with v·T + v·(v − v_l)/c ≤ room, c = 2√(ab): the positive root of
        // v²/c + v·(T − v_l/c) − room = 0.
        let c = 2.0 * (self.idm.accel * self.idm.decel).sqrt();
        let p = self.idm.time_headway - leader_speed / c;
        let allowed = 0.5 * c * (-p + (p * p + 4.0 * room / c).sqrt());
        let speed = wanted.min(allowed);
        // Entering slower than both its wish and its leader would put a crawling car at the entry.
        (speed >= wanted.min(leader_speed) - 1e-9).then_some(speed)
    }
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::model::scene::{Kind, VehicleState};

    fn planned(id: &str, origin: Origin, lane: u32, depart: f64, speed: f64) -> PlannedVehicle {
        PlannedVehicle {
            id: id.into(),
            kind: Kind::Hdv,
            origin,
            entry: usize::from(origin == Origin::Ramp),
            exit: None,
            depart,
            depart_lane: lane,
            depart_speed: speed,
            desired_speed: 30.0,
        }
    }

    fn car(s: f64, lane: i32, speed: f64) -> VehicleState {
        VehicleState {
            desired_speed: 30.0,
            ..VehicleState::on_lane("x", Kind::Hdv, Origin::Main, s, lane, speed)
        }
    }

    #[test]
    fn free_entry_admits_at_the_drawn_speed_in_order() {
        let c = Config::default();
        let mut e = EntryControl::new(
            &c,
            &Road::paper_default(),
            &[
                planned("a", Origin::Main, 0, 0.0, 30.0),
                planned("b", Origin::Main, 0, 0.0, 28.0),
            ],
        );
        let got = e.admit(0.0, &Scene::on_paper_road(0.0, vec![]));
        assert_eq!(got.len(), 1, "one per entry and step");
        assert_eq!((got[0].vehicle.id.as_str(), got[0].speed), ("a", 30.0));
        assert_eq!(e.pending(), 1);
    }

    #[test]
    fn not_before_the_scheduled_time() {
        let c = Config::default();
        let mut e = EntryControl::new(
            &c,
            &Road::paper_default(),
            &[planned("a", Origin::Ramp, 0, 1.0, 30.0)],
        );
        assert!(e.admit(0.8, &Scene::on_paper_road(0.0, vec![])).is_empty());
        assert_eq!(e.admit(1.0, &Scene::on_paper_road(0.0, vec![])).len(), 1);
    }

    #[test]
    fn close_leader_blocks_and_slow_leader_lowers_speed() {
        let c = Config::default(); // s0 = 5, a = 3, b = 5, T = 1.5
                                   // Leader just ahead of the entry: 5 m gap -> no room.
        let mut e = EntryControl::new(
            &c,
            &Road::paper_default(),
            &[planned("a", Origin::Main, 0, 0.0, 30.0)],
        );
        assert!(e
            .admit(0.0, &Scene::on_paper_road(0.0, vec![car(12.5, 1, 20.0)]))
            .is_empty());
        // Leader at 20 m/s with rear 45 m ahead of the entry front (5 m): room 40 m.
        // c = 2√15 = 7.745967; p = 1.5 − 20/c = −1.081989;
        // v = c/2·(−p + √(p² + 4·40/c)) = 3.872983·(1.081989 + 4.671896) = 22.2847
        let got = e.admit(
            0.0,
            &Scene::on_paper_road(0.0, vec![car(5.0 + 45.0 + 2.5, 1, 20.0)]),
        );
        assert_eq!(got.len(), 1);
        assert!((got[0].speed - 22.2847).abs() < 1e-3, "{}", got[0].speed);
        // At 30 m/s wanted, a leader at 10 m/s that close means waiting.
        let mut e = EntryControl::new(
            &c,
            &Road::paper_default(),
            &[planned("b", Origin::Main, 0, 0.0, 30.0)],
        );
        assert!(e
            .admit(
                0.0,
                &Scene::on_paper_road(0.0, vec![car(5.0 + 12.0 + 2.5, 1, 10.0)])
            )
            .is_empty());
    }

    #[test]
    fn other_lanes_do_not_block() {
        let c = Config::default();
        let mut e = EntryControl::new(
            &c,
            &Road::paper_default(),
            &[planned("a", Origin::Main, 1, 0.0, 30.0)],
        );
        assert_eq!(
            e.admit(0.0, &Scene::on_paper_road(0.0, vec![car(10.0, 1, 0.0)]))
                .len(),
            1
        );
    }
}
