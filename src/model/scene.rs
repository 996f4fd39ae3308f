//! What a controller sees each step: every vehicle's state in the road frame.

use std::sync::Arc;

use crate::model::road::Road;

/// Who drives a vehicle.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Kind {
    /// Connected automated vehicle: commanded by the controller under test.
    Cav,
    /// Human-driven vehicle: SUMO's driver models (plus the ramp merge rule).
    #[default]
    Hdv,
}

impl Kind {
    /// The SUMO vehicle type id, also used in CSV files.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Cav => "cav",
            Kind::Hdv => "hdv",
        }
    }

    /// Parses a SUMO type id; SUMO names a per-vehicle copy of a type `type@vehicle`, and the
    /// driver types of a heterogeneous profile are `hdv.0`, `hdv.1`, ….
    pub fn from_type_id(s: &str) -> Option<Kind> {
        match s.split(['@', '.']).next().unwrap_or(s) {
            "cav" => Some(Kind::Cav),
            "hdv" => Some(Kind::Hdv),
            _ => None,
        }
    }
}

/// Where a vehicle entered the section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Origin {
    /// Entered at the main carriageway's source.
    Main,
    /// Entered on an on-ramp.
    Ramp,
}

impl Origin {
    /// The name used in CSV files: `main` or `ramp`.
    pub fn as_str(self) -> &'static str {
        match self {
            Origin::Main => "main",
            Origin::Ramp => "ramp",
        }
    }
}

/// One vehicle at one instant, in the road frame.
#[derive(Debug, Clone, PartialEq)]
pub struct VehicleState {
    /// SUMO's vehicle id.
    pub id: Arc<str>,
    /// Who drives it.
    pub kind: Kind,
    /// Where it entered the section.
    pub origin: Origin,
    /// Longitudinal position of the vehicle's centre (m).
    pub s: f64,
    /// Road-frame lane the vehicle is assigned to (0 = ramp / acceleration lane).
    pub lane: i32,
    /// Lateral offset from that lane's centre (m, positive to the left): non-zero mid lane change.
    pub lateral: f64,
    /// Speed (m/s).
    pub speed: f64,
    /// Acceleration in the last step (m/s²).
    pub accel: f64,
    /// Heading relative to the road direction (rad, positive to the left).
    pub heading: f64,
    /// The speed the vehicle wants to drive (m/s).
    pub desired_speed: f64,
    /// Body length, bumper to bumper (m).
    pub length: f64,
    /// Body width (m).
    pub width: f64,
    /// Its own top speed (m/s; on a scenario of the user's own its SUMO type's `maxSpeed`, or the
    /// limit of the lane it drives on where that is lower):
    /// a CAV's plans stay below it. Infinite where the planners' `v_max` is the only limit (the
    /// paper's demand, whose CAV type's `maxSpeed` is `v_max`).
    pub max_speed: f64,
    /// Its own acceleration and braking limits: a CAV's plans ask no more of it.
    pub limits: Limits,
    /// Still on the ramp edge (cannot change lanes yet).
    pub on_ramp: bool,
}

/// What a vehicle can do longitudinally (m/s², positive): its SUMO type's `accel`, `decel` and
/// `emergencyDecel` on a scenario of the user's own, and the gap it follows at. A planner's own
/// accelerations apply where they are lower (the paper's: 2, 2 and 6 m/s², below every SUMO
/// default but a truck's or a bus's `accel`, 1.3 and 1.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Greatest acceleration.
    pub accel: f64,
    /// Comfortable deceleration.
    pub decel: f64,
    /// Greatest deceleration.
    pub emergency_decel: f64,
    /// The gap its SUMO type follows at (none: not a SUMO vehicle's, the paper's demand).
    pub following: Option<Following>,
}

/// The gap a SUMO vehicle type keeps to its leader at equal speeds: `minGap` + `tau` · speed.
/// SUMO's lane-change model asks as much of a merger's new follower.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Following {
    /// `tau` (s).
    pub tau: f64,
    /// `minGap` (m).
    pub min_gap: f64,
}

impl Following {
    /// SUMO's defaults (`tau` 1 s, `minGap` 2.5 m).
    pub const SUMO_DEFAULT: Following = Following {
        tau: 1.0,
        min_gap: 2.5,
    };

    /// The bumper gap kept behind a leader at `speed` (m).
    pub fn gap_at(&self, speed: f64) -> f64 {
        self.min_gap + self.tau * speed
    }
}

impl Limits {
    /// No limit of the vehicle's own: the planners' accelerations alone (the paper's demand,
    /// whose types can do more than they ask).
    pub const NONE: Limits = Limits {
        accel: f64::INFINITY,
        decel: f64::INFINITY,
        emergency_decel: f64::INFINITY,
        following: None,
    };
}

impl VehicleState {
    /// A 5 m × 2 m vehicle on the centre of `lane`, driving straight at `speed` and wanting
    /// 35 m/s: for scenes built by hand (tests, the Python bindings).
    pub fn on_lane(id: &str, kind: Kind, origin: Origin, s: f64, lane: i32, speed: f64) -> Self {
        VehicleState {
            id: Arc::from(id),
            kind,
            origin,
            s,
            lane,
            lateral: 0.0,
            speed,
            accel: 0.0,
            heading: 0.0,
            desired_speed: 35.0,
            length: 5.0,
            width: 2.0,
            max_speed: f64::INFINITY,
            limits: Limits::NONE,
            on_ramp: false,
        }
    }

    /// Position of the front bumper (m).
    pub fn front(&self) -> f64 {
        self.s + 0.5 * self.length
    }

