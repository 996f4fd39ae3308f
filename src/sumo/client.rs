//! The SUMO calls an episode makes between two steps, as one trait: answered by the in-process
//! libsumo [`Simulation`] for `bkpbs episode`, by the caller's own TraCI loop (the Python
//! `Controller(sumocfg=…)`), so that both keep one set of books and plan alike, or by a scripted
//! fake in the loops' unit tests.

use super::{Collision, NewVehicle, RawVehicleState, Simulation, SumoError, VehicleReadings};
use crate::model::scene::Limits;

/// What an episode asks of SUMO between two steps. The caller steps SUMO; every call here reads
/// or commands the state after a step (or, [`SumoClient::add_vehicle`], before the next).
pub trait SumoClient {
    /// SUMO's simulation time (s).
    fn time(&self) -> Result<f64, SumoError>;
    /// Vehicles inserted in the last step.
    fn departed(&self) -> Result<Vec<String>, SumoError>;
    /// Vehicles that reached their destination (or were removed) in the last step.
    fn arrived(&self) -> Result<Vec<String>, SumoError>;
    /// Vehicles whose departure time has come but which SUMO has not inserted.
    fn pending(&self) -> Result<Vec<String>, SumoError>;
    /// Ids of the vehicle types loaded.
    fn vehicle_type_ids(&self) -> Result<Vec<String>, SumoError>;
    /// The edges whose vehicles [`SumoClient::read_vehicles`] reports by their index here.
    fn set_edge_codes(&mut self, edges: &[&str]) -> Result<(), SumoError>;
    /// Every vehicle in the network, in SUMO's order of `vehicle.getIDList`.
    fn read_vehicles(&self, out: &mut VehicleReadings) -> Result<(), SumoError>;
    /// Collisions detected during the last step.
    fn collisions(&self) -> Result<Vec<Collision>, SumoError>;
    /// A vehicle's type id.
    fn vehicle_type(&self, id: &str) -> Result<String, SumoError>;
    /// The edges of a vehicle's route (also of one not yet inserted).
    fn vehicle_route(&self, id: &str) -> Result<Vec<String>, SumoError>;
    /// A vehicle's length and width (m).
    fn vehicle_size(&self, id: &str) -> Result<(f64, f64), SumoError>;
    /// A vehicle's own top speed (m/s).
    fn vehicle_max_speed(&self, id: &str) -> Result<f64, SumoError>;
    /// A vehicle's own speed factor: its desired speed is this times the lane's speed limit,
    /// at most its top speed.
    fn vehicle_speed_factor(&self, id: &str) -> Result<f64, SumoError>;
    /// A vehicle's own acceleration, deceleration and emergency deceleration (m/s²).
    fn vehicle_limits(&self, id: &str) -> Result<Limits, SumoError>;
    /// Driving distance along the vehicle's route to `pos` on `edge` (negative: off it).
    fn driving_distance(&self, id: &str, edge: &str, pos: f64) -> Result<f64, SumoError>;
    /// Speeds for the next step (m/s; negative hands speed back to SUMO).
    fn set_speeds(&mut self, speeds: &[(&str, f64)]) -> Result<(), SumoError>;
    /// A vehicle's speed for the next step (m/s; negative hands speed back to SUMO).
    fn set_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError>;
    /// SUMO's `speedMode` bits for a vehicle.
    fn set_speed_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError>;
    /// SUMO's `laneChangeMode` bits for a vehicle.
    fn set_lane_change_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError>;
    /// Starts a lane change into `lane_index` of the vehicle's edge, lasting `duration` s.
    fn change_lane(&mut self, id: &str, lane_index: i32, duration: f64) -> Result<(), SumoError>;
    /// Takes a vehicle out of the simulation now.
    fn remove_vehicle(&mut self, id: &str) -> Result<(), SumoError>;
    /// Adds `v`, departing now from the start of its route on its lane at its speed; SUMO
    /// inserts it in the coming step if there is room, else retries.
    fn add_vehicle(&mut self, v: NewVehicle) -> Result<(), SumoError>;
    /// A vehicle's own top speed (m/s), which SUMO's car-following models take as its desired
    /// speed.
    fn set_max_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError>;
    /// Colours a vehicle in sumo-gui (red, green, blue).
    fn set_color(&mut self, id: &str, rgb: [u8; 3]) -> Result<(), SumoError>;
}

