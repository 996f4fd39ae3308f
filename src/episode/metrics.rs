//! Episode metrics (paper eq. 1 and section VI): per-vehicle records, travel delay against the
//! free-flow time t*, the system delay of every demanded vehicle (arrived or not), collision
//! attribution, and the one-row episode summary.

use crate::controller::PlanStats;
use crate::episode::summary::{Summary, SystemDelay, TravelFigures};
use crate::model::kinematics::free_flow_time;
use crate::model::scene::{Kind, Origin};

/// How a vehicle's episode ended.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Outcome {
    /// Still in the network when the episode ended.
    #[default]
    Present,
    /// Left the section (at its end, or by an off-ramp) without a collision.
    Arrived,
    /// Removed in a collision.
    Crashed,
    /// Scheduled by the demand but never inserted: it waited at its entry to the end.
    NeverInserted,
}

impl Outcome {
    /// The outcome's name in `vehicles.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Present => "present",
            Outcome::Arrived => "arrived",
            Outcome::Crashed => "crashed",
            Outcome::NeverInserted => "never_inserted",
        }
    }
}

/// The free-flow model t* is computed with: accelerate at `accel` up to `v_max`, then cruise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeFlow {
    /// Acceleration (m/s², `scenario.free_flow_accel`).
    pub accel: f64,
    /// Speed cap (m/s, `scenario.v_max`).
    pub v_max: f64,
}

impl FreeFlow {
    /// Free-flow time (s) over `distance` from `v0`, capped at `v_max`.
    pub fn time(&self, distance: f64, v0: f64) -> f64 {
        free_flow_time(distance, v0, self.accel, self.v_max)
    }

    /// The same at the vehicle's own desired speed `desired` (at most `v_max`): the time it
    /// needs even on an empty road.
    pub fn time_at_own_speed(&self, distance: f64, v0: f64, desired: f64) -> f64 {
        free_flow_time(distance, v0, self.accel, desired.min(self.v_max))
    }
}

/// One vehicle of the episode, from its scheduled departure to arrival, crash or the end (a
/// vehicle never inserted has a record too: its delay is the whole wait).
#[derive(Debug, Clone, PartialEq)]
pub struct VehicleRecord {
    /// SUMO vehicle id.
    pub id: String,
    /// CAV or HDV.
    pub kind: Kind,
    /// SUMO's vehicle type (a heterogeneous profile's driver type, `hdv.7`); not in the CSV.
    pub sumo_type: String,
    /// Main road or on-ramp.
    pub origin: Origin,
    /// Departure time the demand scheduled (s).
    pub scheduled_depart: f64,
    /// Insertion speed the demand drew (m/s); t* starts from it.
    pub scheduled_speed: f64,
    /// Road-frame lane at insertion.
    pub insert_lane: i32,
    /// Time the vehicle was first seen in the network, at its insertion position (s).
    pub insert_time: f64,
    /// Speed SUMO inserted it with: the drawn one, or less when traffic ahead forbade it.
    pub insert_speed: f64,
    /// Desired speed the demand drew (m/s; v_max for a CAV).
    pub desired_speed: f64,
    /// Route distance from the insertion position to the end of the section (m); for a vehicle
    /// never inserted the distance of the vehicles inserted at its entry (NaN if none was).
    pub distance: f64,
    /// Free-flow travel time t* (s) over `distance`.
    pub t_star: f64,
    /// Distance covered from insertion to arrival or the episode's end (m; 0 never inserted).
    pub covered: f64,
    /// System delay (s): time from the scheduled departure to the arrival or the episode's end,
    /// less the free-flow time of `covered`; `None` for a crashed vehicle (see
    /// [`VehicleRecord::settle`]).
    pub system_delay: Option<f64>,
    /// The part of `system_delay` no controller can remove (s): the free-flow time of
    /// `covered` at the vehicle's own desired speed less that at v_max; `None` crashed.
    pub own_speed_delay: Option<f64>,
    /// How its episode ended.
    pub outcome: Outcome,
    /// Time the front bumper crossed the section end (s), interpolated within the last step.
    pub arrival_time: Option<f64>,
    /// Time of its first collision (s), if it crashed.
    pub crash_time: Option<f64>,
    /// The other vehicles of the collision(s) it was removed in.
    pub crashed_with: Vec<String>,
    /// Removed in a collision that involved at least one CAV.
    pub controllable_crash: bool,
}

impl VehicleRecord {
    /// Travel delay t_f − t* of a vehicle that arrived without collision, with t_f counted
    /// from its scheduled departure: time spent queueing at a congested entry is delay too.
    pub fn delay(&self) -> Option<f64> {
        self.arrival_time
            .map(|t| t - self.scheduled_depart - self.t_star)
    }

