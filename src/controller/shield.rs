//! The safety shield (the paper's "safety envelope"): a last check of every CAV's next step
//! against bounded worst-case behaviour of the others, in the spirit of responsibility-sensitive
//! safety, before a search-based planner's maneuvers go to SUMO.
//!
//! Worst cases: every other vehicle may brake at its emergency deceleration (HDVs
//! `idm.max_decel`, SUMO's emergencyDecel; CAVs `planner.emergency_decel`) and keeps its lane; a
//! lane change under way completes, so a vehicle off its lane centre occupies both lanes; a ramp
//! HDV on the acceleration lane may merge into main lane 1 at any time. A CAV's maneuver is safe
//! when, executed for one step and followed by braking at `planner.emergency_decel`, the CAV never
//! comes closer than the margin to any vehicle ahead of it (by centre) in any lane it occupies,
//! and, if it starts a lane change, the follower in the target lane stays clear of it braking at
//! its comfortable deceleration `idm.decel`. Motion is stepped as SUMO steps it (Euler: a step's
//! end speed times `dt`), and gaps are checked at step ends, where SUMO checks collisions.
//!
//! An unsafe maneuver is replaced by the least intrusive safe one: keep the lane (a lane-change
//! start is cancelled; one under way is left to finish), at the highest safe speed between the
//! strongest braking and the planned speed, else the strongest braking.

use super::{CavBelief, CavHandling, Command, Controller, LaneChange, Maneuver, PlanStats, Source};
use crate::config::Config;
use crate::model::road::{FIRST_MAIN_LANE, FORCED_MERGE_ZONE, MERGE_LANE};
use crate::model::scene::{Kind, Origin, Scene, VehicleState};
use crate::planner::guard::StartGuard;

/// Lateral offset (m) from the lane centre beyond which a vehicle counts as changing lanes.
pub const CHANGING_LATERAL: f64 = 0.1;

/// The worst-case bounds the shield assumes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
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
}

impl Bounds {
    /// The bounds of `config`; the margin is the planner's longitudinal box inflation
    /// (`planner.margin_long`), which absorbs the difference between modelled and executed motion.
    pub fn from_config(config: &Config) -> Self {
        Bounds {
            dt: config.scenario.dt,
            cav_decel: config.planner.emergency_decel,
            hdv_decel: config.idm.max_decel,
            hdv_accel: config.idm.accel,
            follower_decel: config.idm.decel,
            margin: config.planner.margin_long,
        }
    }

    fn emergency_decel(&self, kind: Kind) -> f64 {
        match kind {
            Kind::Cav => self.cav_decel,
            Kind::Hdv => self.hdv_decel,
        }
    }
}

/// Lane bit of a lane set (lanes outside 0..64 are no lane of this road).
fn bit(lane: i32) -> u64 {
    if (0..64).contains(&lane) {
        1 << lane
    } else {
        0
    }
}

/// The lane a vehicle off its lane centre is moving to or from (either way it occupies both).
fn changing_toward(v: &VehicleState) -> Option<i32> {
    (v.lateral.abs() > CHANGING_LATERAL).then(|| v.lane + v.lateral.signum() as i32)
}

/// Lanes vehicle `v` occupies: its own, and the other one of a lane change under way.
fn lanes_now(v: &VehicleState) -> u64 {
    bit(v.lane) | changing_toward(v).map_or(0, bit)
}

/// A ramp HDV on the acceleration lane: it may start its merge at any moment (SUMO's lane-change
/// model decides when). A CAV changing into lane 1 beside it must let it (a CAV in lane 2 and a
/// ramp HDV 16 m ahead of it once moved into lane 1 in the same step: each saw the lane free);
/// a CAV already driving in lane 1 is not asked to, see [`may_merge`].
fn on_acceleration_lane(v: &VehicleState) -> bool {
    v.kind == Kind::Hdv && v.origin == Origin::Ramp && v.lane == MERGE_LANE && !v.on_ramp
}

