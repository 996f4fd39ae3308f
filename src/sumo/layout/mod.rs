//! The merge regions of any SUMO network: each carriageway that on-ramps join, cut to the
//! stretch around its merges, with its on-ramps (the acceleration lane each feeds and where that
//! lane ends), the off-ramps leaving that stretch, and the reference line of its frame. Every
//! edge of no region is left out with why: SUMO drives the vehicles there on their own models.
//!
//! A region runs from [`UPSTREAM`] metres before its first merge (whole edges, so a vehicle
//! enters it at an edge's start) to [`DOWNSTREAM`] metres after its last merge lane ends; a
//! carriageway that begins or ends sooner is taken whole, so each of the shipped networks is
//! one region from its source to its sink. The distance along a region counts the junctions'
//! internal lanes between its edges. The road frame of a region is built in `road_frame.rs`.
//!
//! Besides the regions, every forced lane change of the network is named by its kind
//! (`lane_ends.rs`), with where it is planned or why not; an on-ramp alongside another merge's
//! auxiliary lane is named so (`alongside.rs`), and a region where one's acceleration lane
//! begins beside another's is left to SUMO's drivers.

mod alongside;
mod describe;
pub mod lane_ends;
mod merges;

use std::collections::{BTreeMap, BTreeSet};

use crate::model::math::Point;
use crate::model::reference_line::ReferenceLine;
use crate::sumo::network::Net;

pub use lane_ends::{ForcedChange, Kind, LANE_GAIN};
pub use merges::{Merge, NotAMerge, MIN_WEAVING_LANE};

/// How far upstream of its first merge a region begins (m): longer than the planners'
/// horizon at the speed limit, so that a CAV is planned before it reaches the merge.
pub const UPSTREAM: f64 = 300.0;
/// How far downstream of its last merge lane's end a region ends (m): room for the vehicles
/// that merged last to settle.
pub const DOWNSTREAM: f64 = 100.0;

/// An edge of the main carriageway and where it starts along it.
#[derive(Debug, Clone, PartialEq)]
pub struct MainEdge {
    /// SUMO's edge id.
    pub id: String,
    /// Distance along the carriageway to the edge's start (m), internal lanes included.
    pub s_start: f64,
    /// Its length along the carriageway (m), measured on its leftmost lane.
    pub length: f64,
    /// Number of lanes.
    pub lanes: u32,
    /// The index of its leftmost through lane, the frame's reference (its leftmost lane, but
    /// where a left-side on-ramp's lane lies left of it).
    pub reference: u32,
}

/// An on-ramp: its edges, and the main-road lane it feeds.
#[derive(Debug, Clone, PartialEq)]
pub struct OnRamp {
    /// Its edges, up to the main carriageway (not included): from where it forks off another
    /// road (or its source, or [`UPSTREAM`] metres back) on.
    pub edges: Vec<String>,
    /// The main edge it joins and the lane of it the ramp's lane continues into.
    pub joins: String,
    /// Lane index on `joins`.
    pub lane: u32,
    /// The main edge on which that lane ends (`joins`, or one downstream after a lane gain; in
    /// a weaving section, the last before the lane turns off into the off-ramp).
    pub ends_on: String,
    /// Its lane index there.
    pub end_lane: u32,
    /// Where that lane ends along the carriageway (m): the acceleration lane's end (in a
    /// weaving section, where it turns off), by which a ramp vehicle must have merged.
    pub merge_end: f64,
    /// Where that lane starts along the carriageway (m): merging may begin here.
    pub merge_start: f64,
    /// In a weaving section, the off-ramp edge the lane runs on into at `merge_end` (one of the
    /// region's off-ramps); `None` where the lane ends there.
    pub weaves_into: Option<String>,
    /// The further lanes of a ramp of several, from the one beside `lane` outwards.
    pub outer: Vec<OuterEnd>,
    /// Whether it joins at the nose, without an acceleration lane: its lane and the
    /// carriageway's lane `lane` lead into one where `joins` begins (`merge_start` is
    /// `merge_end`), and its traffic merges by driving on.
    pub nose: bool,
}

