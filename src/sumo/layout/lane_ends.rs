//! Every forced lane change of a network, named as a SUMO user would: a lane open to cars
//! that ends while its traffic goes on (its edge leads on, the lane has no connection), traced
//! back to where it began, and every ramp that joins at the nose (its lane and a main lane
//! lead into one). Where a lane began says what it is:
//!
//! - fed by a one-lane on-ramp on the right: an **acceleration lane** (what the planners plan);
//! - fed by an on-ramp of two lanes or more on the right: a **two-lane on-ramp** if its first
//!   lane ends within [`LANE_GAIN`] metres of where it joined, else a **lane gain dropped
//!   later**;
//! - fed by an on-ramp left of the carriageway's lanes: a **left-side on-ramp**;
//! - part of the carriageway since its source, or begun on it without a feeder: a **lane
//!   drop**.
//!
//! Weaving sections and on-ramps alongside another merge's auxiliary lane are merges of a
//! region, named by the region (`mod.rs`); junctions' turning lanes stay "not a merge".

use std::collections::{BTreeMap, BTreeSet};

use super::merges::{joins_at_nose, lanes_fed, main_feeder, NOSE_MERGE_MIN_SPEED};
use crate::sumo::network::Net;

/// How far an on-ramp's lanes run on before the first of them ends for the carriageway to
/// have gained them (m): longer than any acceleration lane (250–300 m in German and US
/// guidelines), so that a two-lane ramp whose lanes end in turn within that is an on-ramp.
pub const LANE_GAIN: f64 = 500.0;

/// How far upstream a lane is traced to find where it began (m): past that it is the
/// carriageway's own.
const TRACE_LIMIT: f64 = 5000.0;

/// What kind of forced lane change, in the words a SUMO user knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    /// A one-lane on-ramp's lane that ends: the merge the planners plan.
    AccelerationLane,
    /// A weaving section: a ramp's lane that turns off into an off-ramp.
    Weaving,
    /// An on-ramp whose edges run, along the carriageway, beside another merge's auxiliary
    /// lane.
    Alongside,
    /// An on-ramp of two lanes or more whose lanes end in turn.
    TwoLaneOnRamp,
    /// Lanes an on-ramp adds that run on [`LANE_GAIN`] metres or more, then end.
    GainDroppedLater,
    /// A lane of the main road that ends.
    LaneDrop,
    /// A ramp joining at the nose, without an acceleration lane.
    NoseMerge,
    /// An on-ramp joining on the left.
    LeftSideOnRamp,
}

impl Kind {
    /// Its name in `bkpbs network`'s lines and the guide.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::AccelerationLane => "acceleration lane",
            Kind::Weaving => "weaving section",
            Kind::Alongside => "on-ramp alongside another's auxiliary lane",
            Kind::TwoLaneOnRamp => "two-lane on-ramp",
            Kind::GainDroppedLater => "lane gain dropped later",
            Kind::LaneDrop => "lane drop",
            Kind::NoseMerge => "nose merge",
            Kind::LeftSideOnRamp => "left-side on-ramp",
        }
    }
}

/// A forced lane change found in a network.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcedChange {
    /// Its kind.
    pub kind: Kind,
    /// The on-ramp's last edge whose traffic must change lanes; `None` for a lane drop.
    pub ramp: Option<String>,
    /// For a lane drop, the edge on which the lane ends.
    pub drop: Option<String>,
    /// Where, in words after the kind's name (`'on' → 'acc': …`, `3 → 2 lanes on 'mid'`).
    pub what: String,
}

/// Where a lane that ends began.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
enum Origin {
    /// On the carriageway: at its source, or where it widened.
    Carriageway,
    /// Fed by on-ramp `ramp` where it joins edge `joins`.
    Ramp { ramp: String, joins: String },
}

/// A lane that ends: its edge, its index, and how far it ran from where it began (m).
struct End {
    edge: String,
    lane: u32,
    run: f64,
}

