//! What a controller sees each step: every vehicle's state in the road frame.

use std::sync::Arc;

use crate::model::road::Road;

/// Who drives a vehicle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Kind {
    /// Connected automated vehicle: commanded by the controller under test.
    Cav,
    /// Human-driven vehicle: SUMO's driver models (plus the ramp merge rule).
    Hdv,
}

impl Kind {
    /// The SUMO vehicle type id, also used in CSV files.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Cav => "cav",
            Kind::Hdv => "hdv",
        }
    }

    /// Parses a SUMO type id; SUMO names a per-vehicle copy of a type `type@vehicle`, and the
    /// driver types of a heterogeneous profile are `hdv.0`, `hdv.1`, ….
    pub fn from_type_id(s: &str) -> Option<Kind> {
        match s.split(['@', '.']).next().unwrap_or(s) {
            "cav" => Some(Kind::Cav),
            "hdv" => Some(Kind::Hdv),
            _ => None,
        }
    }
}

/// Where a vehicle entered the section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Origin {
    Main,
    Ramp,
}

impl Origin {
    pub fn as_str(self) -> &'static str {
        match self {
            Origin::Main => "main",
            Origin::Ramp => "ramp",
        }
    }
}

/// One vehicle at one instant, in the road frame.
#[derive(Debug, Clone, PartialEq)]
pub struct VehicleState {
    pub id: Arc<str>,
    pub kind: Kind,
    pub origin: Origin,
    /// Longitudinal position of the vehicle's centre (m).
    pub s: f64,
    /// Road-frame lane the vehicle is assigned to (0 = ramp / acceleration lane).
    pub lane: i32,
    /// Lateral offset from that lane's centre (m, positive to the left): non-zero mid lane change.
    pub lateral: f64,
    /// Speed (m/s).
    pub speed: f64,
    /// Acceleration in the last step (m/s²).
    pub accel: f64,
    /// Heading relative to the road direction (rad, positive to the left).
    pub heading: f64,
    /// The speed the vehicle wants to drive (m/s).
    pub desired_speed: f64,
    pub length: f64,
    pub width: f64,
    /// Still on the ramp edge (cannot change lanes yet).
    pub on_ramp: bool,
}

impl VehicleState {
    /// A 5 m × 2 m vehicle on the centre of `lane`, driving straight at `speed` and wanting
    /// 35 m/s: for scenes built by hand (tests, the Python bindings).
    pub fn on_lane(id: &str, kind: Kind, origin: Origin, s: f64, lane: i32, speed: f64) -> Self {
        VehicleState {
            id: Arc::from(id),
            kind,
            origin,
            s,
            lane,
            lateral: 0.0,
            speed,
            accel: 0.0,
            heading: 0.0,
            desired_speed: 35.0,
            length: 5.0,
            width: 2.0,
            on_ramp: false,
        }
    }

    /// Position of the front bumper (m).
    pub fn front(&self) -> f64 {
        self.s + 0.5 * self.length
    }

    /// Position of the rear bumper (m).
    pub fn rear(&self) -> f64 {
        self.s - 0.5 * self.length
    }
}

/// All vehicles at one step.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Simulation time (s).
    pub time: f64,
    pub road: Road,
    pub vehicles: Vec<VehicleState>,
}

impl Scene {
    /// A scene on the shipped network's road ([`Road::paper_default`]) at `time`: for scenes
    /// built by hand (tests, planning without SUMO).
    pub fn on_paper_road(time: f64, vehicles: Vec<VehicleState>) -> Scene {
        Scene {
            time,
            road: Road::paper_default(),
            vehicles,
        }
    }

    /// Indices of the CAVs, in scene order.
    pub fn cav_indices(&self) -> Vec<usize> {
        (0..self.vehicles.len())
            .filter(|&i| self.vehicles[i].kind == Kind::Cav)
            .collect()
    }

    /// Index of the nearest vehicle ahead of `s` on `lane` (excluding `skip`), by centre position.
    pub fn leader(&self, lane: i32, s: f64, skip: usize) -> Option<usize> {
        self.nearest(lane, skip, |o| o > s, |a, b| a < b)
    }

    /// Index of the nearest vehicle behind `s` on `lane` (excluding `skip`).
    pub fn follower(&self, lane: i32, s: f64, skip: usize) -> Option<usize> {
        self.nearest(lane, skip, |o| o <= s, |a, b| a > b)
    }

    fn nearest(
        &self,
        lane: i32,
        skip: usize,
        side: impl Fn(f64) -> bool,
        closer: impl Fn(f64, f64) -> bool,
    ) -> Option<usize> {
        let mut best: Option<usize> = None;
        for (i, v) in self.vehicles.iter().enumerate() {
            if i == skip || v.lane != lane || !side(v.s) {
                continue;
            }
            if best.map_or(true, |b| closer(v.s, self.vehicles[b].s)) {
                best = Some(i);
            }
        }
        best
    }
}