/// A further lane of an on-ramp of several (a two-lane on-ramp, a lane gain dropped later):
/// the lane of `joins` it feeds and where it ends.
#[derive(Debug, Clone, PartialEq)]
pub struct OuterEnd {
    /// Lane index on the ramp's `joins`.
    pub lane: u32,
    /// The main edge on which it ends.
    pub ends_on: String,
    /// Its lane index there.
    pub end_lane: u32,
    /// Where it ends along the carriageway (m): its traffic must have moved over by then.
    pub merge_end: f64,
}

/// A lane drop: the carriageway's rightmost or leftmost lane ends on edge `ends_on`, at
/// `merge_end` along it (m); its traffic must have moved one lane over by then.
#[derive(Debug, Clone, PartialEq)]
pub struct LaneDrop {
    /// The main edge on which the lane ends.
    pub ends_on: String,
    /// Its index there: 0, or the edge's leftmost.
    pub lane: u32,
    /// Where the lane ends along the carriageway (m).
    pub merge_end: f64,
}

/// An off-ramp: the main edge it leaves and its edges.
#[derive(Debug, Clone, PartialEq)]
pub struct OffRamp {
    /// The main edge it leaves from.
    pub leaves: String,
    /// Its edges, up to a sink, a fork or a junction with another road.
    pub edges: Vec<String>,
}

/// The merge layout of one region.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// The main carriageway's edges in the region, in driving order.
    pub main: Vec<MainEdge>,
    /// The on-ramps.
    pub on_ramps: Vec<OnRamp>,
    /// The carriageway's outer lanes that end (lane drops), in order along it.
    pub lane_drops: Vec<LaneDrop>,
    /// The off-ramps.
    pub off_ramps: Vec<OffRamp>,
    /// The curvilinear frame's reference line: s along it, d from it (positive left).
    pub line: ReferenceLine,
}

/// A region found but left to SUMO's drivers, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct LeftToSumo {
    /// The region.
    pub layout: Layout,
    /// The on-ramp (its last edge) that cannot be planned.
    pub ramp: String,
    /// Why, in one phrase.
    pub why: String,
}

/// Where a forced lane change is planned, or that it is not.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// In the region of this index in [`Discovery::regions`].
    Region(usize),
    /// In the region of this index in [`Discovery::left_to_sumo`].
    LeftToSumo(usize),
    /// Nowhere: SUMO's drivers drive it.
    NotPlanned,
}

/// What was found in a network: its merge regions, in file order of their first merge, every
/// forced lane change by kind, and why every other edge was left out.
#[derive(Debug, Clone, PartialEq)]
pub struct Discovery {
    /// The regions to plan: each a carriageway's stretch around its merges.
    pub regions: Vec<Layout>,
    /// Regions found that the planners cannot plan yet, each with why.
    pub left_to_sumo: Vec<LeftToSumo>,
    /// Every forced lane change, by kind, with where it is planned.
    pub changes: Vec<(ForcedChange, Status)>,
    /// Ramps joining a carriageway where no merge is planned, each with why.
    pub not_merges: Vec<NotAMerge>,
    /// Every edge in no region, with why (closed to cars, or far from any merge).
    pub left_out: Vec<(String, String)>,
}

impl Discovery {
    /// The merge regions of `net`.
    pub fn of(net: &Net) -> Discovery {
        let (merges, mut not_merges) = merges::find(net);
        let (order, by_road) = by_carriageway(net, merges);
        let (mut regions, mut left_to_sumo) = (Vec::new(), Vec::new());
        for road in &order {
            let (merges, drops) = &by_road[road];
            match Layout::of_region(net, road, merges, drops) {
                Some(layout) => match alongside::why(net, &layout) {
                    Some((ramp, why)) => left_to_sumo.push(LeftToSumo { layout, ramp, why }),
                    None => regions.push(layout),
                },
                None => not_merges.extend(merges.iter().map(|m| NotAMerge {
                    ramp: m.ramp.clone(),
                    why: format!("joins '{}', a carriageway without lane shapes", m.joins),
                })),
            }
        }
        let beside = (regions.iter())
            .chain(left_to_sumo.iter().map(|l| &l.layout))
            .flat_map(|l| alongside::beside(net, l))
            .collect::<Vec<_>>();
        let changes = changes(lane_ends::find(net), &regions, &left_to_sumo, &beside);
        let used: BTreeSet<&str> = regions.iter().flat_map(Layout::edge_ids).collect();
        let sumos: BTreeSet<&str> = left_to_sumo
            .iter()
            .flat_map(|l| l.layout.edge_ids())
            .collect();
        let mut left_out = net.closed.clone();
        for e in net.edges.iter().filter(|e| !used.contains(e.id.as_str())) {
            let why = if sumos.contains(e.id.as_str()) {
                "in a merge region left to SUMO's drivers"
            } else {
                "in no merge region"
            };
            left_out.push((e.id.clone(), why.to_string()));
        }
        Discovery {
            regions,
            left_to_sumo,
            changes,
            not_merges,
            left_out,
        }
    }
}

