//! Where an on-ramp's traffic must join a carriageway, found edge by edge in any network: an
//! edge fed by two roads, the one on the left (the carriageway) feeding its left lanes and the
//! one on the right (the ramp) feeding only lanes right of them, where the ramp's lane does not
//! run on along the carriageway for good. It ends, on that edge or further down the carriageway
//! (an acceleration lane; a lane gain followed by a lane drop), or it turns off into an
//! off-ramp (a weaving section). In a weaving section the ramp traffic that stays on the
//! carriageway must have left the lane before it turns off, just as it must have left an
//! acceleration lane before its end: so the merge's lane ends, for the planners, at the end of
//! the auxiliary lane on the last carriageway edge before the off-ramp, and the traffic that
//! weaves the other way (into the off-ramp) leaves the region there. A ramp lane that never
//! ends is a lane gain, no merge to plan; one that turns off after less than
//! [`MIN_WEAVING_LANE`], or after passing another road that joins or leaves the carriageway, is
//! a junction's turning lane (on SUMO's A10KW, both are local streets), not planned either.
//! Each is reported with why.
//!
//! The carriageway through a merge is followed by its leftmost lane, upstream and downstream,
//! so that a net with several roads (two carriageways, an interchange, local streets) gives
//! each merge the carriageway it lies on.

use std::collections::BTreeSet;

use crate::sumo::network::Net;

/// The shortest lane a ramp may feed and an off-ramp take off again for the two to be a weaving
/// section (m), measured along the lanes: the length a driver at 50 km/h covers in 3.6 s, about
/// the least a lane change needs. A shorter one is a junction's turning lane (on SUMO's A10KW a
/// street joins another for 7.81 m before turning off), where SUMO's own drivers sort
/// themselves out.
pub const MIN_WEAVING_LANE: f64 = 50.0;

/// A merge found: ramp edge `ramp` feeds lane `lane` of edge `joins`, and that lane ends at the
/// end of lane `end_lane` of edge `ends_on` (`joins` itself, or an edge downstream on the same
/// carriageway), or, in a weaving section, turns off there into off-ramp `weaves_into`.
#[derive(Debug, Clone, PartialEq)]
pub struct Merge {
    /// The ramp's last edge.
    pub ramp: String,
    /// The carriageway edge it joins.
    pub joins: String,
    /// The lane of `joins` it feeds.
    pub lane: u32,
    /// The carriageway edge on which that lane ends, for the traffic staying on the
    /// carriageway.
    pub ends_on: String,
    /// Its lane index there.
    pub end_lane: u32,
    /// In a weaving section, the off-ramp edge the lane runs on into; `None` where it ends.
    pub weaves_into: Option<String>,
    /// The further lanes of a ramp of several, from the one beside `lane` outwards.
    pub outer: Vec<OuterLane>,
    /// Whether the ramp joins at the nose: its lane and the carriageway's lane `lane` lead into
    /// lane `lane` of `joins`, with no acceleration lane (`ends_on` is `joins`).
    pub nose: bool,
}

/// A further lane of an on-ramp of several, outside the one next to the carriageway: the lane
/// of the joined edge it feeds, and the carriageway edge and lane where it ends.
#[derive(Debug, Clone, PartialEq)]
pub struct OuterLane {
    /// The lane of the joined edge it feeds.
    pub lane: u32,
    /// The carriageway edge on which it ends.
    pub ends_on: String,
    /// Its lane index there.
    pub end_lane: u32,
}

/// An edge where a ramp joins but no merge is planned, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct NotAMerge {
    /// The ramp's last edge.
    pub ramp: String,
    /// Why its junction is no merge to plan.
    pub why: String,
}

