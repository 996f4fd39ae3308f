//! Planning on other networks, on real SUMO: the shipped `three-lane` and `corridor` and nets
//! the tests write themselves (other edge ids, straight and curved, 2–4 main lanes, one and two
//! ramps). Every planner runs 400 steps; every vehicle is accounted for and, at every step, in
//! the road frame at the place SUMO has it.

mod common;

use std::path::{Path, PathBuf};

use bkpbs::config::{Config, TrajectoryFormat};
use bkpbs::episode;
use bkpbs::model::road::Road;
use bkpbs::sumo::layout::{Discovery, Layout};
use bkpbs::sumo::network::Net;
use common::netconvert_net;

const PLANNERS: [&str; 4] = ["sumo", "idm-mobil", "bk-mastar", "bk-pbs"];

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("sumo_net/{name}.net.xml"))
}

/// How far SUMO's front-bumper positions lie from where the road frame puts them (m): the
/// largest distance over the rows on the main carriageway's edges, and the largest
/// |x − s_front| there (on a straight net starting at x = 0 the paper's frame had s = x).
struct FrameCheck {
    off_frame_rows: usize,
    worst_xy: f64,
    worst_x_vs_s: f64,
    worst_row: String,
}

/// Reads `trajectories.csv` text and compares each row's frame pose with SUMO's.
fn check_rows(csv: &str, layout: &Layout, config: &Config, road: &Road) -> FrameCheck {
    let mut out = FrameCheck {
        off_frame_rows: 0,
        worst_xy: 0.0,
        worst_x_vs_s: 0.0,
        worst_row: String::new(),
    };
    let half = 0.5 * config.scenario.vehicle_length;
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |k: usize| f[k].parse::<f64>().unwrap();
        if f[10].is_empty() {
            out.off_frame_rows += 1;
            continue;
        }
        let (x, y, s, lane, lateral) = (num(7), num(8), num(10), num(11), num(12));
        // Ramp s counts along the ramp, not the reference line; junction lanes bend off the
        // reference line's own junction lane, so an offset from it says little there.
        if road.edge(f[4]).is_none_or(|e| e.on_ramp) || f[4].starts_with(':') {
            continue;
        }
        let d = (lane - f64::from(road.top_lane())) * road.lane_width + lateral;
        let p = layout.line.to_xy(s + half, d);
        let off = ((p.x - x).powi(2) + (p.y - y).powi(2)).sqrt();
        if off > out.worst_xy {
            out.worst_xy = off;
            out.worst_row = line.to_string();
        }
        out.worst_x_vs_s = out.worst_x_vs_s.max((x - (s + half)).abs());
    }
    out
}

/// Every planner for 400 steps on `net`: all vehicles accounted for, every reading in the
/// frame, the frame where SUMO has the vehicle (to `tol_xy`; on `straight` nets s = x to 1 cm).
fn every_planner_runs_on(net: &Path, straight: bool, tol_xy: f64) {
    let parsed = Net::read(net).unwrap();
    let layout = Discovery::of(&parsed).regions.remove(0);
    let road = bkpbs::sumo::frame::road_from_net(&parsed, net, &[]).unwrap();
    for planner in PLANNERS {
        let mut c = Config::default();
        c.scenario.net_file = Some(net.to_path_buf());
        c.scenario.steps = 400;
        c.scenario.seed = 3;
        c.output.trajectories = TrajectoryFormat::Csv;
        let what = format!("{planner} on {}", net.display());
        let r = episode::run(&c, planner).unwrap_or_else(|e| panic!("{what}: {e}"));
        let s = &r.summary;
        assert!(s.inserted > 20, "{what}: {} inserted", s.inserted);
        assert_eq!(s.scheduled, Some(s.inserted + s.never_inserted), "{what}");
        assert_eq!(s.inserted, s.arrived + s.crashed + s.present, "{what}");
        let file = r.trajectories.unwrap();
        let csv = String::from_utf8(file.bytes).unwrap();
        let check = check_rows(&csv, &layout, &c, &road);
        assert_eq!(check.off_frame_rows, 0, "{what}: readings off the frame");
        assert!(
            check.worst_xy < tol_xy,
            "{what}: frame off by {} m at {}",
            check.worst_xy,
            check.worst_row
        );
        if straight {
            assert!(
                check.worst_x_vs_s < 0.01,
                "{what}: s vs x {}",
                check.worst_x_vs_s
            );
        }
        eprintln!(
            "{what}: inserted {}, arrived {}, crashed {}, frame within {:.3} m",
            s.inserted, s.arrived, s.crashed, check.worst_xy
        );
    }
}

#[test]
fn three_lane() {
    every_planner_runs_on(&shipped("three-lane"), true, 0.01);
}

#[test]
fn corridor() {
    every_planner_runs_on(&shipped("corridor"), false, 0.15);
}

/// Main-road HDVs leave by the corridor's off-ramps (`demand.exit_share`): they arrive at the
/// off-ramp's end, their free-flow reference is that shorter route, and every vehicle is still
/// accounted for.
#[test]
fn vehicles_leave_by_the_off_ramps() {
    for planner in ["sumo", "bk-pbs"] {
        let mut c = Config::default();
        c.scenario.net_file = Some(shipped("corridor"));
        c.scenario.steps = 600;
        c.scenario.lambda = 4000.0;
        c.demand.exit_share = 0.4;
        let r = episode::run(&c, planner).unwrap();
        let s = &r.summary;
        assert_eq!(s.inserted, s.arrived + s.crashed + s.present, "{planner}");
        let off: Vec<_> = r
            .vehicles
            .iter()
            .filter(|v| v.distance < 2500.0 && v.origin == bkpbs::model::scene::Origin::Main)
            .collect();
        assert!(off.len() > 5, "{planner}: {} leaving", off.len());
        let arrived = off.iter().filter(|v| v.arrival_time.is_some()).count();
        assert!(arrived > 0, "{planner}: none arrived at an off-ramp");
        eprintln!(
            "{planner}: {} of {} vehicles leave, {arrived} arrived at an off-ramp",
            off.len(),
            s.inserted
        );
    }
}

#[test]
fn nets_written_by_the_test() {
    for (lanes, ramps, curved) in [
        (2, vec![300.0], false),
        (3, vec![300.0, 900.0], true),
        (4, vec![400.0], true),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let net = netconvert_net(dir.path(), lanes, &ramps, curved);
        // The test's curve bends harder than the corridor's, and junctions cut the lanes of
        // an edge off at different positions: up to 0.4 m was seen there.
        every_planner_runs_on(&net, !curved, if curved { 0.5 } else { 0.01 });
    }
}
