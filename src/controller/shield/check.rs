//! The shield's pure worst-case check: is one CAV's next step safe whatever the others do
//! within bounds, and if not, what is the least intrusive safe step instead.
//!
//! This is the second of the crate's two safety models, and the last word. The first,
//! [`crate::planner::safety::SafetyRule`], is the planners' own: it judges whole *predicted*
//! trajectories, pair by pair over the planning horizon (inflated bodies must not overlap; a
//! gap of `safe_gap` + reaction time + stopping-distance difference in the lane), so a plan is
//! only as safe as the HDV predictions it was made against. The shield trusts no prediction
//! and looks one step ahead: it takes the maneuver actually about to be sent, the scene as it
//! is now, and bounded worst cases of every other vehicle ([`WorstCase`]: everyone may brake at
//! its emergency deceleration, a lane change under way completes, a ramp HDV near the lane end
//! may merge at any moment), and steps the motion as SUMO integrates it, checking the bumper
//! gap against `planner.margin_long` at every step end. Both models share their braking
//! numbers (`planner.emergency_decel`, `idm.decel` for a cut-in's follower) so that a plan the
//! rule admits is rarely overridden here.
//!
//! Worst cases: every other vehicle may brake at its emergency deceleration (HDVs
//! `idm.max_decel`, SUMO's emergencyDecel; CAVs `planner.emergency_decel`) and keeps its lane; a
//! lane change under way completes, so a vehicle off its lane centre occupies both lanes; a ramp
//! vehicle that changed into lane 1 with its rear still on the ramp occupies the ramp's lane too
//! (`tail_on_ramp`); a ramp HDV on the acceleration lane may merge into main lane 1 at any
//! time; a main-road HDV beside the CAV may change into its lane in front of it wherever SUMO's
//! lane-change model would let it, and then brake as hard as SUMO expects of it (`may_cut_in`,
//! [`super::cut_in`]); under a gap-acceptance profile a ramp HDV may move over in front of a
//! lane-1 CAV anywhere on the acceleration lane (`may_take_gap`); an HDV two lanes over may
//! change into the lane a CAV changes into, in the same second: a middle lane of three or more,
//! lane 1 of a weaving section from lane 2, and lane 1 from lane 2 beside a ramp CAV on an
//! acceleration lane when the HDV is level with it or can come level within the change
//! ([`super::far_side`]). A CAV's maneuver is safe
//! when, executed for one step and followed by braking at `planner.emergency_decel`, the CAV never
//! comes closer than the margin to any vehicle ahead of it (by centre) in any lane it occupies,
//! and, if it starts a lane change, the follower in the target lane stays clear of it braking at
//! its comfortable deceleration `idm.decel`. Motion is stepped as SUMO steps it (Euler: a step's
//! end speed times `dt`), and gaps are checked at step ends, where SUMO checks collisions.
//!
//! An unsafe maneuver is replaced by the least intrusive safe one: keep the lane (a lane-change
//! start is cancelled; one under way is left to finish), at the highest safe speed between the
//! strongest braking and the planned speed, else the strongest braking.

use super::cut_in::CutIn;
use super::far_side::FarSide;
use crate::config::hdv::RampMergeStyle;
use crate::config::Config;
use crate::controller::Maneuver;
use crate::model::braking::{stays_clear, Braking};
use crate::model::road::{Road, FORCED_MERGE_ZONE};
use crate::model::scene::{Kind, Origin, Scene, VehicleState};

/// The shield's worst-case braking model: how hard every vehicle may brake (and an HDV
/// accelerate), and the gap kept at every step end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorstCase {
    /// Step length (s).
    pub dt: f64,
    /// Hardest braking of a CAV, the checked one included (m/s², positive).
    pub cav_decel: f64,
    /// Hardest braking of an HDV (m/s², positive).
    pub hdv_decel: f64,
    /// Strongest acceleration of an HDV (m/s²): how soon a ramp HDV can reach the forced-merge
    /// zone.
    pub hdv_accel: f64,
    /// Braking a lane change may ask of the new follower at most (m/s², positive).
    pub follower_decel: f64,
    /// Smallest bumper gap kept at every step end (m).
    pub margin: f64,
    /// Extra gap kept behind a ramp HDV that may merge into the CAV's lane (m): SUMO's minGap
    /// of the CAV type, which SUMO wants free behind a merger even when it forces its way in.
    pub yield_gap: f64,
    /// When SUMO lets a main-road HDV change lanes in front of a CAV (see `may_cut_in`).
    pub cut_in: CutIn,
    /// Whether ramp HDVs merge by gap acceptance, without SUMO's safety check (profiles such as
    /// `paper`): then one may move over anywhere on the acceleration lane (see `may_take_gap`).
    pub gap_accepting_mergers: bool,
    /// Which HDV two lanes over may change into a CAV's target lane with it (see
    /// [`super::far_side`]).
    pub far_side: FarSide,
}

