//! Episode metrics (paper eq. 1 and section VI): per-vehicle records, travel delay against the
//! free-flow time t*, collision attribution, and the one-row episode summary.

use std::sync::OnceLock;

use serde::Serialize;

use crate::controller::PlanStats;
use crate::episode::cells;
use crate::model::scene::{Kind, Origin};

/// How a vehicle's episode ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Still in the network when the episode ended.
    Present,
    /// Left the section (at its end, or by an off-ramp) without a collision.
    Arrived,
    /// Removed in a collision.
    Crashed,
}

impl Outcome {
    /// The outcome's name in `vehicles.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Present => "present",
            Outcome::Arrived => "arrived",
            Outcome::Crashed => "crashed",
        }
    }
}

/// One inserted vehicle, from insertion to arrival or crash.
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
    /// Route distance from the insertion position to the end of the section (m).
    pub distance: f64,
    /// Free-flow travel time t* (s).
    pub t_star: f64,
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

/// The episode's one-row summary (reproducible: no wall-clock figure in it): the one definition
/// of the `episode.csv` row. Its serde names, in field order, are the columns (the planner's
/// [`PlanStats`] inline, under theirs); a float's `serialize_with` gives its CSV decimals
/// ([`cells::decimals`]). Adding a metric is adding a field here and computing it in
/// [`Summary::compute`].
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Summary {
    /// The controller's name (`bk-pbs`, `idm-mobil`...).
    pub planner: String,
    /// CAV penetration α (`scenario.alpha`).
    pub alpha: f64,
    /// Total arrival rate λ (veh/h, `scenario.lambda`).
    pub lambda: f64,
    /// The episode's random seed (`scenario.seed`).
    pub seed: u64,
    /// The HDV driver profile SUMO ran (`[hdv] profile`).
    pub hdv_profile: String,
    /// Simulated steps.
    pub steps: u32,
    /// Vehicles the demand scheduled within the horizon.
    pub scheduled: usize,
    /// Vehicles SUMO inserted.
    pub inserted: usize,
    /// Scheduled but never inserted (SUMO found no room in time).
    pub undeparted: usize,
    /// CAVs among the inserted vehicles.
    pub inserted_cav: usize,
    /// Vehicles that left the section without a collision.
    pub arrived: usize,
    /// Vehicles removed in collisions (any).
    pub crashed: usize,
    /// Vehicles still in the network at the end.
    pub present: usize,
    /// Vehicles removed in collisions involving a CAV.
    pub controllable_crashed: usize,
    /// Share of the inserted vehicles removed in collisions involving a CAV (0 for none).
    #[serde(serialize_with = "cells::decimals::<6, _>")]
    pub controllable_collision_rate: f64,
    /// Collisions between two HDVs (events), out of any controller's reach.
    pub hdv_collisions: usize,
    /// Vehicles removed in collisions between two HDVs.
    pub hdv_crashed: usize,
    /// Mean travel delay t_f − t* of the vehicles that arrived (s; `None` if none did).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_s: Option<f64>,
    /// Mean travel delay of the CAVs that arrived (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_cav_s: Option<f64>,
    /// Mean travel delay of the HDVs that arrived (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_hdv_s: Option<f64>,
    /// Vehicles that arrived per hour of simulated time (veh/h).
    #[serde(serialize_with = "cells::decimals::<2, _>")]
    pub throughput_veh_h: f64,
    /// Mean speed over all vehicle-steps (m/s).
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    pub mean_speed_mps: f64,
    /// Vehicles standing (< 1 m/s) on the acceleration lane at the end (a jam indicator).
    pub ramp_queue_end: usize,
    /// Planner effort over the episode.
    pub plan_stats: PlanStats,
}

impl Summary {
    /// The `episode.csv` columns, in order.
    pub fn columns() -> &'static [&'static str] {
        static COLUMNS: OnceLock<Vec<&'static str>> = OnceLock::new();
        COLUMNS.get_or_init(|| {
            Summary::default()
                .cells()
                .into_iter()
                .map(|c| c.column)
                .collect()
        })
    }

    /// The summary's cells, one per column: the typed values the CSV row is written from.
    pub fn cells(&self) -> Vec<cells::Cell> {
        cells::cells(self).expect("the summary is a flat record")
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
    /// Simulated steps.
    pub steps: u32,
    /// Step length (s).
    pub dt: f64,
    /// Vehicles the demand scheduled within the horizon.
    pub scheduled: usize,
    /// Every inserted vehicle's record.
    pub vehicles: &'a [VehicleRecord],
    /// Every collision SUMO reported.
    pub collisions: &'a [CollisionEvent],
    /// Sum of the speeds of every vehicle reading on the section (m/s).
    pub speed_sum: f64,
    /// Number of readings summed in `speed_sum`.
    pub speed_samples: u64,
    /// Vehicles standing on the acceleration lane at the end.
    pub ramp_queue_end: usize,
    /// Planner effort over the episode.
    pub plan_stats: PlanStats,
}