/// Every merge of `net`, in file order of the edges joined, and the junctions that looked like
/// one but are not.
pub fn find(net: &Net) -> (Vec<Merge>, Vec<NotAMerge>) {
    let mut merges = Vec::new();
    let mut not = Vec::new();
    for e in &net.edges {
        let preds = net.predecessors(&e.id);
        if preds.len() < 2 {
            continue;
        }
        let Some(main) = feeder(net, &e.id) else {
            continue;
        };
        let main_lanes = lanes_fed(net, main, &e.id);
        let lowest_main = main_lanes.first().copied().unwrap_or(0);
        let lanes = |id: &str| net.edge(id).lanes.iter().filter(|l| l.for_cars).count();
        for ramp in preds.into_iter().filter(|p| *p != main) {
            if lanes(ramp) > lanes(main) {
                // `ramp` is the carriageway, and `main`, feeding the lanes left of it, a
                // left-side on-ramp.
                match left_merge(net, (main, ramp), &e.id) {
                    Some(Ok(m)) => merges.push(m),
                    Some(Err(n)) => not.push(n),
                    None => {}
                }
                continue;
            }
            let fed = lanes_fed(net, ramp, &e.id);
            if let Some(lane) = joins_at_nose(net, ramp, &e.id) {
                match nose_merge(net, ramp, &e.id, lane) {
                    Ok(m) => merges.push(m),
                    Err(n) => not.push(n),
                }
                continue;
            }
            if fed.iter().any(|l| *l >= lowest_main) {
                continue; // joins beside or left of the carriageway: a junction, not a ramp
            }
            let lane = *fed.last().expect("a predecessor feeds a lane");
            let merge = classify(ramp, &e.id, lane, follow_lane(net, &e.id, lane)).and_then(|m| {
                match lanes_feeding(net, ramp, &e.id) {
                    1 => Ok(m),
                    _ => with_outer_lanes(net, m, &fed),
                }
            });
            match merge {
                Ok(m) => merges.push(m),
                Err(n) => not.push(n),
            }
        }
    }
    (merges, not)
}

/// The merge of on-ramp `ramp` joining carriageway `main` on the left at `joins`: its lane (the
/// one beside the carriageway's) and where it ends; `None` where it feeds no lane left of the
/// carriageway's (a junction), and a ramp of several lanes is not planned.
fn left_merge(
    net: &Net,
    (ramp, main): (&str, &str),
    joins: &str,
) -> Option<Result<Merge, NotAMerge>> {
    let fed = lanes_fed(net, ramp, joins);
    let top_main = *lanes_fed(net, main, joins).last()?;
    if fed.iter().any(|l| *l <= top_main) {
        return None;
    }
    if lanes_feeding(net, ramp, joins) > 1 {
        return Some(Err(NotAMerge {
            ramp: ramp.to_string(),
            why: format!(
                "joins '{joins}' on the left with {} lanes: a left-side on-ramp of several \
                 lanes is not planned",
                fed.len()
            ),
        }));
    }
    let lane = fed[0];
    Some(classify(ramp, joins, lane, follow_lane(net, joins, lane)))
}

/// `merge` with the further lanes of its ramp, `fed` (the joined edge's lanes the ramp feeds,
/// rightmost first, the last the merge's own): each must end on the carriageway, as a lane of
/// a two-lane on-ramp or a lane gain dropped later does; one that never ends or turns off is
/// not planned.
fn with_outer_lanes(net: &Net, mut merge: Merge, fed: &[u32]) -> Result<Merge, NotAMerge> {
    for &lane in fed.iter().rev().skip(1) {
        match follow_lane(net, &merge.joins, lane) {
            LaneEnd::Ends(ends_on, end_lane) => merge.outer.push(OuterLane {
                lane,
                ends_on,
                end_lane,
            }),
            _ => {
                return Err(NotAMerge {
                    ramp: merge.ramp,
                    why: format!(
                        "a ramp of {} lanes whose lane {lane} on '{}' does not end on the \
                         carriageway (it is kept or turns off): not planned",
                        fed.len(),
                        merge.joins
                    ),
                })
            }
        }
    }
    Ok(merge)
}

/// The lowest speed limit (m/s, 60 km/h) of a road on which a ramp joining at the nose is a
/// merge: on slower roads (city streets) a side street joining is a junction, where SUMO's
/// right of way decides (SUMO's `DRT` game listed ten such "nose merges" without it).
pub(super) const NOSE_MERGE_MIN_SPEED: f64 = 60.0 / 3.6;

/// Whether `ramp` joins `edge` at the nose, and into which of its lanes (the lowest it feeds):
/// `edge`, on a road of at least [`NOSE_MERGE_MIN_SPEED`], is fed by two roads, and every lane
/// the one that is not the carriageway (leading only there) feeds is a lane the carriageway
/// feeds too.
pub(super) fn joins_at_nose(net: &Net, ramp: &str, edge: &str) -> Option<u32> {
    let e = net.edge(edge);
    let limit = e.lanes.iter().map(|l| l.speed).fold(0.0, f64::max);
    let preds = net.predecessors(edge);
    if limit < NOSE_MERGE_MIN_SPEED || preds.len() != 2 || !preds.contains(&ramp) {
        return None;
    }
    let main = main_feeder(net, edge).filter(|m| *m != ramp)?;
    let main_fed = lanes_fed(net, main, edge);
    let fed = lanes_fed(net, ramp, edge);
    let shared = !fed.is_empty() && fed.iter().all(|l| main_fed.contains(l));
    (shared && net.successors(ramp) == [edge]).then(|| fed[0])
}

