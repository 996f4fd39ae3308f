//! The one control hand-over of both traffics: how SUMO drives a vehicle while a planner
//! commands it, when the planner hands it back, and (on the paper's demand) a ramp HDV whose
//! lane change the merge rule decides. Every mode bkpbs sets is here, by name.

use crate::sumo::{SumoClient, SumoError};

/// SUMO speed mode for commanded CAVs: no checks at all, the commanded speed is the speed.
const SPEED_MODE_COMMANDED: i32 = 0;
/// SUMO lane-change mode for commanded CAVs: no own changes; requests obeyed without checks.
const LC_MODE_COMMANDED: i32 = 0;
/// SUMO's defaults, restored when a CAV leaves the planned part of a region: every safety check
/// on, and its own lane changes (SUMO's `speedMode` 31 and `laneChangeMode` 1621).
const SPEED_MODE_SUMO: i32 = 31;
const LC_MODE_SUMO: i32 = 0b110_0101_0101;
/// SUMO lane-change mode for ramp HDVs: no own changes (the merge rule decides when), requests
/// executed only into safe gaps, adapting speed to find one.
const LC_MODE_RAMP_HDV: i32 = 0b10_0000_0000;
/// The same for a ramp HDV stuck at the lane end: requests executed avoiding only immediate
/// collisions (see `merge_rule`).
const LC_MODE_RAMP_HDV_FORCED: i32 = 0b01_0000_0000;

/// The speed mode and lane-change mode of a commanded CAV (for a caller's own TraCI loop, which
/// sets them itself: the Python `bkpbs.sumo.apply`).
pub const COMMANDED_MODES: (i32, i32) = (SPEED_MODE_COMMANDED, LC_MODE_COMMANDED);

/// A planner takes CAV `id` over: SUMO drives it exactly as commanded.
pub fn take_over(sim: &mut impl SumoClient, id: &str) -> Result<(), SumoError> {
    sim.set_speed_mode(id, SPEED_MODE_COMMANDED)?;
    sim.set_lane_change_mode(id, LC_MODE_COMMANDED)
}

/// The planner hands CAV `id` back: SUMO's own driver, its checks and lane changes, at its own
/// speed again.
pub fn hand_back(sim: &mut impl SumoClient, id: &str) -> Result<(), SumoError> {
    sim.set_speed(id, -1.0)?;
    sim.set_speed_mode(id, SPEED_MODE_SUMO)?;
    sim.set_lane_change_mode(id, LC_MODE_SUMO)
}

/// Ramp HDV `id` changes lanes only when the merge rule asks, into a safe gap.
pub fn ramp_hdv_waits_for_the_rule(sim: &mut impl SumoClient, id: &str) -> Result<(), SumoError> {
    sim.set_lane_change_mode(id, LC_MODE_RAMP_HDV)
}

/// Ramp HDV `id`, stuck at the lane end, changes lanes avoiding only immediate collisions.
pub fn ramp_hdv_forced(sim: &mut impl SumoClient, id: &str) -> Result<(), SumoError> {
    sim.set_lane_change_mode(id, LC_MODE_RAMP_HDV_FORCED)
}
