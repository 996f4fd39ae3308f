//! A scripted stand-in for SUMO, so that the loops that talk to SUMO only through
//! [`SumoClient`] can be unit-tested without starting it.
//!
//! A test writes the script step by step: who departs (with its type's figures), where every
//! vehicle in the network is after the step, who arrives, who collides. [`FakeSumo::step`]
//! plays the next step; the loop under test then reads it through the trait, and every
//! command it sends is recorded, in order, in [`FakeSumo::sent`]. As in SUMO, a vehicle that
//! arrived or was removed is gone: it is no longer read, and a command to it is an error.

use std::collections::{HashMap, HashSet};

use super::{Collision, NewVehicle, RawVehicleState, SumoClient, SumoError, VehicleReadings};
use crate::model::scene::{Following, Limits};

/// A vehicle SUMO inserts, with what its type tells the loop about it.
#[derive(Debug, Clone)]
pub(crate) struct FakeVehicle {
    /// SUMO's vehicle id.
    pub id: String,
    /// Its SUMO type id.
    pub type_id: String,
    /// Its length and width (m).
    pub size: (f64, f64),
    /// Its own top speed (m/s).
    pub max_speed: f64,
    /// Its own speed factor (its desired speed over the lane's limit).
    pub speed_factor: f64,
    /// Its own accelerations (m/s²).
    pub limits: Limits,
    /// What [`SumoClient::driving_distance`] answers for it, whatever the place asked about
    /// (negative: off its route).
    pub distance: f64,
}

impl FakeVehicle {
    /// A 5 m × 1.8 m vehicle of type `type_id`, SUMO's default passenger car's figures (speed
    /// factor 1), whose route runs through every place asked about.
    pub fn new(id: &str, type_id: &str) -> FakeVehicle {
        FakeVehicle {
            id: id.into(),
            type_id: type_id.into(),
            size: (5.0, 1.8),
            max_speed: 55.56,
            speed_factor: 1.0,
            limits: Limits {
                accel: 2.6,
                decel: 4.5,
                emergency_decel: 9.0,
                following: Some(Following::SUMO_DEFAULT),
            },
            distance: 1000.0,
        }
    }

    /// The same vehicle, [`SumoClient::driving_distance`] answering `distance`.
    pub fn distance(self, distance: f64) -> FakeVehicle {
        FakeVehicle { distance, ..self }
    }

    /// The same vehicle with its own `speed_factor` and top speed `max_speed` (m/s).
    pub fn desiring(self, speed_factor: f64, max_speed: f64) -> FakeVehicle {
        FakeVehicle {
            speed_factor,
            max_speed,
            ..self
        }
    }
}

/// One vehicle's state after a step, its edge by name (the fake codes it as SUMO would).
#[derive(Debug, Clone)]
pub(crate) struct Reading {
    /// SUMO's vehicle id.
    pub id: String,
    /// The SUMO edge it is on.
    pub edge: String,
    /// Its state; the edge code in it is ignored (set from `edge` when read).
    pub state: RawVehicleState,
}

impl Reading {
    /// Vehicle `id` on lane `lane_index` of `edge`, its front at `lane_position`, driving
    /// straight along the lane at `speed`.
    pub fn on(id: &str, edge: &str, lane_index: i32, lane_position: f64, speed: f64) -> Reading {
        Reading {
            id: id.into(),
            edge: edge.into(),
            state: RawVehicleState {
                speed,
                angle: 90.0,
                lane_position,
                lane_index,
                edge_code: -1,
                ..RawVehicleState::default()
            },
        }
    }
}

/// What happened in one SUMO step, and where every vehicle is after it.
#[derive(Debug, Clone, Default)]
pub(crate) struct Step {
    /// Vehicles inserted in the step.
    pub departed: Vec<FakeVehicle>,
    /// The state of each vehicle in the network after it, in SUMO's order of ids.
    pub vehicles: Vec<Reading>,
    /// Vehicles that left the network in it.
    pub arrived: Vec<String>,
    /// Collisions detected in it.
    pub collisions: Vec<Collision>,
    /// Vehicles whose departure time has come but which are not inserted after it, each with
    /// its route's edges.
    pub pending: Vec<(String, Vec<String>)>,
}

