//! HDV driver profiles: who the human drivers are. A profile is a set of SUMO vehicle-type
//! settings (car-following model and its parameters, lane-change model parameters, per-driver
//! draws) plus how ramp HDVs merge. `[hdv] profile` picks one; built-in profiles are below, and
//! a config file may define its own under `[hdv.profiles.NAME]`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::ConfigError;

/// The profile used when none is named: today's drivers, results unchanged.
pub const DEFAULT_PROFILE: &str = "sumo-safe";

/// Names of the built-in profiles, in the order `bkpbs config` lists them.
pub const BUILT_IN: [&str; 5] = ["sumo-safe", "paper", "heterogeneous", "krauss", "eidm"];

/// The `[hdv]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HdvSettings {
    /// The driver profile of every HDV: a built-in one or one of `profiles`.
    pub profile: String,
    /// Profiles defined by the user; a name of a built-in one replaces it.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub profiles: BTreeMap<String, HdvProfile>,
}

impl Default for HdvSettings {
    fn default() -> Self {
        HdvSettings {
            profile: DEFAULT_PROFILE.into(),
            profiles: BTreeMap::new(),
        }
    }
}

/// SUMO's car-following models a profile may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CarFollowing {
    /// The Intelligent Driver Model with `[idm]`'s parameters.
    #[serde(rename = "IDM")]
    Idm,
    /// Krauss, SUMO's default, with driver imperfection `sigma`.
    Krauss,
    /// The Extended IDM (Salles et al. 2020) with driver errors and reaction time.
    #[serde(rename = "EIDM")]
    Eidm,
}

impl CarFollowing {
    /// SUMO's name of the model.
    pub fn sumo_name(self) -> &'static str {
        match self {
            CarFollowing::Idm => "IDM",
            CarFollowing::Krauss => "Krauss",
            CarFollowing::Eidm => "EIDM",
        }
    }
}

/// How a ramp HDV that decided to merge (see `ramp_merge`) moves over.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "style")]
pub enum RampMergeStyle {
    /// Into a gap SUMO judges safe (its lane-change model's safety check), adapting speed to
    /// find one.
    Safe,
    /// Into any gap whose time gap to the new follower is at least the driver's critical gap,
    /// drawn per driver from a log-normal distribution; SUMO then only avoids an immediate
    /// overlap, so the follower may have to brake harder than it can.
    GapAcceptance {
        /// Median critical time gap (s).
        median_s: f64,
        /// Standard deviation of its logarithm.
        log_sd: f64,
    },
}

/// One driver profile.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HdvProfile {
    /// What the profile models, for `bkpbs config` and the guide.
    pub description: String,
    /// SUMO's car-following model of the profile's HDVs.
    pub car_following: CarFollowing,
    /// Further SUMO vType attributes as SUMO spells them (`sigma`, `lcAssertive`,
    /// `treaction`, …); they override the ones bkpbs derives from `[idm]`.
    pub attributes: BTreeMap<String, String>,
    /// Heterogeneous drivers: vType attributes drawn per driver type, uniform in [low, high]
    /// (e.g. `tau`, `minGap`, `accel`, `decel`); empty for one type shared by all HDVs.
    pub draws: BTreeMap<String, [f64; 2]>,
    /// How many driver types are drawn (with `draws`); SUMO assigns each HDV one of them.
    pub driver_types: usize,
    /// How a ramp HDV that decided to merge moves over to the main road.
    pub ramp_merge: RampMergeStyle,
}

impl Default for HdvProfile {
    fn default() -> Self {
        HdvProfile {
            description: String::new(),
            car_following: CarFollowing::Idm,
            attributes: BTreeMap::new(),
            draws: BTreeMap::new(),
            driver_types: 20,
            ramp_merge: RampMergeStyle::Safe,
        }
    }
}

impl HdvProfile {
    /// The largest value any of the profile's driver types gives SUMO vType attribute `key`:
    /// the top of its draw range, else its fixed value, else `default` (what bkpbs or SUMO
    /// sets when the profile leaves it alone). The shield bounds the HDVs by it (e.g. the most
    /// assertive lane changer), since it cannot tell which driver type an HDV drew.
    pub fn max_attribute(&self, key: &str, default: f64) -> f64 {
        match (self.draws.get(key), self.attributes.get(key)) {
            (Some([_, high]), _) => *high,
            (None, Some(v)) => v.trim().parse().unwrap_or(default),
            (None, None) => default,
        }
    }
}

/// The largest magnitude of a numeric vType attribute: beyond it no physical vehicle (SUMO
/// asserts on some, e.g. `accel = 1e308`).
const ATTRIBUTE_MAGNITUDE: f64 = 1e4;

