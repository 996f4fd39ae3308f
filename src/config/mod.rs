//! Scenario and driver-model settings: one serde struct whose defaults are the paper's.
//!
//! A TOML file may set any subset of fields; the rest keep their defaults. Unknown fields are an
//! error, so a misspelt key never silently leaves a default in place.

pub mod hdv;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use hdv::{HdvProfile, HdvSettings};

/// Why a configuration could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read config file {path}: {cause}")]
    Read {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("malformed config file {path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("invalid setting {field} = {value}: {reason}")]
    Invalid {
        field: &'static str,
        value: String,
        reason: &'static str,
    },
    #[error("unknown HDV profile '{name}' (hdv.profile); known: {known}")]
    UnknownProfile { name: String, known: String },
    #[error("invalid setting hdv draw {key} = [{low}, {high}]: must be positive and low ≤ high")]
    InvalidDraw { key: String, low: f64, high: f64 },
}

/// Everything an episode needs besides the controller.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Config {
    pub scenario: Scenario,
    pub demand: Demand,
    /// Longitudinal model of HDVs (SUMO's IDM) and of idm-mobil CAVs (the Rust IDM).
    pub idm: Idm,
    /// Lane-change model of idm-mobil CAVs (HDVs on the main road use SUMO's LC2013).
    pub mobil: Mobil,
    /// Stochastic merge decision of HDVs on the ramp.
    pub ramp_merge: RampMerge,
    /// Who the human drivers are (README: "HDV driver profiles").
    pub hdv: HdvSettings,
    /// Motion primitives and M-A* (BK-M-A*, BK-PBS).
    pub planner: PlannerSettings,
    /// The high-level search of BK-PBS.
    pub pbs: PbsSettings,
    /// How the planners predict HDVs (BK-M-A*, BK-PBS).
    pub predictor: PredictorSettings,
    pub sumo: SumoSettings,
    /// Choices in how the episode metrics are computed.
    pub metrics: MetricsSettings,
    /// The safety shield in front of the search-based planners.
    pub safety: SafetySettings,
    /// The RL-PPO baseline (`rl-ppo`): which policy, shielded or not.
    #[serde(skip_serializing_if = "RlSettings::is_default")]
    pub rl: RlSettings,
    /// Optional per-episode outputs; they do not change any result.
    pub output: OutputSettings,
}

/// Optional outputs of an episode. A campaign does not record them in its settings: they do
/// not change results, so runs with and without them may share a directory.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSettings {
    /// One row per vehicle and step (README: "Trajectories").
    pub trajectories: TrajectoryFormat,
}

/// Whether and how an episode writes its trajectories.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum TrajectoryFormat {
    /// None written.
    #[default]
    None,
    /// `trajectories.csv`: SUMO's and the road frame's view, and the maneuvers sent.
    Csv,
    /// `trajectories.fcd.xml`: SUMO's floating-car-data format.
    Fcd,
}

/// The safety shield (README: "Safety shield"): every CAV's next step of bk-mastar and bk-pbs
/// checked against bounded worst-case behaviour of the others, and replaced when unsafe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SafetySettings {
    /// Shield bk-mastar and bk-pbs (idm-mobil and sumo are never shielded).
    pub shield: bool,
}

impl Default for SafetySettings {
    fn default() -> Self {
        SafetySettings { shield: true }
    }
}

/// The RL-PPO baseline (README: "RL-PPO").
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RlSettings {
    /// Policy file of `bkpbs train-rl`; unset: the one embedded in the binary
    /// (`models/rl-ppo.json`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub policy: Option<PathBuf>,
    /// Put the safety shield in front of the policy. Off by default: the paper's RL-PPO has none.
    pub shield: bool,
}

impl RlSettings {
    /// Whether nothing is set (then a config file does not show the table).
    pub fn is_default(&self) -> bool {
        *self == RlSettings::default()
    }
}

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
    pub vehicle_length: f64,
    pub vehicle_width: f64,
    /// Time SUMO takes to move a vehicle across one lane (s, `--lanechange.duration`).
    pub lane_change_duration: f64,
    /// The merge network; `None` uses the one embedded in the binary (`sumo_net/merge.net.xml`).
    pub net_file: Option<PathBuf>,
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

/// Choices in how the episode metrics are computed (see the README's "How metrics are
/// computed").
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MetricsSettings {
    /// The insertion speed the free-flow time t* starts from.
    pub t_star_speed: TStarSpeed,
}

/// Lane changes a CAV may make below the bicycle model's minimum lane-change speed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LowSpeedLaneChanges {
    /// None: a slow CAV keeps its lane.
    Off,
    /// Merges out of the acceleration lane only.
    #[default]
    Merge,
    /// Every lane change.
    All,
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

/// Intelligent Driver Model parameters (highway-env's values, in bumper-to-bumper terms).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Idm {
    /// Maximum acceleration a (m/s²).
    pub accel: f64,
    /// Comfortable deceleration b (m/s², positive).
    pub decel: f64,
    /// Jam distance s0 (m, bumper to bumper).
    pub min_gap: f64,
    /// Safe time headway T (s).
    pub time_headway: f64,
    /// Acceleration exponent δ.
    pub delta: f64,
    /// Hardest braking a vehicle can do (m/s², positive); SUMO's emergencyDecel and the Rust
    /// IDM's lower clamp.
    pub max_decel: f64,
}