impl Step {
    /// The step with `vehicle` inserted too.
    pub fn depart(mut self, vehicle: FakeVehicle) -> Step {
        self.departed.push(vehicle);
        self
    }

    /// The step with `reading` among the network's vehicles after it.
    pub fn read(mut self, reading: Reading) -> Step {
        self.vehicles.push(reading);
        self
    }

    /// The step with vehicle `id` waiting to be inserted after it, on a route through none of
    /// the regions.
    pub fn wait(self, id: &str) -> Step {
        self.wait_on(id, &[])
    }

    /// The step with vehicle `id` waiting to be inserted after it, on a route over `edges`.
    pub fn wait_on(mut self, id: &str, edges: &[&str]) -> Step {
        let route = edges.iter().map(|e| e.to_string()).collect();
        self.pending.push((id.into(), route));
        self
    }

    /// The step with vehicle `id` arriving in it.
    pub fn arrive(mut self, id: &str) -> Step {
        self.arrived.push(id.into());
        self
    }

    /// The step with `collider` driving into `victim` in it.
    pub fn collide(mut self, collider: &str, victim: &str) -> Step {
        self.collisions.push(Collision {
            collider: collider.into(),
            victim: victim.into(),
            collider_type: String::new(),
            victim_type: String::new(),
            kind: "collision".into(),
            lane: String::new(),
            position: 0.0,
        });
        self
    }
}

/// A command the loop sent to SUMO, as recorded by the fake.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Sent {
    /// A speed for the next step (negative: back to SUMO); each entry of a batch is one.
    Speed(String, f64),
    /// SUMO's `speedMode` bits.
    SpeedMode(String, i32),
    /// SUMO's `laneChangeMode` bits.
    LaneChangeMode(String, i32),
    /// A lane change into a lane index, lasting some seconds.
    ChangeLane(String, i32, f64),
    /// The vehicle taken out of the simulation.
    Remove(String),
    /// Its colour in sumo-gui.
    Color(String, [u8; 3]),
    /// A vehicle added to depart now: its route, type, lane and speed.
    Add(String, String, String, i32, f64),
    /// Its own top speed.
    MaxSpeed(String, f64),
}

impl Sent {
    /// The vehicle the command is for.
    pub fn vehicle(&self) -> &str {
        match self {
            Sent::Speed(id, _)
            | Sent::SpeedMode(id, _)
            | Sent::LaneChangeMode(id, _)
            | Sent::ChangeLane(id, _, _)
            | Sent::Remove(id)
            | Sent::Color(id, _)
            | Sent::Add(id, ..)
            | Sent::MaxSpeed(id, _) => id,
        }
    }
}

/// A scripted SUMO: plays one [`Step`] per [`FakeSumo::step`] and records what it is sent.
#[derive(Debug, Default)]
pub(crate) struct FakeSumo {
    /// The step length (s).
    dt: f64,
    /// Steps played so far: SUMO's time is this many steps.
    played: u32,
    /// The steps not played yet, the next last.
    script: Vec<Step>,
    /// The step played last.
    current: Step,
    /// Every vehicle inserted so far, by id.
    inserted: HashMap<String, FakeVehicle>,
    /// The vehicles that arrived or were removed: no longer in the network.
    gone: HashSet<String>,
    /// The edges readings report by index, in the order of their codes.
    edge_codes: Vec<String>,
    /// Every command sent, in order.
    pub sent: Vec<Sent>,
}

impl FakeSumo {
    /// SUMO at time 0 with steps of `dt` seconds, to play `script` in order.
    pub fn new(dt: f64, mut script: Vec<Step>) -> FakeSumo {
        script.reverse();
        FakeSumo {
            dt,
            script,
            ..FakeSumo::default()
        }
    }

