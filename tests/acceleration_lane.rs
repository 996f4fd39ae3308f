//! Vehicles SUMO inserts on an acceleration lane (a scenario's routes may depart there, as
//! A10KW's boundary routes do): each must merge like a ramp vehicle, wherever its route began.
//! Seen as main-road cars, such CAVs were never merged by the planners, and such an HDV,
//! standing at the lane end, was not expected to move over by the shield.

mod common;

use std::path::{Path, PathBuf};

use common::netconvert::merge;
use common::{csv_rows, scenario_run_safely, write_scenario};

/// A two-lane motorway with a 300 m acceleration lane that ends, fed by a one-lane ramp; main
/// traffic, and vehicles departing on the acceleration lane itself, for 200 s.
fn scenario(dir: &Path) -> PathBuf {
    let net = merge(dir, 300.0);
    let routes = r#"<routes>
    <vType id="car" length="5" maxSpeed="33.33"/>
    <vType id="starter" length="5" maxSpeed="33.33" color="1,0,0"/>
    <route id="main" edges="up acc down"/>
    <route id="onacc" edges="acc down"/>
    <flow id="m" type="car" route="main" begin="0" end="200" vehsPerHour="2400" departSpeed="max" departLane="best"/>
    <flow id="s" type="starter" route="onacc" begin="0" end="200" vehsPerHour="300" departLane="0" departPos="20" departSpeed="10"/>
</routes>
"#;
    write_scenario(dir, "acc", &net, routes, 200)
}

#[test]
fn cavs_inserted_on_the_acceleration_lane_merge_and_arrive() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = scenario(dir.path());
    for planner in ["bk-pbs", "bk-mastar"] {
        let out = dir.path().join(planner);
        let flags = ["--cav-types", "starter", "--seed", "2"];
        scenario_run_safely(&cfg, planner, &flags, &out, planner);
        let vehicles = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
        let starters: Vec<_> = vehicles.iter().filter(|v| v["type"] == "starter").collect();
        assert!(
            starters.len() >= 10,
            "{planner}: {} starters",
            starters.len()
        );
        // Every starter that departed in the first 150 s reached the end of its route (1 km
        // at most, well within the 50 s left): none stands at the lane end.
        for v in starters
            .iter()
            .filter(|v| v["depart_s"].parse::<f64>().unwrap() < 150.0)
        {
            assert_eq!(v["kind"], "cav");
            assert_eq!(v["outcome"], "arrived", "{planner}: {v:?}");
        }
    }
}