impl WorstCase {
    /// The worst cases of `config`; the margin is the planner's longitudinal box inflation
    /// (`planner.margin_long`), which absorbs the difference between modelled and executed motion.
    pub fn from_config(config: &Config) -> Self {
        let profile = config.hdv.resolved().unwrap_or_default();
        let assertive = profile.max_attribute("lcAssertive", 1.0);
        WorstCase {
            dt: config.scenario.dt,
            cav_decel: config.planner.emergency_decel,
            hdv_decel: config.idm.max_decel,
            hdv_accel: config.idm.accel,
            follower_decel: config.idm.decel,
            margin: config.planner.margin_long,
            yield_gap: config.idm.min_gap,
            cut_in: CutIn {
                min_gap: config.idm.min_gap,
                // SUMO wants lcAssertive > 0; anything else is taken as "accepts any gap".
                factor: if assertive > 0.0 {
                    1.0 / assertive
                } else {
                    0.0
                },
                secure_decel: config.idm.decel,
                brake_decel: profile
                    .max_attribute("decel", config.idm.decel)
                    .max(config.idm.decel),
            },
            gap_accepting_mergers: matches!(
                profile.ramp_merge,
                RampMergeStyle::GapAcceptance { .. }
            ),
            far_side: FarSide {
                duration: config.scenario.lane_change_duration,
                margin: config.planner.margin_long,
                cav_decel: config.planner.emergency_decel,
                hdv_decel: config.idm.max_decel,
                hdv_accel: config.idm.accel,
                step: config.scenario.dt,
            },
        }
    }

    fn emergency_decel(&self, kind: Kind) -> f64 {
        match kind {
            Kind::Cav => self.cav_decel,
            Kind::Hdv => self.hdv_decel,
        }
    }
}

/// The lane whose bit is a lane set's lowest: auxiliary lanes on the right down to it have one.
const LOWEST_LANE_BIT: i32 = -16;

/// Lane bit of a lane set (lanes outside −16..48 are no lane of this road).
pub fn bit(lane: i32) -> u64 {
    let index = lane - LOWEST_LANE_BIT;
    if (0..64).contains(&index) {
        1 << index
    } else {
        0
    }
}

/// Lanes vehicle `v` occupies: its own, the other one of a lane change under way
/// ([`VehicleState::other_lane`]: moving to it or from it, either way it occupies both), and the
/// ramp's lane while its rear is still on the ramp (`tail_on_ramp`).
fn lanes_now(road: &Road, v: &VehicleState) -> u64 {
    lanes_beside(v) | tail_on_ramp(road, v).map_or(0, bit)
}

/// The lanes `v` occupies side by side: its own and the other one of a change under way. (A
/// CAV's own rear on the ramp is its followers' business, not a lane its check must keep clear
/// ahead.)
fn lanes_beside(v: &VehicleState) -> u64 {
    bit(v.lane) | v.other_lane().map_or(0, bit)
}

/// Whether ramp vehicle `v` changed into main lane 1 so early that its rear still lies behind
/// the start of the acceleration lane, on the ramp: SUMO keeps that rear on the ramp's lane
/// (the ramp has no lane beside it to move it to) until it has driven off it, and a vehicle
/// following on the ramp runs into it there, although the change has ended. (Default drivers,
/// α 0.4, λ 3000, seed 7002: a ramp HDV standing at the acceleration lane's very start, its
/// front 1.25 m into it, changed into lane 1 at 143.4–144.2 s; a CAV stopped 2 m behind it on
/// the ramp then saw its lane free and accelerated, and at 145.2 s hit the rear, 3.6 m back
/// on the ramp.) The zone's start is taken for where the vehicle's ramp joins; a ramp vehicle
/// passing a later ramp's junction in lane 1 counts too, for the moment it takes. The lane
/// its tail is on: the auxiliary lane merging into its own.
fn tail_on_ramp(road: &Road, v: &VehicleState) -> Option<i32> {
    let zone = road.zone_into(v.lane, v.front())?;
    (v.origin == Origin::Ramp && v.rear() < zone.start).then_some(zone.lane)
}

