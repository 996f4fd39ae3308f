//! The road frame of a merge network: where each of SUMO's lanes lies in it (the mapping of
//! readings and commands between the two is `crate::sumo::frame`, and the frame is built from
//! the network's layout in `crate::sumo::network`).
//!
//! Frame: `s` is the arc length along the main carriageway's reference line (SUMO's x on the
//! straight paper network); lanes 1..=N are the main carriageway's lanes from the right, and
//! each auxiliary lane (a ramp, its acceleration lane, or a deceleration lane) has a frame lane
//! of its own outside them: 0, −1, … on the right, N+1, … on the left, each with the role its
//! [`MergeZone`] gives it (where it begins and ends, and the lane its traffic must move to). On
//! the paper's merge the one auxiliary lane is lane 0 ([`MERGE_LANE`]). On a
//! ramp, `s` is measured backwards from where its acceleration lane begins, along the ramp, so
//! route distances stay exact even though a ramp is curved. A curved carriageway is
//! straightened: a vehicle that follows its lane keeps its lateral offset and heading 0.

use std::sync::Arc;

use super::reference_line::ReferenceLine;

/// Road-frame lane of the paper's ramp and acceleration lane, and of any auxiliary lane right
/// beside the carriageway's rightmost lane.
pub const MERGE_LANE: i32 = 0;
/// The rightmost lane of the main carriageway.
pub const FIRST_MAIN_LANE: i32 = 1;
/// Within this distance (m) of the acceleration lane's end a ramp HDV that has come to a stop
/// forces its way into the main road (the episode's merge rule), so a CAV must expect it there.
pub const FORCED_MERGE_ZONE: f64 = 10.0;
/// Slower than this (m/s) a ramp HDV counts as standing, for the forced merge.
pub const STANDING_SPEED: f64 = 0.5;

/// The merge network as embedded in the binary (`sumo_net/merge.net.xml`).
pub const EMBEDDED_NET: &str = include_str!("../../sumo_net/merge.net.xml");

/// Where one SUMO lane lies in the frame: its frame lane, and `s = s0 + scale · pos` for SUMO's
/// lane position `pos` (scale 1 on a straight lane; the ratio of the reference line's arc
/// length to the lane's on a curve), or, on a bending lane beside the reference, piecewise
/// linear through `knots` (`(pos, s)` at the lane's shape points, which lie across the road
/// from the reference lane's).
#[derive(Debug, Clone, PartialEq)]
pub struct LaneFrame {
    /// Frame lane the SUMO lane lies on.
    pub lane: i32,
    /// Frame `s` of the lane's start, SUMO position 0 (m).
    pub s0: f64,
    /// Frame metres per metre of SUMO lane position.
    pub scale: f64,
    /// `(pos, s)` pairs (m) of a lane mapped piecewise linearly; `None`: linear by `s0`, `scale`.
    pub knots: Option<Arc<[(f64, f64)]>>,
    /// The SUMO lane's speed limit (m/s; infinite on a frame built by hand).
    pub speed_limit: f64,
}

impl LaneFrame {
    /// A lane whose positions count along `s` one to one from `s0`.
    pub fn straight(lane: i32, s0: f64) -> LaneFrame {
        LaneFrame {
            lane,
            s0,
            scale: 1.0,
            knots: None,
            speed_limit: f64::INFINITY,
        }
    }

    /// The same lane, its SUMO lane limited to `speed_limit` (m/s).
    pub fn limited(self, speed_limit: f64) -> LaneFrame {
        LaneFrame {
            speed_limit,
            ..self
        }
    }

    /// Frame `s` of SUMO lane position `pos`.
    pub fn s_at(&self, pos: f64) -> f64 {
        let Some(k) = &self.knots else {
            return self.s0 + pos * self.scale;
        };
        // The segment holding `pos`, the first or last one beyond the ends.
        let i = k.partition_point(|&(p, _)| p < pos).clamp(1, k.len() - 1);
        let ((p0, s0), (p1, s1)) = (k[i - 1], k[i]);
        if p1 - p0 < 1e-9 {
            return s0;
        }
        s0 + (pos - p0) * (s1 - s0) / (p1 - p0)
    }
}

