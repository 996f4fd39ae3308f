//! Regions found in the shipped networks and in hand-written ones.

use super::*;
use crate::sumo::network::Net;
use std::path::Path;

fn shipped(name: &str) -> Layout {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("sumo_net/{name}.net.xml"));
    let net = Net::read(&path).unwrap();
    let mut found = Discovery::of(&net);
    assert_eq!(found.regions.len(), 1, "{name}: one region");
    assert!(found.left_out.is_empty(), "{name}: {:?}", found.left_out);
    found.regions.remove(0)
}

fn ids(l: &Layout) -> Vec<&str> {
    l.main.iter().map(|m| m.id.as_str()).collect()
}

#[test]
fn the_paper_net() {
    let l = shipped("merge");
    assert_eq!(ids(&l), ["main_in", "acc", "main_out"]);
    assert_eq!(l.on_ramps.len(), 1);
    let r = &l.on_ramps[0];
    assert_eq!(
        (r.edges.clone(), r.joins.as_str(), r.lane),
        (vec!["ramp".to_string()], "acc", 0)
    );
    assert!((r.merge_start - 150.0).abs() < 1e-6, "{r:?}");
    assert!((r.merge_end - 330.0).abs() < 1e-6, "{r:?}");
    assert!((l.length() - 460.0).abs() < 1e-6);
    assert!(l.off_ramps.is_empty());
    // Straight: s is SUMO's x, as in the fixed frame; the right main lane 4.5 m right of
    // the reference (the left lane's centre line).
    let (s, d) = l.line.to_frame(Point::new(123.4, -6.75));
    assert!(
        (s - 123.4).abs() < 0.01 && (d + 4.5).abs() < 0.01,
        "{s} {d}"
    );
}

#[test]
fn three_lanes_with_internal_lanes() {
    let l = shipped("three-lane");
    assert_eq!(ids(&l), ["hw_a", "hw_merge", "hw_b"]);
    assert_eq!(
        l.main.iter().map(|m| m.lanes).collect::<Vec<_>>(),
        [3, 4, 3]
    );
    let r = &l.on_ramps[0];
    // 200 m, a 3 m internal lane, then the 220 m acceleration lane.
    assert!((r.merge_start - 203.0).abs() < 0.01, "{r:?}");
    assert!((r.merge_end - 423.0).abs() < 0.01, "{r:?}");
    assert!((l.length() - 631.0).abs() < 0.01, "{}", l.length());
    // The acceleration lane's centre: three lanes of 3.6 m right of the reference.
    let (s, d) = l.line.to_frame(Point::new(300.0, 37.4));
    assert!(
        (s - 300.0).abs() < 0.01 && (d + 10.8).abs() < 0.01,
        "{s} {d}"
    );
}

#[test]
fn the_corridor() {
    let l = shipped("corridor");
    assert_eq!(l.on_ramps.len(), 3);
    assert_eq!(l.off_ramps.len(), 2);
    assert_eq!(l.main.first().unwrap().id, "hw0");
    assert_eq!(l.main.last().unwrap().id, "hw5");
    assert!((l.length() - 3000.48).abs() < 0.5, "{}", l.length());
    let ends: Vec<f64> = l.on_ramps.iter().map(|r| r.merge_end).collect();
    assert!(ends.windows(2).all(|w| w[0] < w[1]), "{ends:?}");
    for r in &l.on_ramps {
        let len = r.merge_end - r.merge_start;
        assert!((150.0..260.0).contains(&len), "{r:?}");
    }
    // Curved: the reference turns, and frame and back agree.
    let k: Vec<f64> = (0..30)
        .map(|i| l.line.curvature_at(i as f64 * 100.0).abs())
        .collect();
    assert!(k.iter().any(|&c| c > 1e-4), "{k:?}");
    let p = l.line.to_xy(1234.5, -7.2);
    let (s, d) = l.line.to_frame(p);
    assert!((s - 1234.5).abs() < 0.01 && (d + 7.2).abs() < 0.01);
}

