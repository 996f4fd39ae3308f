//! Regression of the shield on real SUMO: an HDV two lanes over moving into the lane a ramp CAV
//! changes into, in the same second (`controller::shield::far_side`). An audited bk-pbs episode
//! on a two-carriageway scenario with 16.5 m trucks had a ramp CAV on the acceleration lane
//! sent into lane 1 while a truck was alongside in lane 2; the truck moved right into lane 1 in
//! the same second and they collided. Here a three-lane carriageway with an acceleration lane
//! (a lane beyond the ramp CAV's target) carries cars and 16.5 m trucks that SUMO's own lane
//! changing moves between lanes (trucks keep right hard, `lcKeepRight` 10, and the ramp flow
//! is heavy), and neither search planner may take part in a collision.

mod common;

use std::path::{Path, PathBuf};

use common::netconvert::merge_of;
use common::{csv_rows, scenario_run, stderr};

/// Cars and 16.5 m trucks, entering the main road on random lanes 300 m before the merge, and a
/// ramp flow of both, for 150 s (the simulation runs 180 s) at the planners' step.
fn scenario(dir: &Path) -> PathBuf {
    let net = merge_of(dir, 3, 300.0, 250.0);
    let routes = r#"<routes>
    <vTypeDistribution id="mix">
        <vType id="car" probability="0.6" length="5" maxSpeed="33.33"/>
        <vType id="truck16" probability="0.4" vClass="truck" length="16.5" width="2.55" accel="1" decel="4" maxSpeed="25" lcKeepRight="10"/>
    </vTypeDistribution>
    <route id="main" edges="up acc down"/>
    <route id="ramp" edges="on acc down"/>
    <flow id="m" type="mix" route="main" begin="0" end="150" vehsPerHour="3000" departSpeed="max" departLane="random"/>
    <flow id="r" type="mix" route="ramp" begin="0" end="150" vehsPerHour="700" departSpeed="max"/>
</routes>
"#;
    std::fs::write(dir.join("far.rou.xml"), routes).unwrap();
    let cfg = format!(
        r#"<configuration>
    <input><net-file value="{}"/><route-files value="far.rou.xml"/></input>
    <time><begin value="0"/><end value="180"/><step-length value="0.2"/></time>
</configuration>
"#,
        net.file_name().unwrap().to_str().unwrap()
    );
    let path = dir.join("far.sumocfg");
    std::fs::write(&path, cfg).unwrap();
    path
}

/// bk-pbs and bk-mastar, shield on (the default), α 0.55, seeds 26–28: no controllable
/// collision, and HDV trucks and CAV cars crossed the merge. Before the far-side worst case
/// covered HDVs level with a CAV across an acceleration lane's boundary, seed 27 had one under
/// both planners: a CAV in lane 2 changed into lane 1 at 149.2 s beside a ramp truck of 16.5 m
/// that merged in the same step, and they collided 34.6 m into the merge edge at 150.0 s.
#[test]
fn no_ramp_cav_collides_with_an_hdv_moving_in_from_two_lanes_over() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = scenario(dir.path());
    for planner in ["bk-pbs", "bk-mastar"] {
        for seed in ["26", "27", "28"] {
            let out = dir.path().join(format!("{planner}-{seed}"));
            let flags = ["--alpha", "0.55", "--seed", seed];
            let o = scenario_run(&cfg, planner, &flags, &out);
            assert!(o.status.success(), "{planner} {seed}: {}", stderr(&o));
            let ep = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
            let n = |k: &str| ep[k].parse::<u64>().unwrap();
            assert_eq!(n("controllable_crashed"), 0, "{planner} {seed}: {ep:?}");
            let vehicles = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
            let crossed = |kind: &str, vtype: &str| {
                vehicles
                    .iter()
                    .any(|v| v["kind"] == kind && v["type"] == vtype && v["outcome"] == "arrived")
            };
            assert!(
                crossed("hdv", "truck16") && crossed("cav", "car"),
                "{planner} {seed}"
            );
        }
    }
}
