//! A user's scenario runs as SUMO runs it, and nothing in it reaches outside: with no CAV the
//! episode is `sumo -c` trip for trip (the configuration's own tripinfo output included);
//! a TraCI server port, an output prefix, a random seed and a configuration without an end are
//! refused, pinned or named, each in one line.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use common::{assert_ok, csv_rows, output_within, refused_naming};

/// The configuration's time: 150 s of steps of 0.2 s.
const TIME: &str = r#"<time><begin value="0"/><end value="150"/><step-length value="0.2"/></time>"#;

/// A three-lane motorway with an on-ramp (netconvert's), a vehicle type distribution of cars,
/// eager lane changers and trucks on flows with random lanes, and `options` (the elements of
/// the configuration beside its input): the configuration's path.
fn motorway(dir: &Path, options: &str) -> PathBuf {
    motorway_at(dir, options, (2700, 700))
}

/// The same motorway with its flows at `(main, ramp)` vehicles per hour.
fn motorway_at(dir: &Path, options: &str, (main, ramp): (u32, u32)) -> PathBuf {
    common::netconvert_net(dir, 3, &[600.0], false);
    let routes = r#"<routes>
    <vTypeDistribution id="mix">
        <vType id="car" probability="0.6" sigma="0.5" speedFactor="normc(1,0.1,0.7,1.3)"/>
        <vType id="eager" probability="0.25" lcSpeedGain="3" lcKeepRight="0.2" speedFactor="1.15"/>
        <vType id="truck" vClass="truck" probability="0.15" length="12" maxSpeed="25"/>
    </vTypeDistribution>
    <route id="main" edges="road0 merge0 tail"/>
    <route id="ramp" edges="entry0 merge0 tail"/>
    <flow id="m" type="mix" route="main" begin="0" end="150" vehsPerHour="MAIN" departLane="random" departSpeed="random"/>
    <flow id="r" type="mix" route="ramp" begin="0" end="150" vehsPerHour="RAMP" departSpeed="max"/>
</routes>
"#;
    let routes = routes
        .replace("MAIN", &main.to_string())
        .replace("RAMP", &ramp.to_string());
    std::fs::write(dir.join("m.rou.xml"), routes).unwrap();
    let cfg = dir.join("m.sumocfg");
    std::fs::write(
        &cfg,
        format!(
            r#"<configuration>
    <input><net-file value="n.net.xml"/><route-files value="m.rou.xml"/></input>
    {options}
</configuration>
"#
        ),
    )
    .unwrap();
    cfg
}

/// SUMO's trips in a tripinfo file: id → (arrival, timeLoss), to 0.01 s; unfinished trips
/// (arrival -1) left out.
fn trips(path: &Path) -> BTreeMap<String, (String, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let num = |n: roxmltree::Node, k: &str| n.attribute(k).unwrap().parse::<f64>().unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("tripinfo") && num(*n, "arrival") >= 0.0)
        .map(|n| {
            let id = n.attribute("id").unwrap().to_string();
            let arrival = format!("{:.2}", num(n, "arrival"));
            (id, (arrival, format!("{:.2}", num(n, "timeLoss"))))
        })
        .collect()
}

/// `sumo -c cfg --seed seed` as a user runs it.
fn sumo_alone(cfg: &Path, seed: &str) {
    let o = Command::new("sumo")
        .args(["-c", cfg.to_str().unwrap(), "--seed", seed, "--no-step-log"])
        .output()
        .unwrap();
    assert_ok(&o);
}