/// Per carriageway (its edges), its merges and the edges its right lanes drop on.
type OnCarriageway = BTreeMap<Vec<String>, (Vec<Merge>, Vec<(String, u32)>)>;

/// The merges and planned lane drops of `net`, grouped by the carriageway they lie on: the
/// carriageways in the order their first merge or drop was found, and each one's merges and
/// the edges its lanes drop on.
fn by_carriageway(net: &Net, merges: Vec<Merge>) -> (Vec<Vec<String>>, OnCarriageway) {
    let mut by_road = OnCarriageway::new();
    let mut order: Vec<Vec<String>> = Vec::new();
    let mut road_of = |edge: &str| {
        let road = merges::carriageway(net, edge);
        if !order.contains(&road) {
            order.push(road.clone());
        }
        road
    };
    let mut grouped = Vec::new();
    for m in merges {
        grouped.push((road_of(&m.joins), Some(m), None));
    }
    for d in lane_ends::planned_lane_drops(net) {
        grouped.push((road_of(&d.0), None, Some(d)));
    }
    for (road, m, d) in grouped {
        let (merges, drops) = by_road.entry(road).or_default();
        merges.extend(m);
        drops.extend(d);
    }
    (order, by_road)
}

/// The forced lane changes `found`, with the weaving sections of the regions, each with where
/// it is planned; an on-ramp running alongside another's auxiliary lane (`beside`: its name and
/// what it runs beside) is named so.
fn changes(
    mut found: Vec<ForcedChange>,
    regions: &[Layout],
    left: &[LeftToSumo],
    beside: &[(String, String)],
) -> Vec<(ForcedChange, Status)> {
    let layouts = regions.iter().chain(left.iter().map(|l| &l.layout));
    for r in layouts.flat_map(|l| &l.on_ramps) {
        if let Some(exit) = &r.weaves_into {
            found.push(ForcedChange {
                kind: Kind::Weaving,
                ramp: Some(alongside::ramp_name(r).to_string()),
                drop: None,
                what: format!(
                    "'{}' → '{}': its lane runs on into off-ramp '{exit}' on '{}'",
                    alongside::ramp_name(r),
                    r.joins,
                    r.ends_on
                ),
            });
        }
    }
    let has = |l: &Layout, ramp: &str| l.on_ramps.iter().any(|r| alongside::ramp_name(r) == ramp);
    let drops = |l: &Layout, edge: &str| l.lane_drops.iter().any(|d| d.ends_on == edge);
    let mut out: Vec<(ForcedChange, Status)> = found
        .into_iter()
        .map(|mut c| {
            let planned = matches!(
                c.kind,
                Kind::AccelerationLane
                    | Kind::Weaving
                    | Kind::TwoLaneOnRamp
                    | Kind::GainDroppedLater
                    | Kind::LeftSideOnRamp
                    | Kind::NoseMerge
            );
            let ramp = c.ramp.as_deref().filter(|_| planned).unwrap_or_default();
            let drop = c.drop.as_deref().unwrap_or_default();
            if let Some((_, what)) = beside.iter().find(|(r, _)| r == ramp) {
                c.kind = Kind::Alongside;
                c.what = what.clone();
            }
            let status = if let Some(k) = regions.iter().position(|l| drops(l, drop)) {
                Status::Region(k)
            } else if let Some(k) = regions.iter().position(|l| has(l, ramp)) {
                Status::Region(k)
            } else if let Some(k) = left.iter().position(|l| has(&l.layout, ramp)) {
                Status::LeftToSumo(k)
            } else {
                Status::NotPlanned
            };
            (c, status)
        })
        .collect();
    out.sort_by_key(|(c, _)| c.kind);
    out
}

