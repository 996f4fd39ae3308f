//! Courtesy in real SUMO (`[planner] courtesy`, on by default on a scenario of the user's own):
//! main-road CAVs leave a ramp HDV ahead of them the gap SUMO's lane-change model asks of its
//! new follower, so SUMO's driver merges at speed instead of waiting at the lane's end for a gap
//! the CAVs' own safety rule never opens wide enough; with `courtesy = false` it waits.

mod common;

use std::path::{Path, PathBuf};

use common::netconvert::merge_of;
use common::{csv_rows, scenario_run_safely, write_scenario};

/// A one-lane motorway with a 200 m acceleration lane: a file of CAVs at up to 25 m/s on the
/// main road (3000 veh/h, 1.2 s apart) and SUMO's drivers entering from the ramp, for 150 s.
fn scenario(dir: &Path) -> PathBuf {
    let net = merge_of(dir, 1, 500.0, 200.0);
    let routes = r#"<routes>
    <vType id="cav" length="5" maxSpeed="25"/>
    <vType id="hdv" length="5" maxSpeed="25"/>
    <route id="main" edges="up acc down"/>
    <route id="onramp" edges="on acc down"/>
    <flow id="m" type="cav" route="main" begin="0" end="150" vehsPerHour="3000" departLane="0" departSpeed="max"/>
    <flow id="r" type="hdv" route="onramp" begin="10" end="150" vehsPerHour="360" departLane="0" departSpeed="15"/>
</routes>
"#;
    write_scenario(dir, "courtesy", &net, routes, 150)
}

/// The ramp HDVs' region delays (s) of one run.
fn ramp_hdv_delays(out: &Path) -> Vec<f64> {
    let rows = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
    (rows.iter())
        .filter(|r| r["kind"] == "hdv" && r["region_origin"] == "ramp")
        .filter(|r| r["outcome"] == "arrived")
        .map(|r| r["region_delay_s"].parse::<f64>().unwrap())
        .collect()
}

#[test]
fn main_road_cavs_let_a_ramp_hdv_ahead_merge() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = scenario(dir.path());
    let off = dir.path().join("off.toml");
    std::fs::write(&off, "[planner]\ncourtesy = false\n").unwrap();
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut flags = vec!["--cav-types", "cav", "--seed", "5"];
        flags.extend_from_slice(extra);
        scenario_run_safely(&cfg, "bk-pbs", &flags, &out, name);
        ramp_hdv_delays(&out)
    };
    let mean = |d: &[f64]| d.iter().sum::<f64>() / d.len() as f64;
    let polite = run("polite", &[]);
    let rude = run("rude", &["--config", off.to_str().unwrap()]);
    // Measured (SUMO 1.15): 11 ramp HDVs arrived, delayed 6.9-15.2 s each, against 8 delayed
    // 6.9-41.1 s (the first two alike, before the main road filled up).
    assert!(
        polite.len() >= 10 && polite.len() > rude.len(),
        "{polite:?} {rude:?}"
    );
    assert!(mean(&polite) + 5.0 < mean(&rude), "{polite:?} {rude:?}");
}