    /// Plays the next step of the script (an empty one past its end): the clock advances, its
    /// departures are inserted and its arrivals leave the network.
    pub fn step(&mut self) {
        self.current = self.script.pop().unwrap_or_default();
        self.played += 1;
        for v in &self.current.departed {
            self.inserted.insert(v.id.clone(), v.clone());
        }
        self.gone.extend(self.current.arrived.iter().cloned());
    }

    /// The commands sent to vehicle `id`, in order.
    pub fn sent_to(&self, id: &str) -> Vec<Sent> {
        self.sent
            .iter()
            .filter(|s| s.vehicle() == id)
            .cloned()
            .collect()
    }

    /// Vehicle `id`, inserted and not gone, or SUMO's error for an unknown one in `call`.
    fn present(&self, call: &'static str, id: &str) -> Result<&FakeVehicle, SumoError> {
        self.inserted
            .get(id)
            .filter(|_| !self.gone.contains(id))
            .ok_or_else(|| SumoError::Sumo {
                call,
                message: format!("Vehicle '{id}' is not known."),
            })
    }

    /// Records `command` to a vehicle in the network, or fails as SUMO does for one not in it.
    fn send(&mut self, call: &'static str, command: Sent) -> Result<(), SumoError> {
        self.present(call, command.vehicle())?;
        self.sent.push(command);
        Ok(())
    }
}