impl Layout {
    /// The region of carriageway `road` around `merges` and the lane drops `drops` (edge, lane)
    /// (all on it, in its order).
    fn of_region(
        net: &Net,
        road: &[String],
        merges: &[Merge],
        drops: &[(String, u32)],
    ) -> Option<Layout> {
        let at = |id: &str| road.iter().position(|e| e == id).expect("on the road");
        let firsts = merges.iter().map(|m| at(&m.joins));
        let first = firsts.chain(drops.iter().map(|d| at(&d.0))).min()?;
        let lasts = merges.iter().map(|m| at(&m.ends_on));
        let last = lasts.chain(drops.iter().map(|d| at(&d.0))).max()?;
        let length = |id: &String| net.edge(id).lanes.last().map_or(0.0, |l| l.length);
        let mut begin = first;
        let mut upstream = 0.0;
        while begin > 0 && upstream < UPSTREAM {
            begin -= 1;
            upstream += length(&road[begin]);
        }
        let mut end = last;
        let mut downstream = 0.0;
        while end + 1 < road.len() && downstream < DOWNSTREAM {
            end += 1;
            downstream += length(&road[end]);
        }
        let ids = &road[begin..=end];
        let through = leftmost_through(net, ids);
        let line = reference_line(net, ids, &through)?;
        let main = positions(net, ids, &through, &line);
        let on_main: BTreeSet<&str> = road.iter().map(String::as_str).collect();
        let on_ramps = merges
            .iter()
            .map(|m| on_ramp(net, m, &on_main, &line))
            .collect();
        let next = road.get(end + 1).map(String::as_str);
        let lane_drops = (drops.iter())
            .map(|(edge, lane)| LaneDrop {
                ends_on: edge.clone(),
                lane: *lane,
                merge_end: net.edge(edge).lanes[*lane as usize]
                    .shape
                    .last()
                    .map_or(0.0, |p| line.to_frame(*p).0),
            })
            .collect();
        Some(Layout {
            off_ramps: off_ramps(net, ids, next, &on_main),
            main,
            on_ramps,
            lane_drops,
            line,
        })
    }

    /// Every edge of the region: main, on-ramps, off-ramps.
    pub fn edge_ids(&self) -> impl Iterator<Item = &str> {
        let main = self.main.iter().map(|m| m.id.as_str());
        let on = self.on_ramps.iter().flat_map(|r| r.edges.iter());
        let off = self.off_ramps.iter().flat_map(|r| r.edges.iter());
        main.chain(on.chain(off).map(String::as_str))
    }

    /// The edges its on-ramps join and its lanes drop on: the region's names in `[scenario]
    /// regions`.
    pub fn merge_edges(&self) -> impl Iterator<Item = &str> {
        let drops = self.lane_drops.iter().map(|d| d.ends_on.as_str());
        self.on_ramps.iter().map(|r| r.joins.as_str()).chain(drops)
    }

    /// Length of the main carriageway along the reference line (m).
    pub fn length(&self) -> f64 {
        self.line.length()
    }
}

/// Per main edge of `ids`, the index of its leftmost through lane: the lane the carriageway's
/// leftmost lane runs on, followed upstream from the last edge's leftmost lane. It is the
/// edge's leftmost lane but where a left-side on-ramp's lane lies left of it.
fn leftmost_through(net: &Net, ids: &[String]) -> Vec<u32> {
    let top = |id: &String| net.edge(id).lanes.len() as u32 - 1;
    let mut out: Vec<u32> = ids.iter().map(top).collect();
    for k in (0..ids.len().saturating_sub(1)).rev() {
        let (next, into) = (&ids[k + 1], out[k + 1]);
        let from = (net.outgoing(&ids[k]))
            .filter(|c| &c.to == next && c.to_lane == into)
            .map(|c| c.from_lane)
            .max();
        out[k] = from.unwrap_or(out[k]);
    }
    out
}