/// Whether SUMO can be given vType attribute `key = value`: a name as SUMO spells its
/// attributes (letters, digits, `_`, `.`, from a letter), a number finite and within
/// ±[`ATTRIBUTE_MAGNITUDE`] (SUMO spins for ever on `minGap = nan`), and no markup (a `"` would
/// end the attribute and let the rest be read as XML).
fn check_attribute(key: &str, value: &str) -> Result<(), &'static str> {
    let name_ok = key.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.');
    if !name_ok || key == "id" {
        return Err(
            "not a SUMO vType attribute name (letters, digits, '_', from a letter; not id)",
        );
    }
    if value
        .chars()
        .any(|c| matches!(c, '<' | '>' | '&' | '"' | '\'') || c.is_control())
    {
        return Err(
            "SUMO attribute values hold no markup characters (< > & \" ') or control characters",
        );
    }
    // Rust reads "nan", "inf" and "1e308" as numbers, as SUMO does; "1,0,0" or "center" are
    // no number and pass as text.
    match value.trim().parse::<f64>() {
        Ok(x) if !(x.is_finite() && x.abs() <= ATTRIBUTE_MAGNITUDE) => {
            Err("must be a finite number within ±10000")
        }
        Ok(x) => check_range(key, x),
        _ => Ok(()),
    }
}

/// SUMO's own range for the vType attributes whose out-of-range values make it assert or
/// misbehave (a zero length asserts, a zero deceleration divides by it); others pass.
fn check_range(key: &str, x: f64) -> Result<(), &'static str> {
    const POSITIVE: [&str; 12] = [
        "accel",
        "decel",
        "emergencyDecel",
        "apparentDecel",
        "length",
        "width",
        "height",
        "maxSpeed",
        "desiredMaxSpeed",
        "tau",
        "speedFactor",
        "actionStepLength",
    ];
    const NON_NEGATIVE: [&str; 4] = ["minGap", "speedDev", "minGapLat", "maxSpeedLat"];
    if POSITIVE.contains(&key) && x <= 0.0 {
        Err("must be positive (SUMO's range for this attribute)")
    } else if NON_NEGATIVE.contains(&key) && x < 0.0 {
        Err("must not be negative (SUMO's range for this attribute)")
    } else if key == "sigma" && !(0.0..=1.0).contains(&x) {
        Err("must lie in [0, 1] (SUMO's range for the driver imperfection)")
    } else {
        Ok(())
    }
}

