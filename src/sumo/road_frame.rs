//! The road frame of a network's layout: every lane of the main carriageway, of the on-ramps
//! and of the junctions between them (internal lanes) placed in the frame of
//! `crate::model::road`, so that any reading SUMO gives on the merge section has a frame `s` and
//! lane, and any frame lane a SUMO lane index to command.
//!
//! Main lanes are numbered from the left edge of the carriageway: an edge with the
//! carriageway's N lanes holds frame lanes 1..=N, an edge with one lane more also holds the
//! auxiliary lane 0 (an acceleration or deceleration lane, or a weaving section's lane, whose
//! merge zone ends where it turns off into the off-ramp). The reference line is the centre
//! line of each edge's leftmost lane and of the junction lane joining it to the next: a lane
//! position on an edge maps to the `s` of the same position on its leftmost lane, as SUMO
//! itself aligns the lanes of an edge (a lane change keeps the position), and a position on a
//! junction lane to the same fraction of the reference's junction lane. (Projecting each
//! lane's ends on the reference line instead went wrong by metres where a junction lane bends
//! the reference line.) Lanes
//! that leave towards an off-ramp, and the off-ramps, are not part of the frame: a vehicle there
//! has left the section.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::model::road::{
    EdgeFrame, Entry, Exit, LaneFrame, MergeZone, Road, FIRST_MAIN_LANE, MERGE_LANE,
};
use crate::sumo::layout::{LaneDrop, Layout, MainEdge, OnRamp};
use crate::sumo::network::{Lane, Net};

/// The shortest acceleration lane a merge is planned on (m): room for one car.
const MIN_ACCELERATION_LANE: f64 = 5.0;

/// How far before the nose a ramp joining there without an acceleration lane lets its vehicles
/// commit to merging (m): about two seconds at a motorway's speed, room for one lane change of
/// the planners' (`scenario.lane_change_duration`, 1 s) to start and end before the nose. Past
/// that point a committed vehicle counts as changing lanes until the nose (`episode::nose`).
pub const NOSE_ZONE: f64 = 60.0;

/// Where each main edge lies: its frame-lane offset and the span of its reference lane.
struct MainFrames<'n> {
    /// The carriageway's lanes (frame lanes 1 to it).
    main_lanes: i32,
    offsets: BTreeMap<&'n str, i32>,
    spans: BTreeMap<&'n str, LaneFrame>,
}

/// The road frame of `layout` (found in `net`); the error says in one phrase why the layout
/// cannot be planned on.
pub fn road(net: &Net, layout: &Layout) -> Result<Road, String> {
    // The carriageway's own lanes: as many as its narrowest edge has; the rest are auxiliary.
    let main_lanes = layout
        .main
        .iter()
        .map(|m| m.lanes)
        .min()
        .expect("a main edge") as i32;
    let first = net.edge(&layout.main[0].id);
    let lane_width = first.lanes.last().expect("lanes checked").width;
    let outer_lanes = (layout.on_ramps.iter()).map(|r| r.outer.len()).max();
    let bottom = MERGE_LANE - outer_lanes.unwrap_or(0) as i32;
    let left_ramps = (layout.on_ramps.iter()).any(|r| on_the_left(layout, r));
    let left_drops = (layout.lane_drops.iter()).any(|d| d.lane > 0);
    let top = main_lanes + i32::from(left_ramps || left_drops);
    let (mut edges, main) = main_edges(net, layout, main_lanes, (bottom, top))?;
    let mut internal = main_junctions(net, layout, &main);
    let mut ramps: Vec<&OnRamp> = layout.on_ramps.iter().collect();
    ramps.sort_by(|a, b| a.merge_start.total_cmp(&b.merge_start));
    let mut zones = ramp_zones(net, layout, &ramps, &main, (&mut edges, &mut internal))?;
    for d in &layout.lane_drops {
        zones.push(drop_zone(net, layout, d, &main)?);
    }
    edges.extend(internal.into_edges());
    let entries = entries(net, layout, &ramps);
    let last = layout.main.last().expect("a main carriageway");
    let end_lane = &net.edge(&last.id).lanes[last.reference as usize];
    let section_end = main.spans[last.id.as_str()].s_at(end_lane.length);
    Ok(Road {
        edges,
        lane_width,
        main_lanes,
        zones,
        section_end,
        end_edge: (Arc::from(last.id.as_str()), end_lane.length),
        entries,
        exits: exits(net, layout),
        line: (!layout.line.is_straight_east()).then(|| Arc::new(layout.line.clone())),
    })
}

