//! A vehicle an episode asks SUMO to add: the one argument of [`super::SumoClient::add_vehicle`]
//! and [`super::Simulation::add_vehicle`], so that every client spells the call alike.

/// A vehicle to add, departing now from the start of its route; SUMO inserts it in the coming
/// step if there is room, else retries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewVehicle<'a> {
    /// Its id, not yet in the simulation.
    pub id: &'a str,
    /// The id of a route SUMO has loaded; the vehicle starts at its first edge.
    pub route: &'a str,
    /// The id of a vehicle type SUMO has loaded.
    pub type_id: &'a str,
    /// The lane index on the route's first edge (0: the rightmost).
    pub lane: i32,
    /// Its speed on entering (m/s).
    pub speed: f64,
}