/// Every lane end and nose merge of `net`, by kind, then in file order.
pub fn find(net: &Net) -> Vec<ForcedChange> {
    let mut by_origin: BTreeMap<Origin, Vec<End>> = BTreeMap::new();
    for (edge, lane) in lane_ends(net) {
        let (origin, run) = origin(net, edge, lane);
        let end = End {
            edge: edge.to_string(),
            lane,
            run,
        };
        by_origin.entry(origin).or_default().push(end);
    }
    let mut out = Vec::new();
    for (origin, ends) in by_origin {
        match origin {
            Origin::Carriageway => out.extend(lane_drops(net, &ends)),
            Origin::Ramp { ramp, joins } => out.push(ramp_lanes(net, &ramp, &joins, &ends)),
        }
    }
    out.extend(nose_merges(net));
    out.sort_by_key(|c| c.kind);
    out
}

/// Every car lane that ends on an edge leading on: `(edge, lane)`, in file order.
fn lane_ends(net: &Net) -> Vec<(&str, u32)> {
    let mut out = Vec::new();
    for e in &net.edges {
        if net.successors(&e.id).is_empty() {
            continue;
        }
        let on: BTreeSet<u32> = net.outgoing(&e.id).map(|c| c.from_lane).collect();
        let ends = e
            .lanes
            .iter()
            .filter(|l| l.for_cars && !on.contains(&l.index));
        out.extend(ends.map(|l| (e.id.as_str(), l.index)));
    }
    out
}

/// Where lane `lane` of `edge` began, followed upstream along the carriageway's lanes, and
/// how far it ran from there (m).
fn origin(net: &Net, edge: &str, lane: u32) -> (Origin, f64) {
    let (mut edge, mut lane) = (edge.to_string(), lane);
    let mut seen = BTreeSet::new();
    let mut run = 0.0;
    loop {
        run += net
            .edge(&edge)
            .lanes
            .get(lane as usize)
            .map_or(0.0, |l| l.length);
        if !seen.insert((edge.clone(), lane)) || run > TRACE_LIMIT {
            return (Origin::Carriageway, run);
        }
        let sources: Vec<_> = net.incoming(&edge).filter(|c| c.to_lane == lane).collect();
        let Some(main) = main_feeder(net, &edge) else {
            return (Origin::Carriageway, run);
        };
        let Some(first) = sources.first() else {
            return (Origin::Carriageway, run);
        };
        match sources
            .iter()
            .filter(|c| c.from == main)
            .max_by_key(|c| c.from_lane)
        {
            Some(c) => (edge, lane) = (c.from.clone(), c.from_lane),
            None => {
                let ramp = first.from.clone();
                return (Origin::Ramp { ramp, joins: edge }, run);
            }
        }
    }
}

/// The lane drops the planners plan, in file order, each as its edge and the lane that ends:
/// the carriageway's rightmost lane (lane 0) ending on a road that nothing joins there, or its
/// leftmost lane ending, while two lanes or more go on, on a road of [`NOSE_MERGE_MIN_SPEED`]
/// or more (its traffic moves one lane over before the end).
pub fn planned_lane_drops(net: &Net) -> Vec<(String, u32)> {
    let ends = lane_ends(net);
    let ending = |edge: &str| ends.iter().filter(|(e, _)| *e == edge).count();
    let mut out: Vec<(String, u32)> = Vec::new();
    for &(edge, lane) in &ends {
        let e = net.edge(edge);
        let cars = e.lanes.iter().filter(|l| l.for_cars).count();
        let limit = e.lanes.iter().map(|l| l.speed).fold(0.0, f64::max);
        let right = lane == 0 && net.predecessors(edge).len() == 1;
        let left = lane as usize + 1 == e.lanes.len();
        let plannable = (right || left)
            && cars >= 3
            && ending(edge) == 1
            && limit >= NOSE_MERGE_MIN_SPEED
            && origin(net, edge, lane).0 == Origin::Carriageway;
        if plannable && !out.iter().any(|(o, _)| o == edge) {
            out.push((edge.to_string(), lane));
        }
    }
    out
}