/// With α = 0 there is no CAV, and every vehicle moves as under `sumo -c` with the same seed:
/// each trip's arrival and timeLoss in `vehicles.csv` are those of SUMO's own tripinfo, to
/// 0.01 s, for `--planner sumo` and for a planner that would drive CAVs; and the
/// configuration's own tripinfo output is written where it says, with the same trips. Before
/// bkpbs left the scenario alone (lane changes of 1 s for every vehicle, no teleports, its
/// own tripinfo in place of the configuration's), 15 of 303 trips agreed on such a motorway.
/// Each arrived vehicle of an episode's `vehicles.csv` rows: its arrival and timeLoss as
/// written, by id (as SUMO's tripinfo gives them).
fn arrivals(rows: &[BTreeMap<String, String>]) -> BTreeMap<String, (String, String)> {
    rows.iter()
        .filter(|r| r["outcome"] == "arrived")
        .map(|r| {
            let v = (r["arrival_s"].clone(), r["time_loss_s"].clone());
            (r["id"].clone(), v)
        })
        .collect()
}

#[test]
fn with_no_cav_every_trip_is_sumo_alones() {
    let tmp = tempfile::tempdir().unwrap();
    let own = r#"<output><tripinfo-output value="trips.xml"/></output>"#;
    let cfg = motorway(tmp.path(), &format!("{TIME}{own}"));
    sumo_alone(&cfg, "11");
    let alone = trips(&tmp.path().join("trips.xml"));
    std::fs::remove_file(tmp.path().join("trips.xml")).unwrap();
    assert!(alone.len() > 100, "{}", alone.len());
    for planner in ["sumo", "bk-pbs"] {
        let out = tmp.path().join(planner);
        let flags = ["--alpha", "0", "--seed", "11"];
        let o = common::scenario_run(&cfg, planner, &flags, &out);
        assert_ok(&o);
        let rows = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
        let ours = arrivals(&rows);
        let agree = alone
            .iter()
            .filter(|(k, v)| ours.get(*k) == Some(v))
            .count();
        assert_eq!(
            (agree, ours.len()),
            (alone.len(), alone.len()),
            "{planner}: trips agreeing with sumo -c, trips arrived"
        );
        assert_eq!(trips(&tmp.path().join("trips.xml")), alone, "{planner}");
    }
}

/// The `<vehicles>` counts and the `<vehicleTripStatistics>` of SUMO's statistic output.
fn statistics(path: &Path) -> (BTreeMap<String, f64>, BTreeMap<String, f64>) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let attributes = |tag: &str| {
        let n = doc.descendants().find(|n| n.has_tag_name(tag)).unwrap();
        n.attributes()
            .filter_map(|a| Some((a.name().to_string(), a.value().parse().ok()?)))
            .collect()
    };
    (attributes("vehicles"), attributes("vehicleTripStatistics"))
}

/// The trips SUMO never started in a tripinfo file written with `write-undeparted`: id →
/// departDelay, to 0.01 s.
fn undeparted(path: &Path) -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("tripinfo") && n.attribute("depart") == Some("-1"))
        .map(|n| {
            let delay: f64 = n.attribute("departDelay").unwrap().parse().unwrap();
            (
                n.attribute("id").unwrap().to_string(),
                format!("{delay:.2}"),
            )
        })
        .collect()
}

