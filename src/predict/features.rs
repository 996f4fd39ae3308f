//! What the lane-change model b_θ sees of one HDV at one step (paper IV.D; the features and scales
//! are told in the guide's predictor chapter, docs/src/predictor.md).
//!
//! An [`Observation`] holds physical quantities (m, m/s): (a) the HDV itself and the leading and
//! following vehicle on its own lane and on each adjacent lane within [`SENSING_RANGE`], and
//! (b) the states of up to [`CAV_NODES`] CAVs near it over the next [`PREVIEW`] steps (their
//! planned — in the training data: actual — positions and speeds). [`encode_a`] and
//! [`encode_b`] turn it into the node-feature matrices of the two GCN blocks; the layout and the
//! scales are fixed here and recorded in every model file ([`FeatureLayout`]).
//!
//! The same extraction serves the data collector (scenes recorded from SUMO) and the predictor
//! (states rolled out over the horizon), so training and deployment see identical features.

use serde::{Deserialize, Serialize};

use crate::model::road::{Road, MERGE_LANE};
use crate::model::scene::{Kind, Origin, VehicleState};

/// Neighbour slots of graph (a), in node order after the HDV itself.
pub const SLOTS: [Slot; 6] = [
    Slot::OwnLeader,
    Slot::OwnFollower,
    Slot::LeftLeader,
    Slot::LeftFollower,
    Slot::RightLeader,
    Slot::RightFollower,
];
/// Nodes of graph (a): the HDV and its six neighbour slots.
pub const NODES_A: usize = 1 + SLOTS.len();
/// CAV nodes of each graph of sequence (b).
pub const CAV_NODES: usize = 4;
/// Preview horizon p^c (steps) of sequence (b).
pub const PREVIEW: usize = 15;
/// Neighbours farther than this (centre to centre, m) count as absent.
pub const SENSING_RANGE: f64 = 100.0;
/// CAVs farther than this (m, at the current step) are not part of sequence (b).
pub const CAV_RANGE: f64 = 60.0;
/// Node features of graph (a).
pub const FEATURES_A: usize = 20;
/// Node features of each graph of sequence (b).
pub const FEATURES_B: usize = 6;
/// Columns (nodes) of the encoded sequence (b): [`PREVIEW`] graphs of [`CAV_NODES`] nodes.
pub const COLUMNS_B: usize = PREVIEW * CAV_NODES;

/// Scales that bring the physical quantities to order one.
const DS_SCALE: f64 = 50.0;
/// Lateral distances are measured in lanes of the paper's width.
const DY_SCALE: f64 = 4.5;
const SPEED_SCALE: f64 = 35.0;
const DV_SCALE: f64 = 10.0;
const ZONE_SCALE: f64 = 180.0;
const ACCEL_SCALE: f64 = 3.0;
const HEADWAY_CAP: f64 = 5.0;

/// Which neighbour a node of graph (a) stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    /// Nearest vehicle ahead on the HDV's own lane.
    OwnLeader,
    /// Nearest vehicle behind on the HDV's own lane.
    OwnFollower,
    /// Nearest vehicle ahead on the lane to the left.
    LeftLeader,
    /// Nearest vehicle behind on the lane to the left.
    LeftFollower,
    /// Nearest vehicle ahead on the lane to the right.
    RightLeader,
    /// Nearest vehicle behind on the lane to the right.
    RightFollower,
}

impl Slot {
    /// Lane offset of the slot relative to the HDV's lane (left = +1).
    pub fn lane_offset(self) -> i32 {
        match self {
            Slot::OwnLeader | Slot::OwnFollower => 0,
            Slot::LeftLeader | Slot::LeftFollower => 1,
            Slot::RightLeader | Slot::RightFollower => -1,
        }
    }

    /// Whether the slot is ahead of the HDV.
    pub fn ahead(self) -> bool {
        matches!(self, Slot::OwnLeader | Slot::LeftLeader | Slot::RightLeader)
    }
}