/// A ramp HDV whose merge will happen whatever the CAVs do: on the acceleration lane within
/// [`FORCED_MERGE_ZONE`] of its end, or able to come to a stand there within `horizon` seconds
/// (accelerating at `b.hdv_accel`, then braking at `b.hdv_decel`), where the merge rule forces
/// it in once it stands. A creeping HDV a metre short of the zone is one such. Merges already
/// under way count through the lateral offset ([`changing_toward`]). Other ramp HDVs are not
/// assumed to merge at any moment: that assumption cost a fifth of the throughput and no
/// collision it prevented was seen.
pub fn may_merge(scene: &Scene, v: &VehicleState, horizon: f64, b: &Bounds) -> bool {
    let zone = scene.road.zone_ahead(v.front()).end - FORCED_MERGE_ZONE;
    let can_stand_in_zone = || {
        farthest_stand(v.speed, horizon, b.hdv_accel, b.hdv_decel)
            .is_some_and(|reach| v.front() + reach >= zone)
    };
    on_acceleration_lane(v) && (v.front() + v.speed * horizon >= zone || can_stand_in_zone())
}

/// How far ahead a vehicle at `speed` can be standing within `horizon` seconds, accelerating
/// at `accel` and then braking at `decel` (none if it cannot stop within the horizon).
fn farthest_stand(speed: f64, horizon: f64, accel: f64, decel: f64) -> Option<f64> {
    if speed > decel * horizon {
        return None;
    }
    let t_accel = (horizon * decel - speed) / (accel + decel);
    let peak = speed + accel * t_accel;
    Some(0.5 * (speed + peak) * t_accel + peak * peak / (2.0 * decel))
}

/// Lanes another vehicle may occupy within `horizon` seconds under the worst cases.
fn lanes_of_other(scene: &Scene, v: &VehicleState, horizon: f64, b: &Bounds) -> u64 {
    let merge = if may_merge(scene, v, horizon, b) {
        bit(FIRST_MAIN_LANE)
    } else {
        0
    };
    lanes_now(v) | merge
}

/// Lanes the CAV occupies while executing `m`: its lanes now and the target of a change it starts.
fn lanes_of_cav(v: &VehicleState, m: &Maneuver) -> u64 {
    lanes_now(v) | m.lane_change.map_or(0, |lc| bit(v.lane + lc.offset()))
}

/// One vehicle's worst-case longitudinal motion: `first` as the speed at the end of the first
/// step (none: braking from the start), then braking at `decel` to a stop, or stopped dead after
/// `reach` metres (the end of the acceleration lane, where SUMO halts a vehicle on the spot).
#[derive(Debug, Clone, Copy)]
struct Motion {
    speed: f64,
    first: Option<f64>,
    decel: f64,
    reach: f64,
}

impl Motion {
    fn speed_after(&self, step: usize, previous: f64, dt: f64) -> f64 {
        match (step, self.first) {
            (1, Some(v)) => v,
            _ => (previous - self.decel * dt).max(0.0),
        }
    }
}

/// Whether `back`, `gap` metres (bumper to bumper) behind `front`, stays at least `margin` behind
/// it at every step end until it stands, both moving as SUMO steps them.
fn stays_clear(back: Motion, front: Motion, gap: f64, b: &Bounds) -> bool {
    let (mut vb, mut vf, mut gap, mut moved) = (back.speed, front.speed, gap, 0.0);
    for step in 1..=10_000 {
        vb = back.speed_after(step, vb, b.dt);
        vf = front.speed_after(step, vf, b.dt);
        let advance = (vf * b.dt).min(front.reach - moved).max(0.0);
        moved += advance;
        gap += advance - vb * b.dt;
        if gap < b.margin {
            return false;
        }
        if vb <= 0.0 {
            // The one behind stands; the one in front never moves backwards.
            return true;
        }
    }
    true
}

/// The CAV's own worst case after `m`: `m.speed` for one step, then its emergency braking.
fn cav_motion(v: &VehicleState, m: &Maneuver, b: &Bounds) -> Motion {
    Motion {
        speed: v.speed,
        first: Some(m.speed),
        decel: b.cav_decel,
        reach: f64::INFINITY,
    }
}

/// How far `v` can drive before its lane ends: to the end of the acceleration lane for a vehicle
/// on it, else without limit.
fn reach(scene: &Scene, v: &VehicleState) -> f64 {
    if v.lane == MERGE_LANE {
        (scene.road.zone_ahead(v.front()).end - v.front()).max(0.0)
    } else {
        f64::INFINITY
    }
}