/// The reference line of a region: the centre line of each main edge's leftmost through lane
/// (`through`, by edge) and of the internal lane joining it to the next edge's, in order;
/// `None` if their shapes hold fewer than two distinct points.
fn reference_line(net: &Net, ids: &[String], through: &[u32]) -> Option<ReferenceLine> {
    let mut points: Vec<Point> = Vec::new();
    for (k, id) in ids.iter().enumerate() {
        let left = &net.edge(id).lanes[through[k] as usize];
        points.extend(&left.shape);
        let Some(next) = ids.get(k + 1) else { break };
        let via = net
            .outgoing(id)
            .filter(|c| &c.to == next && c.from_lane == through[k])
            .max_by_key(|c| c.to_lane)
            .and_then(|c| c.via.as_ref())
            .and_then(|v| net.internal.get(v));
        if let Some(lane) = via {
            points.extend(&lane.shape);
        }
    }
    ReferenceLine::new(points)
}

/// Where each main edge starts along the reference line (measured on its leftmost through
/// lane, `through`).
fn positions(net: &Net, ids: &[String], through: &[u32], line: &ReferenceLine) -> Vec<MainEdge> {
    ids.iter()
        .zip(through)
        .map(|(id, &reference)| {
            let e = net.edge(id);
            let left = &e.lanes[reference as usize];
            let s_start = left.shape.first().map_or(0.0, |p| line.to_frame(*p).0);
            let s_end = left.shape.last().map_or(0.0, |p| line.to_frame(*p).0);
            MainEdge {
                id: id.clone(),
                s_start,
                length: s_end - s_start,
                lanes: e.lanes.len() as u32,
                reference,
            }
        })
        .collect()
}

/// The on-ramp of `merge`: its edges walked upstream while each has one way in and one way
/// out (up to [`UPSTREAM`] metres), and where its lane starts and ends along `line`.
fn on_ramp(net: &Net, merge: &Merge, on_main: &BTreeSet<&str>, line: &ReferenceLine) -> OnRamp {
    let mut edges = vec![merge.ramp.clone()];
    let mut length = net.edge(&merge.ramp).lanes[0].length;
    while length < UPSTREAM {
        let here = &edges[0];
        let [p] = net.predecessors(here)[..] else {
            break;
        };
        if on_main.contains(p) || net.successors(p).len() != 1 || edges.iter().any(|e| e == p) {
            break;
        }
        length += net.edge(p).lanes[0].length;
        edges.insert(0, p.to_string());
    }
    let at = |p: Option<&Point>| p.map_or(0.0, |p| line.to_frame(*p).0);
    let start = &net.edge(&merge.joins).lanes[merge.lane as usize];
    let end = &net.edge(&merge.ends_on).lanes[merge.end_lane as usize];
    let outer = (merge.outer.iter())
        .map(|o| OuterEnd {
            lane: o.lane,
            ends_on: o.ends_on.clone(),
            end_lane: o.end_lane,
            merge_end: at(net.edge(&o.ends_on).lanes[o.end_lane as usize].shape.last()),
        })
        .collect();
    OnRamp {
        edges,
        joins: merge.joins.clone(),
        lane: merge.lane,
        ends_on: merge.ends_on.clone(),
        end_lane: merge.end_lane,
        merge_start: at(start.shape.first()),
        merge_end: match merge.nose {
            true => at(start.shape.first()),
            false => at(end.shape.last()),
        },
        weaves_into: merge.weaves_into.clone(),
        outer,
        nose: merge.nose,
    }
}

/// The off-ramps of the region `ids`: every road a main edge leads to other than the
/// carriageway (`next`: the carriageway's edge after the region), walked downstream while each
/// edge has one way on and one way in.
fn off_ramps(
    net: &Net,
    ids: &[String],
    next: Option<&str>,
    on_main: &BTreeSet<&str>,
) -> Vec<OffRamp> {
    let mut out = Vec::new();
    for m in ids {
        for first in net.successors(m) {
            if on_main.contains(first) || Some(first) == next {
                continue;
            }
            let mut edges = vec![first.to_string()];
            while let [n] = net.successors(edges.last().expect("non-empty"))[..] {
                if on_main.contains(n)
                    || net.predecessors(n).len() != 1
                    || edges.iter().any(|e| e == n)
                {
                    break;
                }
                edges.push(n.to_string());
            }
            out.push(OffRamp {
                leaves: m.clone(),
                edges,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests;