/// A two-way road: two carriageways of equal width, neither of which the other joins.
#[test]
fn a_two_way_road_has_no_region() {
    let xml = r#"<net>
        <edge id="east"><lane id="east_0" index="0" length="100" width="3.5" shape="0,0 100,0"/></edge>
        <edge id="west"><lane id="west_0" index="0" length="100" width="3.5" shape="100,5 0,5"/></edge>
    </net>"#;
    let path = Path::new("two-way.net.xml");
    let net = Net::parse(path, xml).unwrap();
    let found = Discovery::of(&net);
    assert!(found.regions.is_empty());
    assert_eq!(found.left_out.len(), 2, "{:?}", found.left_out);
    let e = Net::parse(path, "<net><edge").unwrap_err().to_string();
    assert!(e.contains("not valid XML"), "{e}");
}

/// A merge beside a footway, and a road back with turnarounds onto it, as net XML.
fn merge_beside_a_footway() -> String {
    let lane = |id: &str, k: u32, y: f64, extra: &str| {
        format!(
            r#"<lane id="{id}_{k}" index="{k}" length="100" width="3.2" {extra} shape="{x0},{y} {x1},{y}"/>"#,
            x0 = 0.0,
            x1 = 100.0
        )
    };
    let edge = |id: &str, lanes: &[String]| format!(r#"<edge id="{id}">{}</edge>"#, lanes.concat());
    let c = |f: &str, fl: u32, t: &str, tl: u32, dir: &str| {
        format!(r#"<connection from="{f}" to="{t}" fromLane="{fl}" toLane="{tl}" dir="{dir}"/>"#)
    };
    [
        "<net>".to_string(),
        edge("a", &[lane("a", 0, 0.0, ""), lane("a", 1, 3.2, "")]),
        edge(
            "m",
            &[
                lane("m", 0, -3.2, ""),
                lane("m", 1, 0.0, ""),
                lane("m", 2, 3.2, ""),
            ],
        ),
        edge("b", &[lane("b", 0, 0.0, ""), lane("b", 1, 3.2, "")]),
        edge("r", &[lane("r", 0, -6.4, "")]),
        edge("back", &[lane("back", 0, 9.0, "")]),
        edge("walk", &[lane("walk", 0, -9.0, r#"allow="pedestrian""#)]),
        c("a", 0, "m", 1, "s"),
        c("a", 1, "m", 2, "s"),
        c("r", 0, "m", 0, "s"),
        c("m", 1, "b", 0, "s"),
        c("m", 2, "b", 1, "s"),
        c("b", 1, "back", 0, "t"),
        c("back", 0, "a", 1, "t"),
        c("walk", 0, "r", 0, "s"),
        "</net>".to_string(),
    ]
    .concat()
}

/// The footway is closed to cars, the road back is no part of the region, the U-turns no way
/// through it.
#[test]
fn footways_and_turnarounds_are_left_out() {
    let net = Net::parse(Path::new("t.net.xml"), &merge_beside_a_footway()).unwrap();
    assert_eq!(
        net.closed,
        [("walk".to_string(), "closed to cars".to_string())]
    );
    let found = Discovery::of(&net);
    assert_eq!(found.regions.len(), 1);
    let l = &found.regions[0];
    let main: Vec<&str> = l.main.iter().map(|m| m.id.as_str()).collect();
    assert_eq!(main, ["a", "m", "b"]);
    assert_eq!(l.on_ramps[0].edges, ["r"]);
    assert_eq!(
        (l.on_ramps[0].lane, l.on_ramps[0].ends_on.as_str()),
        (0, "m")
    );
    assert!(l.off_ramps.is_empty(), "{:?}", l.off_ramps);
    assert_eq!(
        found.left_out,
        [
            ("walk".to_string(), "closed to cars".to_string()),
            ("back".to_string(), "in no merge region".to_string())
        ]
    );
}

/// A weaving section as net XML: a carriageway of two lanes, `a` then `w` then `b`; ramp `r`
/// joins `w` as its lane 0, which after `weave` metres turns off into off-ramp `off`. With
/// `street`, a side street `s` leaves `w` halfway, splitting it into `w` and `w2`.
fn weaving(weave: f64, street: bool) -> String {
    // Lanes aligned on the left, the carriageway's leftmost at y = 6.4, ramps right of it.
    let lane = |id: &str, k: u32, n: u32, x0: f64, x1: f64| {
        let y = if id == "r" || id == "off" {
            -3.2
        } else {
            3.2 * f64::from(k + 3 - n)
        };
        format!(
            r#"<lane id="{id}_{k}" index="{k}" length="{len}" width="3.2" shape="{x0},{y} {x1},{y}"/>"#,
            len = x1 - x0
        )
    };
    let edge = |id: &str, n: u32, x0: f64, x1: f64| {
        let lanes: String = (0..n).map(|k| lane(id, k, n, x0, x1)).collect();
        format!(r#"<edge id="{id}">{lanes}</edge>"#)
    };
    let c = |f: &str, fl: u32, t: &str, tl: u32| {
        format!(r#"<connection from="{f}" to="{t}" fromLane="{fl}" toLane="{tl}" dir="s"/>"#)
    };
    let (w_end, end) = (100.0 + weave, 200.0 + weave);
    let mut xml = vec![
        "<net>".to_string(),
        edge("a", 2, 0.0, 100.0),
        edge("b", 2, w_end, end),
        edge("r", 1, 0.0, 100.0),
        edge("off", 1, w_end, end),
        c("a", 0, "w", 1),
        c("a", 1, "w", 2),
        c("r", 0, "w", 0),
    ];
    let last = if street {
        let mid = 100.0 + weave / 2.0;
        xml.extend([edge("w", 3, 100.0, mid), edge("w2", 3, mid, w_end)]);
        xml.extend([edge("s", 1, mid, end), c("w", 2, "s", 0)]);
        xml.extend((0..3).map(|k| c("w", k, "w2", k)));
        "w2"
    } else {
        xml.push(edge("w", 3, 100.0, w_end));
        "w"
    };
    xml.extend([c(last, 1, "b", 0), c(last, 2, "b", 1), c(last, 0, "off", 0)]);
    xml.push("</net>".into());
    xml.concat()
}

/// A ramp's lane that runs on into an off-ramp is a merge: the ramp's traffic staying on the
/// carriageway must leave it before it turns off, so its lane ends there, and the off-ramp is
/// the region's. Before weaving sections were planned, this net had no region.
#[test]
fn a_weaving_section_is_a_merge_whose_lane_ends_where_it_turns_off() {
    let net = Net::parse(Path::new("w.net.xml"), &weaving(300.0, false)).unwrap();
    let found = Discovery::of(&net);
    assert!(found.not_merges.is_empty(), "{:?}", found.not_merges);
    assert_eq!(found.regions.len(), 1);
    let l = &found.regions[0];
    assert_eq!(ids(l), ["a", "w", "b"]);
    let r = &l.on_ramps[0];
    assert_eq!(
        (r.joins.as_str(), r.ends_on.as_str(), r.end_lane),
        ("w", "w", 0)
    );
    assert_eq!(r.weaves_into.as_deref(), Some("off"));
    assert!((r.merge_start - 100.0).abs() < 1e-6, "{r:?}");
    assert!((r.merge_end - 400.0).abs() < 1e-6, "{r:?}");
    assert_eq!(l.off_ramps.len(), 1);
    assert_eq!(
        (l.off_ramps[0].leaves.as_str(), &l.off_ramps[0].edges[..]),
        ("w", &["off".to_string()][..])
    );
    assert!(l
        .describe()
        .contains("weaving: its lane runs on into off-ramp 'off'"));
    // Its frame: the auxiliary lane is lane 0 of the merge zone, which ends where it turns off.
    let road = crate::sumo::road_frame::road(&net, l).unwrap();
    let z = road.zones[0];
    assert!(
        (z.start - 100.0).abs() < 1e-6 && (z.end - 400.0).abs() < 1e-6,
        "{z:?}"
    );
    assert_eq!(road.exits.len(), 1);
    assert!(road.edge("off").is_none(), "the off-ramp leaves the frame");
}

/// A turning lane is no weaving section: too short for a lane change, or past a side street
/// whose traffic the region would not see. Each is reported with why.
#[test]
fn short_or_crossed_turning_lanes_are_not_weaving_sections() {
    for (weave, street, why) in [
        (
            20.0,
            false,
            "after 20.00 m, shorter than a weaving section (50 m)",
        ),
        (300.0, true, "past the junction at 'w'"),
    ] {
        let net = Net::parse(Path::new("w.net.xml"), &weaving(weave, street)).unwrap();
        let found = Discovery::of(&net);
        assert!(found.regions.is_empty(), "{weave} {street}");
        assert_eq!(found.not_merges.len(), 1);
        let n = &found.not_merges[0];
        assert!(n.ramp == "r" && n.why.contains(why), "{n:?}");
    }
}
