//! Auxiliary lanes of other roles than the one acceleration lane, on the merge layouts of
//! `sumo_net/layouts/` (each a SUMO scenario: plain XML the test builds with netconvert, flows
//! of 300 s, a configuration): on-ramps of two lanes (a ramp whose lanes end in turn, one that
//! joins as two lanes the carriageway keeps for 800 m and then drops), a main-road lane drop
//! (3 to 2 lanes, on the right and on the left), an on-ramp joining on the left (its lane the frame lane above the
//! carriageway's), and on-ramps whose edges run alongside another merge's auxiliary lane (two
//! on-ramps 150 m apart; a cloverleaf's outer on-ramp beside its weaving lane), and a ramp
//! joining at the nose without an acceleration lane. `bkpbs network`
//! plans each (a ramp's outer lane a frame lane of its own, outside the one beside the
//! carriageway; the dropped lane an auxiliary lane whose traffic is the main road's; a ramp's
//! stretch beside another's lane outside the frame, so it is not planned as if on that lane,
//! which once closed the second ramp: 22 of 84 vehicles got in, mean delay 245 s against 7 s).
//! Under bk-pbs, bk-mastar and idm-mobil no lane is closed: each flow inserts and delivers as
//! many vehicles as under SUMO alone (within 3 %) and its mean delay is at most 3 s above SUMO
//! alone's, without a controllable collision under bk-pbs and bk-mastar; where a planner is
//! held to less, the test says why.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use common::flows::{within_3_percent, FlowCount};
use common::netconvert::{layout, network};
use common::{csv_rows, has_line, scenario_run, stderr};

/// One run of `planner` at `alpha` on `cfg` (seed `seed`): each flow's counts, and the region's
/// controllable collisions.
fn per_flow(
    cfg: &Path,
    planner: &str,
    alpha: &str,
    seed: &str,
) -> (BTreeMap<String, FlowCount>, u64) {
    let out = cfg
        .parent()
        .unwrap()
        .join(format!("{planner}-{alpha}-{seed}"));
    let o = scenario_run(cfg, planner, &["--alpha", alpha, "--seed", seed], &out);
    assert!(o.status.success(), "{planner}: {}", stderr(&o));
    let regions = csv_rows(&std::fs::read(out.join("regions.csv")).unwrap());
    let controllable = (regions.iter())
        .map(|r| r["controllable_crashed"].parse::<u64>().unwrap())
        .sum();
    (common::flows::per_flow(&out), controllable)
}

/// What a planner's episode is held to against SUMO alone's on the same seed.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Held {
    /// Each flow inserts and delivers as many vehicles (within 3 %).
    Counts,
    /// And its mean delay is at most 3 s above SUMO alone's.
    CountsAndDelay,
}

/// The planners as the layouts hold them: each to every flow's counts and delay. IDM+MOBIL on a
/// scenario cooperates at merges and follows with its type's parameters (`[mobil] cooperative`,
/// `type_following`); before that its ramp delays ran 3–11 s above SUMO alone's on the two-lane
/// ramps and 2.9–3.8 s at the nose, and its CAVs collided moving into a lane a ramp vehicle was
/// merging into, so it was held to the counts only.
const AS_A_RULE: [(&str, Held); 3] = [
    ("bk-pbs", Held::CountsAndDelay),
    ("bk-mastar", Held::CountsAndDelay),
    ("idm-mobil", Held::CountsAndDelay),
];

/// Layout `name` copied into a fresh directory (kept while the guard lives), its net built:
/// the guard, the configuration's path and what `bkpbs network` says of the net.
fn layout_and_network(name: &str) -> (tempfile::TempDir, PathBuf, String) {
    let dir = tempfile::tempdir().unwrap();
    let (net, cfg) = layout(dir.path(), name);
    let said = network(&net);
    (dir, cfg, said)
}

/// Each planner at α = 0.6 against SUMO alone on the same seed, held to what `held` says; and
/// neither bk-pbs nor bk-mastar takes part in a controllable collision.
fn flows_as_under_sumo_alone(cfg: &Path, seed: &str, held: &[(&str, Held)]) {
    let (alone, _) = per_flow(cfg, "sumo", "0", seed);
    for &(planner, held) in held {
        let (flows, controllable) = per_flow(cfg, planner, "0.6", seed);
        for (flow, a) in &alone {
            let b = flows[flow];
            eprintln!("{planner} {flow}: {b:?}, SUMO alone {a:?}");
            let near = within_3_percent;
            assert!(a.inserted > 10, "{flow}: {a:?}");
            assert!(
                near(b.inserted, a.inserted),
                "{planner} {flow} inserted: {b:?} vs {a:?}"
            );
            let arrived = near(b.arrived, a.arrived);
            assert!(arrived, "{planner} {flow} arrived: {b:?} vs {a:?}");
            if held == Held::CountsAndDelay {
                // At most 3 s more: a closed ramp's delay runs away; less is no closure (bk-pbs
                // delays the cloverleaf's loop ramp 4.2 s less than SUMO's drivers here).
                let delay = b.delay - a.delay;
                assert!(delay <= 3.0, "{planner} {flow} delay: {b:?} vs {a:?}");
            }
        }
        if planner.starts_with("bk-") {
            assert_eq!(controllable, 0, "{planner}: controllable collisions");
        }
    }
}

