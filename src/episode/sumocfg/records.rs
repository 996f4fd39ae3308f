//! What an episode on a user's scenario records: per vehicle SUMO's own trip figures (from its
//! tripinfo output, unfinished and undeparted trips included, so a vehicle that never arrives
//! still counts with the time it lost, and one never inserted with its wait) and bkpbs's (who
//! was a CAV, when it was in the merge region, collisions), and the scenario's part of the
//! episode's [`Summary`]: its delays are SUMO's `timeLoss`, where the paper demand's are
//! defined against bkpbs's own insertion.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::config::Config;
use crate::episode::cells;
use crate::episode::metrics::Outcome;
use crate::episode::rows::{EntryDelay, Passage, TripFigures, VehicleRow};
use crate::episode::summary::{RegionShare, Summary, TimeLossFigures, Traffic};
use crate::model::scene::Kind;

/// One vehicle of the scenario as the episode books it: one SUMO inserted, or one whose
/// departure time came but which SUMO never inserted (outcome `never_inserted`). Its
/// `vehicles.csv` row is [`VehicleRow::of_scenario`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScenarioVehicle {
    /// SUMO's vehicle id.
    pub id: String,
    /// Its SUMO vehicle type.
    pub sumo_type: String,
    /// CAV or HDV.
    pub kind: Kind,
    /// The first merge region it entered (the edges its on-ramps join), empty if none.
    pub region: String,
    /// Where it entered that region (`main`, `ramp`), empty if it never did.
    pub region_origin: String,
    /// Its departure time in the scenario (s): SUMO's `depart` of the vehicle (of its flow's
    /// schedule), when it wanted to enter; `depart_s` less `depart_delay_s` once inserted.
    pub scheduled_depart_s: Option<f64>,
    /// When SUMO inserted it (s); none if it never did.
    pub depart_s: Option<f64>,
    /// When it was first seen in the region (s).
    pub region_enter_s: Option<f64>,
    /// When it was last seen in the region (s).
    pub region_leave_s: Option<f64>,
    /// How far it drove in the region between its first and last reading there (m).
    pub region_distance_m: Option<f64>,
    /// Its system delay in the region (s): the time between those readings less the free-flow
    /// time over that distance from the speed it entered with (`metrics`' t*, at the region's
    /// `v_max`); a vehicle still there at the end counts to its last reading; none if crashed.
    pub region_delay_s: Option<f64>,
    /// Arrived, crashed, present (still driving at the end) or never inserted.
    pub outcome: Outcome,
    /// When it arrived at its route's end (s).
    pub arrival_s: Option<f64>,
    /// SUMO's `timeLoss` (s): time lost against driving at its ideal speed, to its arrival or to
    /// the episode's end.
    pub time_loss_s: Option<f64>,
    /// SUMO's `departDelay` (s): how long it waited to be inserted after its departure time
    /// (no room at its departure position), which `timeLoss` leaves out; for a vehicle never
    /// inserted, its wait from its departure time to the episode's end.
    pub depart_delay_s: Option<f64>,
    /// SUMO's `routeLength` (m) driven.
    pub route_length_m: Option<f64>,
    /// When it was removed in a collision (s).
    pub crash_time_s: Option<f64>,
    /// Who it collided with, space-separated.
    pub crashed_with: String,
    /// Whether a CAV took part in its collision.
    pub controllable_crash: bool,
    /// The entry by which it came into its first region: `main` (the main carriageway) or the
    /// SUMO edge id of the on-ramp's first edge in the region; empty if it entered none.
    pub region_entry: String,
    /// Its system delay in the region against its own desired speed (s): as `region_delay_s`,
    /// the free-flow time capped at that speed instead of the region's `v_max`: SUMO's speed
    /// factor of the vehicle times the speed limit of the region's main carriageway where it
    /// begins, at most its own top speed; none if crashed or it entered no region.
    pub region_delay_own_s: Option<f64>,
}

