//! Planning every region of a scenario in one round from outside the regions' own planners:
//! the stepped RL environment on a user's scenario (`train::ppo::env`), whose one decision per
//! step covers the agents of every region, as on the paper's merge it covers every CAV.
//!
//! An episode planned this way can also have a single agent: the first vehicle that departs
//! after a warm-up, is a CAV by the scenario's draw and drives through a region; every other
//! vehicle is then an HDV (the paper trains its RL-PPO "in a single CAV environment").

use std::sync::Arc;

use crate::config::Config;
use crate::controller::Command;
use crate::model::scene::Scene;

/// One planning round over every region at once.
pub trait Round: Send {
    /// Each region's configuration and scene, in region order, and the vehicles removed in
    /// collisions since the last round; each region's commands go into its list of `out`
    /// (one per region, empty on entry).
    fn plan(
        &mut self,
        regions: &[(&Config, &Scene)],
        crashed: &[Arc<str>],
        out: &mut [Vec<Command>],
    );
}

/// Which vehicles of the scenario are CAVs.
#[derive(Debug, Clone, PartialEq)]
pub enum Fleet {
    /// Those of the scenario's draw (α or `cav_types`).
    Drawn,
    /// One CAV among HDVs: the first of the draw departing at or after `warmup_s` whose route
    /// runs through a region's end; `chosen` once it has departed.
    Single {
        /// Departures before this time (s) are never the agent.
        warmup_s: f64,
        /// The agent's id, once chosen.
        chosen: Option<String>,
    },
}

impl Fleet {
    /// One CAV among HDVs, chosen after `warmup_s`.
    pub fn single(warmup_s: f64) -> Fleet {
        Fleet::Single {
            warmup_s,
            chosen: None,
        }
    }

    /// Whether a vehicle departing at `now` that the draw makes a CAV when `drawn` is one;
    /// `crosses` says whether its route runs through a region (asked only when it matters).
    /// A single agent, once found, is remembered as `id`.
    pub fn is_cav<E>(
        &mut self,
        id: &str,
        now: f64,
        drawn: bool,
        crosses: impl FnOnce() -> Result<bool, E>,
    ) -> Result<bool, E> {
        match self {
            Fleet::Drawn => Ok(drawn),
            Fleet::Single { warmup_s, chosen } => {
                if chosen.is_some() || !drawn || now < *warmup_s || !crosses()? {
                    return Ok(false);
                }
                *chosen = Some(id.to_string());
                Ok(true)
            }
        }
    }
}