/// The frames of `ramps` (in order along the road) and their zones: each ramp's lane beside
/// the carriageway in that order, then the further lanes of ramps of several.
fn ramp_zones(
    net: &Net,
    layout: &Layout,
    ramps: &[&OnRamp],
    main: &MainFrames<'_>,
    (edges, internal): (&mut Vec<EdgeFrame>, &mut InternalEdges),
) -> Result<Vec<MergeZone>, String> {
    let (mut zones, mut outer) = (Vec::new(), Vec::new());
    for ramp in ramps {
        let end_lane = &net.edge(&ramp.ends_on).lanes[ramp.end_lane as usize];
        let nose = main.spans[ramp.joins.as_str()].s0;
        let joined = match ramp.nose {
            true => (nose, nose),
            false => (
                nose,
                main.spans[ramp.ends_on.as_str()].s_at(end_lane.length),
            ),
        };
        if !ramp.nose && joined.1 - joined.0 < MIN_ACCELERATION_LANE {
            return Err(format!(
                "the acceleration lane of on-ramp '{}' on '{}' is {:.2} m long, shorter than one \
                 vehicle ({MIN_ACCELERATION_LANE} m): no merge to plan",
                ramp.edges[0],
                ramp.joins,
                joined.1 - joined.0
            ));
        }
        // The ramp is in the frame only past every auxiliary lane on its side that ends
        // before it joins.
        let left = on_the_left(layout, ramp);
        let free_from = (zones.iter().chain(&outer))
            .filter(|z: &&MergeZone| (z.lane > MERGE_LANE) == left)
            .map(|z| z.end)
            .filter(|end| *end <= joined.0 + 1e-6)
            .fold(f64::NEG_INFINITY, f64::max);
        let placed = (joined, free_from);
        let zone = ramp_frames(net, ramp, placed, main, edges, internal)?;
        outer.extend(outer_zones(net, ramp, &zone, main)?);
        zones.push(zone);
    }
    zones.extend(outer);
    Ok(zones)
}

/// The frames of the main carriageway's edges: every lane of an edge at the `s` of the same
/// position on its leftmost lane (piecewise through its shape points where it bends).
fn main_edges<'n>(
    net: &'n Net,
    layout: &'n Layout,
    main_lanes: i32,
    (bottom, top): (i32, i32),
) -> Result<(Vec<EdgeFrame>, MainFrames<'n>), String> {
    let mut edges = Vec::new();
    let mut main = MainFrames {
        main_lanes,
        offsets: BTreeMap::new(),
        spans: BTreeMap::new(),
    };
    for m in &layout.main {
        let offset = lane_offset(m, main_lanes, (bottom, top))?;
        let edge = net.edge(&m.id);
        let left = &edge.lanes[m.reference as usize];
        let span = LaneFrame {
            lane: 0,
            s0: m.s_start,
            scale: shape_length(left) / left.length,
            knots: None,
            speed_limit: f64::INFINITY,
        };
        let lanes = edge
            .lanes
            .iter()
            .map(|l| {
                Some(LaneFrame {
                    lane: offset + l.index as i32,
                    knots: knots(l, left, m.s_start),
                    speed_limit: l.speed,
                    ..span.clone()
                })
            })
            .collect();
        main.offsets.insert(&m.id, offset);
        main.spans.insert(&m.id, span);
        edges.push(EdgeFrame {
            name: Arc::from(m.id.as_str()),
            lanes,
            on_ramp: false,
        });
    }
    Ok((edges, main))
}