/// A vehicle reduced to what the features need, in the road frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Agent {
    /// Centre position along the road (m).
    pub s: f64,
    /// Lateral position of the centre (m): lane k's centre is at k · lane width.
    pub y: f64,
    /// Lane the vehicle is assigned to.
    pub lane: i32,
    /// Speed (m/s).
    pub speed: f64,
    /// It is a CAV (else an HDV).
    pub is_cav: bool,
}

impl Agent {
    /// From a scene vehicle.
    pub fn of(v: &VehicleState, lane_width: f64) -> Agent {
        Agent {
            s: v.s,
            y: v.lane as f64 * lane_width + v.lateral,
            lane: v.lane,
            speed: v.speed,
            is_cav: v.kind == Kind::Cav,
        }
    }
}

/// One neighbour node of graph (a), relative to the HDV; absent: all zero.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Neighbour {
    /// A vehicle fills the slot (within [`SENSING_RANGE`]).
    pub present: bool,
    /// Centre distance along the road, neighbour minus HDV (m).
    pub ds: f32,
    /// Lateral distance, neighbour minus HDV (m).
    pub dy: f32,
    /// The neighbour's speed (m/s).
    pub speed: f32,
    /// The neighbour is a CAV.
    pub is_cav: bool,
}

/// One CAV node of one graph of sequence (b); absent: all zero.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CavNode {
    /// A CAV fills the node.
    pub present: bool,
    /// CAV position at step k minus the HDV's constant-speed position at step k (m).
    pub ds: f32,
    /// CAV lateral position at step k minus the HDV's now (m).
    pub dy: f32,
    /// The CAV's speed at step k (m/s).
    pub speed: f32,
}

/// The HDV's own state and where it is.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Ego {
    /// Lane class, as [`lane_class`] gives it: 0 the merge lane, 1 a main lane other than the
    /// leftmost, 2 the leftmost main lane.
    pub lane: u8,
    /// Offset from its lane's centre (m); zero at every decision point.
    pub lateral: f32,
    /// Speed (m/s).
    pub speed: f32,
    /// Acceleration (m/s²).
    pub accel: f32,
    /// Merge-zone end minus the front bumper (m): how much acceleration lane is left.
    pub to_merge_end: f32,
    /// It entered from the ramp (such vehicles never change lanes on their own).
    pub from_ramp: bool,
}

/// Everything b_θ sees of one HDV at one step, in physical units.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Observation {
    /// The HDV itself (graph (a)'s first node).
    pub ego: Ego,
    /// Graph (a)'s neighbours in [`SLOTS`] order.
    pub neighbours: [Neighbour; 6],
    /// Sequence (b): `cavs[k][n]` is CAV n at step k + 1.
    pub cavs: [[CavNode; CAV_NODES]; PREVIEW],
}

/// The part of the road a sample comes from (the paper evaluates them apart).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Subset {
    /// On the acceleration lane: the stochastic merge rule decides.
    Ramp,
    /// On a main-road lane: SUMO's LC2013 decides (ramp vehicles stay in lane).
    Main,
}

impl Subset {
    /// The subset of a sample on a lane of class `lane` ([`lane_class`]): an auxiliary lane
    /// is [`Subset::Ramp`], every other lane [`Subset::Main`].
    pub fn of_lane(lane: i32) -> Subset {
        if lane == MERGE_LANE {
            Subset::Ramp
        } else {
            Subset::Main
        }
    }

    /// Name in evaluation output: `ramp` or `main`.
    pub fn as_str(self) -> &'static str {
        match self {
            Subset::Ramp => "ramp",
            Subset::Main => "main",
        }
    }

    /// Byte code in the binary training-data file (0 ramp, 1 main); also the index of the
    /// subset in per-subset arrays.
    pub fn code(self) -> u8 {
        match self {
            Subset::Ramp => 0,
            Subset::Main => 1,
        }
    }

    /// The subset of a [`Subset::code`]; `None` for an unknown byte.
    pub fn from_code(c: u8) -> Option<Subset> {
        match c {
            0 => Some(Subset::Ramp),
            1 => Some(Subset::Main),
            _ => None,
        }
    }
}

