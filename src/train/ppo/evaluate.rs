//! The trained policy against two reference policies (uniformly random, always idle) on the same
//! held-out episodes: mean return per CAV, CAV collision rate, mean CAV speed.

use std::path::Path;

use super::reward::RewardSettings;
use super::rollout::RolloutStats;
use super::trainer::mix;
use super::workers::{Acting, Pool, PoolError, RolloutRequest};
use crate::config::Config;

/// The policies compared, by name.
pub const POLICIES: [&str; 3] = ["trained", "random", "idle"];

/// Totals of each policy of [`POLICIES`] over the episodes `configs` describe; the trained
/// policy is the file at `policy`, acting greedily.
pub fn compare(
    pool: &mut Pool,
    policy: &Path,
    configs: &[Config],
    reward: &RewardSettings,
) -> Result<Vec<(&'static str, RolloutStats)>, PoolError> {
    let mut out = Vec::new();
    for name in POLICIES {
        let requests = configs
            .iter()
            .enumerate()
            .map(|(index, c)| RolloutRequest {
                index,
                config: c.clone(),
                policy: policy.to_path_buf(),
                acting: match name {
                    "trained" => Acting::Greedy,
                    "random" => Acting::Random(mix(c.scenario.seed, 77)),
                    _ => Acting::Idle,
                },
                reward: reward.clone(),
                single_cav: false,
            })
            .collect();
        let mut total = RolloutStats::default();
        for r in pool.run(requests)? {
            total.add(&r.stats);
        }
        out.push((name, total));
    }
    Ok(out)
}