    /// Travel time t_f from the scheduled departure to the arrival (s): what the delay compares
    /// with t*.
    pub fn travel_time(&self) -> Option<f64> {
        self.arrival_time.map(|t| t - self.scheduled_depart)
    }

    /// Time from insertion into SUMO to the arrival (s): the travel time without the entry delay.
    pub fn time_in_network(&self) -> Option<f64> {
        self.arrival_time.map(|t| t - self.insert_time)
    }

    /// Time the vehicle waited at the entry for room (s).
    pub fn entry_delay(&self) -> f64 {
        (self.insert_time - self.scheduled_depart).max(0.0)
    }

    /// Whether SUMO inserted it (every outcome but [`Outcome::NeverInserted`]).
    pub fn inserted(&self) -> bool {
        self.outcome != Outcome::NeverInserted
    }

    /// Settles the system delay at the episode's end `end` (s): `covered` metres driven since
    /// insertion, t* starting from `v0` as for [`VehicleRecord::t_star`]. Counting to the end
    /// those that did not arrive is what keeps a jam visible: the arrived-only delay forgets
    /// the vehicles stuck in it. An arrived vehicle's system delay is its delay; a crashed one
    /// has none (as it has no delay).
    pub fn settle(&mut self, end: f64, covered: f64, v0: f64, ff: FreeFlow) {
        self.covered = covered;
        if self.outcome == Outcome::Crashed {
            (self.system_delay, self.own_speed_delay) = (None, None);
            return;
        }
        let at_v_max = match self.outcome {
            Outcome::Arrived => self.t_star,
            _ => ff.time(covered, v0),
        };
        let own = ff.time_at_own_speed(covered, v0, self.desired_speed);
        let until = self.arrival_time.unwrap_or(end);
        self.system_delay = Some(until - self.scheduled_depart - at_v_max);
        self.own_speed_delay = Some(own - at_v_max);
    }
}

/// The window in which arrivals were possible (s): from the earliest moment any vehicle could
/// have arrived (its scheduled departure plus its t*, the minimum over the records with a t*)
/// to the episode's end `end`; 0 if none could arrive before the end. Throughput per hour of
/// this window does not count the first seconds, when the road is still filling, as lost.
pub fn arrival_window(vehicles: &[VehicleRecord], end: f64) -> f64 {
    let earliest = vehicles
        .iter()
        .map(|r| r.scheduled_depart + r.t_star)
        .filter(|t| t.is_finite())
        .min_by(f64::total_cmp);
    earliest.map_or(0.0, |t| (end - t).max(0.0))
}

/// One collision as SUMO reported it.
#[derive(Debug, Clone, PartialEq)]
pub struct CollisionEvent {
    /// Simulation time SUMO reported it at (s).
    pub time: f64,
    /// SUMO id of the vehicle that collided (the follower, in a rear-end collision).
    pub collider: String,
    /// SUMO id of the vehicle it collided with.
    pub victim: String,
    /// Kind of the collider; `None` if it cannot be told.
    pub collider_kind: Option<Kind>,
    /// Kind of the victim; `None` if it cannot be told.
    pub victim_kind: Option<Kind>,
    /// SUMO lane id where it happened.
    pub lane: String,
    /// Position along that lane (m).
    pub position: f64,
}

impl CollisionEvent {
    /// Involves at least one CAV, so a controller could have avoided it.
    pub fn controllable(&self) -> bool {
        self.collider_kind == Some(Kind::Cav) || self.victim_kind == Some(Kind::Cav)
    }
}

/// Arithmetic mean, summed in order; `None` for no values. The one mean of the project: the
/// episode summary and the campaign report's tables both use it.
pub fn mean(xs: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (sum, n) = xs
        .into_iter()
        .fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// Everything the summary is computed from.
pub struct SummaryInput<'a> {
    /// The controller's name.
    pub planner: &'a str,
    /// CAV penetration α.
    pub alpha: f64,
    /// Total arrival rate λ (veh/h).
    pub lambda: f64,
    /// The episode's random seed.
    pub seed: u64,
    /// The HDV driver profile SUMO ran.
    pub hdv_profile: &'a str,
    /// The SUMO version that ran the episode.
    pub sumo_version: &'a str,
    /// Simulated steps.
    pub steps: u32,
    /// The episode's end: the time of its last state (s).
    pub end: f64,
    /// Vehicles the demand scheduled within the horizon.
    pub scheduled: usize,
    /// Every vehicle's record, settled ([`VehicleRecord::settle`]): the inserted and the
    /// never inserted.
    pub vehicles: &'a [VehicleRecord],
    /// Every collision SUMO reported.
    pub collisions: &'a [CollisionEvent],
    /// Sum of the speeds of every vehicle reading on the section (m/s).
    pub speed_sum: f64,
    /// Number of readings summed in `speed_sum`.
    pub speed_samples: u64,
    /// Vehicles standing on the acceleration lane at the end.
    pub stranded: usize,
    /// Planner effort over the episode.
    pub plan_stats: PlanStats,
}

