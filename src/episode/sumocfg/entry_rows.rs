//! One row per merge region and entry of an episode on a user's scenario (`entries.csv`): the
//! books of `regions.csv` split by where the vehicles came into the region, the main
//! carriageway and each on-ramp apart. `regions.csv` counts a region's ramps together, so a
//! region of two ramps did not say which of them fed it, nor that one fed nothing.

use serde::Serialize;

use super::records::ScenarioVehicle;
use super::region_rows::{Outcomes, RegionKey};
use crate::episode::cells;
use crate::episode::metrics::mean;
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin};

/// The figures of one entry of a merge region (an `entries.csv` row).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RegionEntryRow {
    /// Its episode and region (the lead columns, inline, as `regions.csv`'s).
    pub key: RegionKey,
    /// The entry: `main`, the main carriageway, or the SUMO edge id of an on-ramp's first edge
    /// in the region (as `vehicles.csv`'s `region_entry`).
    pub entry: String,
    /// `main` or `ramp` (as `vehicles.csv`'s `region_origin`).
    pub origin: String,
    /// Vehicles whose first region it was and which came into it by this entry.
    pub vehicles: usize,
    /// CAVs among them.
    pub cavs: usize,
    /// Vehicles SUMO never inserted (waiting at the end) whose route enters their first
    /// region by this entry.
    pub never_inserted: usize,
    /// What became of its vehicles (inline, as `regions.csv`'s).
    pub outcomes: Outcomes,
    /// Their mean system delay in the region (s), against the region's `v_max`.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_s: Option<f64>,
    /// Their mean system delay in the region against each one's own desired speed (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_own_s: Option<f64>,
}

/// The name of entry `k` (an index of `road.entries`) in the rows: `main` for the main
/// carriageway, an on-ramp's first edge in the region for a ramp.
pub fn entry_name(road: &Road, k: usize) -> String {
    match road.entries.get(k).and_then(|e| e.route.first()) {
        Some(edge) if k > 0 => edge.to_string(),
        _ => "main".into(),
    }
}

/// Where a vehicle coming in by entry `k` (an index of a road's `entries`) comes from: entry 0
/// is the main carriageway, every other an on-ramp.
pub fn origin_of(k: usize) -> Origin {
    if k == 0 {
        Origin::Main
    } else {
        Origin::Ramp
    }
}

/// The entries of a region, in the rows' order: its name, and the name of each entry of its
/// road (the main carriageway first, then the on-ramps in order along the road).
pub fn region_entries(name: &str, road: &Road) -> (String, Vec<String>) {
    let entries = (0..road.entries.len())
        .map(|k| entry_name(road, k))
        .collect();
    (name.to_string(), entries)
}

/// The row of each entry of each region of `regions` (names as [`region_entries`] gives them,
/// in that order), over `vehicles`; `waiting` holds, per vehicle never inserted whose route
/// enters a region, that region's index in `regions` and the entry's. `head` gives the
/// episode's columns.
pub fn entry_rows(
    head: &RegionKey,
    regions: &[(String, Vec<String>)],
    vehicles: &[ScenarioVehicle],
    waiting: &[(usize, usize)],
) -> Vec<RegionEntryRow> {
    let mut rows = Vec::new();
    for (g, (region, entries)) in regions.iter().enumerate() {
        for (k, entry) in entries.iter().enumerate() {
            let origin = origin_of(k).as_str();
            let mine: Vec<&ScenarioVehicle> = (vehicles.iter())
                .filter(|v| v.region == *region && v.region_entry == *entry)
                .filter(|v| v.region_origin == origin)
                .collect();
            let row = RegionEntryRow {
                key: RegionKey {
                    region: region.clone(),
                    ..head.clone()
                },
                entry: entry.clone(),
                origin: origin.into(),
                never_inserted: waiting.iter().filter(|&&w| w == (g, k)).count(),
                ..RegionEntryRow::default()
            };
            rows.push(row_of(row, &mine));
        }
    }
    rows
}

/// `head` filled in with the figures of the vehicles `mine`.
fn row_of(head: RegionEntryRow, mine: &[&ScenarioVehicle]) -> RegionEntryRow {
    let count = |f: &dyn Fn(&ScenarioVehicle) -> bool| mine.iter().filter(|v| f(v)).count();
    RegionEntryRow {
        vehicles: mine.len(),
        cavs: count(&|v| v.kind == Kind::Cav),
        outcomes: Outcomes::of(mine),
        mean_delay_s: mean(mine.iter().filter_map(|v| v.region_delay_s)),
        mean_delay_own_s: mean(mine.iter().filter_map(|v| v.region_delay_own_s)),
        ..head
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::episode::metrics::Outcome;

    fn vehicle(region: &str, origin: &str, entry: &str, delay: f64) -> ScenarioVehicle {
        ScenarioVehicle {
            region: region.into(),
            region_origin: origin.into(),
            region_entry: entry.into(),
            region_delay_s: Some(delay),
            region_delay_own_s: Some(delay / 2.0),
            outcome: Outcome::Arrived,
            ..ScenarioVehicle::default()
        }
    }

    /// Each vehicle in the row of its region and entry, once: a ramp whose first edge SUMO
    /// happens to call `main` is still not the main carriageway.
    #[test]
    fn each_vehicle_is_booked_at_its_own_region_and_entry() {
        let vehicles = [
            vehicle("a", "main", "main", 2.0),
            vehicle("a", "ramp", "main", 4.0),
            vehicle("a", "ramp", "r2", 6.0),
            vehicle("a", "ramp", "r2", 8.0),
            vehicle("b", "main", "main", 1.0),
            vehicle("", "", "", 0.0),
        ];
        let regions = [
            (
                "a".to_string(),
                vec!["main".to_string(), "main".into(), "r2".into()],
            ),
            ("b".to_string(), vec!["main".to_string(), "rb".into()]),
        ];
        let waiting = [(0, 2), (1, 1), (1, 1)];
        let rows = entry_rows(&RegionKey::default(), &regions, &vehicles, &waiting);
        let got: Vec<(&str, &str, &str, usize, usize)> = (rows.iter())
            .map(|r| {
                (
                    &*r.key.region,
                    &*r.entry,
                    &*r.origin,
                    r.vehicles,
                    r.never_inserted,
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                ("a", "main", "main", 1, 0),
                ("a", "main", "ramp", 1, 0),
                ("a", "r2", "ramp", 2, 1),
                ("b", "main", "main", 1, 0),
                ("b", "rb", "ramp", 0, 2),
            ]
        );
        assert_eq!(rows[2].mean_delay_s, Some(7.0));
        assert_eq!(rows[2].mean_delay_own_s, Some(3.5));
        assert_eq!((rows[4].mean_delay_s, rows[4].outcomes.arrived), (None, 0));
    }

    #[test]
    fn the_main_carriageway_is_main_and_a_ramp_its_first_edge() {
        let road = Road::paper_default();
        assert_eq!(
            region_entries("acc", &road),
            ("acc".to_string(), vec!["main".to_string(), "ramp".into()])
        );
    }
}
