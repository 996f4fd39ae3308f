//! The planners as a type: the one list of what can drive the CAVs, with the name each goes by
//! on the command line, in settings files and in CSV rows, and the one place that builds each.
//!
//! Every other list of planners (the CLI's `--planner` values and their help, campaign and
//! collection settings, the Python `bkpbs.PLANNERS`) is read off [`PlannerKind::ALL`], so a new
//! planner is added here and nowhere else.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::{bk_mastar, bk_pbs, idm_mobil, rl_ppo, shield, sumo_native, BuildError, Controller};
use crate::config::Config;
use crate::model::road::Road;

/// Who drives the CAVs.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    Serialize,
    Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum PlannerKind {
    /// SUMO's own car-following and lane-change models, with SUMO's safety checks.
    Sumo,
    /// IDM car following with MOBIL lane changes, computed in Rust and commanded through TraCI.
    IdmMobil,
    /// Each CAV planned alone by multi-phase A* against predictions of all other vehicles.
    BkMastar,
    /// The paper's BK-PBS: all CAVs planned jointly by priority-based search over M-A* plans.
    BkPbs,
    /// The reinforcement-learning baseline: a PPO policy picking one motion primitive per CAV.
    RlPpo,
}

impl PlannerKind {
    /// Every planner, in the order of reports and of the default campaign grid.
    pub const ALL: [PlannerKind; 5] = [
        PlannerKind::Sumo,
        PlannerKind::IdmMobil,
        PlannerKind::BkMastar,
        PlannerKind::BkPbs,
        PlannerKind::RlPpo,
    ];

    /// The name on the command line, in settings files and in CSV rows.
    pub const fn name(self) -> &'static str {
        match self {
            PlannerKind::Sumo => "sumo",
            PlannerKind::IdmMobil => "idm-mobil",
            PlannerKind::BkMastar => "bk-mastar",
            PlannerKind::BkPbs => "bk-pbs",
            PlannerKind::RlPpo => "rl-ppo",
        }
    }

    /// Builds the controller for the road SUMO runs; the search planners predict HDVs with the
    /// predictor `config.predictor` selects ([`crate::predict::configured`]) and sit behind the
    /// safety shield when `config.safety.shield` is on, the `rl-ppo` policy when
    /// `config.rl.shield` is.
    ///
    /// # Errors
    /// A predictor model or policy file the configuration names that cannot be used.
    pub fn build(self, config: &Config, road: &Road) -> Result<Box<dyn Controller>, BuildError> {
        let searched: Box<dyn Controller> = match self {
            PlannerKind::Sumo => return Ok(Box::new(sumo_native::SumoNative)),
            PlannerKind::IdmMobil => return Ok(Box::new(idm_mobil::IdmMobil::new(config))),
            PlannerKind::BkMastar => Box::new(bk_mastar::BkMastar::new(
                config,
                crate::predict::configured(config)?,
                road,
            )),
            PlannerKind::BkPbs => Box::new(bk_pbs::BkPbs::new(
                config,
                crate::predict::configured(config)?,
                road,
            )),
            PlannerKind::RlPpo => {
                let policy: Box<dyn Controller> = Box::new(rl_ppo::RlPpo::from_config(config)?);
                return Ok(if config.rl.shield {
                    Box::new(shield::Shielded::new(policy, config))
                } else {
                    policy
                });
            }
        };
        Ok(if config.safety.shield {
            Box::new(shield::Shielded::new(searched, config))
        } else {
            searched
        })
    }

    /// Checks, before any SUMO starts, that [`PlannerKind::build`] will succeed under `config`:
    /// the predictor or policy it needs loads.
    ///
    /// # Errors
    /// As [`PlannerKind::build`].
    pub fn check(self, config: &Config) -> Result<(), BuildError> {
        match self {
            PlannerKind::Sumo | PlannerKind::IdmMobil => Ok(()),
            PlannerKind::BkMastar | PlannerKind::BkPbs => crate::predict::configured(config)
                .map(drop)
                .map_err(Into::into),
            PlannerKind::RlPpo => {
                crate::policy::model_file::load(config.rl.policy.as_deref(), config.scenario.dt)
                    .map(drop)
                    .map_err(Into::into)
            }
        }
    }
}

/// The names of [`PlannerKind::ALL`], in its order (for lists shown to users and to Python).
pub const PLANNERS: [&str; 5] = {
    let mut names = [""; 5];
    let mut i = 0;
    while i < names.len() {
        names[i] = PlannerKind::ALL[i].name();
        i += 1;
    }
    names
};

/// An unknown planner name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown planner '{0}' (known: {known})", known = PLANNERS.join(", "))]
pub struct UnknownPlanner(pub String);

impl FromStr for PlannerKind {
    type Err = UnknownPlanner;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        PlannerKind::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .ok_or_else(|| UnknownPlanner(name.to_string()))
    }
}

impl fmt::Display for PlannerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    #[test]
    fn names_parse_back_and_agree_with_clap_and_serde() {
        for k in PlannerKind::ALL {
            assert_eq!(k.name().parse::<PlannerKind>().unwrap(), k);
            assert_eq!(k.to_possible_value().unwrap().get_name(), k.name());
            assert_eq!(
                toml::Value::try_from(k).unwrap(),
                toml::Value::String(k.name().into())
            );
        }
        assert_eq!(PlannerKind::value_variants(), PlannerKind::ALL);
        assert_eq!(
            PLANNERS,
            ["sumo", "idm-mobil", "bk-mastar", "bk-pbs", "rl-ppo"]
        );
        let e = "bk-pbz".parse::<PlannerKind>().unwrap_err().to_string();
        assert_eq!(
            e,
            "unknown planner 'bk-pbz' (known: sumo, idm-mobil, bk-mastar, bk-pbs, rl-ppo)"
        );
    }
}