/// The system delay of `v`, over every record with a system delay.
fn system_delay(v: &[VehicleRecord]) -> SystemDelay {
    let delays = || v.iter().filter_map(|r| r.system_delay);
    SystemDelay {
        system_delay_s: mean(delays()),
        system_delay_veh_h: delays().sum::<f64>() / 3600.0,
        own_speed_delay_s: mean(v.iter().filter_map(|r| r.own_speed_delay)),
    }
}

impl Summary {
    /// The summary of an episode's records.
    pub fn compute(inp: &SummaryInput) -> Summary {
        let v = inp.vehicles;
        let count = |f: &dyn Fn(&VehicleRecord) -> bool| v.iter().filter(|r| f(r)).count();
        let inserted = count(&|r| r.inserted());
        let crashed = count(&|r| r.outcome == Outcome::Crashed);
        let controllable_crashed =
            count(&|r| r.outcome == Outcome::Crashed && r.controllable_crash);
        let delays = |k: Option<Kind>| {
            mean(
                v.iter()
                    .filter(|r| k.is_none_or(|k| r.kind == k))
                    .filter_map(|r| r.delay()),
            )
        };
        let window = arrival_window(v, inp.end);
        let arrived = count(&|r| r.outcome == Outcome::Arrived);
        let system = system_delay(v);
        Summary {
            planner: inp.planner.to_string(),
            alpha: inp.alpha,
            lambda: Some(inp.lambda),
            seed: inp.seed,
            hdv_profile: Some(inp.hdv_profile.to_string()),
            sumo_version: inp.sumo_version.to_string(),
            steps: inp.steps,
            system: Some(system),
            scheduled: Some(inp.scheduled),
            inserted,
            never_inserted: count(&|r| !r.inserted()),
            inserted_cav: count(&|r| r.inserted() && r.kind == Kind::Cav),
            arrived,
            crashed,
            present: count(&|r| r.outcome == Outcome::Present),
            controllable_crashed,
            controllable_collision_rate: Some(ratio(controllable_crashed as f64, inserted as f64)),
            hdv_collisions: inp.collisions.iter().filter(|c| !c.controllable()).count(),
            travel: Some(TravelFigures {
                hdv_crashed: count(&|r| r.outcome == Outcome::Crashed && !r.controllable_crash),
                mean_delay_s: delays(None),
                mean_delay_cav_s: delays(Some(Kind::Cav)),
                mean_delay_hdv_s: delays(Some(Kind::Hdv)),
                throughput_veh_h: ratio(arrived as f64, window / 3600.0),
                throughput_window_s: window,
                mean_speed_mps: ratio(inp.speed_sum, inp.speed_samples as f64),
                stranded: inp.stranded,
            }),
            plan_stats: inp.plan_stats,
            ..Summary::default()
        }
    }
}

/// `x / y`, 0 for a `y` of 0 (no vehicle, no window, no reading).
fn ratio(x: f64, y: f64) -> f64 {
    if y > 0.0 {
        x / y
    } else {
        0.0
    }
}

/// Wall-clock figures of one episode: they differ from run to run, so they live apart.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    /// Planning time per step, median over the steps (ms).
    pub plan_ms_median: f64,
    /// Planning time per step, 99th percentile over the steps (ms).
    pub plan_ms_p99: f64,
    /// Planning time per step, maximum over the steps (ms).
    pub plan_ms_max: f64,
    /// Time inside the planner over the whole episode (ms).
    pub plan_ms_total: f64,
    /// Time inside SUMO's step per step (ms).
    pub sumo_ms_per_step: f64,
    /// Whole episode per step, SUMO start excluded (ms).
    pub episode_ms_per_step: f64,
    /// Whole episode including SUMO start and close (s).
    pub wall_s: f64,
    /// Time inside the safety shield per step, median (ms; part of the planning time, 0
    /// unshielded).
    pub shield_ms_median: f64,
    /// Time inside the safety shield per step, 99th percentile (ms).
    pub shield_ms_p99: f64,
    /// Time inside the safety shield per step, maximum (ms).
    pub shield_ms_max: f64,
}

