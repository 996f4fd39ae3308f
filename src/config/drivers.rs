//! The driver models' parameters: IDM (HDVs and idm-mobil CAVs), MOBIL (idm-mobil CAVs) and
//! the ramp HDVs' stochastic merge decision.
//!
//! Apart from the scenario because they describe *who drives*, not what is simulated; the HDV
//! driver profiles built on them live in [`crate::config::hdv`].

use serde::{Deserialize, Serialize};

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
    /// Whether each CAV follows with its SUMO type's `accel`, `decel`, `tau` and `minGap` as
    /// IDM's a, b, T and s0 (as SUMO's own IDM reads them) instead of `[idm]`'s, where SUMO gives
    /// them (`controller::idm_mobil`). Unset (the default): on for a scenario of the user's own
    /// (`scenario.sumocfg`), off on the paper's demand; written into a campaign's settings only
    /// when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub type_following: Option<bool>,
    /// Whether CAVs cooperate at merges: a main-road CAV leaves the ramp HDV whose new follower
    /// it would be room, braking for it up to `merge_safe_braking`; a CAV whose merge is blocked
    /// drops back behind the car alongside; no CAV changes into a lane another vehicle is moving
    /// into nearby (`controller::merging`, `controller::lane_claims`). Unset (the default): on
    /// for a scenario of the user's own, off on the paper's demand; written only when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cooperative: Option<bool>,
}

impl Mobil {
    /// Whether CAVs follow with their type's `tau` and `minGap` (`type_following`), on a scenario
    /// of the user's own (`own_scenario`) or on the paper's demand: as set, else only on the
    /// user's own.
    pub fn follows_type(&self, own_scenario: bool) -> bool {
        self.type_following.unwrap_or(own_scenario)
    }

    /// Whether CAVs cooperate at merges (`cooperative`), on a scenario of the user's own
    /// (`own_scenario`) or on the paper's demand: as set, else only on the user's own.
    pub fn cooperates(&self, own_scenario: bool) -> bool {
        self.cooperative.unwrap_or(own_scenario)
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
            type_following: None,
            cooperative: None,
        }
    }
}

/// Ramp HDVs decide to merge with per-step probability `(ξ)^exponent`, where ξ ∈ [0, 1] is the
/// share of the merge zone already driven (so the probability reaches 1 at the zone's end); a
/// decided HDV then merges as soon as SUMO finds the gap safe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RampMerge {
    /// The exponent of ξ in the per-step merge probability; above 0 (1: linear in ξ, larger:
    /// later merges).
    pub exponent: f64,
}

impl Default for RampMerge {
    fn default() -> Self {
        RampMerge { exponent: 1.0 }
    }
}