/// The end of the acceleration lane, as a standing vehicle in front of a CAV that occupies that
/// lane alone: the CAV must be able to stop before it.
fn clear_of_lane_end(scene: &Scene, v: &VehicleState, m: &Maneuver, b: &Bounds) -> bool {
    if lanes_of_cav(v, m) != bit(MERGE_LANE) {
        return true;
    }
    let wall = Motion {
        speed: 0.0,
        first: None,
        decel: b.cav_decel,
        reach: 0.0,
    };
    stays_clear(
        cav_motion(v, m, b),
        wall,
        scene.road.zone_ahead(v.front()).end - v.front(),
        b,
    )
}

/// Whether CAV `i` executing `m` stays clear of every vehicle ahead of it in a lane it occupies
/// (vehicles on the acceleration lane stop dead at its end), and of that lane's end when it
/// occupies that lane alone.
pub fn clear_of_leaders(
    scene: &Scene,
    i: usize,
    m: &Maneuver,
    b: &Bounds,
    entering: &[u64],
) -> bool {
    let me = &scene.vehicles[i];
    let lanes = lanes_of_cav(me, m);
    let horizon = b.dt + m.speed / b.cav_decel;
    let motion = cav_motion(me, m, b);
    let target = m.lane_change.map(|lc| me.lane + lc.offset());
    let into_lane_1 = target == Some(FIRST_MAIN_LANE);
    let lanes_of = |j: usize, o: &VehicleState| {
        let entered = entering.get(j).copied().unwrap_or(0);
        let merging = match target {
            Some(t) if into_lane_1 && on_acceleration_lane(o) => bit(t),
            Some(t) if may_enter_from_beyond(me, t, o) => bit(t),
            _ => 0,
        };
        lanes_of_other(scene, o, horizon, b) | entered | merging
    };
    clear_of_lane_end(scene, me, m, b)
        && scene
            .vehicles
            .iter()
            .enumerate()
            .filter(|&(j, o)| j != i && o.s > me.s && lanes_of(j, o) & lanes != 0)
            .all(|(_, o)| {
                let worst = Motion {
                    speed: o.speed,
                    first: None,
                    decel: b.emergency_decel(o.kind),
                    reach: reach(scene, o),
                };
                stays_clear(motion, worst, o.rear() - me.front(), b)
            })
}

/// Whether HDV `o` drives on the main-road lane beyond `target`, seen from CAV `me`'s lane, on a
/// road of three or more main lanes: it may change into `target`, a middle lane, in the same
/// second as the CAV (SUMO's LC2013 keeps right and overtakes on the left), and both would be
/// in it at once. (A CAV in lane 3 changing right beside an HDV in lane 1 that was moving back
/// left hit it on the corridor.) Never true on two main lanes: the lane beyond is then the
/// acceleration lane, whose ramp HDVs [`on_acceleration_lane`] covers.
fn may_enter_from_beyond(me: &VehicleState, target: i32, o: &VehicleState) -> bool {
    let beyond = 2 * target - me.lane;
    o.kind == Kind::Hdv
        && !o.on_ramp
        && me.lane >= FIRST_MAIN_LANE
        && beyond >= FIRST_MAIN_LANE
        && o.lane == beyond
}

/// Whether a lane change `m` starts leaves the nearest vehicle behind CAV `i` in the target lane
/// able to stay clear braking at `follower_decel` (true when `m` starts none).
pub fn clear_of_new_follower(
    scene: &Scene,
    i: usize,
    m: &Maneuver,
    b: &Bounds,
    entering: &[u64],
) -> bool {
    let Some(lc) = m.lane_change else {
        return true;
    };
    let me = &scene.vehicles[i];
    let target = bit(me.lane + lc.offset());
    let follower = scene
        .vehicles
        .iter()
        .enumerate()
        .filter(|&(j, o)| {
            let entered = entering.get(j).copied().unwrap_or(0);
            let beyond = may_enter_from_beyond(me, me.lane + lc.offset(), o);
            j != i && o.s <= me.s && ((lanes_now(o) | entered) & target != 0 || beyond)
        })
        .map(|(_, o)| o)
        .max_by(|a, c| a.s.total_cmp(&c.s));
    follower.map_or(true, |f| {
        let back = Motion {
            speed: f.speed,
            first: None,
            decel: b.follower_decel,
            reach: f64::INFINITY,
        };
        stays_clear(back, cav_motion(me, m, b), me.rear() - f.front(), b)
    })
}

