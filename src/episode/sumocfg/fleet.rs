//! Which vehicles of a user's scenario are CAVs: the scenario's draw (α or `cav_types`), or,
//! for the stepped RL environment, a single agent: the first vehicle that departs after a
//! warm-up, is a CAV by the scenario's draw and drives through a region; every other vehicle is
//! then an HDV (the paper trains its RL-PPO "in a single CAV environment").

use crate::episode::region::Region;
use crate::sumo::{SumoClient, SumoError};

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

/// Whether vehicle `id`'s route runs through the end of one of `regions` (SUMO answers a
/// negative distance for an edge off its route).
pub(super) fn crosses_a_region(
    sim: &impl SumoClient,
    id: &str,
    regions: &[Region],
) -> Result<bool, SumoError> {
    for r in regions {
        let (end, pos) = (&r.road.end_edge.0, r.road.end_edge.1);
        if sim.driving_distance(id, end, pos)? >= 0.0 {
            return Ok(true);
        }
    }
    Ok(false)
}
