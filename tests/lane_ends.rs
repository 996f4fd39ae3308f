//! Every lane that ends while its traffic goes on, on networks built here from plain XML by
//! netconvert and SUMO's own games: `bkpbs network` names each kind in a SUMO user's words, and
//! says which it leaves to SUMO's drivers. (The kinds that are planned are driven in
//! `lane_roles.rs`.)

mod common;

use common::netconvert::{build, network, through};
use common::{bkpbs, has_line};

type Con = (&'static str, u32, &'static str, u32);

/// A one-lane ramp joining a two-lane motorway at the nose, without an acceleration lane: its
/// lane and the right main lane both lead into the right lane of `down` (OpenStreetMap imports
/// often look so, at a priority junction). Planned; `tests/lane_roles.rs` runs one.
#[test]
fn a_nose_merge() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = [
        ("a", 0.0, 0.0),
        ("b", 500.0, 0.0),
        ("c", 900.0, 0.0),
        ("r", 300.0, -50.0),
    ];
    let edges = [
        ("up", "a", "b", 2, ""),
        ("down", "b", "c", 2, ""),
        ("on", "r", "b", 1, ""),
    ];
    let mut cons: Vec<Con> = through("up", 2, "down", 2);
    cons.push(("on", 0, "down", 0));
    let out = network(&build(dir.path(), &nodes, &edges, &cons));
    has_line(&out, &["nose merge 'on' → 'down'", "planned in region 1"]);
    has_line(&out, &["on-ramp 1: on → down lane 0: joins at the nose"]);
}

/// Two on-ramps whose acceleration lanes overlap: `on2` joins `both` while the lane `on1`
/// feeds still runs there for 45 m. The region is left to SUMO's drivers with why.
#[test]
fn acceleration_lanes_side_by_side_are_left_to_sumo() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = [
        ("m0", 0.0, 0.0),
        ("m1", 400.0, 0.0),
        ("m2", 550.0, 0.0),
        ("m3", 600.0, 0.0),
        ("m4", 800.0, 0.0),
        ("m5", 1200.0, 0.0),
        ("r1", 250.0, -60.0),
        ("r2", 300.0, -20.0),
    ];
    let edges = [
        ("main_in", "m0", "m1", 2, ""),
        ("acc1", "m1", "m2", 3, ""),
        ("both", "m2", "m3", 4, ""),
        ("acc2", "m3", "m4", 3, ""),
        ("main_out", "m4", "m5", 2, ""),
        ("on1", "r1", "m1", 1, ""),
        ("on2", "r2", "m2", 1, ""),
    ];
    let mut cons: Vec<Con> = through("main_in", 2, "acc1", 3);
    cons.push(("on1", 0, "acc1", 0));
    cons.extend([
        ("acc1", 0, "both", 1),
        ("acc1", 1, "both", 2),
        ("acc1", 2, "both", 3),
    ]);
    cons.extend([("on2", 0, "both", 0), ("both", 0, "acc2", 0)]);
    cons.extend([("both", 2, "acc2", 1), ("both", 3, "acc2", 2)]);
    cons.extend(through("acc2", 3, "main_out", 2));
    let out = network(&build(dir.path(), &nodes, &edges, &cons));
    has_line(
        &out,
        &[
            "region at acc1, both left to SUMO's drivers",
            "'on2'",
            "its own acceleration lane begins beside it",
        ],
    );
}

/// `bkpbs network --sumocfg` on SUMO's shipped game `name` (its stdout).
fn game_network(name: &str) -> String {
    let cfg = common::sumo_game_dir().join(format!("{name}.sumocfg"));
    let o = bkpbs(&["network", "--sumocfg", cfg.to_str().unwrap()]);
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// SUMO's `highway` game: the merge its routes use (3 lanes and a 2-lane ramp joining into 4,
/// the leftmost then dropped) was neither planned nor listed; it is a left-lane drop, planned:
/// an episode under bk-pbs has CAVs in its region and no controllable collision.
#[test]
fn the_highway_game_s_routed_merge_is_a_planned_lane_drop() {
    let said = game_network("highway");
    has_line(
        &said,
        &[
            "lane drop 4 → 3 lanes on '189604289' (its leftmost lane ends)",
            "planned in region 3",
        ],
    );
    let cfg = common::sumo_game_dir().join("highway.sumocfg");
    let dir = tempfile::tempdir().unwrap();
    let flags = ["--alpha", "0.5", "--seed", "1", "--steps", "1500"];
    let o = common::scenario_run(&cfg, "bk-pbs", &flags, dir.path());
    assert!(o.status.success(), "{}", common::stderr(&o));
    let rows = common::csv_rows(&std::fs::read(dir.path().join("regions.csv")).unwrap());
    let drop = rows
        .iter()
        .find(|r| r["region"] == "189604289")
        .expect("its row");
    let n = |k: &str| drop[k].parse::<u64>().unwrap();
    assert!(n("cavs") > 20, "{drop:?}");
    assert_eq!(n("controllable_crashed"), 0, "{drop:?}");
}

/// A merge in a region whose road frame cannot be built (SUMO's `DRT` game) does not read
/// "planned": an episode refuses that region.
#[test]
fn a_merge_of_a_region_that_cannot_be_planned_does_not_read_planned() {
    let said = game_network("DRT");
    assert!(said.contains("cannot be planned on:"), "{said}");
    assert!(
        said.contains("in region 1, which cannot be planned on (an episode refuses it)")
            && !said.contains("planned in region 1"),
        "{said}"
    );
}
