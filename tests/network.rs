//! The merge network, read back through libsumo (real SUMO, in-process).

mod common;

use bkpbs::config::Config;
use bkpbs::sumo::files::EpisodeInput;
use bkpbs::sumo::frame::embedded_road;
use bkpbs::sumo::Simulation;
use common::netconvert_net;

#[test]
fn net_has_the_papers_geometry() {
    let config = Config::default();
    let input = EpisodeInput::write(&config, &embedded_road()).unwrap();
    let sim = Simulation::start(&input.command_line(&config), config.sumo.stall_limit()).unwrap();
    // Lane counts per edge.
    for (edge, lanes) in [("main_in", 2), ("ramp", 1), ("acc", 3), ("main_out", 2)] {
        assert_eq!(sim.edge_lane_count(edge).unwrap(), lanes, "{edge}");
    }
    // Every lane is 4.5 m wide; the section is 460 m long with a 180 m acceleration lane.
    for lane in sim.lane_ids().unwrap() {
        assert!(
            (sim.lane_width(&lane).unwrap() - 4.5).abs() < 1e-9,
            "{lane}"
        );
        assert!(
            sim.lane_max_speed(&lane).unwrap() > config.scenario.v_max,
            "{lane}"
        );
    }
    let len = |l: &str| sim.lane_length(l).unwrap();
    assert!((len("main_in_0") + len("acc_1") + len("main_out_0") - 460.0).abs() < 1e-6);
    assert!((len("acc_0") - 180.0).abs() < 1e-6);
    // The main road is straight along x: lane shapes run at constant y, starting where s says.
    let road = embedded_road();
    let zone = road.zones[0];
    assert_eq!(
        (zone.start, zone.end, road.section_end),
        (150.0, 330.0, 460.0)
    );
    for (edge, s0) in [("main_in", 0.0), ("acc", 150.0), ("main_out", 330.0)] {
        let shape = sim.lane_shape(&format!("{edge}_0")).unwrap();
        assert!(
            (shape[0].0 - s0).abs() < 1e-6,
            "{edge} starts at x = {}",
            shape[0].0
        );
        assert!(
            shape.iter().all(|p| (p.1 - shape[0].1).abs() < 1e-9),
            "{edge} is straight"
        );
    }
    // The acceleration lane leads nowhere: its shape ends at the merge end, and main_out, the
    // only edge after it, has no lane in the frame lane it would continue.
    let acc = sim.lane_shape("acc_0").unwrap();
    assert!((acc.last().unwrap().0 - zone.end).abs() < 1e-6, "{acc:?}");
    assert!(!road.lane_exists(bkpbs::model::road::MERGE_LANE, zone.end));
    let out_lanes = sim.edge_lane_count("main_out").unwrap();
    assert_eq!(out_lanes, 2, "main_out carries only the two main lanes");
    sim.close().unwrap();
}

#[test]
fn start_close_start_in_one_process_reproduces_the_run() {
    // The episode runner relies on this to run many episodes in one worker process.
    let run = || {
        let mut c = Config::default();
        c.scenario.steps = 150;
        bkpbs::episode::run(&c, "idm-mobil").unwrap()
    };
    let a = run();
    let b = run();
    assert_eq!(a.episode_csv(), b.episode_csv());
    assert_eq!(a.vehicles_csv(), b.vehicles_csv());
    assert!(a.summary.inserted > 10);
}

#[test]
fn a_second_simulation_in_the_same_thread_is_refused() {
    let config = Config::default();
    let input = EpisodeInput::write(&config, &embedded_road()).unwrap();
    let sim = Simulation::start(&input.command_line(&config), config.sumo.stall_limit()).unwrap();
    let err = Simulation::start(&input.command_line(&config), config.sumo.stall_limit())
        .err()
        .unwrap();
    assert!(err.to_string().contains("already open"), "{err}");
    sim.close().unwrap();
}

#[test]
fn sumo_errors_carry_sumos_message() {
    let config = Config::default();
    let input = EpisodeInput::write(&config, &embedded_road()).unwrap();
    let mut sim =
        Simulation::start(&input.command_line(&config), config.sumo.stall_limit()).unwrap();
    let err = sim
        .set_speed("no-such-vehicle", 3.0)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no-such-vehicle") && err.contains("setSpeed"),
        "{err}"
    );
    sim.close().unwrap();
}

/// Nets the test writes itself, with other edge ids, straight and curved, 2–4 main lanes, one
/// and two ramps: the layout found is the one built, and the frame's round trip holds.
#[test]
fn layouts_of_nets_written_by_the_test() {
    use bkpbs::sumo::layout::Discovery;
    use bkpbs::sumo::network::Net;
    for (lanes, ramps, curved) in [
        (2, vec![300.0], false),
        (3, vec![300.0, 900.0], true),
        (4, vec![400.0], true),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = netconvert_net(dir.path(), lanes, &ramps, curved);
        let net = Net::read(&path).unwrap();
        let mut found = Discovery::of(&net);
        assert_eq!(found.regions.len(), 1);
        let layout = found.regions.remove(0);
        let what = format!("{lanes} lanes, ramps {ramps:?}, curved {curved}");
        assert_eq!(layout.on_ramps.len(), ramps.len(), "{what}");
        assert!(layout.off_ramps.is_empty());
        assert_eq!(layout.main.first().unwrap().lanes, lanes, "{what}");
        assert_eq!(layout.main.last().unwrap().id, "tail");
        for r in &layout.on_ramps {
            // The acceleration lane spans its own length along the frame (to 2 %: on a curve
            // the reference line, the left lane, is shorter or longer than the right one).
            let span = r.merge_end - r.merge_start;
            let edge = net.edges.iter().find(|e| e.id == r.joins).unwrap();
            let len = edge.lanes[r.lane as usize].length;
            assert!((span - len).abs() < 0.02 * len, "{what}: {r:?}, lane {len}");
            assert!(len > 180.0, "{what}: {len}");
            assert_eq!(r.lane, 0);
        }
        let s = 0.5 * layout.length();
        let (s2, d2) = layout.line.to_frame(layout.line.to_xy(s, -3.6));
        assert!((s2 - s).abs() < 0.01 && (d2 + 3.6).abs() < 0.01, "{what}");
        let bends = (0..20).any(|k| layout.line.curvature_at(k as f64 * 50.0).abs() > 1e-4);
        assert_eq!(bends, curved, "{what}");
    }
}

/// `bkpbs network` prints what it found, and refuses a net that is no merge in one line.
#[test]
fn network_command() {
    let repo = env!("CARGO_MANIFEST_DIR");
    let o = common::bkpbs(&["network", &format!("{repo}/sumo_net/corridor.net.xml")]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert_eq!(text.matches("on-ramp").count(), 3, "{text}");
    assert_eq!(text.matches("off-ramp").count(), 2, "{text}");
    let dir = tempfile::tempdir().unwrap();
    let two_way = dir.path().join("two-way.net.xml");
    std::fs::write(&two_way, common::TWO_WAY_NET).unwrap();
    let o = common::bkpbs(&["network", two_way.to_str().unwrap()]);
    common::refused_naming(&o, &["two-way.net.xml", "no merge to plan"]);
}
