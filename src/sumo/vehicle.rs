//! What bkpbs asks SUMO about one vehicle: its type, size, top speed, speed factor,
//! accelerations, and how far its route still runs to a place.

use std::os::raw::c_char;

use super::{c_string, decode, ffi, Simulation, SumoError};
use crate::model::scene::{Following, Limits};

impl Simulation {
    /// The edges of a vehicle's route, in order (also of one SUMO has not inserted yet).
    pub fn vehicle_route(&self, id: &str) -> Result<Vec<String>, SumoError> {
        let cid = c_string(id)?;
        let mut ptr: *const c_char = std::ptr::null();
        let mut len = 0usize;
        // SAFETY: valid pointers; the returned buffer is copied at once.
        unsafe {
            decode(
                "vehicle.getRoute",
                ffi::bk_vehicle_route(cid.as_ptr(), &mut ptr, &mut len),
            )?;
            Ok(super::split_nul(ptr, len))
        }
    }

    /// The vehicle type id of a vehicle.
    pub fn vehicle_type(&self, id: &str) -> Result<String, SumoError> {
        let cid = c_string(id)?;
        let mut ptr: *const c_char = std::ptr::null();
        let mut len = 0usize;
        // SAFETY: valid pointers; the returned buffer is copied at once.
        unsafe {
            decode(
                "vehicle.getTypeID",
                ffi::bk_vehicle_type(cid.as_ptr(), &mut ptr, &mut len),
            )?;
            let bytes = std::slice::from_raw_parts(ptr as *const u8, len);
            Ok(String::from_utf8_lossy(bytes).into_owned())
        }
    }

    /// The vehicle's length and width (m), from its type.
    pub fn vehicle_size(&self, id: &str) -> Result<(f64, f64), SumoError> {
        let cid = c_string(id)?;
        let (mut length, mut width) = (0.0, 0.0);
        // SAFETY: a valid C string and out-pointers.
        decode("vehicle.getLength/getWidth", unsafe {
            ffi::bk_vehicle_size(cid.as_ptr(), &mut length, &mut width)
        })?;
        Ok((length, width))
    }

    /// The vehicle's own top speed (m/s): its type's `maxSpeed`, or what was set for it.
    pub fn vehicle_max_speed(&self, id: &str) -> Result<f64, SumoError> {
        let cid = c_string(id)?;
        let mut speed = 0.0;
        // SAFETY: a valid C string and out-pointer.
        decode("vehicle.getMaxSpeed", unsafe {
            ffi::bk_vehicle_max_speed(cid.as_ptr(), &mut speed)
        })?;
        Ok(speed)
    }

    /// The vehicle's own speed factor: its desired speed is this times the lane's speed limit
    /// (at most its top speed), drawn by SUMO from its type's `speedFactor` distribution when
    /// it was loaded, or what was set for it.
    pub fn vehicle_speed_factor(&self, id: &str) -> Result<f64, SumoError> {
        let cid = c_string(id)?;
        let mut factor = 0.0;
        // SAFETY: a valid C string and out-pointer.
        decode("vehicle.getSpeedFactor", unsafe {
            ffi::bk_vehicle_speed_factor(cid.as_ptr(), &mut factor)
        })?;
        Ok(factor)
    }

    /// The vehicle's own acceleration, deceleration and emergency deceleration (m/s²) and the
    /// gap it follows at: its type's `accel`, `decel`, `emergencyDecel`, `tau` and `minGap`, or
    /// what was set for it.
    pub fn vehicle_limits(&self, id: &str) -> Result<Limits, SumoError> {
        let cid = c_string(id)?;
        let (mut accel, mut decel, mut emergency_decel) = (0.0, 0.0, 0.0);
        let (mut tau, mut min_gap) = (0.0, 0.0);
        // SAFETY: a valid C string and out-pointers.
        decode(
            "vehicle.getAccel/getDecel/getEmergencyDecel/getTau/getMinGap",
            unsafe {
                ffi::bk_vehicle_limits(
                    cid.as_ptr(),
                    &mut accel,
                    &mut decel,
                    &mut emergency_decel,
                    &mut tau,
                    &mut min_gap,
                )
            },
        )?;
        Ok(Limits {
            accel,
            decel,
            emergency_decel,
            following: Some(Following { tau, min_gap }),
        })
    }

    /// Distance the vehicle still has to drive along its route to position `pos` on `edge`.
    pub fn driving_distance(&self, id: &str, edge: &str, pos: f64) -> Result<f64, SumoError> {
        let cid = c_string(id)?;
        let cedge = c_string(edge)?;
        let mut d = 0.0;
        // SAFETY: valid C strings and out-pointer.
        decode("vehicle.getDrivingDistance", unsafe {
            ffi::bk_vehicle_driving_distance(cid.as_ptr(), cedge.as_ptr(), pos, &mut d)
        })?;
        Ok(d)
    }
}