/// The junction lanes between consecutive main edges: a position on one maps to the same
/// fraction of the reference line's stretch through the junction.
fn main_junctions(net: &Net, layout: &Layout, main: &MainFrames<'_>) -> InternalEdges {
    let mut internal = InternalEdges::default();
    for pair in layout.main.windows(2) {
        let (from, to) = (pair[0].id.as_str(), pair[1].id.as_str());
        let left = &net.edge(from).lanes[pair[0].reference as usize];
        let s_a = main.spans[from].s_at(left.length);
        let s_b = main.spans[to].s0;
        for c in net.outgoing(from).filter(|c| c.to == to) {
            if let Some(via) = c.via.as_ref().and_then(|v| net.internal.get(v)) {
                let frame = LaneFrame {
                    lane: main.offsets[from] + c.from_lane as i32,
                    s0: s_a,
                    scale: if via.length > 1e-6 {
                        (s_b - s_a) / via.length
                    } else {
                        1.0
                    },
                    knots: None,
                    speed_limit: via.speed,
                };
                internal.put(via, frame, false);
            }
        }
    }
    internal
}

/// The main entry and one per on-ramp (in `ramps`' order), with their routes to the end.
fn entries(net: &Net, layout: &Layout, ramps: &[&OnRamp]) -> Vec<Entry> {
    let main: Vec<Arc<str>> = layout
        .main
        .iter()
        .map(|m| Arc::from(m.id.as_str()))
        .collect();
    let limit = |edge: &str| {
        let lanes = &net.edge(edge).lanes;
        lanes.iter().map(|l| l.speed).fold(f64::INFINITY, f64::min)
    };
    let mut out = vec![Entry {
        name: "main".into(),
        route: main.clone(),
        speed_limit: limit(&main[0]),
    }];
    for (k, r) in ramps.iter().enumerate() {
        let join = main
            .iter()
            .position(|m| **m == r.joins)
            .expect("joins the main road");
        let route = r.edges.iter().map(|e| Arc::from(e.as_str()));
        // SUMO refuses to insert a vehicle that cannot slow to the limit of a lane ahead: on a
        // ramp of several short edges, the slowest of them.
        let speed_limit = r
            .edges
            .iter()
            .map(|e| limit(e))
            .fold(f64::INFINITY, f64::min);
        out.push(Entry {
            name: Road::ramp_entry_name(ramps.len(), k),
            route: route.chain(main[join..].iter().cloned()).collect(),
            speed_limit,
        });
    }
    out
}

/// The off-ramps in order along the road, named `off1`, `off2`, …
fn exits(net: &Net, layout: &Layout) -> Vec<Exit> {
    let order = |leaves: &str| layout.main.iter().position(|m| m.id == leaves);
    let mut ramps: Vec<_> = layout.off_ramps.iter().collect();
    ramps.sort_by_key(|r| order(&r.leaves));
    ramps
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let last = r.edges.last().expect("an off-ramp has an edge");
            let lane = &net.edge(last).lanes[0];
            Exit {
                name: format!("off{}", k + 1),
                leaves: Arc::from(r.leaves.as_str()),
                edges: r.edges.iter().map(|e| Arc::from(e.as_str())).collect(),
                end: (Arc::from(last.as_str()), lane.length),
            }
        })
        .collect()
}

/// Frame lane of the edge's lane 0: its leftmost through lane (`reference`) is the
/// carriageway's top lane, and the region's auxiliary lanes reach down to frame lane `bottom`
/// and up to `top`.
fn lane_offset(m: &MainEdge, main_lanes: i32, (bottom, top): (i32, i32)) -> Result<i32, String> {
    let offset = main_lanes - m.reference as i32;
    if offset < bottom || offset + m.lanes as i32 - 1 > top {
        let auxiliary = match FIRST_MAIN_LANE - bottom + top - main_lanes {
            1 => "one auxiliary lane".to_string(),
            n => format!("{n} auxiliary lanes"),
        };
        return Err(format!(
            "edge '{}' has {} lanes, more than the carriageway's {main_lanes} and the \
             {auxiliary} its on-ramps feed",
            m.id, m.lanes
        ));
    }
    Ok(offset)
}

/// Whether on-ramp `r` joins on the left: the lane it feeds lies left of the joined edge's
/// leftmost through lane.
fn on_the_left(layout: &Layout, r: &OnRamp) -> bool {
    (layout.main.iter()).any(|m| m.id == r.joins && r.lane > m.reference)
}

