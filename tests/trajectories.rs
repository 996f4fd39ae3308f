//! Trajectory output on real SUMO: every vehicle-step accounted for, SUMO's own FCD matched,
//! the same bytes for the same seed.

use std::collections::HashMap;

use bkpbs::config::{Config, TrajectoryFormat};
use bkpbs::episode::{self, EpisodeResult};

mod common;

use common::csv_rows;

fn run(planner: &str, format: TrajectoryFormat, extra: impl FnOnce(&mut Config)) -> EpisodeResult {
    let mut c = Config::default();
    c.scenario.alpha = 0.6;
    c.scenario.lambda = 3500.0;
    c.scenario.seed = 7;
    c.scenario.steps = 300;
    c.output.trajectories = format;
    extra(&mut c);
    episode::run(&c, planner).unwrap()
}

#[test]
fn trajectory_rows_account_for_every_vehicle_step() {
    for planner in ["bk-pbs", "idm-mobil", "sumo"] {
        let result = run(planner, TrajectoryFormat::Csv, |_| {});
        let file = result.trajectories.as_ref().unwrap();
        assert_eq!(file.name, "trajectories.csv");
        let rows = csv_rows(&file.bytes);
        let vehicles = csv_rows(&result.vehicles_csv());
        let dt = 0.2;
        let last_label = (300 - 1) as f64 * dt;
        let mut expected_total = 0;
        let mut per_vehicle: HashMap<&str, Vec<f64>> = HashMap::new();
        for r in &rows {
            per_vehicle
                .entry(r["id"].as_str())
                .or_default()
                .push(r["time"].parse().unwrap());
        }
        for v in vehicles.iter().filter(|v| v["outcome"] != "never_inserted") {
            let insert: f64 = v["insert_time_s"].parse().unwrap();
            // Labels insert, insert + dt, …: up to the end, the crash (its reading counts),
            // or the last step before the arrival.
            let count = match v["outcome"].as_str() {
                "present" => ((last_label - insert) / dt).round() as usize + 1,
                "crashed" => {
                    let crash: f64 = v["crash_time_s"].parse().unwrap();
                    ((crash - insert) / dt).round() as usize + 1
                }
                _ => {
                    let arrival: f64 = v["arrival_time_s"].parse().unwrap();
                    ((arrival - insert) / dt - 1e-6).ceil() as usize
                }
            };
            expected_total += count;
            let times = per_vehicle
                .get(v["id"].as_str())
                .cloned()
                .unwrap_or_default();
            assert_eq!(times.len(), count, "{planner} {}: {times:?}", v["id"]);
            for (k, t) in times.iter().enumerate() {
                assert!(
                    (t - (insert + k as f64 * dt)).abs() < 1e-6,
                    "{planner} {}",
                    v["id"]
                );
            }
        }
        assert_eq!(
            rows.len(),
            expected_total,
            "{planner}: rows of unknown vehicles"
        );
        // A commanded CAV carries what was sent at every step but the last (no planning
        // there); HDVs and SUMO-driven CAVs never do.
        for r in &rows {
            let commanded = planner != "sumo" && r["type"] == "cav";
            let planned_step = r["time"].parse::<f64>().unwrap() < last_label - 1e-6;
            assert_eq!(
                !r["source"].is_empty(),
                commanded && planned_step,
                "{planner}: {r:?}"
            );
            assert!(!r["s"].is_empty() && !r["edge"].is_empty(), "{r:?}");
        }
    }
}

#[test]
fn the_same_seed_gives_the_same_trajectory_bytes() {
    let a = run("bk-pbs", TrajectoryFormat::Csv, |_| {});
    let b = run("bk-pbs", TrajectoryFormat::Csv, |_| {});
    assert_eq!(a.trajectories.unwrap().bytes, b.trajectories.unwrap().bytes);
    assert!(run("bk-pbs", TrajectoryFormat::None, |_| {})
        .trajectories
        .is_none());
}