/// Whether `v` is at a decision point: an HDV that could start a lane change at the next step
/// (off the single-lane ramp edge, not already moving sideways). Only these are samples.
pub fn is_decision_point(v: &VehicleState) -> bool {
    v.kind == Kind::Hdv && !v.on_ramp && v.on_lane_centre()
}

/// A lateral move larger than this (m) in one step is a lane change (SUMO moves 0.9 m per step
/// at speed, less when nearly standing).
pub const LATERAL_MOVE: f64 = 0.05;

/// Whether the vehicle, centred on its lane in `now`, has started a lane change by `next`
/// (one step later): the label. Returns the direction (+1 left, −1 right), or 0.
///
/// SUMO's continuous lane change moves the vehicle sideways at constant speed and switches its
/// lane at the midpoint, so the first step of a manoeuvre is the first step with a lateral move
/// from a centred position; later steps of the same manoeuvre start off-centre and never count.
/// The last step of a change ends on the centre but starts off it, so it never counts.
pub fn lane_change_start(now: &VehicleState, next: &VehicleState, lane_width: f64) -> i8 {
    if !now.on_lane_centre() {
        return 0;
    }
    let y0 = now.lane as f64 * lane_width + now.lateral;
    let y1 = next.lane as f64 * lane_width + next.lateral;
    let dy = y1 - y0;
    if dy > LATERAL_MOVE {
        1
    } else if dy < -LATERAL_MOVE {
        -1
    } else {
        0
    }
}

/// The direction an HDV on `lane` moves when it changes lanes: an auxiliary lane's traffic
/// towards the carriageway, the rightmost main lane can only go left (main-road vehicles may
/// not enter the acceleration lane), the leftmost goes right; a middle lane of a wider road is
/// taken to go left, the direction of overtaking.
pub fn lane_change_direction(road: &Road, lane: i32) -> i32 {
    if road.is_auxiliary(lane) {
        road.toward_main(lane) - lane
    } else if lane >= road.main_lanes {
        -1
    } else {
        1
    }
}

/// The ego lane as the model knows it, relative to the road: 0 an auxiliary lane, 2 the
/// leftmost main lane, 1 any other main lane (the rightmost of the paper's two).
pub fn lane_class(road: &Road, lane: i32) -> u8 {
    if road.is_auxiliary(lane) {
        0
    } else if lane >= road.main_lanes {
        2
    } else {
        1
    }
}

/// The HDV part of the observation.
pub fn ego_of(v: &VehicleState, road: &Road) -> Ego {
    Ego {
        lane: lane_class(road, v.lane),
        lateral: v.lateral as f32,
        speed: v.speed as f32,
        accel: v.accel as f32,
        to_merge_end: (road.zone_for(v.lane, v.front()).end - v.front()) as f32,
        from_ramp: v.origin == Origin::Ramp,
    }
}

/// Graph (a)'s neighbours of `ego` among `others` (which must not contain the HDV itself):
/// for each slot the nearest vehicle on that lane ahead (centre strictly ahead) or behind,
/// within [`SENSING_RANGE`]; ties go to the earlier vehicle in `others`.
pub fn neighbours<'a>(ego: &Agent, others: impl Iterator<Item = &'a Agent>) -> [Neighbour; 6] {
    let mut best: [Option<(f64, Agent)>; 6] = [None; 6];
    for o in others {
        let ds = o.s - ego.s;
        if ds.abs() > SENSING_RANGE {
            continue;
        }
        for (k, slot) in SLOTS.iter().enumerate() {
            if o.lane != ego.lane + slot.lane_offset() || (ds > 0.0) != slot.ahead() {
                continue;
            }
            if best[k].is_none_or(|(d, _)| ds.abs() < d) {
                best[k] = Some((ds.abs(), *o));
            }
        }
    }
    best.map(|b| match b {
        Some((_, o)) => Neighbour {
            present: true,
            ds: (o.s - ego.s) as f32,
            dy: (o.y - ego.y) as f32,
            speed: o.speed as f32,
            is_cav: o.is_cav,
        },
        None => Neighbour::default(),
    })
}