/// One SUMO edge (a normal edge or a junction's internal edge) placed in the road frame.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeFrame {
    /// SUMO's edge id.
    pub name: Arc<str>,
    /// By SUMO lane index; `None` for a lane that leaves the section (towards an off-ramp).
    pub lanes: Vec<Option<LaneFrame>>,
    /// Whether the edge belongs to an on-ramp, before its acceleration lane.
    pub on_ramp: bool,
}

/// An auxiliary lane's role: an on-ramp's stretch of frame lane `lane`, the ramp from
/// `ramp_start` to `start`, then the acceleration lane to `end`, by which its vehicles must
/// have moved to the lane next to it towards the carriageway ([`MergeZone::target`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MergeZone {
    /// The frame lane it lies on: 0 or below right of the carriageway, above its lanes on the
    /// left.
    pub lane: i32,
    /// Frame `s` where the ramp begins (m): `start` less the ramp's length along it.
    pub ramp_start: f64,
    /// Frame `s` where the acceleration lane begins: vehicles may merge from here (m).
    pub start: f64,
    /// Frame `s` where the acceleration lane ends: vehicles must have merged (m).
    pub end: f64,
    /// Whether the lane runs on at `end` into an off-ramp (a weaving section): main-road
    /// traffic then crosses the zone towards the exit, the other way from the ramp's.
    pub weaving: bool,
    /// Whether an on-ramp feeds it; `false` for a lane of the carriageway that ends (a lane
    /// drop), whose `ramp_start` is `start`, where the lane begins in the region.
    pub ramp: bool,
    /// Whether the ramp joins at the nose: no lane lies beside it, its lane ends at `end` where
    /// it and the target lane lead into one, and its vehicles move over by driving on (a lane
    /// change there is a commitment to drive into the target lane at `end`, see
    /// `episode::nose`).
    pub nose: bool,
}

impl MergeZone {
    /// The lane its traffic must move to: the next one towards the carriageway.
    pub fn target(&self) -> i32 {
        if self.lane <= MERGE_LANE {
            self.lane + 1
        } else {
            self.lane - 1
        }
    }

    /// Whether `s` lies on it, from where its ramp begins to the lane's end.
    pub fn holds(&self, s: f64) -> bool {
        (self.ramp_start..self.end).contains(&s)
    }
}

/// Where vehicles enter the section: the main carriageway's source (entry 0), then each on-ramp
/// in order along the road. Its name is the SUMO route's id and the prefix of its vehicles' ids.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// SUMO route id, also the prefix of its vehicles' ids (`main`, `ramp`, `ramp2`, …).
    pub name: String,
    /// The edges a vehicle entering here drives, to the end of the section.
    pub route: Vec<Arc<str>>,
    /// The speed limit where vehicles enter (m/s): SUMO refuses to insert one faster.
    pub speed_limit: f64,
}

/// An off-ramp: where vehicles may leave the section (they arrive at its end).
#[derive(Debug, Clone, PartialEq)]
pub struct Exit {
    /// `off1`, `off2`, … in order along the road; a route `ENTRY-NAME` leaves here.
    pub name: String,
    /// The main edge it leaves from and the off-ramp's edges.
    pub leaves: Arc<str>,
    /// The off-ramp's edges, in driving order.
    pub edges: Vec<Arc<str>>,
    /// The off-ramp's last edge and its lane length: where SUMO has leaving vehicles arrive.
    pub end: (Arc<str>, f64),
}

/// The merge section in the road frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Road {
    /// The section's edges, junction-internal ones included; an edge's index is its code.
    pub edges: Vec<EdgeFrame>,
    /// Width of every lane (m): lane k's centre lies at y = k · lane_width.
    pub lane_width: f64,
    /// Lanes of the main carriageway (frame lanes 1..=N).
    pub main_lanes: i32,
    /// The auxiliary lanes' merge zones: each on-ramp's lane beside the carriageway, in order
    /// along the road, then the further lanes of ramps of several lanes.
    pub zones: Vec<MergeZone>,
    /// End of the section: vehicles that stay on the main carriageway arrive here.
    pub section_end: f64,
    /// The last edge of the main carriageway and its lane length: SUMO's place of `section_end`.
    pub end_edge: (Arc<str>, f64),
    /// The main carriageway's source, then the on-ramps in the order of `zones`.
    pub entries: Vec<Entry>,
    /// The off-ramps, in order along the road.
    pub exits: Vec<Exit>,
    /// Where the road frame's `s` runs in SUMO's plane; `None` for a straight road along x.
    pub line: Option<Arc<ReferenceLine>>,
}

