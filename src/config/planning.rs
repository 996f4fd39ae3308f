//! How the CAVs decide: the motion primitives and M-A*, BK-PBS's high-level search, the HDV
//! predictor the planners use, the safety shield, and the RL-PPO baseline.
//!
//! Apart from the scenario and the driver models because they configure the CAVs' controllers,
//! not the traffic the controllers are compared on.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// Motion primitives and the multi-phase A* (the paper's section IV; the guide's planners
/// chapter, docs/src/planners.md, gives the defaults it leaves open).
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
    /// beside a gap it kept planning to take (docs/src/planners.md tells the deadlock and its
    /// rules).
    pub lane_change_deferral_penalty: f64,
    /// Acceleration of the `accelerate` primitive (m/s²), at most the vehicle's own. Unset
    /// (the default): each CAV's own type's `accel` where the scenario gives it one (a user's
    /// SUMO scenario), else [`PAPER_ACCEL`] (the paper's demand, whose types can do more).
    pub accel: Option<f64>,
    /// Deceleration of the `decelerate` primitive (m/s², positive).
    pub decel: f64,
    /// Deceleration of the `emergency-brake` primitive (m/s², positive).
    pub emergency_decel: f64,
    /// Slowest speed from which the bicycle model steers a lane change (m/s).
    pub min_lane_change_speed: f64,
    /// Which lane changes below `min_lane_change_speed` are planned as SUMO executes them there
    /// (a slide: one lane per second, the body along the road) instead of not at all: only
    /// merges out of the acceleration lane by default, so a ramp CAV that had to slow down is
    /// not stuck at the lane end (docs/src/planners.md tells the deadlock and its rules).
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
    /// Whether a ramp CAV on its acceleration lane keeps behind the nearest vehicle ahead of it
    /// in the lane it merges into, as if in its own lane (`planner::mastar::gap_seeking`).
    /// Unset (the default): on for a scenario of the user's own (`scenario.sumocfg`), off on
    /// the paper's demand (the paper's search, see [`PlannerSettings::seeks_gaps`]). Written
    /// into a campaign's settings only when set, so campaigns of earlier versions still match.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_seeking: Option<bool>,
    /// Whether a main-road CAV leaves a ramp HDV ahead of it, about to merge into its lane, the
    /// gap SUMO's lane-change model asks of that merger's new follower, where it can by braking
    /// comfortably (`planner::mastar::courtesy`). Unset (the default): on for a scenario of the
    /// user's own, off on the paper's demand, as `gap_seeking`; written only when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub courtesy: Option<bool>,
}

/// The `accelerate` primitive's acceleration where neither the configuration nor the vehicle
/// sets one (m/s²): the paper's.
pub const PAPER_ACCEL: f64 = 2.0;

impl PlannerSettings {
    /// The `accelerate` primitive's acceleration for a vehicle with no limit of its own.
    pub fn accel_or_paper(&self) -> f64 {
        self.accel.unwrap_or(PAPER_ACCEL)
    }

    /// Whether ramp CAVs seek gaps (`gap_seeking`), on a scenario of the user's own
    /// (`own_scenario`) or on the paper's demand: as set, else only on the user's own. Measured
    /// on SUMO's `ramp` game (docs/src/own-scenario.md) it lowered bk-pbs's region delay by
    /// 2.3 s over 20 seeds; on the paper's merge it made no difference, and there the paper's
    /// search is kept.
    pub fn seeks_gaps(&self, own_scenario: bool) -> bool {
        self.gap_seeking.unwrap_or(own_scenario)
    }

    /// Whether main-road CAVs leave a ramp HDV ahead the gap SUMO asks for it (`courtesy`), on a
    /// scenario of the user's own (`own_scenario`) or on the paper's demand: as set, else only
    /// on the user's own (docs/src/own-scenario.md gives what it changed on SUMO's `ramp` game).
    pub fn is_courteous(&self, own_scenario: bool) -> bool {
        self.courtesy.unwrap_or(own_scenario)
    }
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
            accel: None,
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
            gap_seeking: None,
            courtesy: None,
        }
    }
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

impl Default for PbsSettings {
    fn default() -> Self {
        PbsSettings {
            node_budget: 200,
            time_budget_ms: 0.0,
            independent_groups: Grouping::Auto,
        }
    }
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

/// Which predictor [`PredictorSettings`] selects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum PredictorKind {
    /// The GCN lane-change model b_θ (the paper's predictor).
    Learned,
    /// Constant speed in lane; ramp HDVs merge at their median decision step.
    Constant,
}

/// The safety shield (docs/src/planners.md): every CAV's next step of bk-mastar and bk-pbs
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

/// The RL-PPO baseline (docs/src/python-and-rl.md).
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
