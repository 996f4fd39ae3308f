//! The episode's world: its scenario (α, λ, the step, the road), how its vehicles are
//! generated, and how its metrics are measured.
//!
//! Apart from the driver models and the planners because these settings define *what* is
//! simulated and scored, the same for every controller compared on it.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// The episode's setting: which traffic, how long, on which road.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scenario {
    /// CAV penetration α: probability that an inserted vehicle is a CAV.
    pub alpha: f64,
    /// Total arrival rate λ (veh/h), main road and ramp together.
    pub lambda: f64,
    /// Seed of the demand and of the HDVs' stochastic merging.
    pub seed: u64,
    /// Episode length H in steps.
    pub steps: u32,
    /// Step length dt (s); also the planning period.
    pub dt: f64,
    /// Speed limit v_max (m/s): CAV desired speed, upper bound of every command, and the speed of
    /// the free-flow reference t*.
    pub v_max: f64,
    /// Acceleration used for the free-flow reference t* (m/s²): the IDM maximum acceleration.
    pub free_flow_accel: f64,
    /// Length of every vehicle, CAV and HDV (m; SUMO's vType `length`).
    pub vehicle_length: f64,
    /// Width of every vehicle, CAV and HDV (m; SUMO's vType `width`).
    pub vehicle_width: f64,
    /// Time SUMO takes to move a vehicle across one lane (s, `--lanechange.duration`).
    pub lane_change_duration: f64,
    /// The merge network; `None` uses the one embedded in the binary (`sumo_net/merge.net.xml`).
    pub net_file: Option<PathBuf>,
    /// Which of the network's merge regions to plan, by the edge an on-ramp joins (`bkpbs
    /// network` lists them); `!EDGE` leaves that region out. Empty: every region.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<String>,
    /// A user's SUMO configuration to run instead of the paper's demand: its network, routes,
    /// vehicle types and options (the network is its `net-file`; `net_file` must be unset).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sumocfg: Option<PathBuf>,
    /// On a configuration of your own: the vehicle types (SUMO vType ids, as `vehicles.csv`'s
    /// `type`) whose vehicles are the CAVs, every one of them and no other, instead of a
    /// share α drawn per vehicle. Empty: the draw.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cav_types: Vec<String>,
    /// Set by a campaign over scenarios, per cell: the SHA-256 of `sumocfg` and of every file it
    /// names (net, routes, additional files), by the name it gives them. The cell's record of
    /// its settings carries them, so a cell whose scenario changed runs again; the worker
    /// refuses to run a scenario whose files no longer match. Empty: not checked.
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub sumocfg_digests: std::collections::BTreeMap<String, String>,
}

/// The longest episode bkpbs runs, in steps: longer ones only fill memory.
pub const MAX_STEPS: u32 = 100_000;

impl Default for Scenario {
    fn default() -> Self {
        Scenario {
            alpha: 0.5,
            lambda: 3000.0,
            seed: 0,
            steps: 400,
            dt: 0.2,
            v_max: 35.0,
            free_flow_accel: 3.0,
            vehicle_length: 5.0,
            vehicle_width: 2.0,
            lane_change_duration: 1.0,
            net_file: None,
            regions: Vec::new(),
            sumocfg: None,
            cav_types: Vec::new(),
            sumocfg_digests: std::collections::BTreeMap::new(),
        }
    }
}

impl Scenario {
    /// Steps a lane change takes (SUMO's `--lanechange.duration` on the step grid).
    pub fn lane_change_steps(&self) -> usize {
        Scenario::lane_change_steps_of(self.lane_change_duration, self.dt)
    }

    /// Steps a lane change of `duration` seconds spans on a grid of `dt`: at least one. The one
    /// definition behind [`Scenario::lane_change_steps`], for callers that carry the two numbers
    /// apart from a `Scenario` (the planner's motion-primitive library).
    pub fn lane_change_steps_of(duration: f64, dt: f64) -> usize {
        (duration / dt).round().max(1.0) as usize
    }
}

/// Whether a share is zero (then left out of a written configuration).
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// How vehicles are generated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Demand {
    /// Share of λ arriving on the ramps (split by `ramp_weights`); the rest arrives on the main
    /// lanes equally.
    pub ramp_share: f64,
    /// On a network with off-ramps: the probability that an HDV entering on the main road
    /// leaves by one of them (each equally likely); it arrives at the off-ramp's end. CAVs and
    /// ramp HDVs stay on the main road. Written into a campaign's settings only when above 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub exit_share: f64,
    /// How `ramp_share` is split over the on-ramps, one weight per ramp in order along the road
    /// (normalised); empty, the default: equally. Written into a campaign's settings only when
    /// given.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ramp_weights: Vec<f64>,
    /// Insertion speed range (m/s), uniform.
    pub insertion_speed: [f64; 2],
    /// HDV desired speed range (m/s), uniform.
    pub hdv_desired_speed: [f64; 2],
    /// What α means for an episode's vehicles.
    pub cav_share: CavShare,
}

impl Default for Demand {
    fn default() -> Self {
        Demand {
            ramp_share: 0.2,
            exit_share: 0.0,
            ramp_weights: Vec::new(),
            insertion_speed: [25.0, 35.0],
            hdv_desired_speed: [25.0, 35.0],
            cav_share: CavShare::Exact,
        }
    }
}

/// How α makes CAVs of an episode's vehicles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CavShare {
    /// The paper's definition, α = CAVs / all vehicles: round(α·n) of the n vehicles are CAVs,
    /// chosen at random.
    Exact,
    /// Each vehicle is a CAV with probability α, so an episode's share varies around α.
    Probability,
}

/// Choices in how the episode metrics are computed (the guide's metrics chapter,
/// docs/src/metrics.md, says what each choice changes).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MetricsSettings {
    /// The insertion speed the free-flow time t* starts from.
    pub t_star_speed: TStarSpeed,
}

/// The insertion speed t* is computed from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TStarSpeed {
    /// The speed the demand drew: entering slower because traffic at the entry forbade the
    /// drawn speed counts as delay.
    #[default]
    Drawn,
    /// The speed SUMO actually inserted the vehicle with.
    Inserted,
}
