//! The books per region entry (`entries.csv`, `vehicles.csv`'s `region_entry`, `regions.csv`'s
//! `ramp_traffic`) and the region delay against each vehicle's own desired speed, on a
//! scripted SUMO ([`FakeSumo`]), with the helpers of the loop's own tests.

use std::sync::Arc;

use super::entry_rows::RegionEntryRow;
use super::run::ScenarioRun;
use super::tests::{began, config, finish, paper_run, play, record, sumo_for};
use super::{regions, RegionRow, ScenarioResult};
use crate::episode::metrics::Outcome;
use crate::model::kinematics::free_flow_time;
use crate::model::road::{EdgeFrame, Entry, LaneFrame, MergeZone, Road};
use crate::sumo::fake::{FakeVehicle, Reading, Step};

/// The paper merge with a second on-ramp `ramp2` (frame `s` 360–460) joining `acc2`
/// (460–640, its acceleration lane to 640) past `main_out`, then `out2` (640–770): one region
/// of two ramps, named `acc acc2`, whose entries are `main`, `ramp` and `ramp2`.
fn two_ramps() -> Road {
    let mut road = Road::paper_default();
    let edge = |name: &str, lanes: std::ops::Range<i32>, s0, on_ramp| EdgeFrame {
        name: Arc::from(name),
        lanes: lanes
            .map(|l| Some(LaneFrame::straight(l, s0).limited(40.0)))
            .collect(),
        on_ramp,
    };
    road.edges.extend([
        edge("acc2", 0..3, 460.0, false),
        edge("out2", 1..3, 640.0, false),
        edge("ramp2", 0..1, 360.0, true),
    ]);
    road.zones.push(MergeZone {
        lane: 0,
        ramp_start: 360.0,
        start: 460.0,
        end: 640.0,
        weaving: false,
        ramp: true,
        nose: false,
    });
    road.section_end = 770.0;
    road.end_edge = (Arc::from("out2"), 130.0);
    let main = ["main_in", "acc", "main_out", "acc2", "out2"];
    road.entries = vec![
        Entry::new("main", &main, 40.0),
        Entry::new("ramp1", &["ramp", "acc", "main_out", "acc2", "out2"], 40.0),
        Entry::new("ramp2", &["ramp2", "acc2", "out2"], 40.0),
    ];
    road
}

/// The loop over one region of `road`, SUMO's drivers driving everybody (α 0).
fn run_on(road: Road) -> ScenarioRun<'static> {
    let c = config(0.0, 7);
    ScenarioRun::of_regions(&c, regions(&c, vec![road], "sumo").unwrap())
}

/// Whether the entry rows of `region` add up to its `regions.csv` row: every vehicle, and
/// every one never inserted, booked at exactly one entry.
fn assert_entries_add_up(row: &RegionRow, entries: &[RegionEntryRow]) {
    let mine: Vec<&RegionEntryRow> = entries
        .iter()
        .filter(|e| e.key.region == row.key.region)
        .collect();
    let sum = |f: &dyn Fn(&RegionEntryRow) -> usize| mine.iter().map(|e| f(e)).sum::<usize>();
    let ramps = |f: &dyn Fn(&RegionEntryRow) -> usize| {
        (mine.iter())
            .filter(|e| e.origin == "ramp")
            .map(|e| f(e))
            .sum::<usize>()
    };
    let never = row.never_inserted_main + row.never_inserted_ramp;
    assert_eq!(sum(&|e| e.vehicles), row.vehicles, "{row:?}");
    assert_eq!(sum(&|e| e.cavs), row.cavs);
    assert_eq!(sum(&|e| e.never_inserted), never);
    assert_eq!(sum(&|e| e.outcomes.arrived), row.outcomes.arrived);
    assert_eq!(sum(&|e| e.outcomes.crashed), row.outcomes.crashed);
    assert_eq!(sum(&|e| e.outcomes.present), row.outcomes.present);
    assert_eq!(
        sum(&|e| e.outcomes.controllable_crashed),
        row.outcomes.controllable_crashed
    );
    assert_eq!(ramps(&|e| e.vehicles), row.from_ramp);
    assert_eq!(ramps(&|e| e.never_inserted), row.never_inserted_ramp);
}

/// The rows of `result`'s entries as (entry, origin, vehicles, never inserted, arrived).
fn entry_counts(result: &ScenarioResult) -> Vec<(&str, &str, usize, usize, usize)> {
    (result.entries.iter())
        .map(|e| {
            let counts = (e.vehicles, e.never_inserted, e.outcomes.arrived);
            (&*e.entry, &*e.origin, counts.0, counts.1, counts.2)
        })
        .collect()
}