/// A ramp HDV on the acceleration lane: it may start its merge at any moment (SUMO's lane-change
/// model decides when). A CAV changing into lane 1 beside it must let it (a CAV in lane 2 and a
/// ramp HDV 16 m ahead of it once moved into lane 1 in the same step: each saw the lane free);
/// a CAV already driving in lane 1 is not asked to, see [`may_merge`].
fn on_acceleration_lane(road: &Road, v: &VehicleState) -> bool {
    v.kind == Kind::Hdv && v.origin == Origin::Ramp && road.is_auxiliary(v.lane) && !v.on_ramp
}

/// A ramp HDV whose merge will happen whatever the CAVs do: on the acceleration lane within
/// [`FORCED_MERGE_ZONE`] of its end, or able to come to a stand there within `horizon` seconds
/// (accelerating at `b.hdv_accel`, then braking at `b.hdv_decel`), where the merge rule forces
/// it in once it stands. A creeping HDV a metre short of the zone is one such. Merges already
/// under way count through the lateral offset ([`VehicleState::other_lane`]). Other ramp HDVs are not
/// assumed to merge at any moment: that assumption cost a fifth of the throughput and no
/// collision it prevented was seen.
pub fn may_merge(scene: &Scene, v: &VehicleState, horizon: f64, b: &WorstCase) -> bool {
    let Some(end) = scene.road.lane_end(v.lane, v.front()) else {
        return false;
    };
    let zone = end - FORCED_MERGE_ZONE;
    let can_stand_in_zone = || {
        farthest_stand(v.speed, horizon, b.hdv_accel, b.hdv_decel)
            .is_some_and(|reach| v.front() + reach >= zone)
    };
    on_acceleration_lane(&scene.road, v)
        && (v.front() + v.speed * horizon >= zone || can_stand_in_zone())
}

/// How far ahead a vehicle at `speed` can be standing within `horizon` seconds, accelerating
/// at `accel` and then braking at `decel` (none if it cannot stop within the horizon).
pub(super) fn farthest_stand(speed: f64, horizon: f64, accel: f64, decel: f64) -> Option<f64> {
    if speed > decel * horizon {
        return None;
    }
    let t_accel = (horizon * decel - speed) / (accel + decel);
    let peak = speed + accel * t_accel;
    Some(0.5 * (speed + peak) * t_accel + peak * peak / (2.0 * decel))
}

/// Lanes another vehicle may occupy within `horizon` seconds under the worst cases.
fn lanes_of_other(scene: &Scene, v: &VehicleState, horizon: f64, b: &WorstCase) -> u64 {
    let merge = if may_merge(scene, v, horizon, b) {
        bit(scene.road.toward_main(v.lane))
    } else {
        0
    };
    lanes_now(&scene.road, v) | merge
}

/// Lanes the CAV occupies while executing `m`: its lanes now and the target of a change it starts.
fn lanes_of_cav(v: &VehicleState, m: &Maneuver) -> u64 {
    lanes_beside(v) | m.lane_change.map_or(0, |lc| bit(v.lane + lc.offset()))
}

/// The CAV's own worst case after `m`: `m.speed` for one step, then its emergency braking.
fn cav_motion(v: &VehicleState, m: &Maneuver, b: &WorstCase) -> Braking {
    Braking {
        speed: v.speed,
        first: Some(m.speed),
        decel: b.cav_decel,
        reach: f64::INFINITY,
    }
}

/// How far `v` can drive before its lane ends: to the end of the acceleration lane for a vehicle
/// on it, else without limit.
fn reach(scene: &Scene, v: &VehicleState) -> f64 {
    let end = scene.road.lane_end(v.lane, v.front());
    end.map_or(f64::INFINITY, |end| (end - v.front()).max(0.0))
}

/// The end of the acceleration lane, as a standing vehicle in front of a CAV that occupies that
/// lane alone: the CAV must be able to stop before it.
fn clear_of_lane_end(scene: &Scene, v: &VehicleState, m: &Maneuver, b: &WorstCase) -> bool {
    let Some(end) = scene.road.lane_end(v.lane, v.front()) else {
        return true;
    };
    if lanes_of_cav(v, m) != bit(v.lane) {
        return true;
    }
    let wall = Braking {
        speed: 0.0,
        first: None,
        decel: b.cav_decel,
        reach: 0.0,
    };
    stays_clear(cav_motion(v, m, b), wall, end - v.front(), b.margin, b.dt)
}

