//! Raw declarations of the C++ shim (`shim.cpp`). Only `sumo::Simulation` calls these.
#![allow(dead_code)]

use std::os::raw::c_char;
use std::sync::atomic::{AtomicBool, Ordering};

/// Mirrors `BkVehicleState` in the shim.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct RawVehicleState {
    /// x of the front bumper's centre in SUMO's plane (m).
    pub x: f64,
    /// y of the front bumper's centre in SUMO's plane (m).
    pub y: f64,
    /// Speed (m/s).
    pub speed: f64,
    /// Acceleration in the last step (m/s²).
    pub acceleration: f64,
    /// SUMO's heading (degrees, clockwise from north: 90 = along +x).
    pub angle: f64,
    /// Position of the front bumper along the lane (m from its start).
    pub lane_position: f64,
    /// Offset from the lane's centre (m, positive to the left).
    pub lateral_offset: f64,
    /// Lateral speed (m/s, positive to the left): how fast a lane change moves the vehicle
    /// sideways; NaN where it is not known (a caller's reading without it).
    pub lateral_speed: f64,
    /// SUMO lane index on the edge (0 = rightmost).
    pub lane_index: i32,
    /// Index of the vehicle's edge in the names set by `Simulation::set_edge_codes`; −1 for
    /// any other edge.
    pub edge_code: i32,
}

/// Mirrors `BkCollision` in the shim.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct RawCollision {
    pub collider_speed: f64,
    pub victim_speed: f64,
    pub position: f64,
}

pub const LIST_VEHICLES: i32 = 0;
pub const LIST_DEPARTED: i32 = 1;
pub const LIST_ARRIVED: i32 = 2;
pub const LIST_LANES: i32 = 3;
pub const LIST_EDGES: i32 = 4;
pub const LIST_VEHICLE_TYPES: i32 = 5;
pub const LIST_PENDING: i32 = 6;

/// Which shim the calls go to: libsumo (SUMO in this process) or libtraci (a sumo-gui process
/// driven over TraCI). One simulation per process, so one switch for the process.
static USE_TRACI: AtomicBool = AtomicBool::new(false);

/// Sends the following calls to libtraci (`true`, sumo-gui) or libsumo (`false`).
pub fn use_traci(traci: bool) {
    USE_TRACI.store(traci, Ordering::SeqCst);
}

/// Declares each shim function twice (`bk_*` over libsumo, `bkt_*` over libtraci) and a
/// wrapper named like the first that calls whichever [`use_traci`] chose.
macro_rules! shim_functions {
    ($( fn $name:ident / $traci:ident ( $($arg:ident : $ty:ty),* $(,)? ) -> $ret:ty; )*) => {
        mod raw {
            use super::*;
            extern "C" {
                $( pub fn $name($($arg: $ty),*) -> $ret; pub fn $traci($($arg: $ty),*) -> $ret; )*
            }
        }
        $(
            /// # Safety
            /// The shim's contract for this function (see `shim.cpp`).
            pub unsafe fn $name($($arg: $ty),*) -> $ret {
                if USE_TRACI.load(Ordering::Relaxed) {
                    raw::$traci($($arg),*)
                } else {
                    raw::$name($($arg),*)
                }
            }
        )*
    };
}

shim_functions! {
    fn bk_last_error / bkt_last_error() -> *const c_char;
    fn bk_start / bkt_start(args: *const c_char, argc: usize) -> i32;
    fn bk_close / bkt_close() -> i32;
    fn bk_step / bkt_step() -> i32;
    fn bk_time / bkt_time(out: *mut f64) -> i32;
    fn bk_version / bkt_version(out: *mut *const c_char, len: *mut usize) -> i32;
    fn bk_min_expected_number / bkt_min_expected_number(out: *mut i32) -> i32;
    fn bk_id_list / bkt_id_list(which: i32, buf: *mut *const c_char, len: *mut usize) -> i32;
    fn bk_set_edge_names / bkt_set_edge_names(names: *const c_char, count: usize) -> i32;
    fn bk_vehicle_type / bkt_vehicle_type(id: *const c_char, out: *mut *const c_char, len: *mut usize) -> i32;
    fn bk_vehicle_route / bkt_vehicle_route(id: *const c_char, buf: *mut *const c_char, len: *mut usize) -> i32;
    fn bk_vehicle_size / bkt_vehicle_size(id: *const c_char, length: *mut f64, width: *mut f64) -> i32;
    fn bk_vehicle_max_speed / bkt_vehicle_max_speed(id: *const c_char, out: *mut f64) -> i32;
    fn bk_vehicle_speed_factor / bkt_vehicle_speed_factor(id: *const c_char, out: *mut f64) -> i32;
    fn bk_vehicle_limits / bkt_vehicle_limits(id: *const c_char, accel: *mut f64, decel: *mut f64, emergency: *mut f64, tau: *mut f64, min_gap: *mut f64) -> i32;
    fn bk_read_vehicles / bkt_read_vehicles(states: *mut *const RawVehicleState, count: *mut usize, strings: *mut *const c_char, strings_len: *mut usize) -> i32;
    fn bk_collisions / bkt_collisions(items: *mut *const RawCollision, count: *mut usize, strings: *mut *const c_char, strings_len: *mut usize) -> i32;
    fn bk_set_speed / bkt_set_speed(id: *const c_char, speed: f64) -> i32;
    fn bk_vehicle_add / bkt_vehicle_add(id: *const c_char, route: *const c_char, type_id: *const c_char, lane: i32, speed: f64) -> i32;
    fn bk_vehicle_remove / bkt_vehicle_remove(id: *const c_char) -> i32;
    fn bk_set_speeds / bkt_set_speeds(ids: *const c_char, count: usize, speeds: *const f64) -> i32;
    fn bk_set_max_speed / bkt_set_max_speed(id: *const c_char, speed: f64) -> i32;
    fn bk_set_speed_mode / bkt_set_speed_mode(id: *const c_char, mode: i32) -> i32;
    fn bk_set_lane_change_mode / bkt_set_lane_change_mode(id: *const c_char, mode: i32) -> i32;
    fn bk_change_lane / bkt_change_lane(id: *const c_char, lane_index: i32, duration: f64) -> i32;
    fn bk_vehicle_driving_distance / bkt_vehicle_driving_distance(id: *const c_char, edge: *const c_char, pos: f64, out: *mut f64) -> i32;
    fn bk_lane_length / bkt_lane_length(lane: *const c_char, out: *mut f64) -> i32;
    fn bk_lane_width / bkt_lane_width(lane: *const c_char, out: *mut f64) -> i32;
    fn bk_lane_max_speed / bkt_lane_max_speed(lane: *const c_char, out: *mut f64) -> i32;
    fn bk_edge_lane_count / bkt_edge_lane_count(edge: *const c_char, out: *mut i32) -> i32;
    fn bk_lane_shape / bkt_lane_shape(lane: *const c_char, xy: *mut *const f64, count: *mut usize) -> i32;
    fn bk_set_color / bkt_set_color(id: *const c_char, r: i32, g: i32, b: i32) -> i32;
}