impl SumoClient for Simulation {
    fn time(&self) -> Result<f64, SumoError> {
        Simulation::time(self)
    }
    fn departed(&self) -> Result<Vec<String>, SumoError> {
        Simulation::departed(self)
    }
    fn arrived(&self) -> Result<Vec<String>, SumoError> {
        Simulation::arrived(self)
    }
    fn pending(&self) -> Result<Vec<String>, SumoError> {
        Simulation::pending(self)
    }
    fn vehicle_type_ids(&self) -> Result<Vec<String>, SumoError> {
        Simulation::vehicle_type_ids(self)
    }
    fn set_edge_codes(&mut self, edges: &[&str]) -> Result<(), SumoError> {
        Simulation::set_edge_codes(self, edges)
    }
    fn read_vehicles(&self, out: &mut VehicleReadings) -> Result<(), SumoError> {
        Simulation::read_vehicles(self, out)
    }
    fn collisions(&self) -> Result<Vec<Collision>, SumoError> {
        Simulation::collisions(self)
    }
    fn vehicle_type(&self, id: &str) -> Result<String, SumoError> {
        Simulation::vehicle_type(self, id)
    }
    fn vehicle_route(&self, id: &str) -> Result<Vec<String>, SumoError> {
        Simulation::vehicle_route(self, id)
    }
    fn vehicle_size(&self, id: &str) -> Result<(f64, f64), SumoError> {
        Simulation::vehicle_size(self, id)
    }
    fn vehicle_max_speed(&self, id: &str) -> Result<f64, SumoError> {
        Simulation::vehicle_max_speed(self, id)
    }
    fn vehicle_speed_factor(&self, id: &str) -> Result<f64, SumoError> {
        Simulation::vehicle_speed_factor(self, id)
    }
    fn vehicle_limits(&self, id: &str) -> Result<Limits, SumoError> {
        Simulation::vehicle_limits(self, id)
    }
    fn driving_distance(&self, id: &str, edge: &str, pos: f64) -> Result<f64, SumoError> {
        Simulation::driving_distance(self, id, edge, pos)
    }
    fn set_speeds(&mut self, speeds: &[(&str, f64)]) -> Result<(), SumoError> {
        Simulation::set_speeds(self, speeds.iter().copied())
    }
    fn set_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        Simulation::set_speed(self, id, speed)
    }
    fn set_speed_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        Simulation::set_speed_mode(self, id, mode)
    }
    fn set_lane_change_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        Simulation::set_lane_change_mode(self, id, mode)
    }
    fn change_lane(&mut self, id: &str, lane_index: i32, duration: f64) -> Result<(), SumoError> {
        Simulation::change_lane(self, id, lane_index, duration)
    }
    fn remove_vehicle(&mut self, id: &str) -> Result<(), SumoError> {
        Simulation::remove_vehicle(self, id)
    }
    fn add_vehicle(&mut self, v: NewVehicle) -> Result<(), SumoError> {
        Simulation::add_vehicle(self, v)
    }
    fn set_max_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        Simulation::set_max_speed(self, id, speed)
    }
    fn set_color(&mut self, id: &str, rgb: [u8; 3]) -> Result<(), SumoError> {
        Simulation::set_color(self, id, rgb)
    }
}

/// Readings a client of the caller's own built, in SUMO's order of ids.
impl VehicleReadings {
    /// Replaces the readings with `ids` and their `states`, counting a new generation when the
    /// ids differ from the last ones (as [`Simulation::read_vehicles`] does).
    pub fn replace(&mut self, ids: Vec<String>, states: Vec<RawVehicleState>) {
        debug_assert_eq!(ids.len(), states.len());
        self.states = states;
        if ids != self.ids {
            self.ids = ids;
            self.generation += 1;
        }
    }
}
