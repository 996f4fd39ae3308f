//! HDV driver profiles on real SUMO: SUMO accepts every built-in profile's types, and each
//! profile's defining behaviour shows.

use std::collections::{BTreeSet, HashMap};

use bkpbs::config::{Config, TrajectoryFormat};
use bkpbs::episode::{self, EpisodeResult};

fn run(profile: &str, seed: u64, steps: u32, extra: impl FnOnce(&mut Config)) -> EpisodeResult {
    let mut c = Config::default();
    c.hdv.profile = profile.into();
    c.scenario.seed = seed;
    c.scenario.steps = steps;
    c.output.trajectories = TrajectoryFormat::Csv;
    extra(&mut c);
    c.validate().unwrap();
    episode::run(&c, "sumo").unwrap_or_else(|e| panic!("{profile}: {e}"))
}

#[test]
fn sumo_accepts_every_built_in_profile() {
    for profile in bkpbs::config::hdv::BUILT_IN {
        let r = run(profile, 0, 150, |_| {});
        assert!(r.summary.inserted > 10, "{profile}: {:?}", r.summary);
        assert!(!r.sumo_log.contains("Error"), "{profile}: {}", r.sumo_log);
    }
}

/// A trajectory row, the fields used here.
struct Row {
    time: String,
    id: String,
    hdv: bool,
    ramp: bool,
    lane: String,
    s: f64,
    speed: f64,
}

fn rows(r: &EpisodeResult) -> Vec<Row> {
    let bytes = &r.trajectories.as_ref().unwrap().bytes;
    let mut reader = csv::Reader::from_reader(&bytes[..]);
    reader
        .records()
        .map(|rec| {
            let rec = rec.unwrap();
            Row {
                time: rec[0].to_string(),
                id: rec[1].to_string(),
                hdv: &rec[2] == "hdv",
                ramp: &rec[3] == "ramp",
                lane: rec[11].to_string(),
                s: rec[10].parse().unwrap(),
                speed: rec[14].parse().unwrap(),
            }
        })
        .collect()
}

/// For each ramp HDV's move from the acceleration lane to lane 1, the gap to its new follower
/// divided by the IDM's safe gap s0 + T·v_f + (v_f² − v_m²)/(2b) (with `[idm]`'s parameters).
fn merge_gap_ratios(r: &EpisodeResult) -> Vec<f64> {
    let c = Config::default();
    let (s0, t, b, len) = (c.idm.min_gap, c.idm.time_headway, c.idm.decel, 5.0);
    let all = rows(r);
    let mut by_time: Vec<(&str, Vec<&Row>)> = Vec::new();
    for row in &all {
        match by_time.last_mut() {
            Some((t, v)) if *t == row.time => v.push(row),
            _ => by_time.push((&row.time, vec![row])),
        }
    }
    let mut lane_of: HashMap<&str, &str> = HashMap::new();
    let mut ratios = Vec::new();
    for (_, step) in &by_time {
        for m in step {
            let moved = lane_of.get(m.id.as_str()) == Some(&"0") && m.lane == "1";
            if moved && m.hdv && m.ramp {
                let follower = step
                    .iter()
                    .filter(|u| u.lane == "1" && u.s < m.s)
                    .max_by(|a, b| a.s.total_cmp(&b.s));
                if let Some(f) = follower {
                    let gap = m.s - f.s - len;
                    let safe = s0 + t * f.speed + (f.speed.powi(2) - m.speed.powi(2)) / (2.0 * b);
                    ratios.push(gap / safe.max(0.1));
                }
            }
            lane_of.insert(&m.id, &m.lane);
        }
    }
    ratios
}

#[test]
fn paper_drivers_take_gaps_shorter_than_safe_and_sumo_safe_ones_do_not() {
    let smallest = |profile: &str| {
        (0..5)
            .flat_map(|seed| merge_gap_ratios(&run(profile, seed, 300, |_| {})))
            .fold(f64::INFINITY, f64::min)
    };
    let (safe, paper) = (smallest("sumo-safe"), smallest("paper"));
    assert!(
        paper < 0.7,
        "paper's smallest merge gap is {paper:.2} of the safe gap"
    );
    assert!(
        safe > 0.8,
        "sumo-safe's smallest merge gap is {safe:.2} of the safe gap"
    );
}

#[test]
fn heterogeneous_drivers_differ() {
    let d = tempfile::tempdir().unwrap();
    let fcd = d.path().join("fcd.xml");
    run("heterogeneous", 1, 150, |c| {
        c.sumo.extra_args = vec!["--fcd-output".into(), fcd.display().to_string()];
    });
    // SUMO's own output names each HDV's driver type (`hdv.7`, or `hdv.7@id` once bkpbs set
    // its desired speed).
    let text = std::fs::read_to_string(&fcd).unwrap();
    let types: BTreeSet<&str> = text
        .split("type=\"")
        .skip(1)
        .filter_map(|t| t.split('"').next())
        .filter(|t| t.starts_with("hdv."))
        .map(|t| t.split('@').next().unwrap())
        .collect();
    assert!(types.len() >= 5, "driver types seen: {types:?}");
    let vtypes = bkpbs::sumo::files::vehicle_types(
        &{
            let mut c = Config::default();
            c.hdv.profile = "heterogeneous".into();
            c
        },
        4.5,
    );
    let taus: BTreeSet<&str> = vtypes
        .split("tau=\"")
        .skip(1)
        .filter_map(|t| t.split('"').next())
        .collect();
    assert!(taus.len() >= 15, "{taus:?}");
}

#[test]
fn krauss_and_eidm_drive_differently_from_the_idm() {
    let idm = run("sumo-safe", 2, 200, |_| {});
    for profile in ["krauss", "eidm"] {
        let other = run(profile, 2, 200, |_| {});
        assert_ne!(
            idm.trajectories.as_ref().unwrap().bytes,
            other.trajectories.as_ref().unwrap().bytes,
            "{profile}"
        );
    }
}