/// Indices of the CAVs (among `candidates`, given as (index, agent)) that form sequence (b):
/// on the HDV's lane or an adjacent one, within [`CAV_RANGE`], the [`CAV_NODES`] nearest, in
/// order of their position along the road (ties to the earlier index).
pub fn select_cavs(
    ego: &Agent,
    candidates: impl Iterator<Item = (usize, Agent)>,
    out: &mut Vec<usize>,
) {
    let mut near: [(f64, f64, usize); CAV_NODES] = [(f64::INFINITY, 0.0, usize::MAX); CAV_NODES];
    for (i, a) in candidates {
        let ds = a.s - ego.s;
        if (a.lane - ego.lane).abs() > 1 || ds.abs() > CAV_RANGE {
            continue;
        }
        // Insert into the sorted list of the nearest (by |ds|, then index).
        let key = (ds.abs(), i);
        if let Some(pos) = near.iter().position(|&(d, _, j)| key < (d, j)) {
            near[pos..].rotate_right(1);
            near[pos] = (ds.abs(), ds, i);
        }
    }
    let mut chosen: [(f64, usize); CAV_NODES] = [(0.0, usize::MAX); CAV_NODES];
    let mut n = 0;
    for &(d, ds, i) in &near {
        if d.is_finite() {
            chosen[n] = (ds, i);
            n += 1;
        }
    }
    chosen[..n].sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    out.clear();
    out.extend(chosen[..n].iter().map(|&(_, i)| i));
}

/// The CAV node of a CAV at (`s`, `y`, `speed`) at step `k` (1-based) of the preview, relative
/// to the HDV `ego` driving on at constant speed.
pub fn cav_node(ego: &Agent, k: usize, dt: f64, s: f64, y: f64, speed: f64) -> CavNode {
    CavNode {
        present: true,
        ds: (s - (ego.s + ego.speed * dt * k as f64)) as f32,
        dy: (y - ego.y) as f32,
        speed: speed as f32,
    }
}

/// The feature layout a model was trained with; a model file records it and loading checks it
/// against this build's ([`FeatureLayout::current`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeatureLayout {
    /// Nodes of graph (a) ([`NODES_A`]).
    pub nodes_a: usize,
    /// Node features of graph (a) ([`FEATURES_A`]).
    pub features_a: usize,
    /// CAV nodes of each graph of sequence (b) ([`CAV_NODES`]).
    pub cav_nodes: usize,
    /// Preview horizon of sequence (b), steps ([`PREVIEW`]).
    pub preview: usize,
    /// Node features of each graph of sequence (b) ([`FEATURES_B`]).
    pub features_b: usize,
    /// Neighbour sensing range (m, [`SENSING_RANGE`]).
    pub sensing_range_m: f64,
    /// Range within which CAVs join sequence (b) (m, [`CAV_RANGE`]).
    pub cav_range_m: f64,
    /// Node features of graph (a), in order.
    pub names_a: Vec<String>,
    /// Node features of sequence (b), in order.
    pub names_b: Vec<String>,
}

impl FeatureLayout {
    /// This build's layout: the constants and feature names of this module.
    pub fn current() -> FeatureLayout {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect();
        FeatureLayout {
            nodes_a: NODES_A,
            features_a: FEATURES_A,
            cav_nodes: CAV_NODES,
            preview: PREVIEW,
            features_b: FEATURES_B,
            sensing_range_m: SENSING_RANGE,
            cav_range_m: CAV_RANGE,
            names_a: s(&NAMES_A),
            names_b: s(&NAMES_B),
        }
    }
}