    /// Position of the rear bumper (m).
    pub fn rear(&self) -> f64 {
        self.s - 0.5 * self.length
    }

    /// Whether the vehicle is changing lanes: off its lane's centre by more than
    /// [`CHANGING_LATERAL`]. SUMO moves a vehicle sideways only during a lane change.
    pub fn changing_lanes(&self) -> bool {
        self.lateral.abs() > CHANGING_LATERAL
    }

    /// Whether the vehicle sits exactly on its lane's centre (within [`ON_LANE_CENTRE`]), the
    /// stricter question of the predictor: a vehicle anywhere off the centre, the last
    /// centimetres of a slow change included, is finishing a manoeuvre, not deciding on one. It is
    /// not `!changing_lanes()`: between the two thresholds a vehicle is neither (see
    /// [`CHANGING_LATERAL`] on the last step of a slow change).
    pub fn on_lane_centre(&self) -> bool {
        self.lateral.abs() < ON_LANE_CENTRE
    }

    /// The other lane a vehicle changing lanes straddles: the one it moves to before SUMO
    /// switches its lane at the midpoint, the one it comes from after (its offset points there
    /// either way). `None` on its lane's centre.
    pub fn other_lane(&self) -> Option<i32> {
        self.changing_lanes()
            .then(|| self.lane + self.lateral.signum() as i32)
    }
}

/// Lateral offset (m) beyond which a vehicle counts as changing lanes
/// ([`VehicleState::changing_lanes`]): the one threshold of every such test (the shield's lanes
/// occupied, a merge under way in BK-PBS, the entry's leaders, idm-mobil's settling). The
/// predictor asks the stricter [`VehicleState::on_lane_centre`].
///
/// Why 0.1 m is safe, from what SUMO reports (measured at full precision over 8 episodes, paper
/// and three-lane networks, 726 off-centre readings). On its lane's centre a vehicle reads
/// exactly 0: SUMO (`--lanechange.duration`, no sublanes) moves it sideways only during a
/// change. A change moves it at a constant lane width / duration (0.9 m per 0.2 s step on the
/// paper network's 4.5 m lanes), except that the first step of a change started below about
/// 3.5 m/s is cut to dt · (1 m/s + v), 0.2 m from a standstill, and the rest is made up by one
/// extra last step. So every reading of a change exceeds 0.1 m but such a last one, which can be
/// small (0.029 m and 0.036 m were seen): that vehicle is within 0.1 m of its new lane's centre,
/// its body wholly in that lane (0.7 m inside its edge even on 3.6 m lanes), and SUMO ends the
/// change in that very step.
/// Counting it as arrived loses nothing; the paper grid, three-lane and safety campaigns are
/// byte-identical with the thresholds (0.1 and 0.5 m) this one replaced (with 1e-3 m here one
/// paper-grid episode changes).
pub const CHANGING_LATERAL: f64 = 0.1;

/// Lateral offset (m) below which a vehicle is on its lane's centre
/// ([`VehicleState::on_lane_centre`]): SUMO reports exactly 0 there, so any value well under the
/// smallest step of a change (0.029 m measured) separates the two; it decides the predictor's
/// decision points and training labels, which the committed models were trained on.
pub const ON_LANE_CENTRE: f64 = 1e-3;

/// The most vehicles a scene handed in from outside (the Python `Controller`) may hold: a
/// merge section of a few hundred metres holds a few hundred at a standstill; planning time
/// grows faster than linearly (400 CAVs took 2.1 s a step, 3,000 over 40 s).
pub const MAX_SCENE_VEHICLES: usize = 1000;

/// All vehicles at one step.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Simulation time (s).
    pub time: f64,
    /// The road the vehicles are on, in whose frame their states are given.
    pub road: Road,
    /// Every vehicle in the section at this step.
    pub vehicles: Vec<VehicleState>,
}

impl Scene {
    /// A scene on the shipped network's road ([`Road::paper_default`]) at `time`: for scenes
    /// built by hand (tests, planning without SUMO).
    pub fn on_paper_road(time: f64, vehicles: Vec<VehicleState>) -> Scene {
        Scene {
            time,
            road: Road::paper_default(),
            vehicles,
        }
    }

    /// Indices of the CAVs, in scene order.
    pub fn cav_indices(&self) -> Vec<usize> {
        (0..self.vehicles.len())
            .filter(|&i| self.vehicles[i].kind == Kind::Cav)
            .collect()
    }

    /// Index of the nearest vehicle ahead of `s` on `lane` (excluding `skip`), by centre position.
    pub fn leader(&self, lane: i32, s: f64, skip: usize) -> Option<usize> {
        self.nearest(lane, skip, |o| o > s, |a, b| a < b)
    }

    /// Index of the nearest vehicle behind `s` on `lane` (excluding `skip`).
    pub fn follower(&self, lane: i32, s: f64, skip: usize) -> Option<usize> {
        self.nearest(lane, skip, |o| o <= s, |a, b| a > b)
    }

    fn nearest(
        &self,
        lane: i32,
        skip: usize,
        side: impl Fn(f64) -> bool,
        closer: impl Fn(f64, f64) -> bool,
    ) -> Option<usize> {
        let mut best: Option<usize> = None;
        for (i, v) in self.vehicles.iter().enumerate() {
            if i == skip || v.lane != lane || !side(v.s) {
                continue;
            }
            if best.is_none_or(|b| closer(v.s, self.vehicles[b].s)) {
                best = Some(i);
            }
        }
        best
    }
}
