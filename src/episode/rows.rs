//! The rows of an episode's `vehicles.csv` (either traffic's), `collisions.csv` and
//! `timing.csv`, each one serde record written through [`cells`], as `episode.csv`'s
//! [`Summary`](crate::episode::summary::Summary) and a scenario's files are: the field names are
//! the columns, a float's `serialize_with` its decimals, an absent value an empty field.

use std::sync::OnceLock;

use serde::Serialize;

use crate::episode::cells::{self, TrafficColumns};
use crate::episode::metrics::{CollisionEvent, Timing, VehicleRecord};
use crate::episode::summary::Traffic;
use crate::model::scene::Kind;

/// One vehicle (a `vehicles.csv` row), whatever the traffic: its id, type and outcome and its
/// collisions, and the parts only one traffic measures (an absent part is no column, so each
/// traffic keeps its columns and their order): on the paper's demand its insertion and travel
/// ([`VehicleRow::of`], from its [`VehicleRecord`]), on a scenario of the user's own its passage
/// through its first merge region, SUMO's trip figures and its entry
/// (`episode::sumocfg::records`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct VehicleRow {
    /// SUMO's vehicle id.
    pub id: String,
    /// On the paper's demand `cav` or `hdv`; on a scenario its SUMO vehicle type.
    #[serde(rename = "type")]
    pub type_name: String,
    /// How the paper's demand scheduled and inserted it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub insertion: Option<Insertion>,
    /// Its passage through its first merge region of a scenario.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub passage: Option<Passage>,
    /// `arrived`, `crashed`, `present` (still driving at the end) or `never_inserted`.
    pub outcome: String,
    /// Its travel on the paper's section.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub travel: Option<Travel>,
    /// SUMO's figures of its trip in a scenario.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trip: Option<TripFigures>,
    /// When it was removed in a collision (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub crash_time_s: Option<f64>,
    /// The other vehicles of its collisions, space-separated.
    pub crashed_with: String,
    /// Whether a CAV took part in its collision.
    pub controllable_crash: bool,
    /// Which entry of its first region of a scenario it came by, and its delay there against
    /// its own desired speed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub entry: Option<EntryDelay>,
}

/// How the paper's demand scheduled and inserted a vehicle (empty figures for one never
/// inserted).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Insertion {
    /// `main` or `ramp`.
    pub origin: String,
    /// When the demand scheduled it (s).
    #[serde(serialize_with = "cells::decimals::<2, _>")]
    pub scheduled_depart_s: f64,
    /// The speed the demand drew for its insertion (m/s).
    #[serde(serialize_with = "cells::decimals::<2, _>")]
    pub scheduled_speed_mps: f64,
    /// The SUMO lane it was inserted on.
    pub insert_lane: Option<i32>,
    /// When SUMO inserted it (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub insert_time_s: Option<f64>,
    /// How long the entry gate held it back (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub entry_delay_s: Option<f64>,
    /// The speed it was inserted at (m/s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub insert_speed_mps: Option<f64>,
    /// Its desired speed (m/s): v_max for a CAV, drawn for an HDV.
    #[serde(serialize_with = "cells::decimals::<2, _>")]
    pub desired_speed_mps: f64,
    /// The length of its route on the section (m).
    #[serde(serialize_with = "cells::opt_decimals::<3, _>")]
    pub distance_m: Option<f64>,
    /// Its free-flow time over that route, t* (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub t_star_s: Option<f64>,
}

/// A vehicle's travel on the paper's section (the guide's Metrics chapter).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Travel {
    /// When its front crossed the section's end (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub arrival_time_s: Option<f64>,
    /// Arrival less insertion (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub travel_time_s: Option<f64>,
    /// Arrival less scheduled departure (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub time_in_network_s: Option<f64>,
    /// Travel time less t* (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub delay_s: Option<f64>,
    /// How far it drove on its route (m).
    #[serde(serialize_with = "cells::opt_decimals::<3, _>")]
    pub distance_covered_m: Option<f64>,
    /// Its system delay (s): from its scheduled departure to its arrival or the end, less the
    /// free-flow time of the distance it covered.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub system_delay_s: Option<f64>,
}

/// A scenario vehicle's passage through the first merge region it entered.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Passage {
    /// `cav` or `hdv`.
    pub kind: String,
    /// The region (the edges its on-ramps join), empty if it entered none.
    pub region: String,
    /// Where it entered that region (`main`, `ramp`), empty if it never did.
    pub region_origin: String,
    /// Its departure time in the scenario (s): SUMO's `depart` of the vehicle.
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub scheduled_depart_s: Option<f64>,
    /// When SUMO inserted it (s); none if it never did.
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub depart_s: Option<f64>,
    /// When it was first seen in the region (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub region_enter_s: Option<f64>,
    /// When it was last seen in the region (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub region_leave_s: Option<f64>,
    /// How far it drove in the region between those readings (m).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub region_distance_m: Option<f64>,
    /// Its system delay in the region (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub region_delay_s: Option<f64>,
}