impl Entry {
    /// An entry named `name` whose vehicles drive the edges `route`, entering at `speed_limit`
    /// (m/s).
    pub fn new(name: &str, route: &[&str], speed_limit: f64) -> Entry {
        Entry {
            name: name.into(),
            route: route.iter().map(|&e| Arc::from(e)).collect(),
            speed_limit,
        }
    }
}

impl Road {
    /// The name of the entry of on-ramp `k` (0-based): `ramp` on a road with one, else `ramp1`,
    /// `ramp2`, …
    pub fn ramp_entry_name(ramps: usize, k: usize) -> String {
        if ramps == 1 {
            "ramp".into()
        } else {
            format!("ramp{}", k + 1)
        }
    }

    /// The merge zone a vehicle at `s` deals with: the first whose end lies at or ahead of it,
    /// or the last one when it has passed them all.
    pub fn zone_ahead(&self, s: f64) -> &MergeZone {
        self.zones
            .iter()
            .find(|z| z.end >= s)
            .unwrap_or_else(|| self.zones.last().expect("a road has a merge zone"))
    }

    /// The zone of auxiliary lane `lane` a vehicle on it at `s` deals with: the first on that
    /// lane whose end lies at or ahead of `s`, or its last; `None` on a lane with no zone.
    pub fn zone_on(&self, lane: i32, s: f64) -> Option<&MergeZone> {
        let mut on = self.zones.iter().filter(|z| z.lane == lane);
        let last = on.clone().next_back();
        on.find(|z| z.end >= s).or(last)
    }

    /// The nose zone (a ramp joining without an acceleration lane, [`MergeZone::nose`]) on
    /// `lane` that holds `s`, from where its ramp begins to the nose.
    pub fn nose_zone_at(&self, lane: i32, s: f64) -> Option<&MergeZone> {
        let z = self.zone_on(lane, s)?;
        (z.nose && z.holds(s)).then_some(z)
    }

    /// The zone whose traffic moves into `lane` that a vehicle there at `s` deals with (the
    /// first ahead, or the last), `None` if no auxiliary lane merges into it.
    pub fn zone_into(&self, lane: i32, s: f64) -> Option<&MergeZone> {
        let mut into = self.zones.iter().filter(|z| z.target() == lane);
        let last = into.clone().next_back();
        into.find(|z| z.end >= s).or(last)
    }

    /// The zone a vehicle on `lane` at `s` deals with: its own lane's if it is auxiliary, else
    /// the one merging into its lane, else the one ahead on the road.
    pub fn zone_for(&self, lane: i32, s: f64) -> &MergeZone {
        (self.zone_on(lane, s))
            .or_else(|| self.zone_into(lane, s))
            .unwrap_or_else(|| self.zone_ahead(s))
    }

    /// The on-ramps' zones, one per ramp (its lane beside the carriageway), in order along
    /// the road.
    pub fn ramp_zones(&self) -> impl Iterator<Item = &MergeZone> {
        (self.zones.iter()).filter(|z| z.ramp && !self.is_auxiliary(z.target()))
    }

    /// Whether `lane` is auxiliary: outside the carriageway's lanes.
    pub fn is_auxiliary(&self, lane: i32) -> bool {
        !self.main_lane_range().contains(&lane)
    }

    /// The lane a vehicle on `lane` must move to before its lane ends: the next one towards the
    /// carriageway from an auxiliary lane; a main lane itself.
    pub fn toward_main(&self, lane: i32) -> i32 {
        if lane < FIRST_MAIN_LANE {
            lane + 1
        } else if lane > self.main_lanes {
            lane - 1
        } else {
            lane
        }
    }

    /// How many lane changes a vehicle on `lane` still owes the carriageway: 0 on a main lane,
    /// 2 on the outer lane of a two-lane ramp.
    pub fn lanes_to_main(&self, lane: i32) -> u32 {
        let main = self.main_lane_range();
        let nearest = lane.clamp(*main.start(), *main.end());
        nearest.abs_diff(lane)
    }