/// MOBIL lane-change parameters (highway-env's values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Mobil {
    /// Politeness p: weight of the followers' gain.
    pub politeness: f64,
    /// Acceleration gain a lane change must bring (m/s²).
    pub gain_threshold: f64,
    /// Braking the change may impose on the new follower at most (m/s², positive).
    pub safe_braking: f64,
    /// Mandatory merge from the acceleration lane: the hardest braking the kinematic gap
    /// acceptance may ask of the merging vehicle or its new follower (m/s², positive).
    pub merge_safe_braking: f64,
    /// Mandatory merge: the smallest bumper-to-bumper gap accepted on either side (m).
    pub merge_min_gap: f64,
    /// Minimum time between two lane-change decisions of one vehicle (s).
    pub decision_interval: f64,
}

/// Ramp HDVs decide to merge with per-step probability `(ξ)^exponent`, where ξ ∈ [0, 1] is the
/// share of the merge zone already driven (so the probability reaches 1 at the zone's end); a
/// decided HDV then merges as soon as SUMO finds the gap safe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RampMerge {
    pub exponent: f64,
}

/// Motion primitives and the multi-phase A* (DESIGN §5, §10).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlannerSettings {
    /// Planning horizon T in steps; a plan that survives it ends the search.
    pub horizon: usize,
    /// Phase-1 goal distance d (m).
    pub goal_distance: f64,
    /// Phase-2 goal distance d' (m).
    pub fallback_goal_distance: f64,
    /// Node expansions allowed in phase 1.
    pub phase1_budget: usize,
    /// Node expansions allowed in phase 2.
    pub phase2_budget: usize,
    /// Extra cost (in steps) of a lane change in phase 1: a tie-breaker, so the CAV does not
    /// change lanes for nothing.
    pub phase1_lane_change_penalty: f64,
    /// Extra cost (in steps) of a lane change in phase 2, which prefers braking.
    pub phase2_lane_change_penalty: f64,
    /// Extra cost (in steps) per step a lane change is put off within a plan. Without it a
    /// change possible now and one a second later cost the same, the search may pick the later
    /// one, and the next round puts it off again: a ramp CAV ran the acceleration lane's length
    /// beside a gap it kept planning to take (see the README, "Merge deadlock").
    pub lane_change_deferral_penalty: f64,
    /// Acceleration of the `accelerate` primitive (m/s²).
    pub accel: f64,
    /// Deceleration of the `decelerate` primitive (m/s², positive).
    pub decel: f64,
    /// Deceleration of the `emergency-brake` primitive (m/s², positive).
    pub emergency_decel: f64,
    /// Slowest speed from which the bicycle model steers a lane change (m/s).
    pub min_lane_change_speed: f64,
    /// Which lane changes below `min_lane_change_speed` are planned as SUMO executes them there
    /// (a slide: one lane per second, the body along the road) instead of not at all: only
    /// merges out of the acceleration lane by default, so a ramp CAV that had to slow down is
    /// not stuck at the lane end (see the README, "Merge deadlock").
    pub low_speed_lane_changes: LowSpeedLaneChanges,
    /// The planned CAV's box is inflated by this much along the road (m, each end), to absorb
    /// the small differences between planned and executed motion.
    pub margin_long: f64,
    /// The same across the road (m, each side).
    pub margin_lat: f64,
    /// Smallest bumper gap the planner keeps to the vehicle in front in its lane, and to the one
    /// behind after changing lanes (m), on top of the reaction and braking terms.
    pub safe_gap: f64,
    /// Reaction time in the safe-gap rule (s): one planning step.
    pub reaction_time: f64,
    /// Closed-set bin of M-A* in position (m).
    pub s_bin: f64,
    /// Closed-set bin of M-A* in speed (m/s).
    pub v_bin: f64,
}

impl Default for PlannerSettings {
    fn default() -> Self {
        PlannerSettings {
            horizon: 15,
            goal_distance: 70.0,
            fallback_goal_distance: 30.0,
            phase1_budget: 2000,
            phase2_budget: 1000,
            phase1_lane_change_penalty: 0.1,
            phase2_lane_change_penalty: 2.0,
            lane_change_deferral_penalty: 0.1,
            accel: 2.0,
            decel: 2.0,
            emergency_decel: 6.0,
            min_lane_change_speed: 10.0,
            low_speed_lane_changes: LowSpeedLaneChanges::Merge,
            margin_long: 0.5,
            margin_lat: 0.1,
            safe_gap: 2.0,
            reaction_time: 0.2,
            s_bin: 1.0,
            v_bin: 0.5,
        }
    }
}

/// Bounds of one BK-PBS planning round.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PbsSettings {
    /// High-level nodes expanded at most per round (deterministic).
    pub node_budget: usize,
    /// Wall-time budget per round (ms); 0 = off, the default, since it would make results depend
    /// on the machine's speed.
    pub time_budget_ms: f64,
    /// Whether a round is decomposed into independent groups of agents, searched apart and in
    /// parallel (independence detection over the root's conflicts; see `planner::pbs`), each
    /// with its own node budget: `true`, `false` (one search over every agent, as in the paper)
    /// or `"auto"` (the default: rounds of more than [`AUTO_GROUPING_ABOVE`] agents). Written
    /// into a campaign's settings only when not `"auto"`, so campaigns of earlier versions
    /// still match.
    #[serde(skip_serializing_if = "Grouping::is_auto")]
    pub independent_groups: Grouping,
}

/// Agents in a round above which `independent_groups = "auto"` decomposes it. One search over
/// every agent is the paper's algorithm and runs well within a step up to a few dozen agents
/// (the paper's network never holds more than 42 vehicles in any committed campaign); on a full
/// 3 km corridor (130 to 190 vehicles) it no longer does, and groups searched in parallel do.
pub const AUTO_GROUPING_ABOVE: usize = 64;