impl VehicleRow {
    /// The `vehicles.csv` row of scenario vehicle `v`.
    pub fn of_scenario(v: &ScenarioVehicle) -> VehicleRow {
        VehicleRow {
            id: v.id.clone(),
            type_name: v.sumo_type.clone(),
            passage: Some(Passage {
                kind: v.kind.as_str().into(),
                region: v.region.clone(),
                region_origin: v.region_origin.clone(),
                scheduled_depart_s: v.scheduled_depart_s,
                depart_s: v.depart_s,
                region_enter_s: v.region_enter_s,
                region_leave_s: v.region_leave_s,
                region_distance_m: v.region_distance_m,
                region_delay_s: v.region_delay_s,
            }),
            outcome: v.outcome.as_str().into(),
            trip: Some(TripFigures {
                arrival_s: v.arrival_s,
                time_loss_s: v.time_loss_s,
                depart_delay_s: v.depart_delay_s,
                route_length_m: v.route_length_m,
            }),
            crash_time_s: v.crash_time_s,
            crashed_with: v.crashed_with.clone(),
            controllable_crash: v.controllable_crash,
            entry: Some(EntryDelay {
                region_entry: v.region_entry.clone(),
                region_delay_own_s: v.region_delay_own_s,
            }),
            ..VehicleRow::default()
        }
    }
}

/// The `vehicles.csv` text of the scenario's `vehicles`.
pub fn vehicles_csv(vehicles: &[ScenarioVehicle]) -> Vec<u8> {
    let rows: Vec<VehicleRow> = vehicles.iter().map(VehicleRow::of_scenario).collect();
    VehicleRow::csv(Traffic::Scenario, &rows)
}

impl Summary {
    /// The episode's own columns of `episode.csv` on a scenario: which scenario, planner,
    /// CAVs, seed and `regions` (the rest [`Summary::of_scenario`] fills in).
    pub fn head_of_scenario(config: &Config, planner: &str, regions: &[String]) -> Summary {
        let sc = &config.scenario;
        Summary {
            scenario: Some(
                sc.sumocfg
                    .as_deref()
                    .and_then(Path::file_name)
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
            ),
            planner: planner.into(),
            sumo_version: crate::sumo::version::BUILT.into(),
            alpha: sc.alpha,
            cav_types: Some(sc.cav_types.join(" ")),
            seed: sc.seed,
            steps: sc.steps,
            regions: Some(regions.join("; ")),
            ..Summary::template(Traffic::Scenario)
        }
    }

    /// The summary of a scenario's `vehicles` (`hdv_collisions`: how many collisions involved
    /// HDVs only) of an episode that ended at `end` (s, SUMO's clock); `head` gives the
    /// episode's own columns ([`Summary::template`] of
    /// [`Traffic::Scenario`](crate::episode::summary::Traffic::Scenario) filled in).
    pub fn of_scenario(
        head: Summary,
        vehicles: &[ScenarioVehicle],
        hdv_collisions: usize,
        end: f64,
    ) -> Self {
        let count = |f: &dyn Fn(&ScenarioVehicle) -> bool| vehicles.iter().filter(|v| f(v)).count();
        let inserted = count(&|v| v.outcome != Outcome::NeverInserted);
        let inserted_cav = count(&|v| v.outcome != Outcome::NeverInserted && v.kind == Kind::Cav);
        Summary {
            inserted,
            never_inserted: vehicles.len() - inserted,
            inserted_cav,
            share: Some(RegionShare {
                cav_share: if inserted == 0 {
                    0.0
                } else {
                    inserted_cav as f64 / inserted as f64
                },
                in_region: count(&|v| v.region_enter_s.is_some()),
            }),
            arrived: count(&|v| v.outcome == Outcome::Arrived),
            crashed: count(&|v| v.outcome == Outcome::Crashed),
            present: count(&|v| v.outcome == Outcome::Present),
            controllable_crashed: count(&|v| v.controllable_crash),
            hdv_collisions,
            time_loss: Some(time_loss_figures(vehicles, end)),
            ..head
        }
    }
}