/// The zone of lane drop `d`: the carriageway's outer lane (frame lane 0 on the right, the
/// one above the carriageway's on the left) from where it begins in the region (the first of
/// the edges before the drop that hold it) to its end.
fn drop_zone(
    net: &Net,
    layout: &Layout,
    d: &LaneDrop,
    main: &MainFrames<'_>,
) -> Result<MergeZone, String> {
    let at = (layout.main.iter()).position(|m| m.id == d.ends_on);
    let at = at.expect("a lane drop lies on the region's carriageway");
    let lane = main.offsets[d.ends_on.as_str()] + d.lane as i32;
    if lane != MERGE_LANE && lane != main.main_lanes + 1 {
        return Err(format!(
            "the lane dropped on '{}' is not the one lane the carriageway has more there",
            d.ends_on
        ));
    }
    let holds = |k: usize| {
        let (m, offset) = (&layout.main[k], main.offsets[layout.main[k].id.as_str()]);
        match lane {
            MERGE_LANE => m.lanes == layout.main[at].lanes,
            _ => offset <= lane && lane < offset + m.lanes as i32,
        }
    };
    let first = (0..=at)
        .rev()
        .take_while(|&k| holds(k))
        .last()
        .unwrap_or(at);
    let start = main.spans[layout.main[first].id.as_str()].s0;
    let length = net.edge(&d.ends_on).lanes[d.lane as usize].length;
    Ok(MergeZone {
        lane,
        ramp_start: start,
        start,
        end: main.spans[d.ends_on.as_str()].s_at(length),
        weaving: false,
        ramp: false,
        nose: false,
    })
}

/// The zones of the further lanes of `ramp`, a ramp of several lanes, whose lane beside the
/// carriageway has `zone`: frame lanes −1, −2, … outwards, each from where the ramp joins to
/// where it ends, which must be no later than where the lane inside it ends (the lanes end in
/// turn from the outside in, or together).
fn outer_zones(
    net: &Net,
    ramp: &OnRamp,
    zone: &MergeZone,
    main: &MainFrames<'_>,
) -> Result<Vec<MergeZone>, String> {
    let mut inside = *zone;
    let mut out = Vec::new();
    for (k, o) in ramp.outer.iter().enumerate() {
        let lane = MERGE_LANE - 1 - k as i32;
        if main.offsets[ramp.joins.as_str()] + o.lane as i32 != lane {
            return Err(format!(
                "on-ramp '{}' feeds lane {} of '{}', not the lane beside its others: its lanes \
                 must join side by side",
                ramp.edges[0], o.lane, ramp.joins
            ));
        }
        let length = net.edge(&o.ends_on).lanes[o.end_lane as usize].length;
        let end = main.spans[o.ends_on.as_str()].s_at(length);
        if end > inside.end + 1e-6 {
            return Err(format!(
                "lane {} of on-ramp '{}' ends after the lane inside it ({end:.2} m, past \
                 {:.2} m): a ramp's lanes must end in turn from the outside in",
                o.lane, ramp.edges[0], inside.end
            ));
        }
        inside = MergeZone {
            lane,
            end,
            weaving: false,
            ..inside
        };
        out.push(inside);
    }
    Ok(out)
}

/// The knots of lane `l` of an edge whose leftmost lane, the reference, is `left` and starts
/// at `s0`: SUMO builds an edge's lanes as offsets of one line, so their k-th shape points lie
/// across the road from each other, and the reference's arc length at its k-th point is the
/// `s` of the lane's. `None` where a straight line is exact (two shape points, or the reference
/// itself) or the shapes do not pair up.
fn knots(l: &Lane, left: &Lane, s0: f64) -> Option<Arc<[(f64, f64)]>> {
    if l.index == left.index || l.shape.len() != left.shape.len() || l.shape.len() < 3 {
        return None;
    }
    let arcs = |lane: &Lane| {
        let mut acc = vec![0.0];
        for w in lane.shape.windows(2) {
            acc.push(acc.last().expect("non-empty") + (w[1] - w[0]).norm());
        }
        acc
    };
    let (a, b) = (arcs(l), arcs(left));
    let (a_len, b_len) = (*a.last()?, *b.last()?);
    if a_len < 1e-6 || b_len < 1e-6 {
        return None;
    }
    let ratio = l.length / a_len;
    Some(
        a.iter()
            .zip(&b)
            .map(|(ai, bi)| (ai * ratio, s0 + bi))
            .collect(),
    )
}