/// When BK-PBS decomposes a round into independent groups.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "GroupingSetting", into = "GroupingSetting")]
pub enum Grouping {
    /// Never: one search over every agent.
    Never,
    /// Rounds of more than [`AUTO_GROUPING_ABOVE`] agents.
    #[default]
    Auto,
    /// Every round.
    Always,
}

impl Grouping {
    fn is_auto(&self) -> bool {
        *self == Grouping::Auto
    }

    /// Whether a round of `agents` agents is decomposed.
    pub fn applies(self, agents: usize) -> bool {
        match self {
            Grouping::Never => false,
            Grouping::Auto => agents > AUTO_GROUPING_ABOVE,
            Grouping::Always => true,
        }
    }
}

/// How [`Grouping`] is written: `true`, `false` or `"auto"`.
#[derive(Serialize, Deserialize)]
#[serde(untagged)]
enum GroupingSetting {
    Flag(bool),
    Word(String),
}

impl TryFrom<GroupingSetting> for Grouping {
    type Error = String;

    fn try_from(v: GroupingSetting) -> Result<Self, String> {
        match v {
            GroupingSetting::Flag(true) => Ok(Grouping::Always),
            GroupingSetting::Flag(false) => Ok(Grouping::Never),
            GroupingSetting::Word(w) if w == "auto" => Ok(Grouping::Auto),
            GroupingSetting::Word(w) => Err(format!(
                "pbs.independent_groups is \"{w}\": expected true, false or \"auto\""
            )),
        }
    }
}

impl From<Grouping> for GroupingSetting {
    fn from(g: Grouping) -> Self {
        match g {
            Grouping::Never => GroupingSetting::Flag(false),
            Grouping::Auto => GroupingSetting::Word("auto".into()),
            Grouping::Always => GroupingSetting::Flag(true),
        }
    }
}

impl Default for PbsSettings {
    fn default() -> Self {
        PbsSettings {
            node_budget: 200,
            time_budget_ms: 0.0,
            independent_groups: Grouping::Auto,
        }
    }
}

/// The HDV predictor of the planners (the learned b_θ or constant speed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PredictorSettings {
    /// `learned`: the GCN lane-change model b_θ; `constant`: constant speed in lane, ramp HDVs
    /// merging at their median decision step.
    pub kind: PredictorKind,
    /// Model file of the conditioned b_θ (used when higher-priority CAV plans are given);
    /// unset: the model embedded in the binary (`models/gcn-conditioned.json`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub conditioned_model: Option<PathBuf>,
    /// Model file of the unconditioned b_θ (BK-M-A*, the PBS root); unset: the embedded
    /// `models/gcn-unconditioned.json`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unconditioned_model: Option<PathBuf>,
    /// `calibration.json` of `bkpbs calibrate` for the profile SUMO runs: predicted HDVs then
    /// follow their present leader by the fitted IDM instead of keeping their speed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub calibration: Option<PathBuf>,
    /// A directory of calibrations per profile (`DIR/<profile>/calibration.json`, as in
    /// `models/profiles`): the one of the profile SUMO runs is used when `calibration` is unset
    /// (a campaign over several profiles), and so is b_θ trained on that profile
    /// (`DIR/<profile>/gcn-conditioned.json`, `gcn-unconditioned.json`) where the directory
    /// has it and no model file is named.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub calibrations: Option<PathBuf>,
    /// Accept a calibration made for another profile than SUMO runs: a mismatch experiment.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub calibration_for_any_profile: bool,
    /// A lane change is predicted to start at the first step at which the probability that it
    /// has started (from the per-step probabilities along the rollout) reaches this value.
    pub decision_probability: f64,
}

/// Which predictor [`PredictorSettings`] selects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum PredictorKind {
    Learned,
    Constant,
}

impl Default for PredictorSettings {
    fn default() -> Self {
        PredictorSettings {
            kind: PredictorKind::Learned,
            conditioned_model: None,
            unconditioned_model: None,
            calibration: None,
            calibrations: None,
            calibration_for_any_profile: false,
            decision_probability: 0.5,
        }
    }
}

/// How SUMO is run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SumoSettings {
    /// Let SUMO print its warnings and step log.
    pub verbose: bool,
    /// Additional SUMO files (detectors, extra vehicles, …) loaded with the vehicle types.
    pub additional_files: Vec<PathBuf>,
    /// Extra SUMO command-line options, appended last.
    pub extra_args: Vec<String>,
    /// Run the episode in SUMO's own sumo-gui (through libtraci) instead of in-process
    /// libsumo; the results are the same. Needs a display.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub gui: bool,
    /// Pause of sumo-gui per step (ms); default: real time (one step length).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gui_delay_ms: Option<f64>,
}

impl Scenario {
    /// Steps a lane change takes (SUMO's `--lanechange.duration` on the step grid).
    pub fn lane_change_steps(&self) -> usize {
        (self.lane_change_duration / self.dt).round().max(1.0) as usize
    }
}

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
        }
    }
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

impl Default for Idm {
    fn default() -> Self {
        Idm {
            accel: 3.0,
            decel: 5.0,
            min_gap: 5.0,
            time_headway: 1.5,
            delta: 4.0,
            max_decel: 9.0,
        }
    }
}

impl Default for Mobil {
    fn default() -> Self {
        Mobil {
            politeness: 0.0,
            gain_threshold: 0.2,
            safe_braking: 2.0,
            merge_safe_braking: 3.0,
            merge_min_gap: 2.5,
            decision_interval: 1.0,
        }
    }
}

impl Default for RampMerge {
    fn default() -> Self {
        RampMerge { exponent: 1.0 }
    }
}

