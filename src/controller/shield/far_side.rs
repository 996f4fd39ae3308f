//! An HDV two lanes over moving into the lane a CAV changes into, in the same second: the
//! shield's worst case of a lane change from the far side of the CAV's target.
//!
//! SUMO decides its drivers' lane changes one vehicle at a time, the one ahead first, so an HDV
//! level with a CAV on the far side of the CAV's target lane sees that lane free and moves
//! into it in the step the CAV's commanded change starts, or in the second it lasts
//! (`scenario.lane_change_duration`); a change under way is never taken back, and the CAV,
//! alongside, cannot brake out of the other's way. On a road of three or more main lanes the
//! middle lanes are entered from both sides everywhere (LC2013 keeps right and overtakes on the
//! left), so a main-road CAV expects any HDV beyond its target to come. A ramp CAV changing
//! into lane 1 expects only an HDV in lane 2 that is level with it or can come level within
//! the change: a truck of 16.5 m alongside it in lane 2 moved right into lane 1 in the second a
//! ramp CAV changed into it (bk-pbs, its lane change from a round's best node), and they
//! collided. Expecting every lane-2 HDV to come, as on the main road, kept ramp CAVs behind
//! lane-2 traffic with its emergency braking's gaps and prevented no collision; in a weaving
//! section lane-2 drivers cross lane 1 towards the exit anywhere, and there every one counts.
//! The same holds the other way round: a main-road CAV changing from lane 2 into lane 1
//! expects a ramp HDV level with it on the acceleration lane to merge with it (one ahead of
//! it by centre is expected to merge anyway, see `check::clear_of_leaders`). On a three-lane
//! carriageway with 16.5 m trucks (`tests/shield_far_side.rs`, seed 27, α 0.55) a CAV in lane
//! 2 changed right at 149.2 s beside a ramp truck whose centre was 0.13 m behind its own, the
//! truck merged in the same step, and they collided at 150.0 s, under bk-pbs and bk-mastar.
//!
//! Only an HDV SUMO decides before the CAV can do so: SUMO's lane changer takes an edge's
//! vehicles front first (`MSLaneChanger::findCandidate`, the largest position on the lane), and
//! from the CAV's turn on its change holds the target lane (its shadow leads there), so an HDV
//! whose front is behind the CAV's after the step's move sees the CAV in the target lane and
//! changes behind it only with SUMO's own safe gap. Both trucks above had their front ahead of
//! the CAV's. Expecting also the HDVs behind kept ramp CAVs on a gained lane level with the
//! main road's right lane until its traffic passed (the two-lane gain layout: its outer lane's
//! delay 3.1 to 5.6 s above SUMO alone's under bk-mastar).

use crate::model::road::Road;
use crate::model::scene::{Kind, VehicleState};

/// How far a CAV and an HDV beside its target lane can move against each other while a lane
/// change lasts: everything the check needs of the configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FarSide {
    /// How long a lane change lasts (s, `scenario.lane_change_duration`).
    pub duration: f64,
    /// Smallest bumper gap kept (m, `planner.margin_long`).
    pub margin: f64,
    /// Hardest braking of the CAV (m/s², positive).
    pub cav_decel: f64,
    /// Hardest braking of the HDV (m/s², positive).
    pub hdv_decel: f64,
    /// Strongest acceleration of the HDV (m/s²).
    pub hdv_accel: f64,
    /// The simulation step (s): SUMO moves its vehicles before it changes their lanes.
    pub step: f64,
}

impl FarSide {
    /// Whether HDV `o`, on the lane beyond `target` seen from CAV `me`'s lane, may change into
    /// `target` in the same second as `me`, which starts its change driving at `speed`:
    /// anywhere when both `me` and `o` drive on main lanes, or when `me` is on an auxiliary lane
    /// of a weaving section; else, when one of them is on an acceleration lane, only when SUMO
    /// can decide `o`'s lane change first ([`FarSide::goes_first`]) and `o` comes level with
    /// `me` within the change ([`FarSide::comes_level`]).
    pub fn may_enter(
        &self,
        road: &Road,
        (me, speed): (&VehicleState, f64),
        target: i32,
        o: &VehicleState,
    ) -> bool {
        let beyond = 2 * target - me.lane;
        let between_main = !road.is_auxiliary(me.lane) && !road.is_auxiliary(beyond);
        let weaving = road.is_auxiliary(me.lane) && road.weaving_at(o.front());
        o.kind == Kind::Hdv
            && !o.on_ramp
            && o.lane == beyond
            && (between_main || weaving || self.first_and_level((me, speed), o))
    }

    fn first_and_level(&self, me: (&VehicleState, f64), o: &VehicleState) -> bool {
        self.goes_first(me, o) && self.comes_level(me, o)
    }

    /// Whether SUMO's lane changer may take `o` before `me` in the step `me`'s change starts:
    /// when `o`'s front can be ahead of `me`'s after the step's move (`me` driving at `speed`,
    /// `o` accelerating as hard as it can).
    pub fn goes_first(&self, (me, speed): (&VehicleState, f64), o: &VehicleState) -> bool {
        // SUMO moves a vehicle by its new speed over the step (Euler).
        let o_most = (o.speed + self.hdv_accel * self.step) * self.step;
        o.front() + o_most >= me.front() + speed * self.step
    }

    /// Whether the bodies of `me` (driving at `speed`) and `o`, taken side by side, overlap
    /// within `margin` now or can within the change's `duration`: `me` at `speed` or braking as
    /// hard as it can, `o` braking or accelerating as hard as it can. Checked at the duration's
    /// end, where the range of their relative displacement, which starts at zero and only
    /// widens, is widest.
    pub fn comes_level(&self, (me, speed): (&VehicleState, f64), o: &VehicleState) -> bool {
        let t = self.duration;
        let (my_least, my_most) = (travel(speed, -self.cav_decel, t), speed * t);
        let (o_least, o_most) = (
            travel(o.speed, -self.hdv_decel, t),
            travel(o.speed, self.hdv_accel, t),
        );
        // `o` gains on `me` by a displacement in [least, most]; level when one closes both gaps.
        let (least, most) = (o_least - my_most, o_most - my_least);
        let ahead = o.rear() - me.front();
        let behind = me.rear() - o.front();
        least < self.margin - ahead && most > behind - self.margin
    }
}

/// Distance driven in `t` seconds from `speed` at constant acceleration `accel`, stopping for
/// good when braking brings it to a stand.
fn travel(speed: f64, accel: f64, t: f64) -> f64 {
    if accel < 0.0 && speed + accel * t < 0.0 {
        return speed * speed / (-2.0 * accel);
    }
    speed * t + 0.5 * accel * t * t
}