/// Graph (a)'s node features. Nodes: the HDV, then [`SLOTS`]. The `ego_*` features are zero on
/// neighbour nodes; an absent neighbour has only its slot flag set.
pub const NAMES_A: [&str; FEATURES_A] = [
    "present",
    "ds/50m",
    "dy/4.5m",
    "speed/35",
    "(speed-ego_speed)/10",
    "is_cav",
    "slot_ego",
    "slot_own_leader",
    "slot_own_follower",
    "slot_left_leader",
    "slot_left_follower",
    "slot_right_leader",
    "slot_right_follower",
    "time_headway_of_rear/5s",
    "ego_lane_is_acceleration_lane",
    "ego_lane_is_right_main",
    "ego_lane_is_left_main",
    "ego_to_merge_end/180m",
    "ego_from_ramp",
    "ego_accel/3",
];

/// Sequence (b)'s node features (each CAV at each preview step; absent: all zero).
pub const NAMES_B: [&str; FEATURES_B] = [
    "present",
    "ds_vs_ego_constant_speed/50m",
    "dy/4.5m",
    "speed/35",
    "(speed-ego_speed)/10",
    "step/15",
];

/// Writes graph (a)'s node features, column-major (`FEATURES_A` rows × `NODES_A` columns), into
/// `out` (length `FEATURES_A * NODES_A`).
pub fn encode_a<T: Copy + From<f32>>(obs: &Observation, out: &mut [T]) {
    debug_assert_eq!(out.len(), FEATURES_A * NODES_A);
    let mut col = [0.0f64; FEATURES_A];
    let e = &obs.ego;
    let v = e.speed as f64;
    // The HDV's own node.
    col[0] = 1.0;
    col[2] = e.lateral as f64 / DY_SCALE;
    col[3] = v / SPEED_SCALE;
    col[6] = 1.0;
    col[14 + e.lane.min(2) as usize] = 1.0;
    col[17] = (e.to_merge_end as f64 / ZONE_SCALE).clamp(-1.0, 2.5);
    col[18] = e.from_ramp as u8 as f64;
    col[19] = (e.accel as f64 / ACCEL_SCALE).clamp(-3.0, 3.0);
    write_col(out, 0, &col);
    for (k, (n, slot)) in obs.neighbours.iter().zip(SLOTS).enumerate() {
        col = [0.0; FEATURES_A];
        col[7 + k] = 1.0;
        if n.present {
            let ds = n.ds as f64;
            let vn = n.speed as f64;
            col[0] = 1.0;
            col[1] = (ds / DS_SCALE).clamp(-2.0, 2.0);
            col[2] = n.dy as f64 / DY_SCALE;
            col[3] = vn / SPEED_SCALE;
            col[4] = (vn - v) / DV_SCALE;
            col[5] = n.is_cav as u8 as f64;
            // Time headway of whichever of the two is behind, bumper to bumper (5 m bodies).
            let gap = (ds.abs() - 5.0).max(0.0);
            let rear_speed = if slot.ahead() { v } else { vn };
            col[13] = (gap / rear_speed.max(1.0)).min(HEADWAY_CAP) / HEADWAY_CAP;
        }
        write_col(out, 1 + k, &col);
    }
}

/// Writes sequence (b)'s node features, column-major (`FEATURES_B` rows × [`COLUMNS_B`]
/// columns, step-major: the nodes of step 1, then of step 2, …), into `out`.
pub fn encode_b<T: Copy + From<f32>>(obs: &Observation, out: &mut [T]) {
    debug_assert_eq!(out.len(), FEATURES_B * COLUMNS_B);
    let v = obs.ego.speed as f64;
    for (k, step) in obs.cavs.iter().enumerate() {
        for (n, c) in step.iter().enumerate() {
            let mut col = [0.0f64; FEATURES_B];
            if c.present {
                col[0] = 1.0;
                col[1] = (c.ds as f64 / DS_SCALE).clamp(-3.0, 3.0);
                col[2] = c.dy as f64 / DY_SCALE;
                col[3] = c.speed as f64 / SPEED_SCALE;
                col[4] = (c.speed as f64 - v) / DV_SCALE;
                col[5] = (k + 1) as f64 / PREVIEW as f64;
            }
            write_col(out, k * CAV_NODES + n, &col);
        }
    }
}