/// SUMO's figures of a scenario vehicle's trip (its tripinfo).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TripFigures {
    /// When it arrived at its route's end (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub arrival_s: Option<f64>,
    /// SUMO's `timeLoss` (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub time_loss_s: Option<f64>,
    /// SUMO's `departDelay` (s).
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub depart_delay_s: Option<f64>,
    /// SUMO's `routeLength` (m) driven.
    #[serde(serialize_with = "cells::opt_decimals::<2, _>")]
    pub route_length_m: Option<f64>,
}

/// The entry by which a scenario vehicle came into its first region, and its delay there
/// against its own desired speed.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct EntryDelay {
    /// `main` or the SUMO edge id of the on-ramp's first edge in the region; empty if it
    /// entered none.
    pub region_entry: String,
    /// Its system delay in the region against its own desired speed (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub region_delay_own_s: Option<f64>,
}

/// `x` if finite (a figure of no insertion, or of no vehicle, is NaN in the record).
fn finite(x: f64) -> Option<f64> {
    Some(x).filter(|x| x.is_finite())
}

impl VehicleRow {
    /// The row of record `r` of the paper's demand; a figure of the insertion is empty for a
    /// vehicle never inserted.
    pub fn of(r: &VehicleRecord) -> VehicleRow {
        let inserted = r.inserted();
        let at_insertion = |x: f64| finite(x).filter(|_| inserted);
        VehicleRow {
            id: r.id.clone(),
            type_name: r.kind.as_str().into(),
            insertion: Some(Insertion {
                origin: r.origin.as_str().into(),
                scheduled_depart_s: r.scheduled_depart,
                scheduled_speed_mps: r.scheduled_speed,
                insert_lane: inserted.then_some(r.insert_lane),
                insert_time_s: at_insertion(r.insert_time),
                entry_delay_s: at_insertion(r.entry_delay()),
                insert_speed_mps: at_insertion(r.insert_speed),
                desired_speed_mps: r.desired_speed,
                distance_m: finite(r.distance),
                t_star_s: finite(r.t_star),
            }),
            outcome: r.outcome.as_str().into(),
            travel: Some(Travel {
                arrival_time_s: r.arrival_time,
                travel_time_s: r.travel_time(),
                time_in_network_s: r.time_in_network(),
                delay_s: r.delay(),
                distance_covered_m: r.system_delay.map(|_| r.covered),
                system_delay_s: r.system_delay,
            }),
            crash_time_s: r.crash_time,
            crashed_with: r.crashed_with.join(" "),
            controllable_crash: r.controllable_crash,
            ..VehicleRow::default()
        }
    }

    /// A row with every part of `traffic`: the template its `vehicles.csv` columns come from.
    pub fn template(traffic: Traffic) -> VehicleRow {
        match traffic {
            Traffic::Demand => VehicleRow {
                insertion: Some(Insertion::default()),
                travel: Some(Travel::default()),
                ..VehicleRow::default()
            },
            Traffic::Scenario => VehicleRow {
                passage: Some(Passage::default()),
                trip: Some(TripFigures::default()),
                entry: Some(EntryDelay::default()),
                ..VehicleRow::default()
            },
        }
    }

    /// The `vehicles.csv` columns of an episode of `traffic`, in order.
    pub fn columns(traffic: Traffic) -> &'static [&'static str] {
        static COLUMNS: TrafficColumns<VehicleRow> = TrafficColumns::new(VehicleRow::template);
        COLUMNS.of(traffic)
    }

    /// The CSV text of `rows`, vehicles of `traffic`, under that traffic's columns.
    pub fn csv(traffic: Traffic, rows: &[VehicleRow]) -> Vec<u8> {
        cells::csv_text(&VehicleRow::template(traffic), rows)
    }
}

/// One collision SUMO reported (a `collisions.csv` row).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CollisionRow {
    #[serde(serialize_with = "cells::decimals::<2, _>")]
    time_s: f64,
    collider: String,
    /// `cav`, `hdv` or `unknown`.
    collider_type: String,
    victim: String,
    victim_type: String,
    lane: String,
    #[serde(serialize_with = "cells::decimals::<2, _>")]
    position_m: f64,
    controllable: bool,
}

impl CollisionRow {
    /// The row of collision `c`.
    pub fn of(c: &CollisionEvent) -> CollisionRow {
        let kind = |k: Option<Kind>| k.map_or("unknown", |k| k.as_str()).to_string();
        CollisionRow {
            time_s: c.time,
            collider: c.collider.clone(),
            collider_type: kind(c.collider_kind),
            victim: c.victim.clone(),
            victim_type: kind(c.victim_kind),
            lane: c.lane.clone(),
            position_m: c.position,
            controllable: c.controllable(),
        }
    }

    /// The `collisions.csv` columns, in order.
    pub fn columns() -> &'static [&'static str] {
        static COLUMNS: OnceLock<Vec<&'static str>> = OnceLock::new();
        cells::columns_once(&COLUMNS, CollisionRow::default)
    }
}