/// The length of a lane's centre line (SUMO's `length` may differ: positions run along the
/// lane in proportion).
fn shape_length(l: &Lane) -> f64 {
    l.shape.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// The frames of an on-ramp's edges and junction lanes, counted back from where its
/// acceleration lane begins, and its merge zone (`joined`: where the acceleration lane begins
/// and ends). The stretch of the ramp before `free_from` (where the last auxiliary lane of the
/// carriageway before it ends) lies beside that lane, not on it: its junction lanes are left
/// out of the frame and its edges have no frame lanes (a vehicle there is not yet in the
/// region's scene), and its zone begins where the ramp is in the frame.
fn ramp_frames(
    net: &Net,
    ramp: &OnRamp,
    (joined, free_from): ((f64, f64), f64),
    main: &MainFrames<'_>,
    edges: &mut Vec<EdgeFrame>,
    internal: &mut InternalEdges,
) -> Result<MergeZone, String> {
    let name = &ramp.edges[0];
    let lane = match ramp.nose {
        true => MERGE_LANE,
        false => main.offsets[ramp.joins.as_str()] + ramp.lane as i32,
    };
    if lane != MERGE_LANE && lane != main.main_lanes + 1 {
        return Err(format!(
            "on-ramp '{name}' feeds lane {} of '{}', which has {} lanes: a ramp must join as \
             the one lane the carriageway gains on the right or on the left",
            ramp.lane,
            ramp.joins,
            net.edge(&ramp.joins).lanes.len()
        ));
    }
    let mut piece = RampPiece {
        s_end: joined.0,
        lanes: 1 + ramp.outer.len(),
        lane,
        free_from,
        nose_into: ramp.nose.then(|| ramp.joins.clone()),
    };
    let mut ramp_start = joined.0;
    let mut next = ramp.joins.as_str();
    let mut ramp_end = joined.1;
    for id in ramp.edges.iter().rev() {
        ramp_start = ramp_start.min(piece.frames(net, (id, next), edges, internal)?);
        if ramp.nose && next == ramp.joins {
            ramp_end = piece.s_end + net.edge(id).lanes.last().map_or(0.0, |l| l.length);
        }
        next = id;
    }
    // At the nose the ramp's lane ends where its junction lane begins (that lane converges
    // with the carriageway's and lies on the target lane); its last stretch before is where
    // its vehicles may commit to merging.
    let (start, end) = match ramp.nose {
        true => ((ramp_end - NOSE_ZONE).max(ramp_start), ramp_end),
        false => joined,
    };
    Ok(MergeZone {
        lane,
        ramp_start,
        start,
        end,
        weaving: ramp.weaves_into.is_some(),
        ramp: true,
        nose: ramp.nose,
    })
}

/// Where the next ramp edge to place, walking upstream, ends (its junction lanes into the
/// edge after it included), how many lanes a ramp edge may have, and the `s` before which the
/// ramp lies beside another auxiliary lane, outside the frame.
struct RampPiece {
    s_end: f64,
    lanes: usize,
    /// The frame lane the ramp's lane beside the carriageway continues into: 0 on the right,
    /// the one above the carriageway's on the left.
    lane: i32,
    free_from: f64,
    /// The edge a ramp joining at the nose joins: its junction lanes into that edge, where its
    /// lane converges with the carriageway's, lie on the lane it merges into.
    nose_into: Option<String>,
}

impl RampPiece {
    /// The frames of ramp edge `id` and of its junction lanes into `next`, which begins at
    /// `s_end`, which moves to where the edge begins; returns the lowest `s` put in the frame
    /// (the edge's old `s_end` if nothing was). Its lanes count from the left: the leftmost
    /// continues into frame lane 0, the others lie outside it.
    fn frames(
        &mut self,
        net: &Net,
        (id, next): (&str, &str),
        edges: &mut Vec<EdgeFrame>,
        internal: &mut InternalEdges,
    ) -> Result<f64, String> {
        let e = net.edge(id);
        if e.lanes.len() > self.lanes {
            return Err(format!(
                "ramp edge '{id}' has {} lanes, more than the {} it feeds the carriageway with",
                e.lanes.len(),
                self.lanes
            ));
        }
        let n = e.lanes.len() as i32;
        // On the right the ramp's leftmost lane continues into `lane`, on the left its
        // rightmost.
        let frame_lane = |index: u32| match self.lane {
            MERGE_LANE => self.lane + index as i32 + 1 - n,
            _ => self.lane + index as i32,
        };
        let in_frame = |s: f64| s >= self.free_from - 1e-6;
        let left = e.lanes.len() as u32 - 1;
        let mut lowest = self.s_end;
        // Each lane's first link into the next edge, through its junction lane.
        let links: Vec<_> = (0..=left)
            .filter_map(|from| {
                let c = net
                    .outgoing(id)
                    .find(|c| c.to == next && c.from_lane == from)?;
                Some((from, net.internal.get(c.via.as_ref()?)?))
            })
            .collect();
        if let Some((_, via)) = links.iter().find(|(from, _)| *from == left) {
            self.s_end -= via.length;
        }
        if in_frame(self.s_end) {
            lowest = self.s_end;
            let into_nose = self.nose_into.as_deref() == Some(next);
            for (from, via) in &links {
                let lane = frame_lane(*from) + i32::from(into_nose);
                let frame = LaneFrame::straight(lane, self.s_end).limited(via.speed);
                internal.put(via, frame, true);
            }
        }
        self.s_end -= e.lanes[left as usize].length;
        let s0 = self.s_end;
        let lane = |l: &Lane| LaneFrame::straight(frame_lane(l.index), s0).limited(l.speed);
        edges.push(EdgeFrame {
            name: Arc::from(id),
            lanes: (e.lanes.iter())
                .map(|l| in_frame(s0).then(|| lane(l)))
                .collect(),
            on_ramp: true,
        });
        Ok(if in_frame(s0) { s0 } else { lowest })
    }
}

/// Junction lanes of the frame, gathered into SUMO's internal edges (lane `:j_0_2` is lane 2
/// of edge `:j_0`).
#[derive(Default)]
struct InternalEdges {
    edges: BTreeMap<String, (Vec<Option<LaneFrame>>, bool)>,
}

impl InternalEdges {
    fn put(&mut self, lane: &Lane, frame: LaneFrame, on_ramp: bool) {
        let suffix = format!("_{}", lane.index);
        let edge = lane
            .id
            .strip_suffix(&suffix)
            .unwrap_or(&lane.id)
            .to_string();
        let (lanes, ramp) = self.edges.entry(edge).or_default();
        let k = lane.index as usize;
        if lanes.len() <= k {
            lanes.resize(k + 1, None);
        }
        lanes[k] = Some(frame);
        *ramp |= on_ramp;
    }

    fn into_edges(self) -> impl Iterator<Item = EdgeFrame> {
        self.edges
            .into_iter()
            .map(|(name, (lanes, on_ramp))| EdgeFrame {
                name: Arc::from(name.as_str()),
                lanes,
                on_ramp,
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn shipped(name: &str) -> Road {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("sumo_net/{name}.net.xml"));
        let net = Net::read(&path).unwrap();
        let found = crate::sumo::layout::Discovery::of(&net);
        road(&net, &found.regions[0]).unwrap()
    }

    /// The paper network's frame is the fixed frame the scenario had before networks were
    /// read: same edges, lanes, positions and zone, to the bit.
    #[test]
    fn the_paper_net_gives_the_fixed_frame() {
        let r = shipped("merge");
        let fixed = Road::paper_default();
        assert_eq!(r.edges, fixed.edges);
        assert_eq!(r.zones, fixed.zones);
        assert_eq!(r.entries, fixed.entries);
        assert_eq!(r.end_edge, fixed.end_edge);
        assert_eq!((r.lane_width, r.main_lanes, r.section_end), (4.5, 2, 460.0));
        assert_eq!(r.heading_at(200.0), 0.0);
    }

    #[test]
    fn three_lanes_with_junction_lanes() {
        let r = shipped("three-lane");
        assert_eq!((r.main_lanes, r.lane_width), (3, 3.6));
        let z = r.zones[0];
        assert!((z.start - 203.0).abs() < 0.01 && (z.end - 423.0).abs() < 0.01);
        // The ramp's internal lane lies right before the acceleration lane.
        let j = r.edge(":a1_3").expect("ramp junction lane mapped");
        let lf = j.lanes[0].clone().unwrap();
        assert!(j.on_ramp && lf.lane == 0);
        assert!((lf.s_at(3.0) - 203.0).abs() < 0.01, "{lf:?}");
        // A main junction lane from hw_merge lane 1 continues frame lane 1.
        let j = r.edge(":a2_0").unwrap();
        assert_eq!(j.lanes[0].as_ref().unwrap().lane, 1);
        assert!((r.section_end - 631.0).abs() < 0.01);
    }

    /// The point at SUMO position `pos` of lane `l`: its shape walked in proportion.
    fn point_at(l: &Lane, pos: f64) -> crate::model::math::Point {
        let mut left = pos * shape_length(l) / l.length;
        for w in l.shape.windows(2) {
            let seg = (w[1] - w[0]).norm();
            if left <= seg {
                return w[0] + (w[1] - w[0]) * (left / seg);
            }
            left -= seg;
        }
        *l.shape.last().unwrap()
    }

    /// Every metre of every main lane: where the frame puts it, carried back onto the reference
    /// line at the lane's offset, lies within `tolerance` of the lane shape.
    fn worst_offset(name: &str) -> f64 {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("sumo_net/{name}.net.xml"));
        let net = Net::read(&path).unwrap();
        let layout = crate::sumo::layout::Discovery::of(&net).regions.remove(0);
        let r = road(&net, &layout).unwrap();
        let mut worst: f64 = 0.0;
        for m in &layout.main {
            let frame = r.edge(&m.id).unwrap();
            for l in &net.edge(&m.id).lanes {
                let f = frame.lanes[l.index as usize].as_ref().unwrap();
                let d = f64::from(f.lane - r.top_lane()) * r.lane_width;
                for k in 0..=(l.length as usize) {
                    let pos = (k as f64).min(l.length);
                    let p = layout.line.to_xy(f.s_at(pos), d);
                    worst = worst.max((p - point_at(l, pos)).norm());
                }
            }
        }
        worst
    }

    #[test]
    fn lanes_lie_where_the_frame_puts_them() {
        assert!(worst_offset("merge") < 1e-9);
        assert!(worst_offset("three-lane") < 1e-6);
        let corridor = worst_offset("corridor");
        eprintln!("corridor: lanes within {corridor:.3} m of the frame");
        assert!(corridor < 0.15, "{corridor}");
    }

    #[test]
    fn the_corridor_has_three_zones_in_order() {
        let r = shipped("corridor");
        assert_eq!(r.zones.len(), 3);
        assert!(r.zones.windows(2).all(|w| w[0].end < w[1].ramp_start));
        assert!(r.edge("off1").is_none(), "off-ramps leave the section");
        let dec = r.edge("hw_off1").unwrap();
        assert_eq!(
            dec.lanes
                .iter()
                .map(|l| l.as_ref().unwrap().lane)
                .collect::<Vec<_>>(),
            [0, 1, 2, 3]
        );
        // Curved lanes: the scale departs from 1 but little.
        let scales: Vec<f64> = r
            .edges
            .iter()
            .flat_map(|e| e.lanes.iter().flatten().map(|l| l.scale))
            .collect();
        assert!(scales.iter().all(|s| (s - 1.0).abs() < 0.05), "{scales:?}");
        assert!(scales.iter().any(|s| (s - 1.0).abs() > 1e-4));
    }

    /// A ramp joining at the nose (the `nose-merge` layout, a zipper junction): its lane ends
    /// where its junction lane begins, that lane lies on lane 1, and its zone is the 60 m before.
    #[test]
    fn a_nose_ramp_ends_where_its_junction_lane_begins_on_lane_1() {
        let r = shipped("layouts/nose-merge/nose-merge");
        let z = r.zones[0];
        assert!(z.nose && z.ramp && z.lane == MERGE_LANE);
        let lane_of = |edge: &str| r.edge(edge).unwrap().lanes[0].clone().unwrap();
        // `:b_0` is the ramp's junction lane into `down` (the net's connection `via`).
        let junction = lane_of(":b_0");
        assert_eq!((lane_of("on").lane, junction.lane), (MERGE_LANE, 1));
        assert!(
            (z.end - junction.s0).abs() < 1e-9,
            "{} vs {}",
            z.end,
            junction.s0
        );
        assert!(z.end < lane_of("down").s0);
        assert!((z.end - z.start - NOSE_ZONE).abs() < 1e-9);
    }
}
