//! The one-row summary of an episode (`episode.csv`), whatever its traffic: the one definition
//! of that row.
//!
//! Its serde names, in field order, are the columns (the planner's [`PlanStats`] and every
//! part inline, under theirs); a float's `serialize_with` gives its CSV decimals
//! ([`cells::decimals`]). What every episode has is a plain field; what only one traffic
//! source can measure is an optional part, absent from the row (no column at all) when the
//! episode's [`Traffic`] does not give it: the paper demand's books of scheduled departures and
//! its free-flow delays, or SUMO's own `timeLoss` of a user's scenario. So each traffic keeps
//! its columns and their order, and adding a metric is adding a field here and computing it
//! where the traffic's books are closed ([`Summary::compute`] for the paper demand,
//! [`Summary::of_scenario`](crate::episode::sumocfg) for a user's scenario); the CSV header,
//! the campaign's checks and the Python dict follow.

use serde::Serialize;

use crate::controller::PlanStats;
use crate::episode::cells::{self, TrafficColumns};
// Named here as before: the traffic decides the summary's parts.
pub use crate::episode::traffic::Traffic;

/// The episode's one-row summary (reproducible: no wall-clock figure in it).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Summary {
    /// The scenario's configuration file name (`A10KW.sumocfg`); a scenario's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scenario: Option<String>,
    /// The controller's name (`bk-pbs`, `idm-mobil`...).
    pub planner: String,
    /// CAV penetration α (`scenario.alpha`; unused with `cav_types`).
    pub alpha: f64,
    /// Total arrival rate λ (veh/h, `scenario.lambda`); the paper demand's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f64>,
    /// The vehicle types whose vehicles are the CAVs instead of a share α (space-separated),
    /// or empty; a scenario's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cav_types: Option<String>,
    /// The episode's random seed (`scenario.seed`: SUMO's, and the CAV draw's).
    pub seed: u64,
    /// The HDV driver profile SUMO ran (`[hdv] profile`); the paper demand's only (a
    /// scenario's drivers are its own).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hdv_profile: Option<String>,
    /// The SUMO version that simulated the episode ([`crate::sumo::version::BUILT`]; a run
    /// against another is refused): results move between SUMO versions.
    pub sumo_version: String,
    /// Simulated steps.
    pub steps: u32,
    /// The regions planned, each as the edges its on-ramps join (`; ` between regions); a
    /// scenario's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub regions: Option<String>,
    /// The system delay of every demanded vehicle; the paper demand's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub system: Option<SystemDelay>,
    /// Vehicles the demand scheduled within the horizon; the paper demand's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scheduled: Option<usize>,
    /// Vehicles SUMO inserted.
    pub inserted: usize,
    /// Vehicles whose departure time had come by the episode's end but which SUMO never
    /// inserted (no room at their departure position).
    pub never_inserted: usize,
    /// CAVs among the inserted vehicles.
    pub inserted_cav: usize,
    /// The realised CAV share and the vehicles in a region; a scenario's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub share: Option<RegionShare>,
    /// Vehicles that reached their route's end without a collision.
    pub arrived: usize,
    /// Vehicles removed in collisions (any).
    pub crashed: usize,
    /// Vehicles still in the network at the end.
    pub present: usize,
    /// Vehicles removed in collisions involving a CAV.
    pub controllable_crashed: usize,
    /// Share of the inserted vehicles removed in collisions involving a CAV (0 for none);
    /// the paper demand's only.
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "cells::opt_decimals::<6, _>"
    )]
    pub controllable_collision_rate: Option<f64>,
    /// Collisions between two HDVs (events), out of any controller's reach.
    pub hdv_collisions: usize,
    /// The travel delays, throughput and speeds measured against the paper's free-flow time;
    /// the paper demand's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub travel: Option<TravelFigures>,
    /// SUMO's own `timeLoss` figures and the delays in the regions; a scenario's only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_loss: Option<TimeLossFigures>,
    /// Planner effort over the episode (every region's rounds summed).
    pub plan_stats: PlanStats,
}

/// The system delay of the paper demand's vehicles (paper eq. 1): every vehicle not crashed,
/// arrived or not, a vehicle never inserted with its wait (see
/// [`VehicleRecord::settle`](crate::episode::metrics::VehicleRecord::settle)).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SystemDelay {
    /// Mean system delay per vehicle (s); `None` if there is none.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub system_delay_s: Option<f64>,
    /// Total system delay (vehicle-hours) of the same vehicles.
    #[serde(serialize_with = "cells::decimals::<6, _>")]
    pub system_delay_veh_h: f64,
    /// Mean per vehicle of the part of the system delay no controller can remove (s): driving
    /// at its own desired speed instead of v_max; `None` if there is no vehicle.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub own_speed_delay_s: Option<f64>,
}

/// Who of a scenario's vehicles were CAVs and went through a region.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RegionShare {
    /// The realised CAV share of the inserted vehicles.
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    pub cav_share: f64,
    /// Vehicles that were in a region.
    pub in_region: usize,
}

/// The paper demand's figures of the vehicles' travel, against its free-flow time t*.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TravelFigures {
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
    /// Vehicles that arrived per hour of the window in which arrivals were possible (veh/h).
    #[serde(serialize_with = "cells::decimals::<2, _>")]
    pub throughput_veh_h: f64,
    /// That window (s; see [`arrival_window`](crate::episode::metrics::arrival_window)).
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    pub throughput_window_s: f64,
    /// Mean speed over all vehicle-steps (m/s).
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    pub mean_speed_mps: f64,
    /// Vehicles standing (< 1 m/s) on the acceleration lane at the end (a jam indicator).
    pub stranded: usize,
}

