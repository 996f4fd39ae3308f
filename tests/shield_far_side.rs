//! Regression of the shield on real SUMO: an HDV two lanes over moving into the lane a ramp CAV
//! changes into, in the same second (`controller::shield::far_side`). An audited bk-pbs episode
//! on a two-carriageway scenario with 16.5 m trucks had a ramp CAV on the acceleration lane
//! sent into lane 1 while a truck was alongside in lane 2; the truck moved right into lane 1 in
//! the same second and they collided. Here a three-lane carriageway with an acceleration lane
//! (a lane beyond the ramp CAV's target) carries cars and 16.5 m trucks that SUMO's own lane
//! changing moves between lanes (trucks keep right hard, `lcKeepRight` 10, and the ramp flow
//! is heavy: the `trucks-beside-merge` layout of `sumo_net/layouts`, its cars and trucks
//! entering the main road on random lanes 300 m before the merge for 150 s), and neither
//! search planner may take part in a collision.

mod common;

use common::netconvert::layout;
use common::{csv_rows, scenario_run, stderr};

/// bk-pbs and bk-mastar, shield on (the default), α 0.55, seeds 26–28: no controllable
/// collision, and HDV trucks and CAV cars crossed the merge. Before the far-side worst case
/// covered HDVs level with a CAV across an acceleration lane's boundary, seed 27 had one under
/// both planners: a CAV in lane 2 changed into lane 1 at 149.2 s beside a ramp truck of 16.5 m
/// that merged in the same step, and they collided 34.6 m into the merge edge at 150.0 s.
#[test]
fn no_ramp_cav_collides_with_an_hdv_moving_in_from_two_lanes_over() {
    let dir = tempfile::tempdir().unwrap();
    let (_, cfg) = layout(dir.path(), "trucks-beside-merge");
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
