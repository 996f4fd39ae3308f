//! Gap seeking in real SUMO (`[planner] gap_seeking`, on by default on a scenario of the user's
//! own): beside a slow, dense right lane a ramp CAV on the acceleration lane lines up behind a
//! gap at that lane's speed instead of racing down the empty lane and braking at its end; with
//! `gap_seeking = false` (the paper's search) it races.

mod common;

use std::path::{Path, PathBuf};

use common::netconvert::merge;
use common::{csv_rows, scenario_run_safely, write_scenario};

/// Lane 1's cars drive at most this fast (m/s).
const SLOW: f64 = 8.0;

/// A two-lane motorway with a 300 m acceleration lane; its right lane a dense file of cars at
/// [`SLOW`] m/s, its left lane free, and ramp cars (the CAVs) entering at 15 m/s, for 150 s.
fn scenario(dir: &Path) -> PathBuf {
    let net = merge(dir, 300.0);
    let routes = format!(
        r#"<routes>
    <vType id="slow" length="5" maxSpeed="{SLOW}" lcStrategic="0" lcSpeedGain="0" lcKeepRight="0"/>
    <vType id="ramp" length="5" maxSpeed="33.33"/>
    <route id="main" edges="up acc down"/>
    <route id="onramp" edges="on acc down"/>
    <flow id="m" type="slow" route="main" begin="0" end="150" vehsPerHour="1500" departLane="0" departSpeed="max"/>
    <flow id="r" type="ramp" route="onramp" begin="20" end="150" vehsPerHour="240" departLane="0" departSpeed="15"/>
</routes>
"#
    );
    write_scenario(dir, "gap", &net, &routes, 150)
}

/// Where and how fast each ramp CAV that moved over on the acceleration lane started to: its
/// position along the lane (m, SUMO's `pos` on edge `acc`) and speed (m/s).
fn merges(out: &Path) -> Vec<(f64, f64)> {
    let region = (std::fs::read_dir(out.join("trajectories")).unwrap())
        .next()
        .unwrap()
        .unwrap();
    let rows = csv_rows(&std::fs::read(region.path().join("trajectories.csv")).unwrap());
    let mut started = std::collections::BTreeMap::new();
    for r in rows
        .iter()
        .filter(|r| r["type"] == "cav" && r["origin"] == "ramp")
    {
        let moving_over = r["lateral"].parse::<f64>().unwrap().abs() > 0.1;
        if r["edge"] == "acc" && r["lane"] == "0" && moving_over {
            let at = |k: &str| r[k].parse::<f64>().unwrap();
            started
                .entry(r["id"].clone())
                .or_insert((at("pos"), at("speed")));
        }
    }
    started.into_values().collect()
}

#[test]
fn a_ramp_cav_beside_a_slow_lane_keeps_to_its_speed() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = scenario(dir.path());
    let off = dir.path().join("off.toml");
    std::fs::write(&off, "[planner]\ngap_seeking = false\n").unwrap();
    // Each run: where its ramp CAVs started to move over (position on `acc`, speed).
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut flags = vec!["--cav-types", "ramp", "--seed", "3", "--trajectories"];
        flags.extend_from_slice(extra);
        scenario_run_safely(&cfg, "bk-pbs", &flags, &out, name);
        merges(&out)
    };
    // The first three find lane 1 still free; the later ones meet its file of slow cars, and
    // the lane ends about 300 m after it begins.
    let seeking = run("seeking", &[]);
    assert!(seeking.len() >= 7, "{seeking:?}");
    let early_and_moving = |&(pos, speed): &(f64, f64)| pos <= 220.0 && speed >= 5.0;
    assert!(seeking.iter().all(early_and_moving), "{seeking:?}");
    // The paper's search races down the empty lane and merges late, or from a stand.
    let racing = run("racing", &["--config", off.to_str().unwrap()]);
    assert!(!racing.iter().all(early_and_moving), "{racing:?}");
}