impl SumoClient for FakeSumo {
    fn time(&self) -> Result<f64, SumoError> {
        Ok(f64::from(self.played) * self.dt)
    }
    fn departed(&self) -> Result<Vec<String>, SumoError> {
        Ok(self.current.departed.iter().map(|v| v.id.clone()).collect())
    }
    fn arrived(&self) -> Result<Vec<String>, SumoError> {
        Ok(self.current.arrived.clone())
    }
    fn set_color(&mut self, id: &str, rgb: [u8; 3]) -> Result<(), SumoError> {
        self.send("vehicle.setColor", Sent::Color(id.into(), rgb))
    }
    fn pending(&self) -> Result<Vec<String>, SumoError> {
        Ok(self
            .current
            .pending
            .iter()
            .map(|(id, _)| id.clone())
            .collect())
    }
    fn vehicle_route(&self, id: &str) -> Result<Vec<String>, SumoError> {
        match self.current.pending.iter().find(|(p, _)| p == id) {
            Some((_, route)) => Ok(route.clone()),
            None => self.present("vehicle.getRoute", id).map(|_| Vec::new()),
        }
    }
    fn vehicle_type_ids(&self) -> Result<Vec<String>, SumoError> {
        let mut types: Vec<String> = self.inserted.values().map(|v| v.type_id.clone()).collect();
        types.sort();
        types.dedup();
        Ok(types)
    }
    /// Codes as the shim does: an edge's code is its first index in `edges`; −1 for any other.
    fn set_edge_codes(&mut self, edges: &[&str]) -> Result<(), SumoError> {
        self.edge_codes = edges.iter().map(|e| e.to_string()).collect();
        Ok(())
    }
    fn read_vehicles(&self, out: &mut VehicleReadings) -> Result<(), SumoError> {
        let code = |edge: &str| {
            let k = self.edge_codes.iter().position(|e| e == edge);
            k.map_or(-1, |k| k as i32)
        };
        let (ids, states) = self
            .current
            .vehicles
            .iter()
            .filter(|r| !self.gone.contains(&r.id))
            .map(|r| {
                let state = RawVehicleState {
                    edge_code: code(&r.edge),
                    ..r.state
                };
                (r.id.clone(), state)
            })
            .unzip();
        out.replace(ids, states);
        Ok(())
    }
    fn collisions(&self) -> Result<Vec<Collision>, SumoError> {
        Ok(self.current.collisions.clone())
    }
    fn vehicle_type(&self, id: &str) -> Result<String, SumoError> {
        Ok(self.present("vehicle.getTypeID", id)?.type_id.clone())
    }
    fn vehicle_size(&self, id: &str) -> Result<(f64, f64), SumoError> {
        Ok(self.present("vehicle.getLength", id)?.size)
    }
    fn vehicle_max_speed(&self, id: &str) -> Result<f64, SumoError> {
        Ok(self.present("vehicle.getMaxSpeed", id)?.max_speed)
    }
    fn vehicle_speed_factor(&self, id: &str) -> Result<f64, SumoError> {
        Ok(self.present("vehicle.getSpeedFactor", id)?.speed_factor)
    }
    fn vehicle_limits(&self, id: &str) -> Result<Limits, SumoError> {
        Ok(self.present("vehicle.getAccel", id)?.limits)
    }
    fn driving_distance(&self, id: &str, _edge: &str, _pos: f64) -> Result<f64, SumoError> {
        Ok(self.present("vehicle.getDrivingDistance", id)?.distance)
    }
    fn set_speeds(&mut self, speeds: &[(&str, f64)]) -> Result<(), SumoError> {
        speeds.iter().try_for_each(|&(id, v)| self.set_speed(id, v))
    }
    fn set_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        self.send("vehicle.setSpeed", Sent::Speed(id.into(), speed))
    }
    fn set_speed_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        self.send("vehicle.setSpeedMode", Sent::SpeedMode(id.into(), mode))
    }
    fn set_lane_change_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        let command = Sent::LaneChangeMode(id.into(), mode);
        self.send("vehicle.setLaneChangeMode", command)
    }
    fn change_lane(&mut self, id: &str, lane_index: i32, duration: f64) -> Result<(), SumoError> {
        let command = Sent::ChangeLane(id.into(), lane_index, duration);
        self.send("vehicle.changeLane", command)
    }
    fn remove_vehicle(&mut self, id: &str) -> Result<(), SumoError> {
        self.send("vehicle.remove", Sent::Remove(id.into()))?;
        self.gone.insert(id.into());
        Ok(())
    }
    /// Recorded only: the script says when SUMO inserts it.
    fn add_vehicle(&mut self, v: NewVehicle) -> Result<(), SumoError> {
        let (route, type_id) = (v.route.into(), v.type_id.into());
        self.sent
            .push(Sent::Add(v.id.into(), route, type_id, v.lane, v.speed));
        Ok(())
    }
    fn set_max_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        self.send("vehicle.setMaxSpeed", Sent::MaxSpeed(id.into(), speed))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_are_coded_by_their_first_index_and_gone_vehicles_are_not_read() {
        let script = vec![
            Step::default()
                .depart(FakeVehicle::new("a", "car"))
                .depart(FakeVehicle::new("b", "car"))
                .read(Reading::on("a", "acc", 1, 20.0, 30.0))
                .read(Reading::on("b", ":n1_0", 0, 2.0, 30.0)),
            Step::default()
                .read(Reading::on("a", "acc", 1, 26.0, 30.0))
                .read(Reading::on("b", "main_out", 0, 4.0, 30.0)),
        ];
        let mut sim = FakeSumo::new(0.2, script);
        sim.set_edge_codes(&["main_in", "acc", "main_out", "acc"])
            .unwrap();
        sim.step();
        let mut out = VehicleReadings::default();
        sim.read_vehicles(&mut out).unwrap();
        assert_eq!(out.ids, ["a", "b"]);
        let codes: Vec<i32> = out.states.iter().map(|s| s.edge_code).collect();
        assert_eq!(codes, [1, -1]);
        sim.remove_vehicle("a").unwrap();
        assert!(sim.remove_vehicle("a").is_err());
        assert!(sim.set_speed("a", 3.0).is_err());
        sim.step();
        assert!((sim.time().unwrap() - 0.4).abs() < 1e-12);
        sim.read_vehicles(&mut out).unwrap();
        assert_eq!(out.ids, ["b"]);
        assert_eq!(out.states[0].edge_code, 2);
        assert_eq!(sim.sent, [Sent::Remove("a".into())]);
    }
}
