//! The merge network, read back through libsumo (real SUMO, in-process).

use bkpbs::config::Config;
use bkpbs::sumo::files::EpisodeInput;
use bkpbs::sumo::Simulation;

#[test]
fn net_has_the_papers_geometry() {
    let config = Config::default();
    let input = EpisodeInput::write(&config).unwrap();
    let sim = Simulation::start(&input.command_line(&config)).unwrap();
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
    let road = bkpbs::sumo::frame::road_from_simulation(&sim).unwrap();
    assert_eq!(
        (road.merge_start, road.merge_end, road.section_end),
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
    assert!(
        (acc.last().unwrap().0 - road.merge_end).abs() < 1e-6,
        "{acc:?}"
    );
    assert!(!road
        .lanes_at(road.merge_end)
        .contains(&bkpbs::model::road::MERGE_LANE));
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
    let input = EpisodeInput::write(&config).unwrap();
    let sim = Simulation::start(&input.command_line(&config)).unwrap();
    let err = Simulation::start(&input.command_line(&config))
        .err()
        .unwrap();
    assert!(err.to_string().contains("already open"), "{err}");
    sim.close().unwrap();
}

#[test]
fn sumo_errors_carry_sumos_message() {
    let config = Config::default();
    let input = EpisodeInput::write(&config).unwrap();
    let mut sim = Simulation::start(&input.command_line(&config)).unwrap();
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
