//! A vehicle's passage through the merge region it enters first: where its route would enter
//! one (for a vehicle SUMO holds back), its first reading there, and what the passage cost it.

use crate::config::Config;
use crate::model::kinematics::free_flow_time;
use crate::model::scene::Origin;
use crate::sumo::frame;
use crate::sumo::{RawVehicleState, SumoClient, SumoError};

use super::records::ScenarioVehicle;
use super::region::Region;
use crate::episode::metrics::Outcome;

/// A vehicle's passage through the first region it entered.
#[derive(Clone, Copy)]
pub(super) struct Entry {
    pub(super) region: usize,
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

/// The region a route enters first, and whether it enters there on an on-ramp.
pub(super) fn first_region_on(regions: &[Region], route: &[String]) -> Option<(usize, Origin)> {
    route.iter().find_map(|edge| {
        regions.iter().enumerate().find_map(|(g, r)| {
            let e = r.road.edge(edge)?;
            Some((
                g,
                if e.on_ramp {
                    Origin::Ramp
                } else {
                    Origin::Main
                },
            ))
        })
    })
}

/// A vehicle's first reading in region `region`: when, where, how fast, from where, and
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
    Ok(Entry {
        region: g,
        origin: if frame::is_on_ramp(&region.road, raw.edge_code) {
            Origin::Ramp
        } else {
            Origin::Main
        },
        // SUMO answers a negative distance for an edge off the vehicle's route.
        leaves_early: sim.driving_distance(id, end, pos)? < 0.0,
        time: now,
        front,
        speed: raw.speed,
        last: (now, front),
    })
}

/// Fills in a vehicle's passage through its first region: when it was there, how far it
/// drove, and its delay against driving that far free from the speed it entered with.
pub(super) fn passage(v: &mut ScenarioVehicle, e: &Entry, config: &Config) {
    let s = &config.scenario;
    let (last_time, last_front) = e.last;
    let distance = (last_front - e.front).max(0.0);
    let free = free_flow_time(distance, e.speed, s.free_flow_accel, s.v_max.max(e.speed));
    v.region_origin = e.origin.as_str().into();
    v.region_enter_s = Some(e.time);
    v.region_leave_s = Some(last_time);
    v.region_distance_m = Some(distance);
    if v.outcome != Outcome::Crashed {
        v.region_delay_s = Some(last_time - e.time - free);
    }
}
