//! The books per region entry on real SUMO: a netconvert motorway whose one merge region has
//! two on-ramps (`entry0` joining `merge0`, `entry1` joining `merge1`), run as a scenario of
//! the user's own. `entries.csv` books each ramp apart and adds up to `regions.csv`; the same
//! road fed by its main carriageway alone flags the region (`ramp_traffic` false) and warns.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::{assert_ok, csv_rows, netconvert_net, scenario_run, stderr};

/// The routes of the net's three entries, to its end.
const MAIN: &str = "road0 merge0 road1 merge1 tail";
const RAMP0: &str = "entry0 merge0 road1 merge1 tail";
const RAMP1: &str = "entry1 merge1 tail";

/// A configuration in `dir` of `net` with a flow per `(id, route, veh/h)` over 120 s, at the
/// planners' step.
fn scenario(dir: &Path, net: &Path, flows: &[(&str, &str, u32)]) -> PathBuf {
    let mut routes = String::from("<routes>\n<vType id=\"car\" length=\"5\" maxSpeed=\"33\"/>\n");
    for (id, edges, rate) in flows {
        routes += &format!("<route id=\"r_{id}\" edges=\"{edges}\"/>\n");
        routes += &format!(
            "<flow id=\"{id}\" type=\"car\" route=\"r_{id}\" begin=\"0\" end=\"120\" \
             vehsPerHour=\"{rate}\" departSpeed=\"max\" departLane=\"best\"/>\n"
        );
    }
    std::fs::write(dir.join("s.rou.xml"), routes + "</routes>\n").unwrap();
    let cfg = format!(
        "<configuration>\n<input><net-file value=\"{}\"/><route-files value=\"s.rou.xml\"/></input>\n\
         <time><begin value=\"0\"/><end value=\"120\"/><step-length value=\"0.2\"/></time>\n\
         </configuration>\n",
        net.file_name().unwrap().to_str().unwrap()
    );
    let path = dir.join("s.sumocfg");
    std::fs::write(&path, cfg).unwrap();
    path
}

/// The rows of file `name` in `dir`.
fn rows(dir: &Path, name: &str) -> Vec<BTreeMap<String, String>> {
    csv_rows(&std::fs::read(dir.join(name)).unwrap())
}

/// Column `column` of `row` as a count.
fn count(row: &BTreeMap<String, String>, column: &str) -> usize {
    row[column]
        .parse()
        .unwrap_or_else(|_| panic!("{column}: {row:?}"))
}

/// Each region's entry rows add up to its `regions.csv` row, and each entry's vehicles are
/// those of `vehicles.csv` that came into the region by it.
fn assert_books_add_up(out: &Path) {
    let entries = rows(out, "entries.csv");
    let vehicles = rows(out, "vehicles.csv");
    for region in rows(out, "regions.csv") {
        let mine: Vec<_> = (entries.iter())
            .filter(|e| e["region"] == region["region"])
            .collect();
        let sum = |c: &str| mine.iter().map(|e| count(e, c)).sum::<usize>();
        for c in ["vehicles", "cavs", "arrived", "crashed", "present"] {
            assert_eq!(sum(c), count(&region, c), "{c}: {region:?}");
        }
        assert_eq!(
            sum("controllable_crashed"),
            count(&region, "controllable_crashed")
        );
        let never = count(&region, "never_inserted_main") + count(&region, "never_inserted_ramp");
        assert_eq!(sum("never_inserted"), never, "{region:?}");
        for e in &mine {
            let came = (vehicles.iter())
                .filter(|v| v["region"] == e["region"] && v["region_entry"] == e["entry"])
                .count();
            assert_eq!(came, count(e, "vehicles"), "{e:?}");
        }
    }
}

#[test]
fn two_ramps_of_one_region_are_booked_apart_and_a_region_without_ramp_traffic_warns() {
    let dir = tempfile::tempdir().unwrap();
    let net = netconvert_net(dir.path(), 2, &[300.0, 900.0], false);
    let flows = [("m", MAIN, 1800), ("a", RAMP0, 400), ("b", RAMP1, 300)];
    let cfg = scenario(dir.path(), &net, &flows);
    let out = dir.path().join("ramps");
    let o = scenario_run(&cfg, "bk-pbs", &["--alpha", "0.5", "--seed", "1"], &out);
    assert_ok(&o);
    assert!(!stderr(&o).contains("warning: region"), "{}", stderr(&o));
    let region = &rows(&out, "regions.csv")[0];
    assert_eq!(
        rows(&out, "regions.csv").len(),
        1,
        "one region of two ramps"
    );
    assert_eq!(region["region"], "merge0 merge1");
    assert_eq!(region["ramp_traffic"], "true");
    let entries = rows(&out, "entries.csv");
    let names: Vec<(&str, &str)> = (entries.iter())
        .map(|e| (e["entry"].as_str(), e["origin"].as_str()))
        .collect();
    assert_eq!(
        names,
        [("main", "main"), ("entry0", "ramp"), ("entry1", "ramp")]
    );
    for e in &entries {
        eprintln!(
            "{}: {} vehicles, {} arrived, mean delay {} s, own {} s",
            e["entry"], e["vehicles"], e["arrived"], e["mean_delay_s"], e["mean_delay_own_s"]
        );
        assert!(count(e, "vehicles") > 5, "{e:?}");
    }
    // Each ramp's vehicles are its flow's, every one of them.
    let vehicles = rows(&out, "vehicles.csv");
    for v in vehicles.iter().filter(|v| !v["region"].is_empty()) {
        let flow = v["id"].split('.').next().unwrap();
        let entry = [("m", "main"), ("a", "entry0"), ("b", "entry1")];
        let expected = entry.iter().find(|(f, _)| *f == flow).unwrap().1;
        assert_eq!(v["region_entry"], expected, "{v:?}");
    }
    assert_books_add_up(&out);
    // The same seed gives the same bytes.
    let again = dir.path().join("ramps-again");
    let o = scenario_run(&cfg, "bk-pbs", &["--alpha", "0.5", "--seed", "1"], &again);
    assert_ok(&o);
    common::assert_same_files(&out, &again, &common::SCENARIO_FILES, "run twice");

    // Fed by its main carriageway alone: flagged, its ramps at zero, one warning naming them.
    let main_only = dir.path().join("main-only");
    std::fs::create_dir(&main_only).unwrap();
    let net_copy = main_only.join("n.net.xml");
    std::fs::copy(&net, &net_copy).unwrap();
    let cfg = scenario(&main_only, &net_copy, &[("m", MAIN, 1800)]);
    let out = main_only.join("out");
    let o = scenario_run(&cfg, "bk-pbs", &["--alpha", "0.5", "--seed", "1"], &out);
    assert_ok(&o);
    let region = &rows(&out, "regions.csv")[0];
    assert_eq!(region["ramp_traffic"], "false", "{region:?}");
    let said = stderr(&o);
    let warnings: Vec<&str> = (said.lines())
        .filter(|l| l.starts_with("warning: region"))
        .collect();
    assert_eq!(warnings.len(), 1, "{said}");
    assert!(
        warnings[0].starts_with(
            "warning: region merge0 merge1 received no vehicle from its on-ramps (entry0, entry1)"
        ),
        "{warnings:?}"
    );
    let ramps: Vec<usize> = (rows(&out, "entries.csv").iter())
        .filter(|e| e["origin"] == "ramp")
        .map(|e| count(e, "vehicles"))
        .collect();
    assert_eq!(ramps, [0, 0]);
    assert_books_add_up(&out);
}
