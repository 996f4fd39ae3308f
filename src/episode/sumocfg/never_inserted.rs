//! The vehicles of a user's scenario that SUMO never inserted: those whose departure time came
//! during the episode but which SUMO still held back after its last step (its pending
//! vehicles, the `waiting` of its statistics). Each is a `vehicles.csv` row of outcome
//! `never_inserted` (the paper demand's [`Outcome::NeverInserted`]), with SUMO's own figures
//! from the undeparted trips of its tripinfo output (`--tripinfo-output.write-undeparted`,
//! SUMO 1.9.1 and later): its vehicle type, and its `departDelay`, the time from its departure
//! time to the end, from which that departure time follows.

use std::collections::BTreeMap;

use super::records::{ScenarioVehicle, Trip};
use crate::episode::metrics::Outcome;
use crate::model::scene::Kind;

/// The row of each vehicle of `pending` (in that order), SUMO's `trips` giving its type and its
/// wait to the episode's `end` (s); `kind_of(id, type)` says what it would have been had it
/// departed. A vehicle without a trip (its tripinfo device switched off) has neither.
pub fn never_inserted_rows(
    pending: &[String],
    trips: &BTreeMap<String, Trip>,
    end: f64,
    kind_of: impl Fn(&str, &str) -> Kind,
) -> Vec<ScenarioVehicle> {
    pending
        .iter()
        .map(|id| {
            let trip = trips.get(id).filter(|t| !t.departed);
            let sumo_type = trip.and_then(|t| t.sumo_type.clone()).unwrap_or_default();
            let wait = trip.map(|t| t.depart_delay);
            ScenarioVehicle {
                id: id.clone(),
                kind: kind_of(id, &sumo_type),
                sumo_type,
                scheduled_depart_s: wait.map(|w| to_ms(end - w)),
                depart_delay_s: wait,
                outcome: Outcome::NeverInserted,
                ..ScenarioVehicle::default()
            }
        })
        .collect()
}

/// `t` (s) on SUMO's clock, which counts whole milliseconds.
pub fn to_ms(t: f64) -> f64 {
    (t * 1000.0).round() / 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trip(departed: bool, depart_delay: f64, sumo_type: &str) -> Trip {
        Trip {
            time_loss: 0.0,
            route_length: 5.1,
            depart_delay,
            departed,
            sumo_type: Some(sumo_type.into()),
        }
    }

    /// Each pending vehicle is one row: its type and wait from SUMO's undeparted trip, its
    /// departure time the end less that wait; one SUMO wrote no trip for keeps its id alone.
    #[test]
    fn each_pending_vehicle_is_a_row_with_its_wait_to_the_end() {
        let trips = BTreeMap::from([
            ("m.102".to_string(), trip(false, 16.56, "truck")),
            ("r.62".to_string(), trip(false, 0.72, "car")),
            ("a".to_string(), trip(true, 1.0, "car")),
        ]);
        let pending = ["m.102".to_string(), "r.62".into(), "lost".into()];
        let rows = never_inserted_rows(&pending, &trips, 90.0, |_, t| match t {
            "truck" => Kind::Cav,
            _ => Kind::Hdv,
        });
        assert_eq!(rows.len(), 3);
        let m = &rows[0];
        assert_eq!((m.id.as_str(), m.sumo_type.as_str()), ("m.102", "truck"));
        assert_eq!((m.kind, m.outcome), (Kind::Cav, Outcome::NeverInserted));
        assert_eq!(
            (m.scheduled_depart_s, m.depart_delay_s),
            (Some(73.44), Some(16.56))
        );
        assert_eq!((m.depart_s, m.time_loss_s, m.arrival_s), (None, None, None));
        assert_eq!(rows[1].scheduled_depart_s, Some(89.28));
        let lost = &rows[2];
        assert_eq!((lost.id.as_str(), lost.kind), ("lost", Kind::Hdv));
        assert_eq!((lost.scheduled_depart_s, lost.depart_delay_s), (None, None));
    }
}