/// Nearest-rank percentile of `samples` (sorted in place); 0 for none.
pub fn percentile(samples: &mut [f64], q: f64) -> f64 {
    if samples.is_empty() {
        return 0.0;
    }
    samples.sort_by(f64::total_cmp);
    let rank = ((q / 100.0) * samples.len() as f64).ceil() as usize;
    samples[rank.clamp(1, samples.len()) - 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    const FF: FreeFlow = FreeFlow {
        accel: 3.0,
        v_max: 35.0,
    };

    fn rec(
        kind: Kind,
        outcome: Outcome,
        controllable: bool,
        arrival: Option<f64>,
    ) -> VehicleRecord {
        VehicleRecord {
            id: "x".into(),
            kind,
            sumo_type: kind.as_str().into(),
            origin: Origin::Main,
            scheduled_depart: 1.0,
            scheduled_speed: 30.0,
            insert_lane: 1,
            insert_time: 1.0,
            insert_speed: 30.0,
            desired_speed: 30.0,
            distance: 455.0,
            t_star: 13.0,
            covered: 0.0,
            system_delay: None,
            own_speed_delay: None,
            outcome,
            arrival_time: arrival,
            crash_time: None,
            crashed_with: vec![],
            controllable_crash: controllable,
        }
    }

    fn input<'a>(vs: &'a [VehicleRecord], scheduled: usize) -> SummaryInput<'a> {
        SummaryInput {
            planner: "p",
            hdv_profile: "sumo-safe",
            sumo_version: "1.15.0",
            alpha: 0.5,
            lambda: 3000.0,
            seed: 1,
            steps: 400,
            end: 79.8,
            scheduled,
            vehicles: vs,
            collisions: &[],
            speed_sum: 10.0,
            speed_samples: 4,
            stranded: 0,
            plan_stats: PlanStats::default(),
        }
    }

    fn close_to(x: Option<f64>, want: f64) -> bool {
        x.is_some_and(|x| (x - want).abs() < 1e-6)
    }

    #[test]
    fn summary_counts_and_rates() {
        let mut never = rec(Kind::Cav, Outcome::NeverInserted, false, None);
        never.t_star = f64::NAN;
        let vs = vec![
            rec(Kind::Cav, Outcome::Arrived, false, Some(20.0)), // delay 20 − 1 − 13 = 6
            rec(Kind::Hdv, Outcome::Arrived, false, Some(18.0)), // delay 4
            rec(Kind::Cav, Outcome::Crashed, true, None),
            rec(Kind::Hdv, Outcome::Crashed, true, None),
            rec(Kind::Hdv, Outcome::Crashed, false, None),
            rec(Kind::Hdv, Outcome::Present, false, None),
            never.clone(),
            never,
        ];
        let s = Summary::compute(&input(&vs, 8));
        assert_eq!(
            (
                s.inserted,
                s.never_inserted,
                s.arrived,
                s.crashed,
                s.present
            ),
            (6, 2, 2, 3, 1)
        );
        assert_eq!(s.inserted_cav, 2);
        assert_eq!(s.controllable_crashed, 2);
        assert!((s.controllable_collision_rate.unwrap() - 2.0 / 6.0).abs() < 1e-12);
        assert_eq!(s.travel().mean_delay_s, Some(5.0));
        assert_eq!(s.travel().mean_delay_cav_s, Some(6.0));
        // Arrivals possible from 1 + 13 = 14 s (the NaN t* of a vehicle never inserted
        // ignored) to the end at 79.8 s: 65.8 s.
        assert!((s.travel().throughput_window_s - 65.8).abs() < 1e-9);
        assert!((s.travel().throughput_veh_h - 2.0 / (65.8 / 3600.0)).abs() < 1e-9);
        assert_eq!(s.travel().mean_speed_mps, 2.5);
    }

    #[test]
    fn system_delay_of_an_arrived_vehicle_is_its_delay() {
        // Drawn at 30 m/s, wants 30: t* at v_max = 5/3 s to reach 35 over (35² − 30²)/6 =
        // 54.1667 m, then 400.8333 m at 35 m/s: 1.666667 + 11.452381 = 13.119048 s. At its own
        // 30 m/s: 455 / 30 = 15.166667 s.
        let mut r = rec(Kind::Hdv, Outcome::Arrived, false, Some(20.0));
        r.t_star = FF.time(455.0, 30.0);
        assert!((r.t_star - 13.119_048).abs() < 1e-6, "{}", r.t_star);
        r.settle(79.8, 455.0, 30.0, FF);
        assert_eq!(r.system_delay, r.delay());
        assert!(close_to(r.system_delay, 20.0 - 1.0 - 13.119_048));
        assert!(close_to(r.own_speed_delay, 15.166_667 - 13.119_048));
        assert_eq!(r.covered, 455.0);
    }

    #[test]
    fn system_delay_of_a_present_vehicle_counts_to_the_end() {
        // Scheduled at 1 s, still driving at 79.8 s after 100 m from 35 m/s: free flow takes
        // 100 / 35 = 2.857143 s, so 78.8 − 2.857143 = 75.942857 s of delay. At its own 30 m/s
        // (it starts at 30): 100 / 30 = 3.333333 s, 0.476190 s of them unavoidable.
        let mut r = rec(Kind::Hdv, Outcome::Present, false, None);
        r.settle(79.8, 100.0, 35.0, FF);
        assert!(close_to(r.system_delay, 75.942_857), "{:?}", r.system_delay);
        assert!(
            close_to(r.own_speed_delay, 0.476_190),
            "{:?}",
            r.own_speed_delay
        );
        // A CAV wants v_max: nothing of its delay is its own.
        let mut c = rec(Kind::Cav, Outcome::Present, false, None);
        c.desired_speed = 35.0;
        c.settle(79.8, 100.0, 35.0, FF);
        assert_eq!(c.own_speed_delay, Some(0.0));
    }

    #[test]
    fn never_inserted_waits_to_the_end_and_crashed_have_none() {
        let mut n = rec(Kind::Cav, Outcome::NeverInserted, false, None);
        n.scheduled_depart = 70.0;
        n.settle(79.8, 0.0, 30.0, FF);
        assert!(close_to(n.system_delay, 9.8));
        assert_eq!(n.own_speed_delay, Some(0.0));
        let mut c = rec(Kind::Cav, Outcome::Crashed, true, None);
        c.settle(79.8, 50.0, 30.0, FF);
        assert_eq!((c.system_delay, c.own_speed_delay), (None, None));
    }

    #[test]
    fn summary_system_delay_mean_total_and_own_speed_part() {
        let mut vs = vec![
            rec(Kind::Cav, Outcome::Arrived, false, Some(20.0)),
            rec(Kind::Hdv, Outcome::Present, false, None), // 75.942857 s
            rec(Kind::Cav, Outcome::NeverInserted, false, None), // 79.8 − 70 = 9.8 s
            rec(Kind::Hdv, Outcome::Crashed, false, None), // not counted
        ];
        vs[0].desired_speed = 35.0;
        vs[0].t_star = FF.time(455.0, 30.0); // 13.119048 s: a delay of 5.880952 s
        vs[2].scheduled_depart = 70.0;
        let settled = [(455.0, 30.0), (100.0, 35.0), (0.0, 30.0), (40.0, 30.0)];
        for (r, (covered, v0)) in vs.iter_mut().zip(settled) {
            r.settle(79.8, covered, v0, FF);
        }
        let s = Summary::compute(&input(&vs, 3));
        let total = 5.880_952 + 75.942_857 + 9.8;
        assert!(
            close_to(s.system.as_ref().unwrap().system_delay_s, total / 3.0),
            "{:?}",
            s.system.as_ref().unwrap().system_delay_s
        );
        assert!((s.system.as_ref().unwrap().system_delay_veh_h - total / 3600.0).abs() < 1e-9);
        // Only the present HDV drives slower than v_max by its own choice: 0.476190 s.
        assert!(close_to(
            s.system.as_ref().unwrap().own_speed_delay_s,
            0.476_190 / 3.0
        ));
        // The paper's delay sees only the arrived vehicle.
        assert!(close_to(s.travel().mean_delay_s, 5.880_952));
    }

    #[test]
    fn no_window_no_throughput() {
        let vs = vec![rec(Kind::Cav, Outcome::Present, false, None)];
        let mut inp = input(&vs, 1);
        inp.end = 10.0; // before 1 + 13 s: nobody could have arrived yet
        let s = Summary::compute(&inp);
        assert_eq!(
            (s.travel().throughput_window_s, s.travel().throughput_veh_h),
            (0.0, 0.0)
        );
        assert_eq!(arrival_window(&[], 10.0), 0.0);
    }

    #[test]
    fn percentile_nearest_rank() {
        let mut xs = vec![5.0, 1.0, 3.0, 2.0, 4.0];
        assert_eq!(percentile(&mut xs, 50.0), 3.0);
        assert_eq!(percentile(&mut xs, 99.0), 5.0);
        assert_eq!(percentile(&mut [], 50.0), 0.0);
    }
}
