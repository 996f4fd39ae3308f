//! One row per merge region of an episode on a user's scenario (`regions.csv`): what the
//! comparison of planners is made of. A scenario's regions differ (A10KW's two carriageways
//! carry different traffic), so a mean over the whole network hides which merge a planner helps;
//! these rows are the vehicles of `vehicles.csv` grouped by the first region each entered.

use serde::Serialize;

use super::records::ScenarioVehicle;
use crate::episode::cells;
use crate::episode::metrics::{mean, Outcome};
use crate::model::scene::{Kind, Origin};

/// Which episode and merge region a row of `regions.csv` or `entries.csv` is of: their lead
/// columns.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RegionKey {
    /// The configuration's file name.
    pub scenario: String,
    /// The controller's name.
    pub planner: String,
    /// The share α of the scenario's vehicles made CAVs.
    pub alpha: f64,
    /// The episode's seed.
    pub seed: u64,
    /// The region: the edges its on-ramps join (as `vehicles.csv`'s `region`).
    pub region: String,
}

/// What became of a group of vehicles of a region (columns of `regions.csv` and
/// `entries.csv`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Outcomes {
    /// Those that reached their route's end.
    pub arrived: usize,
    /// Those removed in collisions.
    pub crashed: usize,
    /// Those still driving at the end.
    pub present: usize,
    /// Those removed in a collision a CAV took part in.
    pub controllable_crashed: usize,
}

impl Outcomes {
    /// The outcomes of `vehicles`.
    pub fn of(vehicles: &[&ScenarioVehicle]) -> Outcomes {
        let count = |o: Outcome| vehicles.iter().filter(|v| v.outcome == o).count();
        Outcomes {
            arrived: count(Outcome::Arrived),
            crashed: count(Outcome::Crashed),
            present: count(Outcome::Present),
            controllable_crashed: vehicles.iter().filter(|v| v.controllable_crash).count(),
        }
    }
}

/// The figures of one merge region (a `regions.csv` row).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RegionRow {
    /// Its episode and region (the lead columns, inline).
    pub key: RegionKey,
    /// Vehicles whose first region it was.
    pub vehicles: usize,
    /// CAVs among them.
    pub cavs: usize,
    /// Those that entered it on the main carriageway.
    pub from_main: usize,
    /// Those that entered it from an on-ramp.
    pub from_ramp: usize,
    /// Vehicles SUMO never inserted (waiting at the end) whose route enters it first, on the
    /// main carriageway.
    pub never_inserted_main: usize,
    /// The same, entering it from an on-ramp.
    pub never_inserted_ramp: usize,
    /// What became of its vehicles (inline).
    pub outcomes: Outcomes,
    /// Mean system delay in the region (s), every vehicle not crashed.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_s: Option<f64>,
    /// The same over its CAVs.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_cav_s: Option<f64>,
    /// The same over its HDVs.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_hdv_s: Option<f64>,
    /// The same over those from the main carriageway.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_main_s: Option<f64>,
    /// The same over those from an on-ramp.
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_ramp_s: Option<f64>,
    /// Mean SUMO `timeLoss` of its vehicles not crashed, over their whole trip (s).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_time_loss_s: Option<f64>,
    /// Whether any vehicle entered it from an on-ramp: without, its figures are of traffic past
    /// a merge nobody used (`entries.csv` says which ramp fed it).
    pub ramp_traffic: bool,
    /// Mean system delay in the region against each vehicle's own desired speed (s), every
    /// vehicle not crashed (`vehicles.csv`'s `region_delay_own_s`).
    #[serde(serialize_with = "cells::opt_decimals::<4, _>")]
    pub mean_delay_own_s: Option<f64>,
}

/// The row of each region named in `regions` (in that order, a region no vehicle entered
/// included), over `vehicles`; `head` gives the episode's columns.
pub fn region_rows(
    head: &RegionKey,
    regions: &[String],
    vehicles: &[ScenarioVehicle],
) -> Vec<RegionRow> {
    regions
        .iter()
        .map(|name| {
            let mine: Vec<&ScenarioVehicle> =
                vehicles.iter().filter(|v| v.region == *name).collect();
            let key = RegionKey {
                region: name.clone(),
                ..head.clone()
            };
            row_of(key, &mine)
        })
        .collect()
}