fn write_col<T: From<f32>, const F: usize>(out: &mut [T], c: usize, col: &[f64; F]) {
    for (o, &x) in out[c * F..(c + 1) * F].iter_mut().zip(col) {
        *o = T::from(x as f32);
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::model::scene::Kind;

    fn veh(kind: Kind, s: f64, lane: i32, speed: f64) -> VehicleState {
        VehicleState {
            id: Arc::from("v"),
            kind,
            origin: Origin::Main,
            s,
            lane,
            lateral: 0.0,
            speed,
            accel: 0.0,
            heading: 0.0,
            desired_speed: speed,
            length: 5.0,
            width: 2.0,
            max_speed: f64::INFINITY,
            limits: crate::model::scene::Limits::NONE,
            on_ramp: false,
        }
    }

    fn agents(vs: &[VehicleState]) -> Vec<Agent> {
        vs.iter().map(|v| Agent::of(v, 4.5)).collect()
    }

    #[test]
    fn neighbours_on_own_and_adjacent_lanes_nearest_first() {
        // Ego on the right main lane at s = 200.
        let vs = [
            veh(Kind::Hdv, 200.0, 1, 30.0), // ego
            veh(Kind::Hdv, 230.0, 1, 28.0), // own leader
            veh(Kind::Hdv, 260.0, 1, 28.0), // farther own leader: not chosen
            veh(Kind::Cav, 190.0, 1, 31.0), // own follower
            veh(Kind::Hdv, 205.0, 2, 33.0), // left leader
            veh(Kind::Hdv, 150.0, 2, 33.0), // left follower
            veh(Kind::Hdv, 199.0, 0, 20.0), // right follower (acceleration lane)
            veh(Kind::Hdv, 320.0, 2, 33.0), // beyond the sensing range
        ];
        let a = agents(&vs);
        let n = neighbours(&a[0], a[1..].iter());
        let ds: Vec<f32> = n.iter().map(|x| x.ds).collect();
        assert_eq!(ds, vec![30.0, -10.0, 5.0, -50.0, 0.0, -1.0]);
        assert!(n.iter().enumerate().all(|(k, x)| x.present == (k != 4)));
        assert!(n[1].is_cav && !n[0].is_cav);
        assert_eq!(n[2].dy, 4.5);
        assert_eq!(n[5].dy, -4.5);
        assert_eq!(
            n[4],
            Neighbour::default(),
            "absent right leader is all zero"
        );
    }

    #[test]
    fn left_lane_has_no_left_neighbours_and_equal_position_is_behind() {
        let vs = [
            veh(Kind::Hdv, 100.0, 2, 30.0),
            veh(Kind::Hdv, 100.0, 1, 30.0),
            veh(Kind::Hdv, 100.0, 2, 30.0),
        ];
        let a = agents(&vs);
        let n = neighbours(&a[0], a[1..].iter());
        assert!(!n[2].present && !n[3].present);
        assert!(n[5].present && n[5].ds == 0.0, "same s counts as following");
        assert!(n[1].present && !n[0].present);
    }

    #[test]
    fn ramp_and_main_are_told_apart() {
        let road = Road::paper_default();
        let mut ramp = veh(Kind::Hdv, 250.0, 0, 20.0);
        ramp.origin = Origin::Ramp;
        let e = ego_of(&ramp, &road);
        assert_eq!(e.lane, 0);
        assert!(e.from_ramp);
        assert_eq!(e.to_merge_end, 330.0 - 252.5);
        assert_eq!(Subset::of_lane(0), Subset::Ramp);
        assert_eq!(Subset::of_lane(2), Subset::Main);
        let obs = Observation {
            ego: e,
            ..Observation::default()
        };
        let mut a = vec![0.0f32; FEATURES_A * NODES_A];
        encode_a(&obs, &mut a);
        assert_eq!(a[14], 1.0, "acceleration-lane flag");
        assert_eq!(a[18], 1.0, "from-ramp flag");
        assert!((a[17] - 77.5 / 180.0).abs() < 1e-6);
        // Absent neighbours: only the slot flag.
        for k in 1..NODES_A {
            let col = &a[k * FEATURES_A..(k + 1) * FEATURES_A];
            assert_eq!(col.iter().filter(|&&x| x != 0.0).count(), 1);
            assert_eq!(col[6 + k], 1.0);
        }
        // Vehicles on the ramp edge or mid-manoeuvre are no decision points.
        assert!(is_decision_point(&ramp));
        ramp.on_ramp = true;
        assert!(!is_decision_point(&ramp));
        let mut mid = veh(Kind::Hdv, 100.0, 1, 30.0);
        mid.lateral = 0.9;
        assert!(!is_decision_point(&mid));
        assert!(!is_decision_point(&veh(Kind::Cav, 100.0, 1, 30.0)));
        let paper = Road::paper_default();
        assert_eq!(lane_change_direction(&paper, 0), 1);
        assert_eq!(lane_change_direction(&paper, 1), 1);
        assert_eq!(lane_change_direction(&paper, 2), -1);
        let three = Road {
            main_lanes: 3,
            ..Road::paper_default()
        };
        assert_eq!(lane_change_direction(&three, 2), 1);
        assert_eq!((lane_class(&three, 0), lane_class(&three, 1)), (0, 1));
        assert_eq!((lane_class(&three, 2), lane_class(&three, 3)), (1, 2));
    }

    #[test]
    fn label_is_the_first_step_of_the_manoeuvre_only() {
        // SUMO's 1 s lane change from lane 1 to 2: lateral 0, 0.9, 1.8, then lane 2 at −1.8,
        // −0.9, 0.
        let track = [
            (1, 0.0),
            (1, 0.0),
            (1, 0.9),
            (1, 1.8),
            (2, -1.8),
            (2, -0.9),
            (2, 0.0),
        ];
        let states: Vec<VehicleState> = track
            .iter()
            .map(|&(lane, lat)| {
                let mut v = veh(Kind::Hdv, 100.0, lane, 30.0);
                v.lateral = lat;
                v
            })
            .collect();
        let labels: Vec<i8> = states
            .windows(2)
            .map(|w| lane_change_start(&w[0], &w[1], 4.5))
            .collect();
        assert_eq!(labels, vec![0, 1, 0, 0, 0, 0]);
        // A slow start (SUMO moves less than 0.9 m when nearly standing) and a right change.
        let mut a = veh(Kind::Hdv, 100.0, 2, 2.0);
        let mut b = a.clone();
        b.lateral = -0.3;
        assert_eq!(lane_change_start(&a, &b, 4.5), -1);
        a.lateral = 0.0;
        b.lateral = 0.0;
        assert_eq!(lane_change_start(&a, &b, 4.5), 0);
        // The last step of a slow change (0.08 m from the centre, then on it) is no start.
        a.lateral = -0.08;
        assert_eq!(lane_change_start(&a, &b, 4.5), 0);
    }

    #[test]
    fn cavs_nearest_on_reachable_lanes_sorted_along_the_road() {
        let ego = Agent {
            s: 100.0,
            y: 4.5,
            lane: 1,
            speed: 30.0,
            is_cav: false,
        };
        let mk = |s: f64, lane: i32| Agent {
            s,
            y: lane as f64 * 4.5,
            lane,
            speed: 30.0,
            is_cav: true,
        };
        let cands = [
            mk(150.0, 1),
            mk(90.0, 2),
            mk(170.0, 1), // beyond 60 m
            mk(105.0, 0),
            mk(80.0, 1),
            mk(60.0, 2),
            mk(130.0, 2),
        ];
        let mut out = Vec::new();
        select_cavs(&ego, cands.iter().copied().enumerate(), &mut out);
        // Nearest four by |ds|: 105 (5), 90 (10), 80 (20), 130 (30); sorted by position.
        assert_eq!(out, vec![4, 1, 3, 6]);
        let node = cav_node(&ego, 5, 0.2, 140.0, 9.0, 31.0);
        assert_eq!((node.ds, node.dy), (10.0, 4.5));
    }
}
