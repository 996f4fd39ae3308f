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

/// A merge network with `main_lanes` lanes, one on-ramp per entry of `ramps_at` (x of the
/// merge), edge ids of its own, straight or bending (a gentle arc through the middle), built
/// by netconvert with its defaults (internal lanes) in `dir`.
fn netconvert_net(
    dir: &std::path::Path,
    main_lanes: u32,
    ramps_at: &[f64],
    curved: bool,
) -> std::path::PathBuf {
    let y = |x: f64| {
        if curved {
            0.0004 * (x - 300.0).powi(2)
        } else {
            0.0
        }
    };
    let mut nodes = String::from("<nodes>\n<node id=\"start\" x=\"0\" y=\"0\"/>\n");
    let mut edges = String::from("<edges>\n");
    let mut cons = String::from("<connections>\n");
    let mut from = "start".to_string();
    let mut prev: Option<String> = None;
    let shape = |x0: f64, x1: f64| {
        (0..=10)
            .map(|k| {
                let x = x0 + (x1 - x0) * k as f64 / 10.0;
                format!("{x:.2},{:.2}", y(x))
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut x = 0.0;
    for (k, &xm) in ramps_at.iter().enumerate() {
        let (a, m) = (format!("j{k}a"), format!("j{k}b"));
        nodes += &format!(
            "<node id=\"{a}\" x=\"{xm}\" y=\"{:.2}\"/>\n<node id=\"{m}\" x=\"{}\" y=\"{:.2}\"/>\n",
            y(xm),
            xm + 200.0,
            y(xm + 200.0)
        );
        nodes += &format!(
            "<node id=\"r{k}\" x=\"{}\" y=\"{:.2}\"/>\n",
            xm - 150.0,
            y(xm) - 60.0
        );
        let before = format!("road{k}");
        edges += &format!("<edge id=\"{before}\" from=\"{from}\" to=\"{a}\" numLanes=\"{main_lanes}\" speed=\"35\" width=\"3.6\" shape=\"{}\"/>\n", shape(x, xm));
        edges += &format!("<edge id=\"merge{k}\" from=\"{a}\" to=\"{m}\" numLanes=\"{}\" speed=\"35\" width=\"3.6\" shape=\"{}\"/>\n", main_lanes + 1, shape(xm, xm + 200.0));
        edges += &format!("<edge id=\"entry{k}\" from=\"r{k}\" to=\"{a}\" numLanes=\"1\" speed=\"30\" width=\"3.6\"/>\n");
        if let Some(p) = &prev {
            for i in 0..main_lanes {
                cons += &format!(
                    "<connection from=\"{p}\" to=\"{before}\" fromLane=\"{}\" toLane=\"{i}\"/>\n",
                    i + 1
                );
            }
        }
        for i in 0..main_lanes {
            cons += &format!(
                "<connection from=\"{before}\" to=\"merge{k}\" fromLane=\"{i}\" toLane=\"{}\"/>\n",
                i + 1
            );
        }
        cons += &format!(
            "<connection from=\"entry{k}\" to=\"merge{k}\" fromLane=\"0\" toLane=\"0\"/>\n"
        );
        prev = Some(format!("merge{k}"));
        from = m;
        x = xm + 200.0;
    }
    nodes += &format!(
        "<node id=\"end\" x=\"{}\" y=\"{:.2}\"/>\n</nodes>\n",
        x + 200.0,
        y(x + 200.0)
    );
    edges += &format!("<edge id=\"tail\" from=\"{from}\" to=\"end\" numLanes=\"{main_lanes}\" speed=\"35\" width=\"3.6\" shape=\"{}\"/>\n</edges>\n", shape(x, x + 200.0));
    for i in 0..main_lanes {
        cons += &format!(
            "<connection from=\"{}\" to=\"tail\" fromLane=\"{}\" toLane=\"{i}\"/>\n",
            prev.as_ref().unwrap(),
            i + 1
        );
    }
    cons += "</connections>\n";
    for (name, text) in [
        ("n.nod.xml", &nodes),
        ("n.edg.xml", &edges),
        ("n.con.xml", &cons),
    ] {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let out = dir.join("n.net.xml");
    let status = std::process::Command::new("netconvert")
        .current_dir(dir)
        .args([
            "--node-files",
            "n.nod.xml",
            "--edge-files",
            "n.edg.xml",
            "--connection-files",
            "n.con.xml",
            "--output-file",
            "n.net.xml",
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "netconvert failed on {}", dir.display());
    out
}

/// Nets the test writes itself, with other edge ids, straight and curved, 2–4 main lanes, one
/// and two ramps: the layout found is the one built, and the frame's round trip holds.
#[test]
fn layouts_of_nets_written_by_the_test() {
    use bkpbs::sumo::network::{Layout, Net};
    for (lanes, ramps, curved) in [
        (2, vec![300.0], false),
        (3, vec![300.0, 900.0], true),
        (4, vec![400.0], true),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = netconvert_net(dir.path(), lanes, &ramps, curved);
        let net = Net::read(&path).unwrap();
        let layout = Layout::discover(&net, &path).unwrap();
        let what = format!("{lanes} lanes, ramps {ramps:?}, curved {curved}");
        assert_eq!(layout.on_ramps.len(), ramps.len(), "{what}");
        assert!(layout.off_ramps.is_empty());
        assert_eq!(layout.main.first().unwrap().lanes, lanes, "{what}");
        assert_eq!(layout.main.last().unwrap().id, "tail");
        for r in &layout.on_ramps {
            // The acceleration lane spans its own length along the frame (to 2 %: on a curve
            // the reference line, the left lane, is shorter or longer than the right one).
            let span = r.merge_end.expect("the acceleration lane ends") - r.merge_start;
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
    let exe = env!("CARGO_BIN_EXE_bkpbs");
    let repo = env!("CARGO_MANIFEST_DIR");
    let o = std::process::Command::new(exe)
        .args(["network", &format!("{repo}/sumo_net/corridor.net.xml")])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert_eq!(text.matches("on-ramp").count(), 3, "{text}");
    assert_eq!(text.matches("off-ramp").count(), 2, "{text}");
    let dir = tempfile::tempdir().unwrap();
    let two_way = dir.path().join("two-way.net.xml");
    std::fs::write(
        &two_way,
        r#"<net><edge id="east"><lane id="east_0" index="0" length="100" shape="0,0 100,0"/></edge>
           <edge id="west"><lane id="west_0" index="0" length="100" shape="100,5 0,5"/></edge></net>"#,
    )
    .unwrap();
    let o = std::process::Command::new(exe)
        .args(["network", two_way.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("not a one-way carriageway with merges"),
        "{err}"
    );
}