/// The `<vehicle …/>` entries of an FCD file by (time, id), attributes as text.
fn fcd_entries(text: &str) -> HashMap<(String, String), HashMap<String, String>> {
    let mut time = String::new();
    let mut out = HashMap::new();
    for line in text.lines().map(str::trim) {
        if let Some(rest) = line.strip_prefix("<timestep ") {
            time = attributes(rest)["time"].clone();
        } else if let Some(rest) = line.strip_prefix("<vehicle ") {
            let a = attributes(rest);
            out.insert((time.clone(), a["id"].clone()), a);
        }
    }
    out
}

fn attributes(tag: &str) -> HashMap<String, String> {
    tag.split('"')
        .collect::<Vec<_>>()
        .chunks(2)
        .filter(|kv| kv.len() == 2)
        .map(|kv| {
            let key = kv[0].trim().trim_end_matches('=').to_string();
            (key, kv[1].to_string())
        })
        .collect()
}

#[test]
fn fcd_trajectories_match_sumo_s_own_fcd_output() {
    let d = tempfile::tempdir().unwrap();
    let sumo_fcd = d.path().join("sumo-fcd.xml");
    let result = run("bk-pbs", TrajectoryFormat::Fcd, |c| {
        c.sumo.extra_args = vec!["--fcd-output".into(), sumo_fcd.display().to_string()];
    });
    let file = result.trajectories.unwrap();
    assert_eq!(file.name, "trajectories.fcd.xml");
    let ours = fcd_entries(std::str::from_utf8(&file.bytes).unwrap());
    let sumo = fcd_entries(&std::fs::read_to_string(&sumo_fcd).unwrap());
    assert!(ours.len() > 1000, "{} entries", ours.len());
    let mut keys: Vec<_> = ours.keys().collect();
    keys.sort();
    let mut theirs: Vec<_> = sumo.keys().collect();
    theirs.sort();
    assert_eq!(keys, theirs, "the same vehicles at the same times");
    for (k, a) in &ours {
        let b = &sumo[k];
        for f in ["x", "y", "speed", "pos", "angle"] {
            let (x, y): (f64, f64) = (a[f].parse().unwrap(), b[f].parse().unwrap());
            assert!((x - y).abs() <= 0.01, "{k:?} {f}: {x} vs SUMO's {y}");
        }
        assert_eq!(a["lane"], b["lane"], "{k:?}");
        // SUMO names the per-vehicle copy of a type it makes when an HDV's desired speed is
        // set (`hdv@main.5`); the type is the same.
        let base = b["type"].split('@').next().unwrap();
        assert_eq!(a["type"], base, "{k:?}");
    }
}

#[test]
fn plot_draws_the_lane_figures_the_same_way_every_time() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("ep");
    let dir_s = dir.to_str().unwrap();
    let o = common::bkpbs(&[
        "episode",
        "--planner",
        "bk-pbs",
        "--steps",
        "150",
        "--trajectories",
        "--out",
        dir_s,
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let figures = [
        "time_space.png",
        "time_space.svg",
        "speed_field.png",
        "speed_field.svg",
    ];
    let draw = || {
        let o = common::bkpbs(&["plot", dir_s]);
        assert!(o.status.success(), "{}", common::stderr(&o));
        figures.map(|f| std::fs::read(dir.join(f)).unwrap())
    };
    let first = draw();
    assert!(first[0].starts_with(b"\x89PNG"));
    let svg = String::from_utf8(first[1].clone()).unwrap();
    assert!(
        svg.contains("lane 1 (right main lane)") && svg.contains("bk-pbs"),
        "{svg:.300}"
    );
    assert_eq!(first, draw());
}

#[test]
fn plot_without_trajectories_says_how_to_get_them() {
    let d = tempfile::tempdir().unwrap();
    let o = common::bkpbs(&["plot", d.path().to_str().unwrap()]);
    common::refused_naming(&o, &["--trajectories"]);
    let o = common::bkpbs(&["plot", "no/such/dir"]);
    assert!(common::stderr(&o).contains("no/such/dir is not a directory"));
}
