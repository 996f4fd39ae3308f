//! A vehicle's passage through the merge region it enters first: where its route would enter
//! one (for a vehicle SUMO holds back), its first reading there and by which of the region's
//! entries it came, and what the passage cost it, against the region's top speed and against
//! its own desired speed.

use crate::model::kinematics::free_flow_time;
use crate::model::road::Road;
use crate::model::scene::Origin;
use crate::sumo::{RawVehicleState, SumoClient, SumoError};

use super::entry_rows::{entry_name, origin_of};
use super::records::ScenarioVehicle;
use crate::episode::metrics::Outcome;
use crate::episode::region::Region;

/// A vehicle's passage through the first region it entered.
#[derive(Clone, Copy)]
pub(super) struct Entry {
    pub(super) region: usize,
    /// The region's entry it came in by: an index of its road's `entries` (0: the main
    /// carriageway).
    pub(super) entry: usize,
    pub(super) origin: Origin,
    /// Whether its route leaves the region before the region's end (by an off-ramp): the
    /// planners keep a CAV on the carriageway, so SUMO drives it.
    pub(super) leaves_early: bool,
    pub(super) time: f64,
    pub(super) front: f64,
    pub(super) speed: f64,
    /// Its last reading in the region: time and front.
    pub(super) last: (f64, f64),
}

/// The region a route enters first, and by which of its entries (an index of the region
/// road's `entries`): that of the first of the route's edges in any region.
pub(super) fn first_region_on(regions: &[Region], route: &[String]) -> Option<(usize, usize)> {
    route.iter().find_map(|edge| {
        regions.iter().enumerate().find_map(|(g, r)| {
            let code = r.road.edges.iter().position(|e| &*e.name == edge)?;
            Some((g, r.road.entry_of_edge(code)))
        })
    })
}

/// The entry of region `region` that vehicle `id`, read first in its frame on edge
/// `edge_code`, came in by: that edge's; where an on-ramp's edges lie outside the frame
/// (beside another auxiliary lane), its route's, so that a ramp vehicle first read where its
/// ramp joins is still the ramp's.
fn entry_of(
    sim: &impl SumoClient,
    id: &str,
    region: &Region,
    edge_code: i32,
) -> Result<usize, SumoError> {
    let road = &region.road;
    let by_edge = usize::try_from(edge_code).map_or(0, |c| road.entry_of_edge(c));
    if by_edge != 0 || !road.has_ramp_edges_outside() {
        return Ok(by_edge);
    }
    Ok(road
        .entry_of_route(&sim.vehicle_route(id)?)
        .unwrap_or(by_edge))
}

/// A vehicle's first reading in region `region`: when, where, how fast, by which entry, and
/// whether its route leaves the region early.
pub(super) fn enter(
    id: &str,
    sim: &impl SumoClient,
    g: usize,
    region: &Region,
    raw: &RawVehicleState,
    front: f64,
    now: f64,
) -> Result<Entry, SumoError> {
    let (end, pos) = (&region.road.end_edge.0, region.road.end_edge.1);
    let entry = entry_of(sim, id, region, raw.edge_code)?;
    Ok(Entry {
        region: g,
        entry,
        origin: origin_of(entry),
        // SUMO answers a negative distance for an edge off the vehicle's route.
        leaves_early: sim.driving_distance(id, end, pos)? < 0.0,
        time: now,
        front,
        speed: raw.speed,
        last: (now, front),
    })
}

/// A vehicle's own desired speed in `road`'s region (m/s), as SUMO's drivers have it: its
/// `speed_factor` times the speed limit of the region's main carriageway where the region
/// begins (the limit the region's `v_max` is capped at; a ramp's lower limits are not
/// counted, as for the top-speed delay), at most its own top speed `max_speed` (its type's
/// `maxSpeed`). Not capped at `v_max`: a vehicle with a factor above 1 wants to go faster.
pub(super) fn own_desired_speed(speed_factor: f64, max_speed: f64, road: &Road) -> f64 {
    (speed_factor * road.entries[0].speed_limit).min(max_speed)
}

/// Fills in a vehicle's passage through its first region `region`: by which entry, when it
/// was there, how far it drove, and its delay against driving that far free from the speed it
/// entered with, at the region's `v_max` and at its own desired speed `own_speed` (m/s; no
/// own-speed delay unless it is positive).
pub(super) fn passage(v: &mut ScenarioVehicle, e: &Entry, region: &Region, own_speed: f64) {
    let s = &region.config.scenario;
    let (last_time, last_front) = e.last;
    let distance = (last_front - e.front).max(0.0);
    let free_at = |top: f64| free_flow_time(distance, e.speed, s.free_flow_accel, top.max(e.speed));
    v.region_origin = e.origin.as_str().into();
    v.region_entry = entry_name(&region.road, e.entry);
    v.region_enter_s = Some(e.time);
    v.region_leave_s = Some(last_time);
    v.region_distance_m = Some(distance);
    if v.outcome != Outcome::Crashed {
        v.region_delay_s = Some(last_time - e.time - free_at(s.v_max));
        v.region_delay_own_s = (own_speed > 0.0).then(|| last_time - e.time - free_at(own_speed));
    }
}