#[test]
fn a_two_lane_ramp_whose_lanes_end_in_turn_is_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("two-lane-ramp");
    has_line(&said, &["two-lane on-ramp", "'on'", "planned in region 1"]);
    has_line(
        &said,
        &["on-ramp 1: on → acc lane 1", "outer lane 0: ends at s"],
    );
    flows_as_under_sumo_alone(&cfg, "5", &AS_A_RULE);
}

#[test]
fn a_two_lane_gain_dropped_later_is_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("two-lane-gain");
    has_line(
        &said,
        &["lane gain dropped later", "'on'", "planned in region 1"],
    );
    flows_as_under_sumo_alone(&cfg, "7", &AS_A_RULE);
}

#[test]
fn a_main_road_lane_drop_is_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("lane-drop");
    has_line(
        &said,
        &["lane drop 3 → 2 lanes on 'mid'", "planned in region 1"],
    );
    has_line(&said, &["lane drop: lane 0 of mid ends at s"]);
    flows_as_under_sumo_alone(&cfg, "5", &AS_A_RULE);
}

#[test]
fn two_ramps_alongside_are_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("two-ramps-alongside");
    has_line(
        &said,
        &[
            "on-ramp alongside another's auxiliary lane",
            "'on2'",
            "'on1'",
            "planned in region 1",
        ],
    );
    flows_as_under_sumo_alone(&cfg, "5", &AS_A_RULE);
}

#[test]
fn a_cloverleaf_is_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("cloverleaf");
    has_line(
        &said,
        &["weaving section", "'loop_on'", "planned in region 1"],
    );
    has_line(
        &said,
        &[
            "on-ramp alongside another's auxiliary lane",
            "'outer_on'",
            "'loop_on'",
            "planned in region 1",
        ],
    );
    flows_as_under_sumo_alone(&cfg, "5", &AS_A_RULE);
}

/// A ramp CAV on the cloverleaf's weaving lane plans to be able to stop 20 m before its end
/// (`WEAVING_ROOM`), so a CAV bound for the loop off-ramp, left to SUMO, can move in front of
/// it. Planned to stop at the very end, on this seed the two stood side by side there, each
/// needing the other's lane, until SUMO teleported one: under bk-pbs the loop off-ramp's flow
/// delivered 16 of its 17 vehicles with a mean delay of 190.9 s.
#[test]
fn a_ramp_cav_on_a_weaving_lane_leaves_room_for_an_exiting_vehicle() {
    let (_dir, cfg, _) = layout_and_network("cloverleaf");
    let held = [("bk-pbs", Held::CountsAndDelay)];
    flows_as_under_sumo_alone(&cfg, "1009", &held);
}

#[test]
fn a_left_side_ramp_is_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("left-side-ramp");
    has_line(&said, &["left-side on-ramp", "'on'", "planned in region 1"]);
    has_line(&said, &["on-ramp 1: on → acc lane 2"]);
    assert!(
        !said.contains("ramp 'up'"),
        "the main road called a ramp:\n{said}"
    );
    flows_as_under_sumo_alone(&cfg, "5", &AS_A_RULE);
}

#[test]
fn a_left_lane_drop_is_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("left-lane-drop");
    has_line(
        &said,
        &[
            "lane drop 3 → 2 lanes on 'mid' (its leftmost lane ends)",
            "planned in region 1",
        ],
    );
    has_line(&said, &["lane drop: lane 2 of mid ends at s"]);
    flows_as_under_sumo_alone(&cfg, "5", &AS_A_RULE);
    // A CAV that came to a stand in the middle lane beside an HDV waiting at the left lane's
    // end held both for good while the HDV was predicted to move over onto it (28 vehicles
    // never arrived; `predict/blocked.rs`). bk-mastar's delays are not held on this seed: its
    // left lane runs 3.9 s above SUMO alone's (its CAVs on the dropped lane slow level with
    // middle-lane HDVs that slow for them).
    flows_as_under_sumo_alone(&cfg, "21", &[("bk-mastar", Held::Counts)]);
}

/// A one-lane ramp joining a two-lane motorway at the nose, without an acceleration lane, at a
/// zipper junction (the `nose-merge` layout; at a netconvert priority junction SUMO's own
/// drivers wait at the nose for 180 s, the guide's SUMO facts). Its lane is frame lane 0 up
/// to where its junction lane begins, that junction lane lies on lane 1, and a ramp CAV sent
/// left on the ramp's last 60 m is committed to merging (`episode::nose`), IDM+MOBIL's too
/// (before, its ramp CAVs braked for the nose as for a wall and never committed: ramp delays 2.9
/// and 3.8 s above SUMO alone's on seeds 5 and 6).
#[test]
fn a_nose_merge_is_planned_and_never_closed() {
    let (_dir, cfg, said) = layout_and_network("nose-merge");
    has_line(&said, &["nose merge 'on' → 'down'", "planned in region 1"]);
    has_line(&said, &["on-ramp 1: on → down lane 0: joins at the nose"]);
    flows_as_under_sumo_alone(&cfg, "5", &AS_A_RULE);
}