/// A scenario's delays: SUMO's `timeLoss` of each trip, and the delay in its region.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TimeLossFigures {
    /// Mean SUMO `timeLoss` per vehicle not crashed, arrived or not (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_time_loss_s: Option<f64>,
    /// The same over the vehicles that were in a region (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_time_loss_region_s: Option<f64>,
    /// Mean of `timeLoss` plus `departDelay` (the wait to be inserted) per vehicle not crashed,
    /// a vehicle never inserted counting with its whole wait to the end (s): a planner that
    /// holds vehicles at the network's entrance pays for it here, as in the paper demand's
    /// system delay.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_time_loss_with_wait_s: Option<f64>,
    /// Mean SUMO `timeLoss` per vehicle inserted, a crashed one included and charged its
    /// unfinished trip: its `timeLoss` when it was removed plus the time from its crash to the
    /// episode's end, as if it had stood there (s). A planner whose crashes take vehicles off
    /// the road cannot look faster here than in `mean_time_loss_s`, which leaves them out.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_time_loss_crashes_charged_s: Option<f64>,
    /// Total `timeLoss` of the vehicles not crashed (vehicle-hours).
    #[serde(serialize_with = "cells::decimals::<6, _>")]
    pub time_loss_veh_h: f64,
    /// Mean system delay in its region over the vehicles that were in one, not crashed (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_region_delay_s: Option<f64>,
}

impl Summary {
    /// A summary with every part `traffic` gives present (its values zero): what fixes the
    /// columns of that traffic's `episode.csv`.
    pub fn template(traffic: Traffic) -> Summary {
        match traffic {
            Traffic::Demand => Summary {
                lambda: Some(0.0),
                hdv_profile: Some(String::new()),
                system: Some(SystemDelay::default()),
                scheduled: Some(0),
                controllable_collision_rate: Some(0.0),
                travel: Some(TravelFigures::default()),
                ..Summary::default()
            },
            Traffic::Scenario => Summary {
                scenario: Some(String::new()),
                cav_types: Some(String::new()),
                regions: Some(String::new()),
                share: Some(RegionShare::default()),
                time_loss: Some(TimeLossFigures::default()),
                ..Summary::default()
            },
        }
    }

    /// The `episode.csv` columns of an episode of `traffic`, in order.
    pub fn columns(traffic: Traffic) -> &'static [&'static str] {
        static COLUMNS: TrafficColumns<Summary> = TrafficColumns::new(Summary::template);
        COLUMNS.of(traffic)
    }

    /// [`Summary::columns`] as owned strings (a CSV header to compare a file's with).
    pub fn header(traffic: Traffic) -> Vec<String> {
        Summary::columns(traffic)
            .iter()
            .map(|c| c.to_string())
            .collect()
    }

    /// The CSV text of `rows`, episodes of `traffic`, under that traffic's columns.
    pub fn csv(traffic: Traffic, rows: &[Summary]) -> Vec<u8> {
        cells::csv_text(&Summary::template(traffic), rows)
    }

    /// The summary's cells, one per column of its traffic: the typed values the CSV row is
    /// written from.
    pub fn cells(&self) -> Vec<cells::Cell> {
        cells::cells(self).expect("the summary is a flat record")
    }

    /// The travel figures (the paper demand's part; zero for a scenario's summary).
    pub fn travel(&self) -> TravelFigures {
        self.travel.clone().unwrap_or_default()
    }

    /// The `timeLoss` figures (a scenario's part; zero for the paper demand's summary).
    pub fn time_loss(&self) -> TimeLossFigures {
        self.time_loss.clone().unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each traffic keeps the columns, and their order, its `episode.csv` had when each was a
    /// struct of its own.
    #[test]
    fn each_traffic_has_its_own_columns_in_their_order() {
        let stats = "plan_searches,plan_nodes_expanded,plan_phase2,plan_fallbacks,pbs_nodes,\
                     pbs_depth_sum,predictions,pbs_fallbacks,time_budget_hits,shield_overrides";
        assert_eq!(
            Summary::columns(Traffic::Demand).join(","),
            format!(
                "planner,alpha,lambda,seed,hdv_profile,sumo_version,steps,system_delay_s,\
                 system_delay_veh_h,own_speed_delay_s,scheduled,inserted,never_inserted,\
                 inserted_cav,arrived,crashed,present,controllable_crashed,\
                 controllable_collision_rate,hdv_collisions,hdv_crashed,mean_delay_s,\
                 mean_delay_cav_s,mean_delay_hdv_s,throughput_veh_h,throughput_window_s,\
                 mean_speed_mps,stranded,{stats}"
            )
        );
        assert_eq!(
            Summary::columns(Traffic::Scenario).join(","),
            format!(
                "scenario,planner,alpha,cav_types,seed,sumo_version,steps,regions,inserted,\
                 never_inserted,inserted_cav,cav_share,in_region,arrived,crashed,present,\
                 controllable_crashed,hdv_collisions,mean_time_loss_s,mean_time_loss_region_s,\
                 mean_time_loss_with_wait_s,mean_time_loss_crashes_charged_s,time_loss_veh_h,\
                 mean_region_delay_s,{stats}"
            )
        );
    }
}