    /// Whether a lane change from `from` to `to` leaves an auxiliary lane towards the
    /// carriageway: a merge.
    pub fn is_merge(&self, from: i32, to: i32) -> bool {
        self.is_auxiliary(from) && to == self.toward_main(from)
    }

    /// Where a vehicle on `lane` at `s` must have left it (m): the end of its auxiliary lane's
    /// zone; `None` on a main lane.
    pub fn lane_end(&self, lane: i32, s: f64) -> Option<f64> {
        self.zone_on(lane, s).map(|z| z.end)
    }

    /// Whether `s` lies in a weaving section's zone, where main-road vehicles may cross towards
    /// the exit.
    pub fn weaving_at(&self, s: f64) -> bool {
        (self.zones.iter()).any(|z| z.weaving && (z.start..=z.end).contains(&s))
    }

    /// Where the first ramp begins (`s`), the lowest `s` of the section.
    pub fn ramp_start(&self) -> f64 {
        self.zones.iter().map(|z| z.ramp_start).fold(0.0, f64::min)
    }

    /// SUMO's index of the first edge's rightmost through lane: 0, or 1 where the section
    /// begins beside an auxiliary lane (a deceleration lane to an off-ramp). Main-road vehicles
    /// enter on the through lanes from there.
    pub fn first_through_lane(&self) -> usize {
        let first = self.edges.first().map_or(0, |e| e.lanes.len());
        first.saturating_sub(self.main_lanes as usize)
    }

    /// The leftmost frame lane: the carriageway's, or a left auxiliary lane's.
    pub fn top_lane(&self) -> i32 {
        (self.zones.iter().map(|z| z.lane)).fold(self.main_lanes, i32::max)
    }

    /// The rightmost frame lane: the lowest auxiliary lane's ([`MERGE_LANE`] on a road
    /// without any on the right).
    pub fn bottom_lane(&self) -> i32 {
        (self.zones.iter().map(|z| z.lane)).fold(MERGE_LANE, i32::min)
    }

    /// Every frame lane, the rightmost to the leftmost.
    pub fn lanes(&self) -> std::ops::RangeInclusive<i32> {
        self.bottom_lane()..=self.top_lane()
    }

    /// The main carriageway's lanes.
    pub fn main_lane_range(&self) -> std::ops::RangeInclusive<i32> {
        FIRST_MAIN_LANE..=self.main_lanes
    }

    /// The nearest frame lane to `lane` (e.g. a lane computed from a predicted position that
    /// strayed off the road).
    pub fn clamp_lane(&self, lane: i32) -> i32 {
        lane.clamp(self.bottom_lane(), self.top_lane())
    }

    /// The frame lane whose centre line is nearest to lateral position `y` (lane `k`'s centre
    /// lies at `k · lane_width`).
    pub fn lane_at(&self, y: f64) -> i32 {
        self.clamp_lane((y / self.lane_width).round() as i32)
    }

    /// Whether a vehicle on auxiliary lane `lane` with its front at `front` and going `speed`
    /// stands in the zone where the merge rule forces it in: the one definition the rule and
    /// the planner (which may not predict such a merge away) share.
    pub fn forces_merge(&self, lane: i32, front: f64, speed: f64) -> bool {
        let end = self.lane_end(lane, front);
        speed < STANDING_SPEED && end.is_some_and(|end| front > end - FORCED_MERGE_ZONE)
    }

    /// Whether a vehicle at `s` may occupy `lane`: a lane of the carriageway, or an auxiliary
    /// lane along its ramp and acceleration lane.
    pub fn lane_exists(&self, lane: i32, s: f64) -> bool {
        self.main_lane_range().contains(&lane)
            || (self.zones.iter()).any(|z| z.lane == lane && z.holds(s))
    }

    /// The road's heading at `s` in SUMO's plane (rad, 0 = east, counter-clockwise).
    pub fn heading_at(&self, s: f64) -> f64 {
        self.line.as_ref().map_or(0.0, |l| l.pose_at(s).1)
    }

    /// The route of a vehicle entering at `entry` and leaving by exit `exit`: the entry's route
    /// up to the edge the exit leaves, then the off-ramp; `None` if the exit lies before the
    /// entry joins.
    pub fn exit_route(&self, entry: usize, exit: usize) -> Option<Vec<Arc<str>>> {
        let (e, x) = (self.entries.get(entry)?, self.exits.get(exit)?);
        let at = e.route.iter().position(|r| *r == x.leaves)?;
        Some(e.route[..=at].iter().chain(&x.edges).cloned().collect())
    }

