//! Episodes on a user's own SUMO scenario (`--sumocfg`), on SUMO's shipped `ramp` game
//! scenario copied as a user would: its routes and vehicle types run, every vehicle SUMO
//! inserted is in vehicles.csv with SUMO's own timeLoss, and with SUMO driving the CAVs the
//! figures are those of SUMO run alone with the same options (the oracle).

mod common;

use std::path::Path;
use std::process::Command;

use common::{bkpbs, csv_rows, game_copy, refused_naming, stderr};

fn scenario(cfg: &Path, planner: &str, steps: &str, out: &Path) -> std::process::Output {
    bkpbs(&[
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        planner,
        "--steps",
        steps,
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ])
}

/// SUMO's own `timeLoss` per vehicle in a tripinfo file.
fn time_losses(path: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let mut out: Vec<(String, String)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("tripinfo"))
        .map(|n| {
            let loss: f64 = n.attribute("timeLoss").unwrap().parse().unwrap();
            (n.attribute("id").unwrap().to_string(), format!("{loss:.2}"))
        })
        .collect();
    out.sort();
    out
}

#[test]
fn the_ramp_game_runs_with_its_own_routes_and_sumo_alone_agrees() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = game_copy(dir.path()).join("ramp.sumocfg");
    let out = dir.path().join("bk-pbs");
    let o = scenario(&cfg, "bk-pbs", "600", &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let ep = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
    let vehicles = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
    let n = |k: &str| ep[k].parse::<usize>().unwrap();
    assert_eq!(n("inserted"), vehicles.len());
    assert_eq!(n("inserted"), n("arrived") + n("crashed") + n("present"));
    assert_eq!(n("controllable_crashed"), 0, "{ep:?}");
    let share: f64 = ep["cav_share"].parse().unwrap();
    assert!(
        n("inserted") > 100 && (0.35..0.65).contains(&share),
        "{ep:?}"
    );
    assert!(vehicles.iter().any(|v| v["region_origin"] == "ramp"));
    assert!(vehicles
        .iter()
        .filter(|v| v["outcome"] != "crashed")
        .all(|v| !v["time_loss_s"].is_empty()));
    let options = std::fs::read_to_string(out.join("sumo_options.txt")).unwrap();
    assert!(options.contains("--collision.action warn"), "{options}");

    // The oracle: with SUMO driving the CAVs, each vehicle's timeLoss is SUMO's own in a run
    // of SUMO alone on the same configuration and options.
    let out = dir.path().join("sumo");
    let o = scenario(&cfg, "sumo", "600", &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let trip = dir.path().join("alone.xml");
    let mut args: Vec<String> = options.split_whitespace().map(String::from).collect();
    let k = args.iter().position(|a| a == "--tripinfo-output").unwrap();
    args[k + 1] = trip.display().to_string();
    let status = Command::new("sumo")
        .args(["-c", cfg.to_str().unwrap(), "--end", "120"])
        .args(&args)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let mut ours: Vec<(String, String)> =
        csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap())
            .into_iter()
            .map(|v| (v["id"].clone(), v["time_loss_s"].clone()))
            .collect();
    ours.sort();
    assert_eq!(ours, time_losses(&trip));
}

#[test]
fn a_scenario_at_another_step_length_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = game_copy(dir.path()).join("A10KW.sumocfg");
    let out = dir.path().join("out");
    let o = scenario(&cfg, "bk-pbs", "10", &out);
    refused_naming(&o, &["A10KW.sumocfg", "step-length 0.5 s", "0.2 s"]);
    assert!(!out.join("episode.csv").exists());
}