/// The merge of `ramp` joining `joins` at the nose into lane `lane`, or why it is not planned:
/// a one-lane ramp into the carriageway's rightmost lane is.
fn nose_merge(net: &Net, ramp: &str, joins: &str, lane: u32) -> Result<Merge, NotAMerge> {
    let why = if lanes_feeding(net, ramp, joins) > 1 {
        "a ramp of several lanes joining at the nose is not planned"
    } else if lane > 0 {
        "a ramp joining at the nose on the left is not planned"
    } else {
        return Ok(Merge {
            ramp: ramp.to_string(),
            joins: joins.to_string(),
            lane,
            ends_on: joins.to_string(),
            end_lane: lane,
            weaves_into: None,
            outer: Vec::new(),
            nose: true,
        });
    };
    Err(NotAMerge {
        ramp: ramp.to_string(),
        why: format!("joins '{joins}' at the nose: {why}"),
    })
}

/// How many lanes of `from` lead into `to`.
fn lanes_feeding(net: &Net, from: &str, to: &str) -> usize {
    let set: BTreeSet<u32> = net
        .outgoing(from)
        .filter(|c| c.to == to)
        .map(|c| c.from_lane)
        .collect();
    set.len()
}

/// The lanes of `to` that `from` feeds, rightmost first.
pub(super) fn lanes_fed(net: &Net, from: &str, to: &str) -> Vec<u32> {
    let set: BTreeSet<u32> = net
        .outgoing(from)
        .filter(|c| c.to == to)
        .map(|c| c.to_lane)
        .collect();
    set.into_iter().collect()
}

/// The merge of `ramp` onto lane `lane` of `joins`, whose lane leads to `end`, or why it is none.
fn classify(ramp: &str, joins: &str, lane: u32, end: LaneEnd) -> Result<Merge, NotAMerge> {
    let merge = |ends_on: String, end_lane, weaves_into| Merge {
        ramp: ramp.to_string(),
        joins: joins.to_string(),
        lane,
        ends_on,
        end_lane,
        weaves_into,
        outer: Vec::new(),
        nose: false,
    };
    let not = |why: String| NotAMerge {
        ramp: ramp.to_string(),
        why,
    };
    match end {
        LaneEnd::Ends(ends_on, end_lane) => Ok(merge(ends_on, end_lane, None)),
        LaneEnd::Gain => Err(not(format!(
            "joins '{joins}' as a lane gain (its lane never ends): no merge to plan"
        ))),
        LaneEnd::Exit(w) => match w.why_no_weave() {
            Some(why) => Err(not(format!(
                "joins '{joins}' on a lane that turns off into '{}' {why}: a junction, not planned",
                w.exit
            ))),
            None => Ok(merge(w.ends_on, w.end_lane, Some(w.exit))),
        },
    }
}

/// Where a lane that a ramp feeds leads.
enum LaneEnd {
    /// It ends at the end of this lane of this edge.
    Ends(String, u32),
    /// It never ends: the carriageway has gained a lane.
    Gain,
    /// It leaves the carriageway into an off-ramp.
    Exit(TurnOff),
}

/// A ramp's lane that leaves the carriageway at the end of lane `end_lane` of edge `ends_on`,
/// into off-ramp edge `exit`.
struct TurnOff {
    ends_on: String,
    end_lane: u32,
    exit: String,
    /// Metres of lane from where the ramp joined.
    length: f64,
    /// The first carriageway edge before `ends_on` at whose end another road leaves or joins.
    crossed: Option<String>,
}

impl TurnOff {
    /// Why it is no weaving section (the lane is too short, or passes a junction on its way,
    /// whose traffic the planners do not see), or `None` if it is one.
    fn why_no_weave(&self) -> Option<String> {
        if let Some(at) = &self.crossed {
            Some(format!("past the junction at '{at}'"))
        } else if self.length < MIN_WEAVING_LANE {
            Some(format!(
                "after {:.2} m, shorter than a weaving section ({MIN_WEAVING_LANE} m)",
                self.length
            ))
        } else {
            None
        }
    }
}