impl Config {
    /// Reads a TOML file; missing fields keep the defaults.
    pub fn from_file(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|cause| ConfigError::Read {
            path: path.to_path_buf(),
            cause,
        })?;
        let config: Config = toml::from_str(&text).map_err(|e| ConfigError::Parse {
            path: path.to_path_buf(),
            message: e.message().to_string()
                + &e.span()
                    .map(|s| format!(" (at byte {})", s.start))
                    .unwrap_or_default(),
        })?;
        config.validate()?;
        Ok(config)
    }

    /// The whole configuration as TOML, as `bkpbs config --print` shows it.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("config always serialises")
    }

    /// Rejects values no episode can run with, section by section; the first failing rule is
    /// the one reported. `sumo` has no rules: SUMO checks its own files and options.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_scenario(&self.scenario)?;
        check_demand(&self.demand, self.scenario.v_max)?;
        check_idm(&self.idm)?;
        check_mobil(&self.mobil)?;
        check_pbs(&self.pbs)?;
        check_planner(&self.planner)?;
        check_ramp_merge(&self.ramp_merge)?;
        check_predictor(&self.predictor)?;
        check_sumo(&self.sumo)?;
        self.hdv.validate()
    }
}

/// sumo-gui's pause per step: from none to ten seconds.
fn check_sumo(s: &SumoSettings) -> Result<(), ConfigError> {
    match s.gui_delay_ms {
        Some(d) if !(0.0..=10_000.0).contains(&d) => Err(ConfigError::Invalid {
            field: "sumo.gui_delay_ms",
            value: d.to_string(),
            reason: "must lie in [0, 10000] ms",
        }),
        _ => Ok(()),
    }
}

/// Highest arrival rate accepted (veh/h): the demand of an episode is drawn in full before it
/// starts, so the rate bounds its memory.
pub const MAX_RATE: f64 = 20_000.0;

/// Why counts and sizes are bounded: each bound keeps an episode's memory and time finite.
const STEPS_RANGE: &str = "must be 1 to 100000 steps (longer episodes only fill memory)";
const V_MAX_RANGE: &str = "must lie in [1, 100] m/s (the lane-change table grows with it)";
const FREE_FLOW_ACCEL_RANGE: &str =
    "must lie in [0.1, 20] m/s² (the free-flow time t* grows without bound near 0)";
const HORIZON_RANGE: &str = "must be 1 to 100 steps (the search grows exponentially with it)";
const SEARCH_BUDGET_RANGE: &str = "must be 1 to 1000000 node expansions";
const PBS_BUDGET_RANGE: &str = "must be 1 to 100000 priority-tree nodes";

/// What a number in the settings must satisfy. Each rule owns its error text, so settings alike
/// are rejected alike.
#[derive(Debug, Clone, Copy)]
enum Rule {
    /// Within [low, high], both included: a bound that keeps memory and run time finite, or a
    /// value physics allows, which the reason names.
    Between(f64, f64, &'static str),
    /// Above zero; unlike [`Rule::Rate`], infinity passes.
    Positive,
    NonNegative,
    /// A share: [0, 1].
    UnitInterval,
    /// A probability strictly between 0 and 1.
    OpenUnitInterval,
    /// The step length: (0, 1] s.
    StepLength,
    /// An arrival rate: positive and at most [`MAX_RATE`].
    Rate,
    /// A time budget: 0 (off) or positive and finite.
    TimeBudget,
    /// At least another setting's value, which the reason names.
    AtLeast(f64, &'static str),
}

impl Rule {
    fn holds(self, v: f64) -> bool {
        match self {
            Rule::Between(low, high, _) => (low..=high).contains(&v),
            Rule::Positive => v > 0.0,
            Rule::NonNegative => v >= 0.0,
            Rule::UnitInterval => (0.0..=1.0).contains(&v),
            Rule::OpenUnitInterval => v > 0.0 && v < 1.0,
            Rule::StepLength => v > 0.0 && v <= 1.0,
            Rule::Rate => v > 0.0 && v <= MAX_RATE,
            Rule::TimeBudget => v >= 0.0 && v.is_finite(),
            Rule::AtLeast(bound, _) => v >= bound,
        }
    }

    fn reason(self) -> &'static str {
        match self {
            Rule::Between(_, _, reason) => reason,
            Rule::Positive => "must be positive",
            Rule::NonNegative => "must not be negative",
            Rule::UnitInterval => "must lie in [0, 1]",
            Rule::OpenUnitInterval => "must lie in (0, 1)",
            Rule::StepLength => "must lie in (0, 1] s",
            Rule::Rate => {
                "must be a positive rate of at most 20000 veh/h (two lanes carry about 4000; \
                 more only queues vehicles at the entry and fills memory)"
            }
            Rule::TimeBudget => "must be 0 (off) or a positive time in ms",
            Rule::AtLeast(_, reason) => reason,
        }
    }
}

/// A setting's value as a [`Rule`] reads it; a count stays an integer so that an error prints it
/// as it was written.
#[derive(Debug, Clone, Copy)]
enum Value {
    Real(f64),
    Count(u64),
}

impl Value {
    fn number(self) -> f64 {
        match self {
            Value::Real(v) => v,
            Value::Count(n) => n as f64,
        }
    }
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Real(v) => write!(f, "{v}"),
            Value::Count(n) => write!(f, "{n}"),
        }
    }
}

impl From<f64> for Value {
    fn from(v: f64) -> Self {
        Value::Real(v)
    }
}

impl From<u32> for Value {
    fn from(n: u32) -> Self {
        Value::Count(n.into())
    }
}

