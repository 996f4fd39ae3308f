//! Which SUMO runs: the one bkpbs was built against, said in every result; a run against
//! another is one error line; and on any version a CAV that changed lanes standing still drives
//! on (on SUMO 1.28 it once stood braking at the lane end for the rest of the episode).
mod common;

use bkpbs::sumo::version::BUILT;
use common::{bkpbs, csv_rows, refused_naming};
use std::collections::BTreeMap;
use std::process::Command;

/// The directory of another SUMO's libsumocpp.so: `BKPBS_OTHER_SUMO_LIB` (make test sets it to
/// the eclipse-sumo wheel's for a Debian build, to Debian's for a wheel build).
fn other_sumo_lib() -> String {
    let dir = std::env::var("BKPBS_OTHER_SUMO_LIB").unwrap_or_default();
    assert!(
        std::path::Path::new(&dir).join("libsumocpp.so").is_file(),
        "no second SUMO to test against: BKPBS_OTHER_SUMO_LIB must name the directory of another \
         SUMO's libsumocpp.so (make test sets it; `make deps SUMO=pip` installs the wheel), got '{dir}'"
    );
    dir
}

#[test]
fn a_run_against_another_libsumo_is_one_error_line_naming_both_versions() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("e");
    let o = Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args(["episode", "--planner", "idm-mobil", "--steps", "5", "--out"])
        .arg(&out)
        .env("LD_LIBRARY_PATH", other_sumo_lib())
        .output()
        .unwrap();
    let built = format!("built against SUMO {BUILT} but runs SUMO");
    refused_naming(&o, &[&built, "libsumocpp.so"]);
    assert!(!out.join("episode.csv").exists());
}

#[test]
fn every_result_names_the_sumo_that_ran_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("c");
    let d = dir.to_str().unwrap();
    let grid = "campaign --planners idm-mobil --alphas 0.5 --lambdas 3000 --seeds 2 --steps 20";
    let args: Vec<&str> = grid.split_whitespace().chain(["--out", d]).collect();
    let o = bkpbs(&args);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let rows = csv_rows(&std::fs::read(dir.join("episodes.csv")).unwrap());
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r["sumo_version"] == BUILT), "{rows:?}");
    let toml = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    assert!(
        toml.contains(&format!("sumo_version = \"{BUILT}\"")),
        "{toml}"
    );
    let version = bkpbs(&["--version"]);
    let text = String::from_utf8_lossy(&version.stdout);
    assert!(text.contains(&format!("SUMO {BUILT}")), "{text}");
}

/// Per CAV, the longest run of consecutive steps it stood (speed 0) on the acceleration lane
/// while bkpbs sent it no speed above 0.
fn longest_commanded_standstill(trajectories: &[BTreeMap<String, String>]) -> (String, usize) {
    let mut run: BTreeMap<&str, usize> = BTreeMap::new();
    let mut longest = (String::new(), 0);
    for r in trajectories.iter().filter(|r| r["type"] == "cav") {
        let held = r["edge"] == "acc"
            && r["speed"].parse::<f64>().unwrap() == 0.0
            && r["speed_sent"].parse::<f64>().is_ok_and(|v| v == 0.0);
        let n = run.entry(r["id"].as_str()).or_default();
        *n = if held { *n + 1 } else { 0 };
        if *n > longest.1 {
            longest = (r["id"].clone(), *n);
        }
    }
    longest
}

/// Default network, α 0.5, λ 3000: the runs where SUMO 1.28 left a CAV braking at the lane
/// end after a lane change at standstill (bk-pbs seed 2, bk-mastar seed 1; 458 brake rows).
#[test]
fn no_cav_stands_braking_at_the_lane_end_after_a_standstill_lane_change() {
    for (planner, seed) in [("bk-pbs", "2"), ("bk-mastar", "1"), ("bk-pbs", "0")] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("e");
        let o = bkpbs(&[
            "episode",
            "--planner",
            planner,
            "--alpha",
            "0.5",
            "--lambda",
            "3000",
            "--seed",
            seed,
            "--trajectories",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", common::stderr(&o));
        let rows = csv_rows(&std::fs::read(out.join("trajectories.csv")).unwrap());
        let (id, steps) = longest_commanded_standstill(&rows);
        // 5 s: a CAV waiting for a gap at the lane end stands ~2 s here on SUMO 1.15.
        assert!(
            steps < 25,
            "{planner} seed {seed}: {id} held at standstill for {steps} steps"
        );
    }
}
