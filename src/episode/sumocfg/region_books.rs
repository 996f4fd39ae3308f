//! The books of an episode's merge regions: the rows of `regions.csv` and of `entries.csv`,
//! both from the same vehicle records and from where each vehicle SUMO never inserted would
//! have come into a region, so that a region's entry rows add up to its row.

use super::entry_rows::{entry_rows, origin_of, region_entries, RegionEntryRow};
use super::records::ScenarioVehicle;
use super::region_rows::{region_rows, RegionKey, RegionRow};
use crate::episode::region::Region;
use crate::episode::summary::Summary;
use crate::model::scene::Origin;

/// The rows of `regions.csv` and `entries.csv` of `regions` over `vehicles`, led by the
/// episode's columns of `head`; `waiting` holds, per vehicle never inserted whose route enters
/// a region, that region's index and the entry's (of its road's `entries`).
pub(super) fn region_books(
    head: &Summary,
    regions: &[Region],
    vehicles: &[ScenarioVehicle],
    waiting: &[(usize, usize)],
) -> (Vec<RegionRow>, Vec<RegionEntryRow>) {
    let key = RegionKey {
        scenario: head.scenario.clone().unwrap_or_default(),
        planner: head.planner.clone(),
        alpha: head.alpha,
        seed: head.seed,
        region: String::new(),
    };
    let names: Vec<String> = regions.iter().map(|r| r.name.clone()).collect();
    let mut rows = region_rows(&key, &names, vehicles);
    for &(g, k) in waiting {
        match origin_of(k) {
            Origin::Main => rows[g].never_inserted_main += 1,
            Origin::Ramp => rows[g].never_inserted_ramp += 1,
        }
    }
    let entries: Vec<(String, Vec<String>)> = (regions.iter())
        .map(|r| region_entries(&r.name, &r.road))
        .collect();
    (rows, entry_rows(&key, &entries, vehicles, waiting))
}