/// The row of region `key` with the figures of the vehicles `mine`.
fn row_of(key: RegionKey, mine: &[&ScenarioVehicle]) -> RegionRow {
    let count = |f: &dyn Fn(&ScenarioVehicle) -> bool| mine.iter().filter(|v| f(v)).count();
    let delay = |f: &dyn Fn(&ScenarioVehicle) -> bool| {
        mean(
            mine.iter()
                .filter(|v| f(v))
                .filter_map(|v| v.region_delay_s),
        )
    };
    let ramp = Origin::Ramp.as_str();
    let from_ramp = count(&|v| v.region_origin == ramp);
    RegionRow {
        vehicles: mine.len(),
        cavs: count(&|v| v.kind == Kind::Cav),
        from_main: count(&|v| v.region_origin == Origin::Main.as_str()),
        from_ramp,
        outcomes: Outcomes::of(mine),
        mean_delay_s: delay(&|_| true),
        mean_delay_cav_s: delay(&|v| v.kind == Kind::Cav),
        mean_delay_hdv_s: delay(&|v| v.kind == Kind::Hdv),
        mean_delay_main_s: delay(&|v| v.region_origin == Origin::Main.as_str()),
        mean_delay_ramp_s: delay(&|v| v.region_origin == ramp),
        mean_time_loss_s: mean(
            mine.iter()
                .filter(|v| v.outcome != Outcome::Crashed)
                .filter_map(|v| v.time_loss_s),
        ),
        ramp_traffic: from_ramp > 0,
        mean_delay_own_s: mean(mine.iter().filter_map(|v| v.region_delay_own_s)),
        key,
        ..RegionRow::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vehicle(region: &str, kind: Kind, origin: &str, delay: f64) -> ScenarioVehicle {
        ScenarioVehicle {
            region: region.into(),
            kind,
            region_origin: origin.into(),
            region_delay_s: Some(delay),
            region_delay_own_s: Some(delay - 1.0),
            time_loss_s: Some(2.0 * delay),
            outcome: Outcome::Arrived,
            ..ScenarioVehicle::default()
        }
    }

    #[test]
    fn each_region_gets_its_own_vehicles_and_an_empty_one_a_row() {
        let vehicles = [
            vehicle("a", Kind::Cav, "ramp", 4.0),
            vehicle("a", Kind::Hdv, "main", 2.0),
            vehicle("b", Kind::Hdv, "main", 10.0),
            vehicle("", Kind::Hdv, "", 0.0),
        ];
        let regions = ["a".to_string(), "b".into(), "c".into()];
        let rows = region_rows(&RegionKey::default(), &regions, &vehicles);
        assert_eq!(rows.len(), 3);
        let a = &rows[0];
        assert_eq!((a.vehicles, a.cavs, a.from_main, a.from_ramp), (2, 1, 1, 1));
        assert_eq!(a.mean_delay_s, Some(3.0));
        assert_eq!(
            (a.mean_delay_cav_s, a.mean_delay_ramp_s),
            (Some(4.0), Some(4.0))
        );
        assert_eq!(
            (a.mean_delay_hdv_s, a.mean_delay_main_s),
            (Some(2.0), Some(2.0))
        );
        assert_eq!(a.mean_time_loss_s, Some(6.0));
        assert_eq!((a.ramp_traffic, a.mean_delay_own_s), (true, Some(2.0)));
        assert_eq!((rows[1].vehicles, rows[1].mean_delay_s), (1, Some(10.0)));
        assert!(
            !rows[1].ramp_traffic,
            "b's only vehicle came by the main road"
        );
        assert_eq!(rows[1].mean_delay_cav_s, None);
        assert_eq!((rows[2].vehicles, rows[2].mean_delay_s), (0, None));
    }
}