/// Follows lane `lane` of `edge` down the carriageway until it ends, leaves it, or the
/// carriageway ends.
fn follow_lane(net: &Net, edge: &str, lane: u32) -> LaneEnd {
    let (mut edge, mut lane) = (edge.to_string(), lane);
    let mut seen = BTreeSet::new();
    let (mut length, mut crossed) = (0.0, None);
    loop {
        if !seen.insert(edge.clone()) {
            return LaneEnd::Gain; // round a loop: it never ends
        }
        length += net
            .edge(&edge)
            .lanes
            .get(lane as usize)
            .map_or(0.0, |l| l.length);
        let next: Vec<_> = net
            .outgoing(&edge)
            .filter(|c| c.from_lane == lane)
            .collect();
        let Some(first) = next.first() else {
            return if net.successors(&edge).is_empty() {
                LaneEnd::Gain // the carriageway ends with it
            } else {
                LaneEnd::Ends(edge, lane)
            };
        };
        let on = successor(net, &edge);
        let Some(c) = next.iter().find(|c| Some(c.to.as_str()) == on) else {
            return LaneEnd::Exit(TurnOff {
                exit: first.to.clone(),
                ends_on: edge,
                end_lane: lane,
                length,
                crossed,
            });
        };
        if crossed.is_none()
            && (net.successors(&edge).len() > 1 || net.predecessors(&c.to).len() > 1)
        {
            crossed = Some(edge.clone());
        }
        (edge, lane) = (c.to.clone(), c.to_lane);
    }
}

/// The edge the leftmost lane of `edge` continues on (the widest, if it forks; none where two
/// equally wide roads part): the carriageway's next edge.
pub fn successor<'n>(net: &'n Net, edge: &str) -> Option<&'n str> {
    let from = net.outgoing(edge).map(|c| c.from_lane).max()?;
    widest(
        net,
        net.outgoing(edge)
            .filter(|c| c.from_lane == from)
            .map(|c| c.to.as_str()),
    )
}

/// The edge that feeds the leftmost lane of `edge` (the widest, if several): the
/// carriageway's previous edge.
pub fn feeder<'n>(net: &'n Net, edge: &str) -> Option<&'n str> {
    let to = net.incoming(edge).map(|c| c.to_lane).max()?;
    widest(
        net,
        net.incoming(edge)
            .filter(|c| c.to_lane == to)
            .map(|c| c.from.as_str()),
    )
}

/// The one edge of `ids` with the most lanes, if one has more than every other.
fn widest<'n>(net: &'n Net, ids: impl Iterator<Item = &'n str>) -> Option<&'n str> {
    let ids: BTreeSet<&str> = ids.collect();
    let lanes = |id: &str| net.edge(id).lanes.len();
    let most = ids.iter().map(|id| lanes(id)).max()?;
    let best: Vec<&str> = ids.into_iter().filter(|id| lanes(id) == most).collect();
    (best.len() == 1).then(|| best[0])
}

/// The road that feeds `edge` as its carriageway: its one predecessor, the one with the most
/// lanes, or (where two are as wide) the one feeding its leftmost lane. (A narrower road
/// feeding the leftmost lane is a left-side on-ramp.)
pub fn main_feeder<'n>(net: &'n Net, edge: &str) -> Option<&'n str> {
    let preds = net.predecessors(edge);
    let lanes = |id: &str| net.edge(id).lanes.iter().filter(|l| l.for_cars).count();
    let most = preds.iter().map(|p| lanes(p)).max()?;
    match preds
        .iter()
        .filter(|p| lanes(p) == most)
        .collect::<Vec<_>>()[..]
    {
        [one] => Some(one),
        _ => feeder(net, edge),
    }
}

/// The carriageway through `edge`: followed upstream by its main feeder ([`main_feeder`]) to a
/// source and downstream by its leftmost lane to a sink (or to where it forks into equal
/// roads, or loops).
pub fn carriageway(net: &Net, edge: &str) -> Vec<String> {
    let mut up = vec![edge.to_string()];
    while let Some(p) = main_feeder(net, up.last().expect("non-empty")) {
        if up.iter().any(|e| e == p) {
            break;
        }
        up.push(p.to_string());
    }
    up.reverse();
    while let Some(n) = successor(net, up.last().expect("non-empty")) {
        if up.iter().any(|e| e == n) {
            break;
        }
        up.push(n.to_string());
    }
    up
}
