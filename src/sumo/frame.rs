//! A road-frame [`VehicleState`] from what SUMO reports about one vehicle: edge, lane, lane
//! position of the front bumper, lateral offset, speed, acceleration and angle.
//!
//! The episode runner reads these values for all vehicles in one libsumo call; a user's own
//! TraCI or libsumo loop reads them one getter at a time (the Python bindings' `Controller`).
//! Both go through this module, so a controller sees the same scene either way.

use std::sync::Arc;

use crate::config::Scenario;
use crate::model::road::{Road, EDGES};
use crate::model::scene::{Kind, Origin, VehicleState};
use crate::sumo::RawVehicleState;

/// What SUMO's readings do not say about a vehicle: who it is and what it wants.
#[derive(Debug, Clone, PartialEq)]
pub struct Identity {
    pub id: Arc<str>,
    pub kind: Kind,
    pub origin: Origin,
    /// The speed the vehicle wants to drive (m/s).
    pub desired_speed: f64,
}

/// The code of a SUMO edge of the merge section (its index in [`EDGES`]), as
/// [`RawVehicleState::edge_code`] carries it; `None` for any other edge (e.g. an internal lane).
pub fn edge_code(road_id: &str) -> Option<i32> {
    EDGES.iter().position(|e| *e == road_id).map(|i| i as i32)
}

/// Where a vehicle entered, from the demand's vehicle ids (`main.N`, `ramp.N`); `None` for ids
/// of another scheme.
pub fn origin_from_id(id: &str) -> Option<Origin> {
    [Origin::Main, Origin::Ramp].into_iter().find(|o| {
        id.strip_prefix(o.as_str())
            .is_some_and(|r| r.starts_with('.'))
    })
}

/// Where a vehicle entered, from the edge it was first seen on: the ramp or else the main road.
pub fn origin_from_edge(road: &Road, edge_code: i32) -> Origin {
    if road.is_on_ramp(edge_code) {
        Origin::Ramp
    } else {
        Origin::Main
    }
}

/// Front-bumper `s` and road-frame lane of a reading; `None` off the merge section.
pub fn frame_position(road: &Road, raw: &RawVehicleState) -> Option<(f64, i32)> {
    road.to_frame(raw.edge_code, raw.lane_index, raw.lane_position)
}

/// The vehicle at the frame position [`frame_position`] gave: the centre lies half a length
/// behind the front bumper, and SUMO's angle (degrees, 0 = north, clockwise) becomes a heading
/// relative to the road (radians, positive to the left; the road runs east).
pub fn state_at(
    road: &Road,
    scenario: &Scenario,
    who: Identity,
    raw: &RawVehicleState,
    front: f64,
    lane: i32,
) -> VehicleState {
    VehicleState {
        id: who.id,
        kind: who.kind,
        origin: who.origin,
        s: front - 0.5 * scenario.vehicle_length,
        lane,
        lateral: raw.lateral_offset,
        speed: raw.speed,
        accel: raw.acceleration,
        heading: (90.0 - raw.angle).to_radians(),
        desired_speed: who.desired_speed,
        length: scenario.vehicle_length,
        width: scenario.vehicle_width,
        on_ramp: road.is_on_ramp(raw.edge_code),
    }
}

/// The vehicle in the road frame; `None` when it is off the merge section.
pub fn vehicle_state(
    road: &Road,
    scenario: &Scenario,
    who: Identity,
    raw: &RawVehicleState,
) -> Option<VehicleState> {
    let (front, lane) = frame_position(road, raw)?;
    Some(state_at(road, scenario, who, raw, front, lane))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_names_map_to_codes() {
        assert_eq!(edge_code("main_in"), Some(0));
        assert_eq!(edge_code("main_out"), Some(3));
        assert_eq!(edge_code(":n1_0"), None);
    }

    #[test]
    fn origin_from_demand_ids_only() {
        assert_eq!(origin_from_id("ramp.12"), Some(Origin::Ramp));
        assert_eq!(origin_from_id("main.0"), Some(Origin::Main));
        assert_eq!(origin_from_id("rampage"), None);
        assert_eq!(origin_from_id("veh0"), None);
    }

    #[test]
    fn reading_on_the_acceleration_lane() {
        let road = Road::paper_default();
        let sc = Scenario::default();
        let raw = RawVehicleState {
            speed: 20.0,
            angle: 80.0,
            lane_position: 30.0,
            lateral_offset: 0.5,
            lane_index: 0,
            edge_code: edge_code("acc").unwrap(),
            ..Default::default()
        };
        let who = Identity {
            id: Arc::from("ramp.3"),
            kind: Kind::Cav,
            origin: Origin::Ramp,
            desired_speed: 35.0,
        };
        let v = vehicle_state(&road, &sc, who, &raw).unwrap();
        assert_eq!((v.s, v.lane, v.on_ramp), (177.5, 0, false));
        assert!((v.heading - 10f64.to_radians()).abs() < 1e-12);
        assert_eq!(v.front(), 180.0);
        let off = RawVehicleState {
            edge_code: -1,
            ..raw
        };
        let who = Identity {
            id: Arc::from("x"),
            kind: Kind::Hdv,
            origin: Origin::Main,
            desired_speed: 30.0,
        };
        assert!(vehicle_state(&road, &sc, who, &off).is_none());
    }
}