    /// The name of the route from `entry` out by `exit`.
    pub fn exit_route_name(&self, entry: usize, exit: usize) -> String {
        format!("{}-{}", self.entries[entry].name, self.exits[exit].name)
    }

    /// The edge named `name`, if it is part of the frame.
    pub fn edge(&self, name: &str) -> Option<&EdgeFrame> {
        self.edges.iter().find(|e| &*e.name == name)
    }

    /// The entry (an index of `entries`) a vehicle on edge `code` came in by: 0, the main
    /// carriageway, for an edge on no on-ramp; for an on-ramp's edge, the ramp whose route
    /// drives it, or, for a junction lane between a ramp's edges (no route names one), the
    /// ramp whose stretch before its acceleration lane holds the lane's start (the first
    /// ramp if none does).
    pub fn entry_of_edge(&self, code: usize) -> usize {
        let Some(edge) = self.edges.get(code).filter(|e| e.on_ramp) else {
            return 0;
        };
        let ramps = || self.entries.iter().enumerate().skip(1);
        if let Some((k, _)) = ramps().find(|(_, e)| e.route.contains(&edge.name)) {
            return k;
        }
        let start = edge.lanes.iter().flatten().map(|l| l.s0).next();
        let holds = |z: &MergeZone| start.is_some_and(|s| (z.ramp_start..=z.start).contains(&s));
        (ramps().zip(&self.zones))
            .find(|(_, z)| holds(z))
            .map_or(1, |((k, _), _)| k)
    }

    /// The entry (an index of `entries`) of a vehicle driving `route`: that of the first of its
    /// edges in the frame's list (with or without frame lanes); `None` if none is.
    pub fn entry_of_route(&self, route: &[String]) -> Option<usize> {
        let code = |edge: &String| self.edges.iter().position(|e| *e.name == **edge);
        route.iter().find_map(code).map(|c| self.entry_of_edge(c))
    }

    /// Whether an on-ramp has edges outside the frame (beside another auxiliary lane): its
    /// vehicles are first read in the frame where it joins, on an edge that does not say
    /// they came by the ramp.
    pub fn has_ramp_edges_outside(&self) -> bool {
        (self.edges.iter()).any(|e| e.on_ramp && e.lanes.iter().all(Option::is_none))
    }