/// The lane drops among `ends` (lanes of the carriageway), one per edge.
fn lane_drops(net: &Net, ends: &[End]) -> Vec<ForcedChange> {
    let mut by_edge: BTreeMap<&str, Vec<u32>> = BTreeMap::new();
    for e in ends {
        by_edge.entry(&e.edge).or_default().push(e.lane);
    }
    let order = |id: &str| net.edges.iter().position(|e| e.id == id);
    let mut edges: Vec<_> = by_edge.into_iter().collect();
    edges.sort_by_key(|(id, _)| order(id));
    edges
        .into_iter()
        .map(|(edge, lanes)| lane_drop(net, edge, &lanes))
        .collect()
}

/// The lane drop of `lanes` of `edge`.
fn lane_drop(net: &Net, edge: &str, lanes: &[u32]) -> ForcedChange {
    let cars = |id: &str| net.edge(id).lanes.iter().filter(|l| l.for_cars).count();
    let n = cars(edge);
    let left = n - lanes.len();
    let plural = if left == 1 { "" } else { "s" };
    let mut what = format!("{n} → {left} lane{plural} on '{edge}'");
    let top = net.edge(edge).lanes.iter().map(|l| l.index).max();
    if lanes.iter().any(|l| Some(*l) == top) {
        what += " (its leftmost lane ends)";
    }
    let main = main_feeder(net, edge);
    let ramps: Vec<String> = net
        .predecessors(edge)
        .into_iter()
        .filter(|p| Some(*p) != main)
        .map(|p| format!("'{p}' ({} lanes)", cars(p)))
        .collect();
    if !ramps.is_empty() {
        let verb = if ramps.len() == 1 { "joins" } else { "join" };
        what += &format!(", where {} {verb}", ramps.join(" and "));
    }
    ForcedChange {
        kind: Kind::LaneDrop,
        ramp: None,
        drop: Some(edge.to_string()),
        what,
    }
}

/// The kind of the lanes on-ramp `ramp` feeds on `joins` that end (`ends`).
fn ramp_lanes(net: &Net, ramp: &str, joins: &str, ends: &[End]) -> ForcedChange {
    let fed = lanes_fed(net, ramp, joins);
    let main = main_feeder(net, joins).map(|m| lanes_fed(net, m, joins));
    let left = main
        .as_deref()
        .and_then(|m| m.last())
        .is_some_and(|top| fed.first().is_some_and(|r| r > top));
    let ramp_lanes: BTreeSet<u32> = net
        .outgoing(ramp)
        .filter(|c| c.to == joins)
        .map(|c| c.from_lane)
        .collect();
    let first = ends.iter().map(|e| e.run).fold(f64::INFINITY, f64::min);
    let kind = if left {
        Kind::LeftSideOnRamp
    } else if ramp_lanes.len() < 2 {
        Kind::AccelerationLane
    } else if first < LANE_GAIN {
        Kind::TwoLaneOnRamp
    } else {
        Kind::GainDroppedLater
    };
    let width = match ramp_lanes.len() {
        0 | 1 => String::new(),
        n => format!(" ({n} lanes)"),
    };
    let on: Vec<String> = ends
        .iter()
        .map(|e| format!("lane {} of '{}' after {:.0} m", e.lane, e.edge, e.run))
        .collect();
    ForcedChange {
        kind,
        ramp: Some(ramp.to_string()),
        drop: None,
        what: format!("'{ramp}'{width} → '{joins}': ends {}", on.join(", ")),
    }
}

/// Every ramp joining at the nose ([`joins_at_nose`]).
fn nose_merges(net: &Net) -> Vec<ForcedChange> {
    let mut out = Vec::new();
    for e in &net.edges {
        for ramp in net.predecessors(&e.id) {
            if let Some(lane) = joins_at_nose(net, ramp, &e.id) {
                out.push(ForcedChange {
                    kind: Kind::NoseMerge,
                    ramp: Some(ramp.to_string()),
                    drop: None,
                    what: format!(
                        "'{ramp}' → '{}': its lane and a main-road lane lead into lane {lane}",
                        e.id
                    ),
                });
            }
        }
    }
    out
}