/// SUMO's `timeLoss` figures of a scenario's `vehicles`, of an episode that ended at `end`.
fn time_loss_figures(vehicles: &[ScenarioVehicle], end: f64) -> TimeLossFigures {
    let mean_of = |loss: &dyn Fn(&ScenarioVehicle) -> Option<f64>,
                   f: &dyn Fn(&ScenarioVehicle) -> bool| {
        let losses: Vec<f64> = vehicles
            .iter()
            .filter(|v| v.outcome != Outcome::Crashed && f(v))
            .filter_map(loss)
            .collect();
        (!losses.is_empty()).then(|| losses.iter().sum::<f64>() / losses.len() as f64)
    };
    let mean = |f: &dyn Fn(&ScenarioVehicle) -> bool| mean_of(&|v| v.time_loss_s, f);
    TimeLossFigures {
        mean_time_loss_s: mean(&|_| true),
        mean_time_loss_region_s: mean(&|v| v.region_enter_s.is_some()),
        mean_time_loss_with_wait_s: mean_of(&time_loss_with_wait, &|_| true),
        mean_time_loss_crashes_charged_s: mean_crashes_charged(vehicles, end),
        mean_region_delay_s: {
            let d: Vec<f64> = vehicles.iter().filter_map(|v| v.region_delay_s).collect();
            (!d.is_empty()).then(|| d.iter().sum::<f64>() / d.len() as f64)
        },
        time_loss_veh_h: vehicles
            .iter()
            .filter(|v| v.outcome != Outcome::Crashed)
            .filter_map(|v| v.time_loss_s)
            .sum::<f64>()
            / 3600.0,
    }
}

/// The mean `timeLoss` of the inserted `vehicles`, each crashed one charged the rest of the
/// episode after its crash (to `end`) on top of what it lost before; none without figures.
fn mean_crashes_charged(vehicles: &[ScenarioVehicle], end: f64) -> Option<f64> {
    let losses: Vec<f64> = vehicles
        .iter()
        .filter(|v| v.outcome != Outcome::NeverInserted)
        .filter_map(|v| {
            let unfinished = match (v.outcome, v.crash_time_s) {
                (Outcome::Crashed, Some(t)) => (end - t).max(0.0),
                _ => 0.0,
            };
            Some(v.time_loss_s? + unfinished)
        })
        .collect();
    (!losses.is_empty()).then(|| losses.iter().sum::<f64>() / losses.len() as f64)
}

/// A vehicle's SUMO `timeLoss` plus its `departDelay` (s): for one never inserted, its wait to
/// the end alone (it lost no time driving); none for one without SUMO's figures.
fn time_loss_with_wait(v: &ScenarioVehicle) -> Option<f64> {
    match v.outcome {
        Outcome::NeverInserted => v.depart_delay_s,
        _ => Some(v.time_loss_s? + v.depart_delay_s.unwrap_or(0.0)),
    }
}

/// SUMO's figures of one trip (a `<tripinfo>` element).
#[derive(Debug, Clone, PartialEq)]
pub struct Trip {
    /// `timeLoss` (s).
    pub time_loss: f64,
    /// `routeLength` (m).
    pub route_length: f64,
    /// `departDelay` (s; 0 where SUMO writes none): for a vehicle never inserted, the time
    /// from its departure time to the end.
    pub depart_delay: f64,
    /// Whether SUMO inserted the vehicle (its `depart` is not -1, which marks a vehicle
    /// `--tripinfo-output.write-undeparted` lists).
    pub departed: bool,
    /// `vType`: its vehicle type.
    pub sumo_type: Option<String>,
}

/// The trips of SUMO's tripinfo output at `path`, by vehicle id, vehicles never inserted
/// included.
///
/// # Errors
/// A file that cannot be read or is no tripinfo output.
pub fn read_trips(path: &Path) -> Result<BTreeMap<String, Trip>, String> {
    let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Data)
        .map_err(|e| format!("cannot read SUMO's tripinfo output {}: {e}", path.display()))?;
    let doc = roxmltree::Document::parse(&text)
        .map_err(|e| format!("SUMO's tripinfo output {}: {e}", path.display()))?;
    let num = |n: roxmltree::Node, k: &str| n.attribute(k).and_then(|v| v.parse::<f64>().ok());
    Ok(doc
        .descendants()
        .filter(|n| n.has_tag_name("tripinfo"))
        .filter_map(|n| {
            let trip = Trip {
                time_loss: num(n, "timeLoss")?,
                route_length: num(n, "routeLength")?,
                depart_delay: num(n, "departDelay").unwrap_or(0.0),
                departed: num(n, "depart").is_none_or(|t| t >= 0.0),
                sumo_type: n.attribute("vType").map(String::from),
            };
            Some((n.attribute("id")?.to_string(), trip))
        })
        .collect())
}