impl Summary {
    /// The summary of an episode's records.
    pub fn compute(inp: &SummaryInput) -> Summary {
        let v = inp.vehicles;
        let count = |f: &dyn Fn(&VehicleRecord) -> bool| v.iter().filter(|r| f(r)).count();
        let inserted = v.len();
        let crashed = count(&|r| r.outcome == Outcome::Crashed);
        let controllable_crashed =
            count(&|r| r.outcome == Outcome::Crashed && r.controllable_crash);
        let delays = |k: Option<Kind>| {
            mean(
                v.iter()
                    .filter(|r| k.map_or(true, |k| r.kind == k))
                    .filter_map(|r| r.delay()),
            )
        };
        let horizon_h = inp.steps as f64 * inp.dt / 3600.0;
        let arrived = count(&|r| r.outcome == Outcome::Arrived);
        Summary {
            planner: inp.planner.to_string(),
            alpha: inp.alpha,
            lambda: inp.lambda,
            seed: inp.seed,
            hdv_profile: inp.hdv_profile.to_string(),
            steps: inp.steps,
            scheduled: inp.scheduled,
            inserted,
            undeparted: inp.scheduled.saturating_sub(inserted),
            inserted_cav: count(&|r| r.kind == Kind::Cav),
            arrived,
            crashed,
            present: count(&|r| r.outcome == Outcome::Present),
            controllable_crashed,
            controllable_collision_rate: if inserted > 0 {
                controllable_crashed as f64 / inserted as f64
            } else {
                0.0
            },
            hdv_collisions: inp.collisions.iter().filter(|c| !c.controllable()).count(),
            hdv_crashed: count(&|r| r.outcome == Outcome::Crashed && !r.controllable_crash),
            mean_delay_s: delays(None),
            mean_delay_cav_s: delays(Some(Kind::Cav)),
            mean_delay_hdv_s: delays(Some(Kind::Hdv)),
            throughput_veh_h: arrived as f64 / horizon_h,
            mean_speed_mps: if inp.speed_samples > 0 {
                inp.speed_sum / inp.speed_samples as f64
            } else {
                0.0
            },
            ramp_queue_end: inp.ramp_queue_end,
            plan_stats: inp.plan_stats,
        }
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
            outcome,
            arrival_time: arrival,
            crash_time: None,
            crashed_with: vec![],
            controllable_crash: controllable,
        }
    }

    #[test]
    fn summary_counts_and_rates() {
        let vs = vec![
            rec(Kind::Cav, Outcome::Arrived, false, Some(20.0)), // delay 20 − 1 − 13 = 6
            rec(Kind::Hdv, Outcome::Arrived, false, Some(18.0)), // delay 4
            rec(Kind::Cav, Outcome::Crashed, true, None),
            rec(Kind::Hdv, Outcome::Crashed, true, None),
            rec(Kind::Hdv, Outcome::Crashed, false, None),
            rec(Kind::Hdv, Outcome::Present, false, None),
        ];
        let s = Summary::compute(&SummaryInput {
            planner: "p",
            hdv_profile: "sumo-safe",
            alpha: 0.5,
            lambda: 3000.0,
            seed: 1,
            steps: 400,
            dt: 0.2,
            scheduled: 8,
            vehicles: &vs,
            collisions: &[],
            speed_sum: 10.0,
            speed_samples: 4,
            ramp_queue_end: 0,
            plan_stats: PlanStats::default(),
        });
        assert_eq!(
            (s.inserted, s.undeparted, s.arrived, s.crashed, s.present),
            (6, 2, 2, 3, 1)
        );
        assert_eq!(s.controllable_crashed, 2);
        assert!((s.controllable_collision_rate - 2.0 / 6.0).abs() < 1e-12);
        assert_eq!(s.mean_delay_s, Some(5.0));
        assert_eq!(s.mean_delay_cav_s, Some(6.0));
        assert!((s.throughput_veh_h - 2.0 / (80.0 / 3600.0)).abs() < 1e-9);
        assert_eq!(s.mean_speed_mps, 2.5);
    }

    #[test]
    fn percentile_nearest_rank() {
        let mut xs = vec![5.0, 1.0, 3.0, 2.0, 4.0];
        assert_eq!(percentile(&mut xs, 50.0), 3.0);
        assert_eq!(percentile(&mut xs, 99.0), 5.0);
        assert_eq!(percentile(&mut [], 50.0), 0.0);
    }
}