impl From<usize> for Value {
    fn from(n: usize) -> Self {
        Value::Count(n as u64)
    }
}

/// One rule of a section's table: the dotted field name, its value and what it must satisfy.
type Row = (&'static str, Value, Rule);

/// The [`Row`]s of one section, `section: value; field => rule, …`: each field is named once,
/// so an error cannot name another field than the one checked.
macro_rules! rows {
    ($section:ident: $settings:expr; $($field:ident => $rule:expr),+ $(,)?) => {
        [$((
            concat!(stringify!($section), ".", stringify!($field)),
            Value::from($settings.$field),
            $rule,
        )),+]
    };
}

/// Checks the rows in order and reports the first that fails.
fn check_rows(rows: &[Row]) -> Result<(), ConfigError> {
    for &(field, value, rule) in rows {
        check(field, value, rule.holds(value.number()), rule.reason())?;
    }
    Ok(())
}

fn check_scenario(s: &Scenario) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(scenario: s;
        alpha => UnitInterval,
        lambda => Rate,
        steps => Between(1.0, 100_000.0, STEPS_RANGE),
        dt => StepLength,
        v_max => Between(1.0, 100.0, V_MAX_RANGE),
        free_flow_accel => Between(0.1, 20.0, FREE_FLOW_ACCEL_RANGE),
        vehicle_length => Positive,
        vehicle_width => Positive,
        lane_change_duration => AtLeast(s.dt, "must be at least one step"),
    ))
}

/// The speed ranges are pairs bounded by the speed limit, so they have a rule of their own.
fn check_demand(d: &Demand, v_max: f64) -> Result<(), ConfigError> {
    check_rows(
        &rows!(demand: d; ramp_share => Rule::UnitInterval, exit_share => Rule::UnitInterval),
    )?;
    let weights = &d.ramp_weights;
    if weights.iter().any(|w| !w.is_finite() || *w < 0.0)
        || (!weights.is_empty() && weights.iter().sum::<f64>() <= 0.0)
    {
        return Err(ConfigError::Invalid {
            field: "demand.ramp_weights",
            value: format!("{weights:?}"),
            reason: "weights must be finite, at least 0, and not all 0",
        });
    }
    for (field, r) in [
        ("demand.insertion_speed", d.insertion_speed),
        ("demand.hdv_desired_speed", d.hdv_desired_speed),
    ] {
        check(
            field,
            format!("{r:?}"),
            r[0] > 0.0 && r[0] <= r[1] && r[1] <= v_max,
            "must be [low, high] with 0 < low <= high <= v_max",
        )?;
    }
    Ok(())
}

fn check_idm(i: &Idm) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(idm: i;
        accel => Positive,
        decel => Positive,
        min_gap => NonNegative,
        time_headway => Positive,
        delta => Positive,
        max_decel => AtLeast(i.decel, "must be at least idm.decel"),
    ))
}

fn check_mobil(m: &Mobil) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(mobil: m;
        politeness => NonNegative,
        safe_braking => Positive,
        merge_safe_braking => Positive,
        merge_min_gap => NonNegative,
        decision_interval => NonNegative,
    ))
}

fn check_pbs(p: &PbsSettings) -> Result<(), ConfigError> {
    check_rows(&rows!(pbs: p;
        node_budget => Rule::Between(1.0, 100_000.0, PBS_BUDGET_RANGE),
        time_budget_ms => Rule::TimeBudget,
    ))
}

fn check_planner(p: &PlannerSettings) -> Result<(), ConfigError> {
    use Rule::*;
    check_rows(&rows!(planner: p;
        horizon => Between(1.0, 100.0, HORIZON_RANGE),
        phase1_budget => Between(1.0, 1e6, SEARCH_BUDGET_RANGE),
        phase2_budget => Between(1.0, 1e6, SEARCH_BUDGET_RANGE),
        goal_distance => Positive,
        fallback_goal_distance => Positive,
        accel => Positive,
        decel => Positive,
        emergency_decel => Positive,
        s_bin => Positive,
        v_bin => Positive,
        phase1_lane_change_penalty => NonNegative,
        phase2_lane_change_penalty => NonNegative,
        lane_change_deferral_penalty => NonNegative,
        min_lane_change_speed => NonNegative,
        margin_long => NonNegative,
        margin_lat => NonNegative,
        safe_gap => NonNegative,
        reaction_time => NonNegative,
    ))
}

fn check_ramp_merge(r: &RampMerge) -> Result<(), ConfigError> {
    check_rows(&rows!(ramp_merge: r; exponent => Rule::Positive))
}

/// Model files are checked with the other settings so that a missing one is reported before
/// any episode starts.
fn check_predictor(p: &PredictorSettings) -> Result<(), ConfigError> {
    check_rows(&rows!(predictor: p; decision_probability => Rule::OpenUnitInterval))?;
    for (field, path) in [
        ("predictor.conditioned_model", &p.conditioned_model),
        ("predictor.unconditioned_model", &p.unconditioned_model),
    ] {
        if let Some(path) = path {
            check(field, path.display(), path.is_file(), "no such model file")?;
        }
    }
    Ok(())
}