/// `--cav-types`: the vehicles of the named types are the CAVs, all of them and no other; a
/// type the scenario does not load is one error line naming it and the types it has.
#[test]
fn cavs_by_vehicle_type() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = game_copy(dir.path()).join("ramp.sumocfg");
    let run = |types: &str, out: &Path| {
        bkpbs(&[
            "episode",
            "--sumocfg",
            cfg.to_str().unwrap(),
            "--planner",
            "bk-pbs",
            "--cav-types",
            types,
            "--steps",
            "300",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let out = dir.path().join("trucks");
    let o = run("truck", &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let vehicles = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
    let kinds: std::collections::BTreeSet<(String, String)> = vehicles
        .iter()
        .map(|v| (v["type"].clone(), v["kind"].clone()))
        .collect();
    let want = [("passenger", "hdv"), ("truck", "cav")].map(|(t, k)| (t.into(), k.into()));
    assert_eq!(kinds, want.into_iter().collect());
    let ep = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
    assert_eq!(ep["cav_types"], "truck");
    let o = run("lorry", &dir.path().join("none"));
    refused_naming(&o, &["'lorry'", "truck", "passenger"]);
    assert!(!dir.path().join("none").join("episode.csv").exists());
}

/// Liveness at the ramp game's lane end: every CAV that entered the region in the first 100 s
/// has left it 40 s later. A 12 m CAV truck in lane 1 that came level with a ramp CAV waiting at
/// the lane end used to stand beside it for good, closing lane 1 and the ramp (bk-pbs, α 0.5,
/// seed 2: four CAVs still in the region at 140 s, 25 at 400 s).
#[test]
fn no_cav_stands_at_the_ramp_games_lane_end_for_good() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = game_copy(dir.path()).join("ramp.sumocfg");
    let out = dir.path().join("out");
    let o = bkpbs(&[
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        "bk-pbs",
        "--alpha",
        "0.5",
        "--seed",
        "2",
        "--steps",
        "700",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let vehicles = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
    let early = |v: &&std::collections::BTreeMap<String, String>| {
        v["kind"] == "cav" && v["region_enter_s"].parse::<f64>().is_ok_and(|t| t < 100.0)
    };
    let stuck: Vec<&String> = vehicles
        .iter()
        .filter(early)
        .filter(|v| v["region_leave_s"] == "139.80")
        .map(|v| &v["id"])
        .collect();
    assert!(vehicles.iter().filter(early).count() > 30);
    assert!(stuck.is_empty(), "still in the region at 140 s: {stuck:?}");
}

/// A10KW at the planners' step: both carriageways' merges are planned in one episode, each by
/// its own planner, and `network --sumocfg` agrees with the episode on what runs.
#[test]
fn the_interchange_plans_both_carriageways_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let game = game_copy(dir.path());
    let text = std::fs::read_to_string(game.join("A10KW.sumocfg")).unwrap();
    let cfg = game.join("A10KW-0.2.sumocfg");
    std::fs::write(
        &cfg,
        text.replace(
            "<step-length value=\"0.5\"/>",
            "<step-length value=\"0.2\"/>",
        ),
    )
    .unwrap();
    let o = bkpbs(&["network", "--sumocfg", cfg.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = bkpbs(&[
        "network",
        "--sumocfg",
        game.join("A10KW.sumocfg").to_str().unwrap(),
    ]);
    refused_naming(&o, &["step-length 0.5 s"]);
    let out = dir.path().join("out");
    let o = scenario(&cfg, "bk-pbs", "750", &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let ep = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
    assert_eq!(ep["regions"], "264308374; 4054057");
    assert_eq!(ep["controllable_crashed"], "0", "{ep:?}");
    let vehicles = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
    for region in ["264308374", "4054057"] {
        let there: Vec<_> = vehicles.iter().filter(|v| v["region"] == region).collect();
        assert!(there.len() > 20, "{region}: {}", there.len());
        assert!(there.iter().any(|v| v["kind"] == "cav"));
        assert!(there
            .iter()
            .filter(|v| v["outcome"] != "crashed")
            .all(|v| !v["region_delay_s"].is_empty()));
    }
    // regions.csv: one row per region, its vehicles those of vehicles.csv that entered it.
    let rows = csv_rows(&std::fs::read(out.join("regions.csv")).unwrap());
    let names: Vec<&str> = rows.iter().map(|r| r["region"].as_str()).collect();
    assert_eq!(names, ["264308374", "4054057"]);
    for row in &rows {
        let there: Vec<_> = vehicles
            .iter()
            .filter(|v| v["region"] == row["region"])
            .collect();
        assert_eq!(row["vehicles"], there.len().to_string());
        let delays: Vec<f64> = there
            .iter()
            .filter_map(|v| v["region_delay_s"].parse().ok())
            .collect();
        let mean: f64 = row["mean_delay_s"].parse().unwrap();
        assert!((mean - delays.iter().sum::<f64>() / delays.len() as f64).abs() < 1e-3);
    }
    // Few reach the on-ramps: the game's local streets jam at their junctions, in SUMO alone
    // as well; the first does within 40 s.
    assert!(vehicles.iter().any(|v| v["region_origin"] == "ramp"));
}

/// Trajectories on a scenario of your own: each region's, in its own road frame, beside a copy
/// of the episode's collisions, drawn by `bkpbs plot`; recording them changes no result.
#[test]
fn each_regions_trajectories_are_written_and_drawn_and_change_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = game_copy(dir.path()).join("ramp.sumocfg");
    let (plain, traced) = (dir.path().join("plain"), dir.path().join("traced"));
    common::assert_ok(&scenario(&cfg, "bk-pbs", "150", &plain));
    let mut args = vec![
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        "bk-pbs",
    ];
    args.extend(["--steps", "150", "--seed", "3", "--trajectories"]);
    args.extend(["--out", traced.to_str().unwrap()]);
    common::assert_ok(&bkpbs(&args));
    common::assert_same_files(
        &plain,
        &traced,
        &common::SCENARIO_FILES,
        "with --trajectories",
    );
    // The planner's effort is in the episode's row, as for the paper's demand.
    let episode = &csv_rows(&std::fs::read(traced.join("episode.csv")).unwrap())[0];
    for effort in [
        "plan_searches",
        "plan_nodes_expanded",
        "pbs_nodes",
        "predictions",
    ] {
        assert!(
            episode[effort].parse::<u64>().unwrap() > 0,
            "{effort}: {episode:?}"
        );
    }
    let region = traced.join("trajectories/gneE7");
    let rows = csv_rows(&std::fs::read(region.join("trajectories.csv")).unwrap());
    let in_region: std::collections::BTreeSet<String> =
        csv_rows(&std::fs::read(traced.join("vehicles.csv")).unwrap())
            .into_iter()
            .filter(|v| v["region"] == "gneE7")
            .map(|v| v["id"].clone())
            .collect();
    let seen: std::collections::BTreeSet<String> = rows.iter().map(|r| r["id"].clone()).collect();
    assert_eq!(
        seen, in_region,
        "every vehicle of the region, and only those"
    );
    assert!(rows
        .iter()
        .any(|r| r["source"] == "pbs-solution" && r["type"] == "cav"));
    assert!(region.join("collisions.csv").is_file());
    common::assert_ok(&bkpbs(&["plot", region.to_str().unwrap()]));
    assert!(region.join("time_space.png").is_file());
    // The episode's own directory finds its regions (before, "no trajectories" there).
    std::fs::remove_file(region.join("time_space.png")).unwrap();
    let o = bkpbs(&["plot", traced.to_str().unwrap()]);
    common::assert_ok(&o);
    assert!(region.join("time_space.png").is_file());
    assert!(String::from_utf8_lossy(&o.stdout).contains("trajectories/gneE7/speed_field.png"));
    // A run without trajectories into the same directory leaves none of the old ones.
    common::assert_ok(&scenario(&cfg, "bk-pbs", "150", &traced));
    assert!(!traced.join("trajectories").exists());
}

/// The planners keep each CAV to the speed limit of the lane it drives on: on the ramp game's
/// `gneE14`, a 13.89 m/s on-ramp between lanes of 33.33, no CAV is told to go faster than that
/// (or than it drove, along its path, as it came onto it: it may hold its speed).
#[test]
fn cavs_keep_to_each_lanes_speed_limit() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = game_copy(dir.path()).join("ramp.sumocfg");
    let out = dir.path().join("limits");
    let mut args = vec!["episode", "--sumocfg", cfg.to_str().unwrap()];
    args.extend(["--planner", "bk-pbs", "--alpha", "0.6", "--steps", "1000"]);
    args.extend([
        "--seed",
        "8",
        "--trajectories",
        "--out",
        out.to_str().unwrap(),
    ]);
    common::assert_ok(&bkpbs(&args));
    let rows = csv_rows(&std::fs::read(out.join("trajectories/gneE7/trajectories.csv")).unwrap());
    let mut on_slow_lane = 0;
    for r in rows.iter().filter(|r| !r["speed_sent"].is_empty()) {
        let num = |k: &str| r[k].parse::<f64>().unwrap();
        let limit: f64 = if r["edge"] == "gneE14" { 13.89 } else { 33.33 };
        let path_speed = num("speed") / num("heading").cos();
        assert!(
            num("speed_sent") <= limit.max(path_speed) + 1e-3,
            "{} on {} told {} (limit {limit}): {r:?}",
            r["id"],
            r["edge"],
            r["speed_sent"]
        );
        on_slow_lane += usize::from(r["edge"] == "gneE14");
    }
    assert!(on_slow_lane > 50, "{on_slow_lane} commands on gneE14");
}

/// `never_inserted` is SUMO's own count of the vehicles whose departure time came but which it
/// could not insert (its statistic output's `waiting` at the end): on the ramp game with 300
/// vehicles of a flow asked onto the on-ramp within 100 s, the episode's count equals that of
/// `sumo -c` given the same options, and `inserted` equals SUMO's too.
#[test]
fn vehicles_never_inserted_are_counted_as_sumo_counts_them() {
    let dir = tempfile::tempdir().unwrap();
    let game = game_copy(dir.path());
    let routes = std::fs::read_to_string(game.join("ramp/ramp.rou.xml")).unwrap();
    let at = routes.find("<flow").unwrap();
    let dense = format!(
        "{}<flow id=\"jam\" route=\"onramp\" begin=\"0\" end=\"100\" number=\"300\" departSpeed=\"max\"/>\n</routes>\n",
        &routes[..at]
    );
    std::fs::write(game.join("ramp/dense.rou.xml"), dense).unwrap();
    let cfg = game.join("dense.sumocfg");
    let text = std::fs::read_to_string(game.join("ramp.sumocfg")).unwrap();
    std::fs::write(
        &cfg,
        text.replace("ramp/ramp.rou.xml", "ramp/dense.rou.xml"),
    )
    .unwrap();
    let out = dir.path().join("episode");
    let o = bkpbs(&[
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        "sumo",
        "--alpha",
        "0",
        "--steps",
        "300",
        "--out",
        out.to_str().unwrap(),
    ]);
    common::assert_ok(&o);
    let stdout = String::from_utf8_lossy(&o.stdout).to_string();
    let options = stdout
        .lines()
        .find_map(|l| l.strip_prefix("SUMO options bkpbs set: "))
        .expect("the options line");
    // The same run by SUMO alone, its tripinfo elsewhere, with its statistics.
    let mut args: Vec<String> = options.split(' ').map(String::from).collect();
    let i = args.iter().position(|a| a == "--tripinfo-output").unwrap();
    args[i + 1] = dir.path().join("trips.xml").display().to_string();
    let stats = dir.path().join("stats.xml");
    let status = std::process::Command::new("sumo")
        .arg("-c")
        .arg(&cfg)
        .args(&args)
        .args(["--end", "60", "--statistic-output", stats.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let xml = std::fs::read_to_string(&stats).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let vehicles = doc
        .descendants()
        .find(|n| n.has_tag_name("vehicles"))
        .unwrap();
    let sumo = |k: &str| vehicles.attribute(k).unwrap().to_string();
    let row = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
    assert_eq!(row["inserted"], sumo("inserted"), "{xml}");
    assert_eq!(row["never_inserted"], sumo("waiting"), "{xml}");
    assert!(
        row["never_inserted"].parse::<usize>().unwrap() > 50,
        "{row:?}"
    );
    assert!(
        stdout.contains(&format!("never inserted {}", sumo("waiting"))),
        "{stdout}"
    );
    // Per region, by where their routes enter it: every one of them passes the weave, the
    // flow asked onto the on-ramp from there.
    let region = &csv_rows(&std::fs::read(out.join("regions.csv")).unwrap())[0];
    let count = |c: &str| region[c].parse::<usize>().unwrap();
    let never = row["never_inserted"].parse::<usize>().unwrap();
    assert_eq!(
        count("never_inserted_main") + count("never_inserted_ramp"),
        never
    );
    assert!(count("never_inserted_ramp") > 50, "{region:?}");
}

/// A region whose merge nobody used in the episode says so: 4 s of SUMO's `ramp` game bring no
/// ramp vehicle into the weave.
#[test]
fn a_region_without_ramp_traffic_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = game_copy(dir.path()).join("ramp.sumocfg");
    let o = scenario(&cfg, "sumo", "20", &dir.path().join("short"));
    common::assert_ok(&o);
    let err = stderr(&o);
    assert!(
        err.contains("warning: region gneE7 received no vehicle from its on-ramp"),
        "{err}"
    );
    let o = scenario(&cfg, "sumo", "600", &dir.path().join("long"));
    common::assert_ok(&o);
    assert!(
        !stderr(&o).contains("received no vehicle"),
        "{}",
        stderr(&o)
    );
}