/// The CSV text of `rows` (columns: the fields of `T`).
pub fn csv_of<T: Serialize + Default>(rows: &[T]) -> Vec<u8> {
    cells::csv_text(&T::default(), rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vehicle(outcome: Outcome, time_loss: f64, crash: Option<f64>) -> ScenarioVehicle {
        ScenarioVehicle {
            outcome,
            time_loss_s: Some(time_loss),
            crash_time_s: crash,
            ..ScenarioVehicle::default()
        }
    }

    /// A scenario's `vehicles.csv` keeps the columns, decimals and empty fields its rows had
    /// when the scenario vehicle was its own serde record (a crashed truck's row, as an
    /// rl-ppo episode on SUMO's `ramp` game wrote it).
    #[test]
    fn vehicles_csv_keeps_its_columns_decimals_and_empty_fields() {
        let truck = ScenarioVehicle {
            id: "highway1.10".into(),
            sumo_type: "truck".into(),
            kind: Kind::Hdv,
            region: "gneE7".into(),
            region_origin: "main".into(),
            scheduled_depart_s: Some(14.4),
            depart_s: Some(14.4),
            region_enter_s: Some(14.4),
            region_leave_s: Some(39.6),
            region_distance_m: Some(675.0249),
            outcome: Outcome::Crashed,
            time_loss_s: Some(0.94),
            depart_delay_s: Some(0.0),
            route_length_m: Some(679.52),
            crash_time_s: Some(39.8),
            crashed_with: "highway1.11".into(),
            controllable_crash: true,
            region_entry: "main".into(),
            ..ScenarioVehicle::default()
        };
        assert_eq!(
            String::from_utf8(vehicles_csv(&[truck])).unwrap(),
            "id,type,kind,region,region_origin,scheduled_depart_s,depart_s,region_enter_s,\
             region_leave_s,region_distance_m,region_delay_s,outcome,arrival_s,time_loss_s,\
             depart_delay_s,route_length_m,crash_time_s,crashed_with,controllable_crash,\
             region_entry,region_delay_own_s\n\
             highway1.10,truck,hdv,gneE7,main,14.40,14.40,14.40,39.60,675.02,,crashed,,0.94,0.00,\
             679.52,39.80,highway1.11,true,main,\n"
        );
    }

    /// A crash takes a vehicle off the road early: left out, it lowers the mean `timeLoss`;
    /// charged its unfinished trip, it raises it.
    #[test]
    fn a_crashed_vehicle_is_charged_the_rest_of_the_episode() {
        let vehicles = [
            vehicle(Outcome::Arrived, 10.0, None),
            vehicle(Outcome::Present, 20.0, None),
            vehicle(Outcome::Crashed, 2.0, Some(70.0)),
            ScenarioVehicle {
                outcome: Outcome::NeverInserted,
                depart_delay_s: Some(5.0),
                ..ScenarioVehicle::default()
            },
        ];
        let s = Summary::of_scenario(
            Summary::template(crate::episode::summary::Traffic::Scenario),
            &vehicles,
            0,
            100.0,
        );
        assert_eq!(s.time_loss().mean_time_loss_s, Some(15.0));
        // (10 + 20 + (2 + 100 − 70)) / 3
        assert_eq!(
            s.time_loss().mean_time_loss_crashes_charged_s,
            Some(62.0 / 3.0)
        );
        assert_eq!((s.crashed, s.never_inserted, s.inserted), (1, 1, 3));
    }
}