/// Whether CAV `i` may execute `m` under the shield's worst cases, `entering[j]` being the lanes
/// scene vehicle `j` enters by a lane change sent this same step (CAVs the shield already let
/// start one: two CAVs may not change into the same lane at once, as bk-mastar's, planned
/// apart, once did).
pub fn is_safe(scene: &Scene, i: usize, m: &Maneuver, b: &Bounds, entering: &[u64]) -> bool {
    clear_of_leaders(scene, i, m, b, entering) && clear_of_new_follower(scene, i, m, b, entering)
}

/// The least intrusive safe replacement of CAV `i`'s maneuver `m`, or `None` when `m` is safe
/// (or when even the replacement would be `m` itself). Keeps the lane (cancels a lane-change
/// start; a change under way continues, as SUMO is already moving the car) at the highest safe
/// speed in [strongest braking, planned speed], else brakes as hard as the CAV can.
pub fn replacement(
    scene: &Scene,
    i: usize,
    m: &Maneuver,
    b: &Bounds,
    entering: &[u64],
) -> Option<Maneuver> {
    if is_safe(scene, i, m, b, entering) {
        return None;
    }
    let keep = |speed| Maneuver {
        speed,
        lane_change: None,
    };
    let safe = |speed| clear_of_leaders(scene, i, &keep(speed), b, entering);
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

/// The shield as the search's [`StartGuard`]: a lane change may be planned only if the shield
/// would let it start, so no plan (which other CAVs are planned against) counts on a start the
/// shield would then withdraw.
impl StartGuard for Bounds {
    fn admits(&self, scene: &Scene, agent: usize, lane_offset: i32, first_speed: f64) -> bool {
        let lane_change = match lane_offset {
            1 => LaneChange::Left,
            -1 => LaneChange::Right,
            _ => return true,
        };
        let m = Maneuver {
            speed: first_speed,
            lane_change: Some(lane_change),
        };
        is_safe(scene, agent, &m, self, &[])
    }
}

/// The shield's bounds as the lane-change guard of the search, when `config` turns it on.
pub fn start_guard(config: &Config) -> Option<Bounds> {
    config.safety.shield.then(|| Bounds::from_config(config))
}

/// Any controller with the shield between it and SUMO: its commands checked and, when unsafe,
/// replaced (marked [`Source::Shield`], counted in [`PlanStats::shield_overrides`]).
pub struct Shielded {
    inner: Box<dyn Controller>,
    bounds: Bounds,
    overrides: u64,
    /// Wall time of the last step's checks (ms).
    last_ms: f64,
}

impl Shielded {
    /// `inner` behind the shield of `config`'s bounds.
    pub fn new(inner: Box<dyn Controller>, config: &Config) -> Self {
        Shielded {
            inner,
            bounds: Bounds::from_config(config),
            overrides: 0,
            last_ms: 0.0,
        }
    }
}

impl Controller for Shielded {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn handling(&self) -> CavHandling {
        self.inner.handling()
    }

    fn plan(&mut self, scene: &Scene, out: &mut Vec<Command>) {
        let start = out.len();
        self.inner.plan(scene, out);
        let started = std::time::Instant::now();
        self.overrides = 0;
        // Lanes entered by the lane changes let through so far this step, per scene vehicle.
        let mut entering = vec![0u64; scene.vehicles.len()];
        for c in &mut out[start..] {
            if let Some(m) = replacement(scene, c.vehicle, &c.maneuver, &self.bounds, &entering) {
                if c.maneuver.lane_change.is_some() && m.lane_change.is_none() {
                    self.inner
                        .lane_change_cancelled(&scene.vehicles[c.vehicle].id);
                }
                c.maneuver = m;
                c.source = Source::Shield;
                self.overrides += 1;
            }
            if let Some(lc) = c.maneuver.lane_change {
                entering[c.vehicle] |= bit(scene.vehicles[c.vehicle].lane + lc.offset());
            }
        }
        self.last_ms = started.elapsed().as_secs_f64() * 1e3;
    }

    fn last_shield_ms(&self) -> f64 {
        self.last_ms
    }

    fn last_stats(&self) -> PlanStats {
        PlanStats {
            shield_overrides: self.overrides,
            ..self.inner.last_stats()
        }
    }

    fn set_tracing(&mut self, on: bool) {
        self.inner.set_tracing(on);
    }

    fn beliefs(&self) -> Vec<CavBelief> {
        self.inner.beliefs()
    }

    fn lane_change_cancelled(&mut self, id: &str) {
        self.inner.lane_change_cancelled(id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::road::Road;
    use crate::model::scene::{Kind, Origin, VehicleState};

    fn cav(s: f64, lane: i32, speed: f64) -> VehicleState {
        VehicleState::on_lane("cav", Kind::Cav, Origin::Main, s, lane, speed)
    }

    fn hdv(id: &str, s: f64, lane: i32, speed: f64) -> VehicleState {
        VehicleState::on_lane(id, Kind::Hdv, Origin::Main, s, lane, speed)
    }

    fn bounds() -> Bounds {
        Bounds::from_config(&Config::default())
    }

    fn go(speed: f64, lane_change: Option<LaneChange>) -> Maneuver {
        Maneuver { speed, lane_change }
    }

    /// Three main lanes: a CAV in lane 3 may not change into the middle lane beside an HDV in
    /// lane 1, which may move into it in the same second; with the HDV far ahead it may. On two
    /// lanes nothing lies beyond: the rule never fires there.
    #[test]
    fn a_middle_lane_is_not_entered_beside_an_hdv_on_its_other_side() {
        let b = bounds();
        let mut road = Road::paper_default();
        road.main_lanes = 3;
        let scene = |hdv_s: f64, hdv_v: f64| Scene {
            time: 0.0,
            road: road.clone(),
            vehicles: vec![cav(2721.2, 3, 27.3), hdv("h", hdv_s, 1, hdv_v)],
        };
        let right = go(27.3, Some(LaneChange::Right));
        assert!(!is_safe(&scene(2726.1, 23.4), 0, &right, &b, &[]));
        assert!(is_safe(&scene(2726.1, 23.4), 0, &go(27.3, None), &b, &[]));
        assert!(is_safe(&scene(2900.0, 23.4), 0, &right, &b, &[]));
        // Close behind the CAV and faster, the HDV in lane 1 counts as its new follower in
        // lane 2; slower, it can stay clear.
        assert!(!is_safe(&scene(2712.0, 34.0), 0, &right, &b, &[]));
        assert!(is_safe(&scene(2712.0, 23.4), 0, &right, &b, &[]));
        let me = cav(100.0, 2, 30.0);
        assert!(!may_enter_from_beyond(&me, 1, &hdv("h", 100.0, 0, 30.0)));
    }

    #[test]
    fn a_cav_closing_fast_on_a_standing_car_is_slowed() {
        let b = bounds();
        // 75 m to a standing car at 30 m/s: the planned +2 m/s² is unsafe, braking is not needed
        // in full.
        let scene = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 30.0), hdv("h", 180.0, 1, 0.0)]);
        let planned = go(30.4, None);
        assert!(!is_safe(&scene, 0, &planned, &b, &[]));
        let m = replacement(&scene, 0, &planned, &b, &[]).unwrap();
        let strongest = 30.0 - b.cav_decel * b.dt;
        assert!(m.speed > strongest && m.speed < 30.4, "{m:?}");
        assert!(is_safe(&scene, 0, &m, &b, &[]));
        assert!(!is_safe(&scene, 0, &go(m.speed + 0.01, None), &b, &[]));
        // 35 m: nothing is safe, so the CAV brakes as hard as it can.
        let scene = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 30.0), hdv("h", 140.0, 1, 0.0)]);
        let m = replacement(&scene, 0, &planned, &b, &[]).unwrap();
        assert!((m.speed - strongest).abs() < 1e-9, "{m:?}");
    }

    #[test]
    fn a_safe_cruise_is_left_alone() {
        let b = bounds();
        // 60 m behind an HDV at the same speed: it stops in 35 m braking at 9 m/s², the CAV in
        // 5 m + 52 m at 6 m/s².
        let scene = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 25.0), hdv("h", 165.0, 1, 25.0)]);
        assert!(is_safe(&scene, 0, &go(25.0, None), &b, &[]));
        assert_eq!(replacement(&scene, 0, &go(25.0, None), &b, &[]), None);
        // Vehicles behind, and ahead in a lane the CAV does not occupy, are not its business.
        let scene = Scene::on_paper_road(
            0.0,
            vec![
                cav(100.0, 1, 25.0),
                hdv("behind", 94.0, 1, 35.0),
                hdv("beside", 110.0, 2, 0.0),
            ],
        );
        assert_eq!(replacement(&scene, 0, &go(25.4, None), &b, &[]), None);
    }

    #[test]
    fn a_lane_change_start_into_a_gap_too_small_for_the_follower_is_cancelled() {
        let b = bounds();
        // The lane-2 follower (30 m/s, 5 m behind) could not stop braking at 5 m/s² if the CAV
        // (25 m/s) braked at 6 m/s² in front of it.
        let scene = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 25.0), hdv("f", 90.0, 2, 30.0)]);
        let planned = go(25.0, Some(LaneChange::Left));
        assert!(clear_of_leaders(&scene, 0, &planned, &b, &[]));
        assert!(!clear_of_new_follower(&scene, 0, &planned, &b, &[]));
        assert_eq!(
            replacement(&scene, 0, &planned, &b, &[]),
            Some(go(25.0, None))
        );
        // 60 m behind, the same follower can stop: the change goes ahead.
        let scene = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 25.0), hdv("f", 40.0, 2, 30.0)]);
        assert_eq!(replacement(&scene, 0, &planned, &b, &[]), None);
    }

    #[test]
    fn a_lane_change_under_way_is_never_cancelled_and_occupies_both_lanes() {
        let b = bounds();
        // Past the middle of a change from lane 1 to lane 2: assigned to lane 2, 1.5 m to its
        // right, so still in lane 1 too, where a car stands 30 m ahead.
        let mut me = cav(100.0, 2, 25.0);
        me.lateral = -1.5;
        let scene = Scene::on_paper_road(0.0, vec![me.clone(), hdv("h", 130.0, 1, 0.0)]);
        let planned = go(25.0, None);
        let m = replacement(&scene, 0, &planned, &b, &[]).unwrap();
        assert_eq!(m.lane_change, None);
        assert!(m.speed < 25.0);
        // Back on its lane centre, the car in lane 1 no longer matters.
        me.lateral = 0.0;
        let scene = Scene::on_paper_road(0.0, vec![me, hdv("h", 130.0, 1, 0.0)]);
        assert_eq!(replacement(&scene, 0, &planned, &b, &[]), None);
        // An HDV changing lanes into the CAV's lane occupies it as well.
        let mut other = hdv("h", 130.0, 2, 0.0);
        other.lateral = -1.0;
        let scene = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 25.0), other]);
        assert!(replacement(&scene, 0, &planned, &b, &[]).is_some());
    }

    #[test]
    fn as_the_search_guard_it_refuses_the_starts_it_would_cancel() {
        let b = bounds();
        // The lane-2 follower (30 m/s, 5 m behind) could not stop behind the CAV: refused, as
        // the shield would cancel it; with that lane empty, admitted.
        let crowded = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 25.0), hdv("f", 90.0, 2, 30.0)]);
        assert!(!b.admits(&crowded, 0, 1, 25.0));
        assert!(replacement(&crowded, 0, &go(25.0, Some(LaneChange::Left)), &b, &[]).is_some());
        let empty = Scene::on_paper_road(0.0, vec![cav(100.0, 1, 25.0)]);
        assert!(b.admits(&empty, 0, 1, 25.0));
        assert!(replacement(&empty, 0, &go(25.0, Some(LaneChange::Left)), &b, &[]).is_none());
    }

    #[test]
    fn two_cavs_may_not_change_into_the_same_lane_at_once() {
        // A ramp CAV standing at the lane end slides into lane 1 while a CAV in lane 2, 55 m
        // behind at 28 m/s, changes into lane 1 too (bk-mastar, α 0.8, λ 3000, seed 209): each
        // start is safe alone; the second one sent must see the first.
        let b = bounds();
        let ramp = VehicleState::on_lane("r", Kind::Cav, Origin::Ramp, 327.0, 0, 0.0);
        let scene = Scene::on_paper_road(0.0, vec![cav(268.0, 2, 28.0), ramp]);
        let (main_in, ramp_in) = (
            go(28.0, Some(LaneChange::Right)),
            go(0.0, Some(LaneChange::Left)),
        );
        assert!(is_safe(&scene, 0, &main_in, &b, &[]));
        assert!(is_safe(&scene, 1, &ramp_in, &b, &[]));
        let mut entering = vec![0u64; 2];
        entering[1] = bit(1);
        assert!(!is_safe(&scene, 0, &main_in, &b, &entering));
        entering = vec![bit(1), 0];
        assert!(!is_safe(&scene, 1, &ramp_in, &b, &entering));
    }

    #[test]
    fn a_cav_changing_into_lane_1_lets_a_ramp_hdv_ahead_merge_first() {
        // bk-pbs, α 0.6, λ 3000, seed 17: a CAV in lane 2 at 35 m/s changed into lane 1 as a
        // ramp HDV 16 m ahead (22.9 m/s) started its merge into it.
        let b = bounds();
        let ramp = VehicleState::on_lane("r", Kind::Hdv, Origin::Ramp, 165.5, 0, 22.9);
        let scene = Scene::on_paper_road(0.0, vec![cav(149.4, 2, 35.0), ramp.clone()]);
        assert!(!is_safe(
            &scene,
            0,
            &go(34.75, Some(LaneChange::Right)),
            &b,
            &[]
        ));
        // Driving on in lane 2, or already in lane 1, it is not asked to expect that merge.
        assert!(is_safe(&scene, 0, &go(35.0, None), &b, &[]));
        let in_lane_1 = Scene::on_paper_road(0.0, vec![cav(149.4, 1, 35.0), ramp]);
        assert!(is_safe(&in_lane_1, 0, &go(35.0, None), &b, &[]));
        // With the acceleration lane empty the change is safe.
        let alone = Scene::on_paper_road(0.0, vec![cav(149.4, 2, 35.0)]);
        assert!(is_safe(
            &alone,
            0,
            &go(34.75, Some(LaneChange::Right)),
            &b,
            &[]
        ));
    }

    #[test]
    fn farthest_stand_hand_computed() {
        // From rest, 2 s, +3 then −9 m/s²: 1.5 s up to 4.5 m/s (3.375 m), 0.5 s down (1.125 m).
        assert!((farthest_stand(0.0, 2.0, 3.0, 9.0).unwrap() - 4.5).abs() < 1e-12);
        // 20 m/s cannot stop within a second at 9 m/s².
        assert_eq!(farthest_stand(20.0, 1.0, 3.0, 9.0), None);
    }

    #[test]
    fn a_ramp_hdv_beside_on_the_acceleration_lane_may_merge() {
        // Near the lane end, where the merge rule forces a stopped HDV in, it may merge at any
        // moment; earlier on the lane it is not assumed to.
        let b = bounds();
        let early = VehicleState::on_lane("r", Kind::Hdv, Origin::Ramp, 203.0, 0, 20.0);
        let scene = Scene::on_paper_road(0.0, vec![cav(200.0, 1, 25.0), early.clone()]);
        assert!(!may_merge(&scene, &early, 1.0, &b));
        let ramp = VehicleState::on_lane("r", Kind::Hdv, Origin::Ramp, 318.0, 0, 5.0);
        let planned = go(25.0, None);
        let scene = Scene::on_paper_road(0.0, vec![cav(312.0, 1, 25.0), ramp.clone()]);
        assert!(may_merge(&scene, &ramp, 1.0, &b));
        // Creeping a metre short of the zone, it can be standing in it within a second; ten
        // metres short, not.
        let zone = scene.road.zone_ahead(0.0).end - FORCED_MERGE_ZONE;
        let creeping = VehicleState::on_lane("r", Kind::Hdv, Origin::Ramp, zone - 3.5, 0, 0.1);
        assert!(may_merge(&scene, &creeping, 1.0, &b));
        let further = VehicleState::on_lane("r", Kind::Hdv, Origin::Ramp, zone - 12.5, 0, 0.1);
        assert!(!may_merge(&scene, &further, 1.0, &b));
        assert!(!is_safe(&scene, 0, &planned, &b, &[]));
        let m = replacement(&scene, 0, &planned, &b, &[]).unwrap();
        assert!(m.speed < 25.0);
        // In lane 2 the CAV is out of its reach; a main-road HDV on lane 0 would not merge.
        let scene = Scene::on_paper_road(0.0, vec![cav(312.0, 2, 25.0), ramp.clone()]);
        assert!(is_safe(&scene, 0, &planned, &b, &[]));
        let main = VehicleState::on_lane("m", Kind::Hdv, Origin::Main, 318.0, 0, 5.0);
        let scene = Scene::on_paper_road(0.0, vec![cav(312.0, 1, 25.0), main]);
        assert!(is_safe(&scene, 0, &planned, &b, &[]));
        // Still far up the ramp edge, it cannot reach the acceleration lane within the horizon.
        let mut far = ramp;
        far.s = 20.0;
        far.on_ramp = true;
        let scene = Scene::on_paper_road(0.0, vec![cav(18.0, 1, 25.0), far]);
        assert!(is_safe(&scene, 0, &planned, &b, &[]));
    }

    #[test]
    fn the_end_of_the_acceleration_lane_stops_everyone_on_it() {
        let b = bounds();
        let ramp_cav = |s, speed| VehicleState::on_lane("c", Kind::Cav, Origin::Ramp, s, 0, speed);
        // 47.5 m before the lane's end at 25 m/s: the CAV could not stop before it.
        let scene = Scene::on_paper_road(0.0, vec![ramp_cav(280.0, 25.0)]);
        assert!(!is_safe(&scene, 0, &go(25.0, None), &b, &[]));
        // Starting its merge it no longer occupies the acceleration lane alone.
        assert!(is_safe(
            &scene,
            0,
            &go(25.0, Some(LaneChange::Left)),
            &b,
            &[]
        ));
        let scene = Scene::on_paper_road(0.0, vec![ramp_cav(200.0, 25.0)]);
        assert!(is_safe(&scene, 0, &go(25.0, None), &b, &[]));
        // A vehicle ahead 5 m before the end halts there, not after braking at 6 m/s².
        let ahead = VehicleState::on_lane("a", Kind::Cav, Origin::Ramp, 322.5, 0, 25.0);
        let scene = Scene::on_paper_road(0.0, vec![cav(280.0, 1, 25.0), ahead.clone()]);
        let mut me = cav(280.0, 0, 25.0);
        me.lateral = 1.0;
        let changing = Scene::on_paper_road(0.0, vec![me, ahead]);
        assert!(is_safe(&scene, 0, &go(25.0, None), &b, &[]));
        assert!(!is_safe(&changing, 0, &go(25.0, None), &b, &[]));
    }

    /// Returns fixed commands and records the lane changes it is told were cancelled.
    struct Fixed {
        commands: Vec<Command>,
        cancelled: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
    }

    impl Controller for Fixed {
        fn name(&self) -> &'static str {
            "bk-pbs"
        }

        fn handling(&self) -> CavHandling {
            CavHandling::Commanded
        }

        fn plan(&mut self, _scene: &Scene, out: &mut Vec<Command>) {
            out.extend(self.commands.iter().copied());
        }

        fn last_stats(&self) -> PlanStats {
            PlanStats {
                searches: 7,
                ..PlanStats::default()
            }
        }

        fn lane_change_cancelled(&mut self, id: &str) {
            self.cancelled.borrow_mut().push(id.to_string());
        }
    }

    #[test]
    fn the_wrapper_replaces_marks_and_counts() {
        let mut fast = cav(100.0, 1, 30.0);
        fast.id = "fast".into();
        let mut merging = cav(300.0, 1, 25.0);
        merging.id = "merging".into();
        let mut free = cav(600.0, 1, 25.0);
        free.id = "free".into();
        let scene = Scene::on_paper_road(
            0.0,
            vec![
                fast,
                hdv("standing", 140.0, 1, 0.0),
                merging,
                hdv("f", 290.0, 2, 30.0),
                free,
            ],
        );
        let command = |vehicle, maneuver| Command {
            vehicle,
            maneuver,
            source: Source::PbsSolution,
        };
        let cancelled = std::rc::Rc::default();
        let inner = Fixed {
            commands: vec![
                command(0, go(30.4, None)),
                command(2, go(25.0, Some(LaneChange::Left))),
                command(4, go(25.4, None)),
            ],
            cancelled: std::rc::Rc::clone(&cancelled),
        };
        let mut shielded = Shielded::new(Box::new(inner), &Config::default());
        assert_eq!(shielded.name(), "bk-pbs");
        assert_eq!(shielded.handling(), CavHandling::Commanded);
        let mut out = Vec::new();
        shielded.plan(&scene, &mut out);
        let sources: Vec<Source> = out.iter().map(|c| c.source).collect();
        assert_eq!(
            sources,
            [Source::Shield, Source::Shield, Source::PbsSolution]
        );
        assert!(out[0].maneuver.speed < 30.0);
        assert_eq!(out[1].maneuver, go(25.0, None));
        assert_eq!(out[2].maneuver, go(25.4, None));
        assert_eq!(*cancelled.borrow(), ["merging"]);
        let stats = shielded.last_stats();
        assert_eq!((stats.shield_overrides, stats.searches), (2, 7));
        // Counts are per round, not cumulative.
        let mut out = Vec::new();
        shielded.plan(&scene, &mut out);
        assert_eq!(shielded.last_stats().shield_overrides, 2);
    }
}