/// What the shield let through this step, before the command under check, for one scene vehicle.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sent {
    /// The lanes it enters by a lane change sent this step (a bit set, [`bit`]).
    pub entering: u64,
    /// The speed sent for the end of this step, when it is a CAV whose command went first.
    pub speed: Option<f64>,
}

/// CAV `i`'s maneuver `m` under check, with `sent[j]` what scene vehicle `j` was sent this same
/// step: the question both checks ([`clear_of_leaders`], [`clear_of_new_follower`]) answer.
#[derive(Debug, Clone, Copy)]
pub struct Candidate<'a> {
    /// The scene the maneuver is checked in.
    pub scene: &'a Scene,
    /// Scene index of the CAV under check.
    pub i: usize,
    /// The maneuver under check.
    pub m: &'a Maneuver,
    /// The worst cases checked against.
    pub b: &'a WorstCase,
    /// Per scene vehicle, what the shield let through for it this step so far.
    pub sent: &'a [Sent],
}

impl<'a> Candidate<'a> {
    /// The CAV under check.
    fn me(&self) -> &'a VehicleState {
        &self.scene.vehicles[self.i]
    }

    /// The lane the maneuver changes into, if it starts a change.
    fn target(&self) -> Option<i32> {
        self.m.lane_change.map(|lc| self.me().lane + lc.offset())
    }

    /// The lanes scene vehicle `j` enters by a lane change sent this step.
    fn entered(&self, j: usize) -> u64 {
        self.sent.get(j).map_or(0, |s| s.entering)
    }

    /// The speed scene vehicle `j` was sent for the end of this step, if any.
    fn sent_speed(&self, j: usize) -> Option<f64> {
        self.sent.get(j).and_then(|s| s.speed)
    }

    /// Every other vehicle of the scene, with its index.
    fn others(&self) -> impl Iterator<Item = (usize, &'a VehicleState)> + '_ {
        let i = self.i;
        self.scene
            .vehicles
            .iter()
            .enumerate()
            .filter(move |&(j, _)| j != i)
    }
}

/// Whether the CAV executing its maneuver stays clear of every vehicle ahead of it in a lane it
/// occupies (vehicles on the acceleration lane stop dead at its end), and of that lane's end
/// when it occupies that lane alone.
pub fn clear_of_leaders(c: &Candidate) -> bool {
    let (scene, me, m, b) = (c.scene, c.me(), c.m, c.b);
    let lanes = lanes_of_cav(me, m);
    let horizon = b.dt + m.speed / b.cav_decel;
    let motion = cav_motion(me, m, b);
    let (road, target) = (&scene.road, c.target());
    let lanes_of = |j: usize, o: &VehicleState| {
        let merges_into = |t: i32| on_acceleration_lane(road, o) && road.toward_main(o.lane) == t;
        let merging = match target {
            Some(t) if merges_into(t) => bit(t),
            Some(t) if b.far_side.may_enter(road, (me, m.speed), t, o) => bit(t),
            _ => 0,
        };
        let lanes = lanes_of_other(scene, o, horizon, b) | c.entered(j) | merging;
        if cannot_cut_in(road, me, o, b) {
            lanes & !bit(road.toward_main(o.lane))
        } else {
            lanes
        }
    };
    clear_of_lane_end(scene, me, m, b)
        && c.others().filter(|&(_, o)| o.s > me.s).all(|(j, o)| {
            // In a lane of the CAV's, braking as hard as it can; cutting in, as SUMO expects.
            let decel = if lanes_of(j, o) & lanes != 0 {
                b.emergency_decel(o.kind)
            } else if may_cut_in(road, (me, m.speed), lanes, o, b)
                || may_take_gap(road, (me, m.speed), lanes, o, b)
            {
                b.cut_in.brake_decel
            } else {
                return true;
            };
            let worst = Braking {
                speed: o.speed,
                first: None,
                decel,
                reach: reach(scene, o),
            };
            let yields = yields_to(road, me, target, o);
            let margin = b.margin + if yields { b.yield_gap } else { 0.0 };
            stays_clear(motion, worst, o.rear() - me.front(), margin, b.dt)
        })
}