/// An episode's wall-clock figures (the `timing.csv` row), each with 4 decimals.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TimingRow {
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    plan_ms_median: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    plan_ms_p99: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    plan_ms_max: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    sumo_ms_per_step: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    episode_ms_per_step: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    wall_s: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    shield_ms_median: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    shield_ms_p99: f64,
    #[serde(serialize_with = "cells::decimals::<4, _>")]
    shield_ms_max: f64,
}

impl TimingRow {
    /// The row of timing `t`.
    pub fn of(t: &Timing) -> TimingRow {
        TimingRow {
            plan_ms_median: t.plan_ms_median,
            plan_ms_p99: t.plan_ms_p99,
            plan_ms_max: t.plan_ms_max,
            sumo_ms_per_step: t.sumo_ms_per_step,
            episode_ms_per_step: t.episode_ms_per_step,
            wall_s: t.wall_s,
            shield_ms_median: t.shield_ms_median,
            shield_ms_p99: t.shield_ms_p99,
            shield_ms_max: t.shield_ms_max,
        }
    }

    /// The `timing.csv` columns, in order.
    pub fn columns() -> &'static [&'static str] {
        static COLUMNS: OnceLock<Vec<&'static str>> = OnceLock::new();
        cells::columns_once(&COLUMNS, TimingRow::default)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::episode::metrics::Outcome;
    use crate::model::scene::Origin;

    fn record(outcome: Outcome) -> VehicleRecord {
        VehicleRecord {
            id: "ramp.3".into(),
            kind: Kind::Cav,
            sumo_type: "cav".into(),
            origin: Origin::Ramp,
            scheduled_depart: 1.005,
            scheduled_speed: 22.123,
            insert_lane: 0,
            insert_time: 2.5,
            insert_speed: 21.0,
            desired_speed: 30.0,
            distance: 455.12345,
            t_star: 17.654321,
            covered: 123.4567,
            system_delay: Some(4.56789),
            own_speed_delay: Some(0.1),
            outcome,
            arrival_time: Some(25.25),
            crash_time: None,
            crashed_with: vec![],
            controllable_crash: false,
        }
    }

    /// The bytes `vehicles.csv` had when each row was formatted by hand: the columns, each
    /// float's decimals, and the empty fields of a vehicle never inserted (whose distance and
    /// t* are NaN when no vehicle entered where it would have).
    #[test]
    fn vehicles_csv_keeps_its_columns_decimals_and_empty_fields() {
        let arrived = record(Outcome::Arrived);
        let crashed = VehicleRecord {
            arrival_time: None,
            system_delay: None,
            crash_time: Some(7.0),
            crashed_with: vec!["main.1".into(), "main.2".into()],
            controllable_crash: true,
            ..record(Outcome::Crashed)
        };
        let never = VehicleRecord {
            arrival_time: None,
            distance: f64::NAN,
            t_star: f64::NAN,
            insert_time: f64::NAN,
            insert_speed: f64::NAN,
            ..record(Outcome::NeverInserted)
        };
        let rows: Vec<VehicleRow> = [arrived, crashed, never]
            .iter()
            .map(VehicleRow::of)
            .collect();
        let text = String::from_utf8(VehicleRow::csv(Traffic::Demand, &rows)).unwrap();
        assert_eq!(
            text,
            "id,type,origin,scheduled_depart_s,scheduled_speed_mps,insert_lane,insert_time_s,\
             entry_delay_s,insert_speed_mps,desired_speed_mps,distance_m,t_star_s,outcome,\
             arrival_time_s,travel_time_s,time_in_network_s,delay_s,distance_covered_m,\
             system_delay_s,crash_time_s,crashed_with,controllable_crash\n\
             ramp.3,cav,ramp,1.00,22.12,0,2.50,1.50,21.00,30.00,455.123,17.6543,arrived,\
             25.2500,24.2450,22.7500,6.5907,123.457,4.5679,,,false\n\
             ramp.3,cav,ramp,1.00,22.12,0,2.50,1.50,21.00,30.00,455.123,17.6543,crashed,\
             ,,,,,,7.00,main.1 main.2,true\n\
             ramp.3,cav,ramp,1.00,22.12,,,,,30.00,,,never_inserted,,,,,123.457,4.5679,,,false\n"
        );
    }

    #[test]
    fn collisions_and_timing_keep_their_columns_and_decimals() {
        let c = CollisionEvent {
            time: 12.345,
            collider: "a".into(),
            collider_kind: Some(Kind::Cav),
            victim: "b".into(),
            victim_kind: None,
            lane: "e_1".into(),
            position: 99.999,
        };
        let text = cells::csv_text(&CollisionRow::default(), &[CollisionRow::of(&c)]);
        assert_eq!(
            String::from_utf8(text).unwrap(),
            "time_s,collider,collider_type,victim,victim_type,lane,position_m,controllable\n\
             12.35,a,cav,b,unknown,e_1,100.00,true\n"
        );
        assert_eq!(
            TimingRow::columns().join(","),
            "plan_ms_median,plan_ms_p99,plan_ms_max,sumo_ms_per_step,episode_ms_per_step,wall_s,\
             shield_ms_median,shield_ms_p99,shield_ms_max"
        );
    }
}