/// More demand than the motorway takes (7000 veh/h on the main road, 1800 on the ramp): with
/// α = 0 every trip is still `sumo -c`'s, and every vehicle SUMO loaded is in the books.
/// `never_inserted` is SUMO's loaded minus inserted (its statistic output), one
/// `never_inserted` row each in `vehicles.csv` with SUMO's own wait to the end (`departDelay`
/// of its undeparted trip; their mean SUMO's `departDelayWaiting`), and the mean with the wait
/// charges those waits. Before, the held-back vehicles were a count in `episode.csv` only.
#[test]
fn vehicles_sumo_never_inserted_are_each_in_the_books() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = motorway_at(tmp.path(), TIME, (7000, 1800));
    let (trips_xml, stats_xml) = (tmp.path().join("alone.xml"), tmp.path().join("stats.xml"));
    let o = Command::new("sumo")
        .args(["-c", cfg.to_str().unwrap(), "--seed", "5", "--no-step-log"])
        .args(["--tripinfo-output", trips_xml.to_str().unwrap()])
        .args(["--tripinfo-output.write-undeparted", "true"])
        .args(["--statistic-output", stats_xml.to_str().unwrap()])
        .output()
        .unwrap();
    assert_ok(&o);
    let (counts, trip_stats) = statistics(&stats_xml);
    let (loaded, inserted) = (counts["loaded"], counts["inserted"]);
    let held_back = undeparted(&trips_xml);
    assert!(loaded - inserted > 20.0, "{counts:?}");
    let out = tmp.path().join("episode");
    assert_ok(&common::scenario_run(
        &cfg,
        "sumo",
        &["--alpha", "0", "--seed", "5"],
        &out,
    ));
    let row = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
    let count = |c: &str| row[c].parse::<f64>().unwrap();
    assert_eq!(
        (count("inserted"), count("never_inserted")),
        (inserted, loaded - inserted),
        "{counts:?}"
    );
    let rows = csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap());
    let arrived = arrivals(&rows);
    assert_eq!(
        arrived,
        trips(&trips_xml),
        "arrival and timeLoss of each trip"
    );
    let never: BTreeMap<String, String> = rows
        .iter()
        .filter(|r| r["outcome"] == "never_inserted")
        .map(|r| (r["id"].clone(), r["depart_delay_s"].clone()))
        .collect();
    assert_eq!(
        never, held_back,
        "each vehicle never inserted, with its wait"
    );
    let waits: Vec<f64> = never.values().map(|w| w.parse().unwrap()).collect();
    let mean_wait = waits.iter().sum::<f64>() / waits.len() as f64;
    assert!(
        (mean_wait - trip_stats["departDelayWaiting"]).abs() < 0.01,
        "{mean_wait} {trip_stats:?}"
    );
    // The mean with the wait, over every vehicle not crashed, inserted or not.
    let with_wait: Vec<f64> = rows
        .iter()
        .map(|r| {
            let num = |c: &str| r[c].parse::<f64>().unwrap_or(0.0);
            num("time_loss_s") + num("depart_delay_s")
        })
        .collect();
    let mean = with_wait.iter().sum::<f64>() / with_wait.len() as f64;
    assert!(
        (count("mean_time_loss_with_wait_s") - mean).abs() < 0.01,
        "{row:?} {mean}"
    );
}

/// A campaign cell whose episode held vehicles back is finished: its `vehicles.csv` holds a row
/// per vehicle inserted and per vehicle never inserted, and the same command run again finds
/// it done (counting only the inserted rows made every such cell stale, run again for ever).
#[test]
fn a_campaign_cell_with_vehicles_never_inserted_is_done_when_run_again() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = motorway_at(tmp.path(), TIME, (7000, 1800));
    let out = tmp.path().join("campaign");
    let (cfg, out_s) = (cfg.to_str().unwrap(), out.to_str().unwrap());
    let args = [
        "campaign",
        "--sumocfg",
        cfg,
        "--planners",
        "sumo",
        "--alphas",
        "0",
        "--seeds",
        "1",
        "--out",
        out_s,
    ];
    assert_ok(&common::bkpbs(&args));
    let episodes = csv_rows(&std::fs::read(out.join("episodes.csv")).unwrap());
    let held_back: u32 = episodes[0]["never_inserted"].parse().unwrap();
    assert!(held_back > 0, "{:?}", episodes[0]);
    let again = common::bkpbs(&args);
    assert_ok(&again);
    let said = String::from_utf8_lossy(&again.stdout);
    assert!(said.contains("already done: 1;"), "{said}");
}