/// Whether HDV `o`, ahead on a main lane beside one of the CAV's `lanes` (`me` about to drive its
/// next step at `speed`), may change into that lane in front of it: at the step's end, when
/// SUMO decides lane changes, the gap is one SUMO's lane-change model may accept (see
/// [`CutIn`]; the HDV's speed as high as a step's acceleration takes it, which widens the gap
/// and shrinks the secure gap). HDVs on the acceleration lane are [`may_merge`]'s and
/// [`may_take_gap`]'s; one changing
/// lanes already occupies both (`lanes_now`). With `lcAssertive = 1` (every built-in profile
/// but `paper`) no cut-in SUMO allows is one a CAV cannot stop for, so this costs nothing there.
/// With `paper`'s 3 it is a third of that: at 75.8 s (seed 7192, α 0.4, λ 3000) main.44 pulled
/// out of the standing lane-1 queue 49.9 m in front of a CAV at 26.3 m/s in lane 2, which needs
/// 55 m to stop at 6 m/s², and was hit at 79.0 s; the shield, assuming HDVs keep their lane, had
/// let the CAV close in at 27 m/s. It now slows such a CAV, to 10 m/s past a standing car.
fn may_cut_in(
    road: &Road,
    (me, speed): (&VehicleState, f64),
    lanes: u64,
    o: &VehicleState,
    b: &WorstCase,
) -> bool {
    let beside = |d: i32| !road.is_auxiliary(o.lane + d) && lanes & bit(o.lane + d) != 0;
    if o.kind != Kind::Hdv || o.on_ramp || road.is_auxiliary(o.lane) || o.changing_lanes() {
        return false;
    }
    let changer_speed = o.speed + b.hdv_accel * b.dt;
    let gap = gap_after_step(me, speed, o, changer_speed, b);
    (beside(1) || beside(-1)) && b.cut_in.allows(gap, speed, changer_speed, b.dt)
}

/// The bumper gap from CAV `me` (driving its next step at `speed`) to `o` ahead at the step's
/// end, `o` driving the step at `o_speed`.
fn gap_after_step(
    me: &VehicleState,
    speed: f64,
    o: &VehicleState,
    o_speed: f64,
    b: &WorstCase,
) -> f64 {
    o.rear() + o_speed * b.dt - (me.front() + speed * b.dt)
}

/// Whether ramp HDV `o`, on the acceleration lane ahead of a CAV that occupies main lane 1
/// (`me`, about to drive its next step at `speed`), may move over in front of it under a
/// gap-acceptance profile: such a driver merges, without SUMO's safety check, wherever its new
/// follower is a critical time gap behind it (`episode::merge_rule::accepts`), and that gap is
/// drawn per driver from a log-normal with no lower bound, so any gap is one some driver takes
/// (the gap ahead of the CAV now, or at the step's end with the HDV as fast as a step's
/// acceleration takes it). Nothing alongside is accepted. Once over it brakes as hard as SUMO
/// expects (`cut_in.brake_decel`): the rule only accepts a gap with room to brake comfortably
/// behind its new leader. (`paper`, α 0.4, λ 3000, seed 40017: ramp.28, slowing to 1.7 m/s
/// 27 m before the lane end, moved over 6.1 m in front of a CAV at 12.6 m/s, a time gap of
/// 0.48 s, which no braking could then stop.) Under SUMO's own merging the safety check keeps
/// such gaps shut, and [`may_merge`] covers the merges it forces.
fn may_take_gap(
    road: &Road,
    (me, speed): (&VehicleState, f64),
    lanes: u64,
    o: &VehicleState,
    b: &WorstCase,
) -> bool {
    if !b.gap_accepting_mergers || !on_acceleration_lane(road, o) {
        return false;
    }
    if lanes & bit(road.toward_main(o.lane)) == 0 {
        return false;
    }
    let fastest = o.speed + b.hdv_accel * b.dt;
    o.rear() - me.front() >= 0.0 || gap_after_step(me, speed, o, fastest, b) >= 0.0
}

/// Whether CAV `me`, in main lane 1, must leave ramp HDV `o` (on the acceleration lane, not
/// yet moving over) room to merge in front of it: SUMO lets a merger in, even forced at the
/// lane end, only with the new follower's minGap free behind it. A CAV that stopped
/// `margin` behind a ramp HDV standing at the lane end held both for good (the right lane stood
/// for the last 120 s of a 300 s run: `paper` drivers, α 0.4, λ 3000). A CAV changing into lane
/// 1 (`target`) behind it owes it the same: ramp CAVs queued behind a standing ramp HDV that
/// took the room beside it one after another kept it standing for 17 s.
fn yields_to(road: &Road, me: &VehicleState, target: Option<i32>, o: &VehicleState) -> bool {
    let into = road.toward_main(o.lane);
    let in_lane_1 = me.lane == into || target == Some(into);
    in_lane_1 && on_acceleration_lane(road, o) && o.other_lane().is_none()
}

