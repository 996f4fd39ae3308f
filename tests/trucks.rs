//! Trucks of 12 and 16.5 m among the CAVs, on a merge the test builds with netconvert and a
//! scenario of its own (`--sumocfg`): the planners see each vehicle with its own type's
//! length, top speed and acceleration, so a CAV truck is planned as a truck (never faster than
//! its type allows: its SUMO timeLoss is never negative; never told to accelerate harder than
//! its type can), and neither search planner takes part in a collision.

mod common;

use std::path::{Path, PathBuf};

use common::netconvert::merge;
use common::{csv_rows, scenario_run, stderr, write_scenario};

/// Cars, 12 m trucks and 16.5 m trucks with their own accelerations and top speeds, on the
/// main road and the ramp, for 300 s at the planners' step.
fn scenario(dir: &Path) -> PathBuf {
    let net = merge(dir, 200.0);
    let routes = r#"<routes>
    <vTypeDistribution id="mix">
        <vType id="car" probability="0.5" length="5" maxSpeed="33.33"/>
        <vType id="truck12" probability="0.25" vClass="truck" length="12" accel="1.3" decel="4" maxSpeed="25"/>
        <vType id="truck16" probability="0.25" vClass="truck" length="16.5" width="2.55" accel="1" decel="4" maxSpeed="22.22"/>
    </vTypeDistribution>
    <route id="main" edges="up acc down"/>
    <route id="ramp" edges="on acc down"/>
    <flow id="m" type="mix" route="main" begin="0" end="300" vehsPerHour="1800" departSpeed="max" departLane="best"/>
    <flow id="r" type="mix" route="ramp" begin="0" end="300" vehsPerHour="400" departSpeed="max"/>
</routes>
"#;
    write_scenario(dir, "mix", &net, routes, 300)
}

#[test]
fn cav_trucks_are_planned_with_their_own_length_and_no_search_planner_collides() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = scenario(dir.path());
    for planner in ["bk-pbs", "bk-mastar"] {
        let out = dir.path().join(planner);
        let flags = ["--alpha", "0.8", "--seed", "5", "--trajectories"];
        let o = scenario_run(&cfg, planner, &flags, &out);
        assert!(o.status.success(), "{planner}: {}", stderr(&o));
        let ep = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
        let n = |k: &str| ep[k].parse::<u64>().unwrap();
        assert_eq!(n("inserted"), n("arrived") + n("present") + n("crashed"));
        assert_eq!(n("controllable_crashed"), 0, "{planner}: {ep:?}");
        let vehicles = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
        for truck in ["truck12", "truck16"] {
            for origin in ["main", "ramp"] {
                let driven = vehicles.iter().filter(|v| {
                    v["type"] == truck && v["kind"] == "cav" && v["region_origin"] == origin
                });
                let arrived: Vec<_> = driven.filter(|v| v["outcome"] == "arrived").collect();
                assert!(
                    arrived.len() >= 2,
                    "{planner}: {truck} CAVs from {origin} that crossed the merge"
                );
                // Planned at the carriageway's 33.33 m/s, they lost -2.7 s against their own
                // top speed.
                for v in arrived {
                    let loss: f64 = v["time_loss_s"].parse().unwrap();
                    assert!(
                        loss >= 0.0,
                        "{planner}: {} faster than its type: {loss}",
                        v["id"]
                    );
                }
            }
        }
        within_their_accelerations(planner, &out, &vehicles);
    }
}

/// Every speed the planner sent a CAV truck is reachable at its type's `accel` (1.3 and 1 m/s²,
/// below the planner's 2) from the speed it drove at along its path: the planner asked no more
/// of it.
fn within_their_accelerations(
    planner: &str,
    out: &Path,
    vehicles: &[std::collections::BTreeMap<String, String>],
) {
    let accel = |t: &str| match t {
        "truck12" => Some(1.3),
        "truck16" => Some(1.0),
        _ => None,
    };
    let of: std::collections::HashMap<&str, f64> = vehicles
        .iter()
        .filter_map(|v| Some((v["id"].as_str(), accel(&v["type"])?)))
        .collect();
    let region = std::fs::read_dir(out.join("trajectories"))
        .unwrap()
        .next()
        .unwrap();
    let rows = csv_rows(&std::fs::read(region.unwrap().path().join("trajectories.csv")).unwrap());
    let mut checked = 0;
    for r in rows.iter().filter(|r| !r["speed_sent"].is_empty()) {
        let Some(a) = of.get(r["id"].as_str()) else {
            continue;
        };
        let num = |k: &str| r[k].parse::<f64>().unwrap();
        // Planned from its speed along its path (mid lane change, it heads off the road).
        let (sent, speed) = (num("speed_sent"), num("speed") / num("heading").cos());
        assert!(
            sent - speed <= a * 0.2 + 0.02,
            "{planner}: {} at {} told {sent} from {speed} (accel {a}): {r:?}",
            r["id"],
            r["time"]
        );
        checked += 1;
    }
    assert!(checked > 500, "{planner}: {checked} commands to CAV trucks");
}