/// The error for `field` unless `ok`.
fn check(
    field: &'static str,
    value: impl std::fmt::Display,
    ok: bool,
    reason: &'static str,
) -> Result<(), ConfigError> {
    if ok {
        Ok(())
    } else {
        Err(ConfigError::Invalid {
            field,
            value: value.to_string(),
            reason,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers() {
        let c = Config::default();
        assert_eq!(c.scenario.steps, 400);
        assert_eq!(c.scenario.dt, 0.2);
        assert_eq!(c.scenario.v_max, 35.0);
        assert_eq!(c.scenario.vehicle_length, 5.0);
        assert_eq!(c.demand.insertion_speed, [25.0, 35.0]);
        c.validate().unwrap();
    }

    #[test]
    fn toml_round_trips() {
        let c = Config::default();
        let back: Config = toml::from_str(&c.to_toml()).unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn partial_file_keeps_defaults() {
        let c: Config = toml::from_str("[scenario]\nalpha = 0.8\n").unwrap();
        assert_eq!(c.scenario.alpha, 0.8);
        assert_eq!(c.scenario.lambda, 3000.0);
    }

    #[test]
    fn the_shield_is_on_by_default_and_can_be_switched_off() {
        assert!(Config::default().safety.shield);
        let c: Config = toml::from_str("[safety]\nshield = false\n").unwrap();
        assert!(!c.safety.shield);
        assert!(toml::from_str::<Config>("[safety]\nsheild = false\n").is_err());
    }

    #[test]
    fn independent_groups_is_a_flag_or_auto() {
        let read = |v: &str| {
            toml::from_str::<Config>(&format!("[pbs]\nindependent_groups = {v}\n"))
                .map(|c| c.pbs.independent_groups)
        };
        assert_eq!(Config::default().pbs.independent_groups, Grouping::Auto);
        assert_eq!(read("true").unwrap(), Grouping::Always);
        assert_eq!(read("false").unwrap(), Grouping::Never);
        assert_eq!(read("\"auto\"").unwrap(), Grouping::Auto);
        let err = read("\"sometimes\"").unwrap_err().to_string();
        assert!(err.contains("expected true, false or \"auto\""), "{err}");
        // Written only when not the default, as `true` / `false`.
        assert!(!Config::default().to_toml().contains("independent_groups"));
        let mut c = Config::default();
        c.pbs.independent_groups = Grouping::Always;
        assert!(c.to_toml().contains("independent_groups = true"));
        // Auto decomposes large rounds only.
        assert!(!Grouping::Auto.applies(AUTO_GROUPING_ABOVE));
        assert!(Grouping::Auto.applies(AUTO_GROUPING_ABOVE + 1));
        assert!(Grouping::Always.applies(1) && !Grouping::Never.applies(1000));
    }

    #[test]
    fn unknown_field_is_rejected() {
        assert!(toml::from_str::<Config>("[scenario]\nalhpa = 0.8\n").is_err());
    }

    #[test]
    fn alpha_outside_unit_interval_is_invalid() {
        let mut c = Config::default();
        c.scenario.alpha = 1.5;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("scenario.alpha"), "{e}");
    }

    /// One way to break the default config: the field, its bad value as the error prints it,
    /// the reason given, and the change.
    type Case = (&'static str, &'static str, &'static str, fn(&mut Config));

    const UNIT: &str = "must lie in [0, 1]";
    const RATE: &str = "must be a positive rate of at most 20000 veh/h (two lanes carry about \
                        4000; more only queues vehicles at the entry and fills memory)";
    const STEP: &str = "must lie in (0, 1] s";
    const POSITIVE: &str = "must be positive";
    const ONE_STEP: &str = "must be at least one step";
    const SPEED_RANGE: &str = "must be [low, high] with 0 < low <= high <= v_max";
    const NON_NEGATIVE: &str = "must not be negative";
    const IDM_DECEL: &str = "must be at least idm.decel";
    const TIME_BUDGET: &str = "must be 0 (off) or a positive time in ms";
    const OPEN_UNIT: &str = "must lie in (0, 1)";
    const MODEL_FILE: &str = "no such model file";

    /// Every rule, in the order `validate` checks them.
    const CASES: [Case; 47] = [
        ("scenario.alpha", "1.5", UNIT, |c| c.scenario.alpha = 1.5),
        ("scenario.lambda", "0", RATE, |c| c.scenario.lambda = 0.0),
        ("scenario.steps", "0", STEPS_RANGE, |c| c.scenario.steps = 0),
        ("scenario.dt", "0", STEP, |c| c.scenario.dt = 0.0),
        ("scenario.v_max", "0", V_MAX_RANGE, |c| {
            c.scenario.v_max = 0.0
        }),
        (
            "scenario.free_flow_accel",
            "0",
            FREE_FLOW_ACCEL_RANGE,
            |c| c.scenario.free_flow_accel = 0.0,
        ),
        ("scenario.vehicle_length", "0", POSITIVE, |c| {
            c.scenario.vehicle_length = 0.0
        }),
        ("scenario.vehicle_width", "0", POSITIVE, |c| {
            c.scenario.vehicle_width = 0.0
        }),
        ("scenario.lane_change_duration", "0.1", ONE_STEP, |c| {
            c.scenario.lane_change_duration = 0.1
        }),
        ("demand.ramp_share", "-0.1", UNIT, |c| {
            c.demand.ramp_share = -0.1
        }),
        ("demand.insertion_speed", "[30.0, 20.0]", SPEED_RANGE, |c| {
            c.demand.insertion_speed = [30.0, 20.0]
        }),
        (
            "demand.hdv_desired_speed",
            "[20.0, 40.0]",
            SPEED_RANGE,
            |c| c.demand.hdv_desired_speed = [20.0, 40.0],
        ),
        ("idm.accel", "0", POSITIVE, |c| c.idm.accel = 0.0),
        ("idm.decel", "0", POSITIVE, |c| c.idm.decel = 0.0),
        ("idm.min_gap", "-1", NON_NEGATIVE, |c| c.idm.min_gap = -1.0),
        ("idm.time_headway", "-1", POSITIVE, |c| {
            c.idm.time_headway = -1.0
        }),
        ("idm.delta", "0", POSITIVE, |c| c.idm.delta = 0.0),
        ("idm.max_decel", "4", IDM_DECEL, |c| c.idm.max_decel = 4.0),
        ("mobil.politeness", "-1", NON_NEGATIVE, |c| {
            c.mobil.politeness = -1.0
        }),
        ("mobil.safe_braking", "0", POSITIVE, |c| {
            c.mobil.safe_braking = 0.0
        }),
        ("mobil.merge_safe_braking", "0", POSITIVE, |c| {
            c.mobil.merge_safe_braking = 0.0
        }),
        ("mobil.merge_min_gap", "-1", NON_NEGATIVE, |c| {
            c.mobil.merge_min_gap = -1.0
        }),
        ("mobil.decision_interval", "-1", NON_NEGATIVE, |c| {
            c.mobil.decision_interval = -1.0
        }),
        ("pbs.node_budget", "0", PBS_BUDGET_RANGE, |c| {
            c.pbs.node_budget = 0
        }),
        ("pbs.time_budget_ms", "-1", TIME_BUDGET, |c| {
            c.pbs.time_budget_ms = -1.0
        }),
        ("planner.horizon", "0", HORIZON_RANGE, |c| {
            c.planner.horizon = 0
        }),
        ("planner.phase1_budget", "0", SEARCH_BUDGET_RANGE, |c| {
            c.planner.phase1_budget = 0
        }),
        ("planner.phase2_budget", "0", SEARCH_BUDGET_RANGE, |c| {
            c.planner.phase2_budget = 0
        }),
        ("planner.goal_distance", "0", POSITIVE, |c| {
            c.planner.goal_distance = 0.0
        }),
        ("planner.fallback_goal_distance", "0", POSITIVE, |c| {
            c.planner.fallback_goal_distance = 0.0
        }),
        ("planner.accel", "0", POSITIVE, |c| c.planner.accel = 0.0),
        ("planner.decel", "0", POSITIVE, |c| c.planner.decel = 0.0),
        ("planner.emergency_decel", "0", POSITIVE, |c| {
            c.planner.emergency_decel = 0.0
        }),
        ("planner.s_bin", "0", POSITIVE, |c| c.planner.s_bin = 0.0),
        ("planner.v_bin", "0", POSITIVE, |c| c.planner.v_bin = 0.0),
        (
            "planner.phase1_lane_change_penalty",
            "-1",
            NON_NEGATIVE,
            |c| c.planner.phase1_lane_change_penalty = -1.0,
        ),
        (
            "planner.phase2_lane_change_penalty",
            "-1",
            NON_NEGATIVE,
            |c| c.planner.phase2_lane_change_penalty = -1.0,
        ),
        (
            "planner.lane_change_deferral_penalty",
            "-1",
            NON_NEGATIVE,
            |c| c.planner.lane_change_deferral_penalty = -1.0,
        ),
        ("planner.min_lane_change_speed", "-1", NON_NEGATIVE, |c| {
            c.planner.min_lane_change_speed = -1.0
        }),
        ("planner.margin_long", "-1", NON_NEGATIVE, |c| {
            c.planner.margin_long = -1.0
        }),
        ("planner.margin_lat", "-1", NON_NEGATIVE, |c| {
            c.planner.margin_lat = -1.0
        }),
        ("planner.safe_gap", "-1", NON_NEGATIVE, |c| {
            c.planner.safe_gap = -1.0
        }),
        ("planner.reaction_time", "-1", NON_NEGATIVE, |c| {
            c.planner.reaction_time = -1.0
        }),
        ("ramp_merge.exponent", "0", POSITIVE, |c| {
            c.ramp_merge.exponent = 0.0
        }),
        ("predictor.decision_probability", "1", OPEN_UNIT, |c| {
            c.predictor.decision_probability = 1.0
        }),
        (
            "predictor.conditioned_model",
            "no/such/model.json",
            MODEL_FILE,
            |c| c.predictor.conditioned_model = Some("no/such/model.json".into()),
        ),
        (
            "predictor.unconditioned_model",
            "no/such/model.json",
            MODEL_FILE,
            |c| c.predictor.unconditioned_model = Some("no/such/model.json".into()),
        ),
    ];

    /// Checks that every field under `reason` rejects its bad value with exactly today's text;
    /// returns how many fields that was.
    fn assert_rule_rejects(reason: &str) -> usize {
        let cases: Vec<&Case> = CASES.iter().filter(|c| c.2 == reason).collect();
        for (field, value, reason, break_it) in &cases {
            let mut c = Config::default();
            break_it(&mut c);
            let e = c.validate().unwrap_err().to_string();
            assert_eq!(e, format!("invalid setting {field} = {value}: {reason}"));
        }
        cases.len()
    }

    /// Checks which numbers a rule lets through, at its edges.
    fn assert_bounds(rule: Rule, good: &[f64], bad: &[f64]) {
        for &v in good {
            assert!(rule.holds(v), "{rule:?} should accept {v}");
        }
        for &v in bad {
            assert!(!rule.holds(v), "{rule:?} should reject {v}");
        }
        assert!(CASES.iter().any(|c| c.2 == rule.reason()));
    }

    #[test]
    fn default_config_passes_every_rule() {
        Config::default().validate().unwrap();
    }

    #[test]
    fn rules_are_checked_in_order_and_the_first_failure_is_reported() {
        // Break every field from the last rule to the first: each time, the newly broken field
        // is the earliest failing one and must be the one reported.
        let mut c = Config::default();
        for (field, _, _, break_it) in CASES.iter().rev() {
            break_it(&mut c);
            let e = c.validate().unwrap_err().to_string();
            assert!(e.starts_with(&format!("invalid setting {field} = ")), "{e}");
        }
    }

    #[test]
    fn unit_interval_rule() {
        assert_eq!(assert_rule_rejects(UNIT), 2);
        assert_bounds(Rule::UnitInterval, &[0.0, 1.0], &[-0.1, 1.5, f64::NAN]);
    }

    #[test]
    fn rate_rule() {
        assert_eq!(assert_rule_rejects(RATE), 1);
        assert_bounds(
            Rule::Rate,
            &[1e-9, MAX_RATE],
            &[0.0, 20_000.5, 1e12, f64::INFINITY, f64::NAN],
        );
    }

    #[test]
    fn bounded_counts_and_sizes() {
        for (reason, n, low, high) in [
            (STEPS_RANGE, 1, 1.0, 100_000.0),
            (V_MAX_RANGE, 1, 1.0, 100.0),
            (FREE_FLOW_ACCEL_RANGE, 1, 0.1, 20.0),
            (HORIZON_RANGE, 1, 1.0, 100.0),
            (SEARCH_BUDGET_RANGE, 2, 1.0, 1e6),
            (PBS_BUDGET_RANGE, 1, 1.0, 100_000.0),
        ] {
            assert_eq!(assert_rule_rejects(reason), n, "{reason}");
            let rule = Rule::Between(low, high, reason);
            let above = high * (1.0 + 1e-9);
            assert_bounds(rule, &[low, high], &[low * 0.99, above, 1e300, f64::NAN]);
        }
    }

    #[test]
    fn absurd_sizes_are_refused_before_anything_runs() {
        // The values that once exhausted memory or hung a worker: each is one error naming its
        // key, at once.
        type Breaker = fn(&mut Config);
        let cases: [(&str, Breaker); 4] = [
            ("scenario.lambda", |c| c.scenario.lambda = 1e12),
            ("scenario.steps", |c| c.scenario.steps = u32::MAX),
            ("scenario.v_max", |c| c.scenario.v_max = 1e300),
            ("planner.horizon", |c| c.planner.horizon = 100_000),
        ];
        for (field, break_it) in cases {
            let mut c = Config::default();
            break_it(&mut c);
            let e = c.validate().unwrap_err().to_string();
            assert!(e.starts_with(&format!("invalid setting {field} = ")), "{e}");
        }
    }

    #[test]
    fn step_length_rule() {
        assert_eq!(assert_rule_rejects(STEP), 1);
        assert_bounds(Rule::StepLength, &[1e-9, 1.0], &[0.0, 1.01, f64::NAN]);
    }

    #[test]
    fn positive_rule() {
        assert_eq!(assert_rule_rejects(POSITIVE), 16);
        assert_bounds(Rule::Positive, &[1e-9, f64::INFINITY], &[0.0, f64::NAN]);
    }

    #[test]
    fn lane_change_duration_rule() {
        assert_eq!(assert_rule_rejects(ONE_STEP), 1);
        assert_bounds(Rule::AtLeast(0.2, ONE_STEP), &[0.2, 1.0], &[0.19, f64::NAN]);
    }

    #[test]
    fn speed_range_rule() {
        assert_eq!(assert_rule_rejects(SPEED_RANGE), 2);
        for bad in [[0.0, 30.0], [30.0, 20.0], [25.0, 36.0], [f64::NAN, 30.0]] {
            let mut c = Config::default();
            c.demand.insertion_speed = bad;
            let e = c.validate().unwrap_err().to_string();
            assert_eq!(
                e,
                format!("invalid setting demand.insertion_speed = {bad:?}: {SPEED_RANGE}")
            );
        }
        let mut c = Config::default();
        c.demand.insertion_speed = [35.0, 35.0];
        c.validate().unwrap();
    }

    #[test]
    fn non_negative_rule() {
        assert_eq!(assert_rule_rejects(NON_NEGATIVE), 12);
        assert_bounds(Rule::NonNegative, &[0.0, f64::INFINITY], &[-1e-9, f64::NAN]);
    }

    #[test]
    fn max_decel_rule() {
        assert_eq!(assert_rule_rejects(IDM_DECEL), 1);
        assert_bounds(
            Rule::AtLeast(5.0, IDM_DECEL),
            &[5.0, 9.0],
            &[4.99, f64::NAN],
        );
    }

    #[test]
    fn time_budget_rule() {
        assert_eq!(assert_rule_rejects(TIME_BUDGET), 1);
        assert_bounds(
            Rule::TimeBudget,
            &[0.0, 1e6],
            &[-1.0, f64::INFINITY, f64::NAN],
        );
    }

    #[test]
    fn open_unit_interval_rule() {
        assert_eq!(assert_rule_rejects(OPEN_UNIT), 1);
        assert_bounds(Rule::OpenUnitInterval, &[1e-9, 0.5], &[0.0, 1.0, f64::NAN]);
    }

    #[test]
    fn model_file_rule() {
        assert_eq!(assert_rule_rejects(MODEL_FILE), 2);
    }

    #[test]
    fn missing_and_malformed_files_name_the_file() {
        let e = Config::from_file(Path::new("no/such/file.toml")).unwrap_err();
        assert!(e.to_string().contains("no/such/file.toml"));
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.toml");
        std::fs::write(&p, "[scenario\nalpha = ").unwrap();
        let e = Config::from_file(&p).unwrap_err().to_string();
        assert!(e.contains("bad.toml") && e.starts_with("malformed"), "{e}");
    }
}