/// A TraCI server port in the configuration is one error line naming the option and the file,
/// before SUMO starts: no socket listens, and the run does not wait for a client (it stalled
/// for 120 s, SUMO listening on every interface, with a message naming no option).
#[test]
fn a_traci_server_port_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let server = format!(r#"<traci_server><remote-port value="{port}"/></traci_server>"#);
    let cfg = motorway(tmp.path(), &format!("{TIME}{server}"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_bkpbs"));
    cmd.args(["episode", "--planner", "sumo", "--sumocfg"])
        .arg(&cfg)
        .arg("--out")
        .arg(tmp.path().join("out"));
    let (o, took) = output_within(&mut cmd, Duration::from_secs(30));
    refused_naming(&o, &["remote-port", "m.sumocfg"]);
    assert!(took < Duration::from_secs(10), "{took:?}");
}

/// Every file under `dir`.
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files_under(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// An `output-prefix` is refused: it moved every output, bkpbs's own tripinfo included (with
/// `../../`, to two directories above its temporary directory), so nothing may be written
/// outside the scenario's folder and the episode's.
#[test]
fn an_output_prefix_is_refused_and_nothing_lands_outside() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = tmp.path().join("a/b/scenario");
    let scratch = tmp.path().join("t/u/v");
    std::fs::create_dir_all(&scenario).unwrap();
    std::fs::create_dir_all(&scratch).unwrap();
    let prefix =
        r#"<output><output-prefix value="../../"/><summary-output value="s.xml"/></output>"#;
    let cfg = motorway(&scenario, &format!("{TIME}{prefix}"));
    let out = tmp.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args(["episode", "--planner", "sumo", "--steps", "50", "--sumocfg"])
        .arg(&cfg)
        .arg("--out")
        .arg(&out)
        .env("TMPDIR", &scratch)
        .output()
        .unwrap();
    refused_naming(&o, &["output-prefix", "m.sumocfg"]);
    let outside: Vec<PathBuf> = files_under(tmp.path())
        .into_iter()
        .filter(|p| !p.starts_with(&scenario) && !p.starts_with(&out))
        .collect();
    assert!(outside.is_empty(), "{outside:?}");
}

/// `<random value="true"/>` would seed SUMO from the clock (two runs of seed 3 inserted 67
/// and 71 vehicles): bkpbs pins it, says so in a line, and two runs are the same.
#[test]
fn a_random_seed_is_pinned_and_named() {
    let tmp = tempfile::tempdir().unwrap();
    let random = r#"<random_number><random value="true"/></random_number>"#;
    let cfg = motorway(tmp.path(), &format!("{TIME}{random}"));
    let run = |name: &str| {
        let out = tmp.path().join(name);
        let flags = ["--alpha", "0", "--seed", "3", "--steps", "300"];
        let o = common::scenario_run(&cfg, "sumo", &flags, &out);
        assert_ok(&o);
        let stdout = String::from_utf8_lossy(&o.stdout).to_string();
        let line = "your configuration sets random = true; bkpbs uses false because";
        assert!(stdout.lines().any(|l| l.starts_with(line)), "{stdout}");
        out
    };
    let (a, b) = (run("a"), run("b"));
    common::assert_same_files(
        &a,
        &b,
        &common::SCENARIO_FILES,
        "between two runs of seed 3",
    );
}

/// A configuration without an end (SUMO runs it until every vehicle has arrived) ran 80 s,
/// silently: now it is one error line naming the file and what to set, and `--steps` runs it.
#[test]
fn a_configuration_without_an_end_needs_steps() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = motorway(tmp.path(), r#"<time><step-length value="0.2"/></time>"#);
    let out = tmp.path().join("out");
    let o = common::scenario_run(&cfg, "sumo", &["--alpha", "0"], &out);
    refused_naming(&o, &["m.sumocfg", "<end>", "--steps"]);
    assert!(!out.join("episode.csv").exists());
    let o = common::scenario_run(&cfg, "sumo", &["--alpha", "0", "--steps", "25"], &out);
    assert_ok(&o);
    let row = &csv_rows(&std::fs::read(out.join("episode.csv")).unwrap())[0];
    assert_eq!(row["steps"], "25");
}