    /// The default road (the shipped network), for unit tests and planning without SUMO.
    pub fn paper_default() -> Road {
        let ramp_start = 150.0 - 166.79;
        let edge = |name: &str, lanes: Vec<Option<LaneFrame>>, on_ramp| EdgeFrame {
            name: Arc::from(name),
            lanes,
            on_ramp,
        };
        // Every lane of the shipped network is limited to 40 m/s.
        let straight = |lanes: std::ops::Range<i32>, s0| {
            lanes
                .map(|l| Some(LaneFrame::straight(l, s0).limited(40.0)))
                .collect()
        };
        Road {
            edges: vec![
                edge("main_in", straight(1..3, 0.0), false),
                edge("acc", straight(0..3, 150.0), false),
                edge("main_out", straight(1..3, 330.0), false),
                edge("ramp", straight(0..1, ramp_start), true),
            ],
            lane_width: 4.5,
            main_lanes: 2,
            zones: vec![MergeZone {
                lane: MERGE_LANE,
                ramp_start,
                start: 150.0,
                end: 330.0,
                weaving: false,
                ramp: true,
                nose: false,
            }],
            section_end: 460.0,
            end_edge: (Arc::from("main_out"), 130.0),
            entries: vec![
                Entry::new("main", &["main_in", "acc", "main_out"], 40.0),
                Entry::new("ramp", &["ramp", "acc", "main_out"], 40.0),
            ],
            exits: Vec::new(),
            line: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_lane_ends_at_merge_end() {
        let r = Road::paper_default();
        assert!(r.lane_exists(0, 200.0));
        assert!(!r.lane_exists(0, 340.0));
        assert!(r.lane_exists(2, 340.0));
        assert_eq!(r.lanes(), 0..=2);
        assert_eq!(r.lane_at(5.0), 1);
        assert_eq!(r.lane_at(50.0), 2);
    }

    #[test]
    fn each_vehicle_deals_with_the_zone_ahead() {
        let mut r = Road::paper_default();
        r.zones.push(MergeZone {
            lane: MERGE_LANE,
            ramp_start: 800.0,
            start: 1000.0,
            end: 1200.0,
            weaving: false,
            ramp: true,
            nose: false,
        });
        assert_eq!(r.zone_ahead(100.0).end, 330.0);
        assert_eq!(r.zone_ahead(500.0).end, 1200.0);
        assert_eq!(r.zone_ahead(5000.0).end, 1200.0);
        assert!(!r.lane_exists(0, 500.0));
        assert!(r.lane_exists(0, 900.0));
        assert!(r.lane_exists(0, 200.0));
    }

    /// Each ramp's edges, and a junction lane between them, belong to that ramp's entry; the
    /// carriageway's edges, its acceleration lanes included, to the main one.
    #[test]
    fn each_edge_belongs_to_the_entry_its_vehicles_come_by() {
        let mut r = Road::paper_default();
        r.zones.push(MergeZone {
            lane: MERGE_LANE,
            ramp_start: 280.0,
            start: 330.0,
            end: 430.0,
            weaving: false,
            ramp: true,
            nose: false,
        });
        r.entries
            .push(Entry::new("ramp2", &["ramp2", "main_out"], 40.0));
        let ramp = |name: &str, s0| EdgeFrame {
            name: Arc::from(name),
            lanes: vec![Some(LaneFrame::straight(MERGE_LANE, s0))],
            on_ramp: true,
        };
        r.edges.push(ramp("ramp2", 280.0));
        r.edges.push(ramp(":j_2", 320.0));
        let entries: Vec<usize> = (0..r.edges.len()).map(|c| r.entry_of_edge(c)).collect();
        // main_in, acc, main_out, ramp, ramp2, the junction lane on ramp2.
        assert_eq!(entries, [0, 0, 0, 1, 2, 2]);
        assert_eq!(r.entry_of_edge(99), 0);
    }

    /// Lane roles: a two-lane ramp on the right (lane −1 ends first, then lane 0) and a ramp on
    /// the left (lane 3 beside the carriageway's lanes 1 and 2): each lane's end, the lane its
    /// traffic moves to, where it exists.
    #[test]
    fn auxiliary_lanes_on_either_side_keep_their_own_roles() {
        let mut r = Road::paper_default();
        let zone = |lane, ramp_start, start, end| MergeZone {
            lane,
            ramp_start,
            start,
            end,
            weaving: false,
            ramp: true,
            nose: false,
        };
        r.zones.push(zone(-1, -16.79, 150.0, 250.0));
        r.zones.push(zone(3, 500.0, 600.0, 700.0));
        assert_eq!(r.lanes(), -1..=3);
        assert_eq!((r.bottom_lane(), r.top_lane()), (-1, 3));
        assert_eq!(r.main_lane_range(), 1..=2);
        assert_eq!(r.lane_end(-1, 100.0), Some(250.0));
        assert_eq!(r.lane_end(0, 100.0), Some(330.0));
        assert_eq!(r.lane_end(1, 100.0), None);
        assert_eq!(r.lane_end(3, 650.0), Some(700.0));
        assert_eq!((r.toward_main(-1), r.toward_main(0)), (0, 1));
        assert_eq!((r.toward_main(3), r.toward_main(2)), (2, 2));
        assert!(r.is_merge(-1, 0) && r.is_merge(3, 2) && !r.is_merge(1, 2) && !r.is_merge(0, -1));
        assert_eq!(r.zone_into(0, 100.0).map(|z| z.lane), Some(-1));
        assert_eq!(r.zone_into(2, 100.0).map(|z| z.lane), Some(3));
        assert_eq!(r.zone_for(2, 100.0).lane, 3);
        assert_eq!(r.zone_for(-1, 100.0).end, 250.0);
        assert!(r.lane_exists(-1, 200.0) && !r.lane_exists(-1, 260.0));
        assert!(r.lane_exists(3, 650.0) && !r.lane_exists(3, 450.0));
        assert!(r.forces_merge(-1, 245.0, 0.0) && !r.forces_merge(0, 245.0, 0.0));
        assert_eq!((r.clamp_lane(-5), r.clamp_lane(9)), (-1, 3));
    }
}