fn attributes(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// The built-in profile `name`, if there is one.
pub fn built_in(name: &str) -> Option<HdvProfile> {
    let p = match name {
        "sumo-safe" => sumo_safe(),
        "paper" => paper(),
        "heterogeneous" => heterogeneous(),
        "krauss" => krauss(),
        "eidm" => eidm(),
        _ => return None,
    };
    Some(p)
}

/// `sumo-safe`, the default: SUMO's IDM and LC2013 as they are.
fn sumo_safe() -> HdvProfile {
    HdvProfile {
        description: "SUMO's IDM with [idm]'s parameters, LC2013, ramp HDVs merging only into \
                      gaps SUMO judges safe (the default)"
            .into(),
        ..HdvProfile::default()
    }
}

/// `paper`: drivers as close to the paper's simulator as SUMO allows.
fn paper() -> HdvProfile {
    HdvProfile {
        description: "closest to the paper's simulator: ramp HDVs accept gaps by a \
                      log-normal critical time gap (median 1.0 s) without SUMO's safety \
                      check; assertive, impatient, little cooperative main-road lane changes"
            .into(),
        attributes: attributes(&[
            ("lcAssertive", "3"),
            ("lcCooperative", "0.2"),
            ("lcSpeedGain", "2"),
            ("lcImpatience", "0.8"),
        ]),
        ramp_merge: RampMergeStyle::GapAcceptance {
            median_s: 1.0,
            log_sd: 0.5,
        },
        ..HdvProfile::default()
    }
}

/// `heterogeneous`: IDM drivers of many types, each drawn from highway ranges.
fn heterogeneous() -> HdvProfile {
    HdvProfile {
        description: "IDM drivers of 20 types, each drawing T, s0, a and b uniformly from \
                      the ranges Treiber and Kesting report for highway traffic"
            .into(),
        draws: [
            ("tau", [0.8, 2.0]),
            ("minGap", [1.0, 3.0]),
            ("accel", [0.8, 2.5]),
            ("decel", [1.0, 3.0]),
        ]
        .iter()
        .map(|(k, r)| (k.to_string(), *r))
        .collect(),
        ..HdvProfile::default()
    }
}

/// `krauss`: SUMO's default car-following model with imperfect drivers.
fn krauss() -> HdvProfile {
    HdvProfile {
        description: "SUMO's Krauss model with driver imperfection sigma = 0.5".into(),
        car_following: CarFollowing::Krauss,
        attributes: attributes(&[("sigma", "0.5")]),
        ..HdvProfile::default()
    }
}

/// `eidm`: the Extended IDM with reaction time and estimation errors.
fn eidm() -> HdvProfile {
    HdvProfile {
        description: "SUMO's Extended IDM with reaction time 0.5 s and estimation errors \
                      of gap, speed and leader speed"
            .into(),
        car_following: CarFollowing::Eidm,
        attributes: attributes(&[
            ("treaction", "0.5"),
            ("sigmagap", "0.1"),
            ("sigmaerror", "0.1"),
            ("sigmaleader", "0.1"),
        ]),
        ..HdvProfile::default()
    }
}

impl HdvSettings {
    /// The profile in use: the user's definition of that name, else the built-in one.
    pub fn resolved(&self) -> Result<HdvProfile, ConfigError> {
        self.profiles
            .get(&self.profile)
            .cloned()
            .or_else(|| built_in(&self.profile))
            .ok_or_else(|| ConfigError::UnknownProfile {
                name: self.profile.clone(),
                known: self.known().join(", "),
            })
    }

    /// Every profile name this configuration knows.
    pub fn known(&self) -> Vec<String> {
        let mut names: Vec<String> = BUILT_IN.iter().map(|s| s.to_string()).collect();
        names.extend(
            self.profiles
                .keys()
                .filter(|k| built_in(k).is_none())
                .cloned(),
        );
        names
    }

    /// Checks the vType attributes profile `p` gives SUMO, fixed or drawn.
    fn check_attributes(&self, p: &HdvProfile) -> Result<(), ConfigError> {
        let fixed = p.attributes.iter().map(|(k, v)| (k, v.clone()));
        let drawn = p.draws.iter().map(|(k, [_, high])| (k, high.to_string()));
        for (key, value) in fixed.chain(drawn) {
            if let Err(reason) = check_attribute(key, &value) {
                return Err(ConfigError::InvalidAttribute {
                    profile: self.profile.clone(),
                    key: key.clone(),
                    value,
                    reason,
                });
            }
        }
        Ok(())
    }

    /// Checks the profile in use (and that it exists).
    pub fn validate(&self) -> Result<(), ConfigError> {
        let p = self.resolved()?;
        let invalid = |field: &'static str, value: String, reason: &'static str| {
            Err(ConfigError::Invalid {
                field,
                value,
                reason,
            })
        };
        if !p.draws.is_empty() && !(1..=1000).contains(&p.driver_types) {
            return invalid(
                "hdv.driver_types",
                p.driver_types.to_string(),
                "must be 1 to 1000 driver types",
            );
        }
        self.check_attributes(&p)?;
        for (key, [low, high]) in &p.draws {
            if !(low.is_finite() && high.is_finite() && *low > 0.0 && low <= high) {
                return Err(ConfigError::InvalidDraw {
                    key: key.clone(),
                    low: *low,
                    high: *high,
                });
            }
        }
        if let RampMergeStyle::GapAcceptance { median_s, log_sd } = p.ramp_merge {
            if !(median_s > 0.0 && median_s <= 10.0) {
                return invalid(
                    "hdv.ramp_merge.median_s",
                    median_s.to_string(),
                    "must lie in (0, 10] s",
                );
            }
            if !(0.0..=3.0).contains(&log_sd) {
                return invalid(
                    "hdv.ramp_merge.log_sd",
                    log_sd.to_string(),
                    "must lie in [0, 3]",
                );
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_built_in_profile_is_valid_and_described() {
        for name in BUILT_IN {
            let s = HdvSettings {
                profile: name.into(),
                ..HdvSettings::default()
            };
            s.validate().unwrap();
            assert!(!s.resolved().unwrap().description.is_empty(), "{name}");
        }
    }

    #[test]
    fn an_unknown_profile_is_named_with_the_known_ones() {
        let s = HdvSettings {
            profile: "reckless".into(),
            ..HdvSettings::default()
        };
        let e = s.validate().unwrap_err().to_string();
        assert!(
            e.contains("reckless") && e.contains("sumo-safe, paper"),
            "{e}"
        );
    }

    #[test]
    fn a_user_profile_is_read_from_toml_and_checked() {
        let text = r#"
            profile = "mine"
            [profiles.mine]
            car_following = "Krauss"
            attributes = { sigma = "0.9" }
            ramp_merge = { style = "gap-acceptance", median_s = 0.6, log_sd = 0.3 }
        "#;
        let s: HdvSettings = toml::from_str(text).unwrap();
        let p = s.resolved().unwrap();
        assert_eq!(p.car_following, CarFollowing::Krauss);
        assert_eq!(p.attributes["sigma"], "0.9");
        s.validate().unwrap();
        let bad = text.replace("median_s = 0.6", "median_s = -1");
        let s: HdvSettings = toml::from_str(&bad).unwrap();
        assert!(s.validate().unwrap_err().to_string().contains("median_s"));
    }

    #[test]
    fn the_largest_value_of_an_attribute_is_a_draws_top_or_the_fixed_value() {
        let paper = built_in("paper").unwrap();
        assert_eq!(paper.max_attribute("lcAssertive", 1.0), 3.0);
        assert_eq!(paper.max_attribute("decel", 5.0), 5.0);
        let mixed = built_in("heterogeneous").unwrap();
        assert_eq!(mixed.max_attribute("decel", 5.0), 3.0);
        assert_eq!(mixed.max_attribute("lcAssertive", 1.0), 1.0);
    }
}