/// `m` comes by the main road, `r1` by the first ramp, `r2a` and `r2b` by the second (`r2b`
/// arrives); of those SUMO never inserts, `w1`'s route enters the region by the second ramp,
/// `w2`'s by the main road, `w3`'s not at all.
#[test]
fn two_ramps_of_one_region_are_booked_apart_and_add_up_to_its_row() {
    let waiting = |step: Step| {
        step.wait_on("w1", &["up", "ramp2", "acc2", "out2"])
            .wait_on("w2", &["main_in", "acc", "main_out", "acc2", "out2"])
            .wait("w3")
    };
    let at = |k: f64| {
        Step::default()
            .read(Reading::on("m", "main_in", 0, 10.0 + 6.0 * k, 30.0))
            .read(Reading::on("r1", "ramp", 0, 20.0 + 4.0 * k, 20.0))
            .read(Reading::on("r2a", "ramp2", 0, 5.0 + 4.0 * k, 20.0))
    };
    let script = vec![
        waiting(at(0.0))
            .depart(FakeVehicle::new("m", "car"))
            .depart(FakeVehicle::new("r1", "car"))
            .depart(FakeVehicle::new("r2a", "car"))
            .depart(FakeVehicle::new("r2b", "car"))
            .read(Reading::on("r2b", "ramp2", 0, 40.0, 20.0)),
        waiting(at(1.0)).arrive("r2b"),
    ];
    let mut run = run_on(two_ramps());
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 2);
    let result = finish(run, "");
    assert_eq!(result.summary.regions.as_deref(), Some("acc acc2"));
    assert_eq!(
        entry_counts(&result),
        [
            ("main", "main", 1, 1, 0),
            ("ramp", "ramp", 1, 0, 0),
            ("ramp2", "ramp", 2, 1, 1),
        ]
    );
    for (id, entry) in [
        ("m", "main"),
        ("r1", "ramp"),
        ("r2a", "ramp2"),
        ("r2b", "ramp2"),
    ] {
        assert_eq!(record(&result, id).region_entry, entry, "{id}");
    }
    assert_eq!(
        record(&result, "w1").region_entry,
        "",
        "never inserted, entered none"
    );
    let row = &result.regions[0];
    assert_eq!(
        (row.from_main, row.from_ramp, row.ramp_traffic),
        (1, 3, true)
    );
    assert_eq!((row.never_inserted_main, row.never_inserted_ramp), (1, 1));
    assert_entries_add_up(row, &result.entries);
    assert!(result.no_ramp_traffic_warnings().is_empty());
}

/// A region fed by its main road alone says so: `ramp_traffic` false, one warning naming its
/// ramp, and an entry row of zeros for the ramp.
#[test]
fn a_region_without_ramp_traffic_is_flagged_and_its_ramp_counts_zero() {
    let script = (0..3)
        .map(|k| {
            let step =
                Step::default().read(Reading::on("m", "acc", 1, 10.0 + 6.0 * f64::from(k), 30.0));
            if k == 0 {
                step.depart(FakeVehicle::new("m", "car"))
            } else {
                step
            }
        })
        .collect();
    let mut run = run_on(Road::paper_default());
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, 3);
    let result = finish(run, "");
    assert!(!result.regions[0].ramp_traffic);
    assert_eq!(
        entry_counts(&result),
        [("main", "main", 1, 0, 0), ("ramp", "ramp", 0, 0, 0)]
    );
    assert_entries_add_up(&result.regions[0], &result.entries);
    let warnings = result.no_ramp_traffic_warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].starts_with("warning: region acc received no vehicle from its on-ramp (ramp)"),
        "{warnings:?}"
    );
}

/// Vehicles cruising at 32 m/s through the region: `slow` wants 0.8 × the carriageway's
/// 40 m/s, `truck` is a type of 32 m/s top speed; each drives at its own desired speed and
/// loses nothing against it, while against the region's 35 m/s each loses what accelerating to
/// it would have won. `fast` (factor 1.2: 48 m/s) loses more against its own than against
/// the region's.
#[test]
fn the_own_speed_delay_is_measured_at_each_vehicles_own_desired_speed() {
    let fleet = [
        (
            "slow",
            0,
            FakeVehicle::new("slow", "car").desiring(0.8, 55.56),
        ),
        (
            "truck",
            1,
            FakeVehicle::new("truck", "truck").desiring(1.0, 32.0),
        ),
        (
            "fast",
            1,
            FakeVehicle::new("fast", "car").desiring(1.2, 55.56),
        ),
    ];
    let steps = 10;
    let script = (0..steps)
        .map(|k| {
            let mut step = Step::default();
            for (j, (id, lane, v)) in fleet.iter().enumerate() {
                if k == 0 {
                    step = step.depart(v.clone());
                }
                let pos = 10.0 + 20.0 * j as f64 + 6.4 * f64::from(k);
                step = step.read(Reading::on(id, "main_in", *lane, pos, 32.0));
            }
            step
        })
        .collect();
    let mut run = paper_run(&config(0.0, 3), "sumo");
    let mut sim = sumo_for(&run, script);
    play(&mut run, &mut sim, steps);
    let result = finish(run, "");
    let time = began(steps) - began(1);
    let distance = 6.4 * f64::from(steps - 1);
    let top = time - free_flow_time(distance, 32.0, 3.0, 35.0);
    assert!(top > 0.1, "{top}");
    for id in ["slow", "truck", "fast"] {
        let v = record(&result, id);
        assert_eq!(v.outcome, Outcome::Present);
        let (delay, own) = (v.region_delay_s.unwrap(), v.region_delay_own_s.unwrap());
        assert!((delay - top).abs() < 1e-9, "{id}: {delay} against {top}");
        match id {
            "fast" => assert!(own > delay + 0.01, "{id}: {own} vs {delay}"),
            _ => assert!(own.abs() < 1e-9, "{id}: {own}"),
        }
    }
    let row = &result.regions[0];
    let own_mean = row.mean_delay_own_s.unwrap();
    let fast = record(&result, "fast").region_delay_own_s.unwrap();
    assert!((own_mean - fast / 3.0).abs() < 1e-9, "{row:?}");
    assert_eq!(result.entries[0].mean_delay_own_s, row.mean_delay_own_s);
}