/// Whether ramp HDV `o`, on the acceleration lane and not yet moving over, cannot merge in
/// front of CAV `me` in lane 1: SUMO refuses a merge, even a forced one, that leaves the new
/// follower less than its minGap (`yield_gap`), so a CAV that close behind it, or alongside,
/// may drive on past it. Held to the worst case instead, a CAV that came to a stand 4.6 m
/// behind a ramp HDV standing at the lane end could never move again, and neither could the
/// HDV (`paper` drivers, α 0.4, λ 3000).
fn cannot_cut_in(road: &Road, me: &VehicleState, o: &VehicleState, b: &WorstCase) -> bool {
    let beside = me.lane == road.toward_main(o.lane);
    beside && yields_to(road, me, None, o) && o.rear() - me.front() < b.yield_gap
}

/// Whether a lane change the maneuver starts leaves the nearest vehicle behind the CAV in the
/// target lane able to stay clear braking at `follower_decel` (true when it starts none).
pub fn clear_of_new_follower(c: &Candidate) -> bool {
    let Some(target) = c.target() else {
        return true;
    };
    let (me, b) = (c.me(), c.b);
    let follower = c
        .others()
        .filter(|&(j, o)| {
            let beyond = b
                .far_side
                .may_enter(&c.scene.road, (me, c.m.speed), target, o);
            let lanes = lanes_now(&c.scene.road, o) | c.entered(j);
            o.s <= me.s && (lanes & bit(target) != 0 || beyond)
        })
        .max_by(|(_, a), (_, c)| a.s.total_cmp(&c.s));
    follower.is_none_or(|(j, f)| {
        // A CAV whose command went first this step drives it before it can brake.
        let back = Braking {
            speed: f.speed,
            first: c.sent_speed(j),
            decel: b.follower_decel,
            reach: f64::INFINITY,
        };
        stays_clear(
            back,
            cav_motion(me, c.m, b),
            me.rear() - f.front(),
            b.margin,
            b.dt,
        )
    })
}

/// Whether CAV `i` may execute `m` under the shield's worst cases, `sent[j]` being what scene
/// vehicle `j` was sent this same step (two CAVs may not change into the same lane at once, as
/// bk-mastar's, planned apart, once did; a CAV sent faster this step cannot brake for a change
/// into its lane before the step's end).
pub fn is_safe(scene: &Scene, i: usize, m: &Maneuver, b: &WorstCase, sent: &[Sent]) -> bool {
    let c = Candidate {
        scene,
        i,
        m,
        b,
        sent,
    };
    clear_of_leaders(&c) && clear_of_new_follower(&c)
}

/// The least intrusive safe replacement of CAV `i`'s maneuver `m`, or `None` when `m` is safe
/// (or when even the replacement would be `m` itself). Keeps the lane (cancels a lane-change
/// start; a change under way continues, as SUMO is already moving the car) at the highest safe
/// speed in [strongest braking, planned speed], else brakes as hard as the CAV can.
pub fn replacement(
    scene: &Scene,
    i: usize,
    m: &Maneuver,
    b: &WorstCase,
    sent: &[Sent],
) -> Option<Maneuver> {
    if is_safe(scene, i, m, b, sent) {
        return None;
    }
    let keep = |speed| Maneuver {
        speed,
        lane_change: None,
    };
    let safe = |speed| {
        clear_of_leaders(&Candidate {
            scene,
            i,
            m: &keep(speed),
            b,
            sent,
        })
    };
    let v = &scene.vehicles[i];
    let strongest = (v.speed - b.cav_decel * b.dt).max(0.0).min(m.speed);
    let speed = if m.lane_change.is_some() && safe(m.speed) {
        m.speed
    } else if !safe(strongest) {
        strongest
    } else {
        // Safety only improves as the first step gets slower: bisect the highest safe speed.
        let (mut lo, mut hi) = (strongest, m.speed);
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            if safe(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    };
    let out = keep(speed);
    (out != *m).then_some(out)
}
