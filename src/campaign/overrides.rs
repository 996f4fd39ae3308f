//! The campaign's command-line flags, before they meet the campaign file: what both kinds of
//! campaign (the paper's demand and scenarios of the user's own) and their checks read.

use crate::config::TrajectoryFormat;

/// Command-line flags; each set one replaces the file's value. Lists arrive as the
/// comma-separated text of the flag so that a bad entry gets a clear error naming the flag.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    /// `--planners`, comma-separated controller names.
    pub planners: Option<String>,
    /// `--alphas`, comma-separated CAV penetrations α.
    pub alphas: Option<String>,
    /// `--lambdas`, comma-separated arrival rates λ (veh/h).
    pub lambdas: Option<String>,
    /// `--seeds`: seeds per grid point.
    pub seeds: Option<u64>,
    /// `--seed-base`: the first seed.
    pub seed_base: Option<u64>,
    /// `--steps`: episode length in steps.
    pub steps: Option<u32>,
    /// `--workers`: worker processes.
    pub workers: Option<usize>,
    /// `--shard k/n`: run only the k-th of n interleaved slices of the grid.
    pub shard: Option<String>,
    /// `--episode-timeout` in seconds.
    pub episode_timeout: Option<f64>,
    /// `--trajectories[-format]`: replaces the file's `output.trajectories`.
    pub trajectories: Option<TrajectoryFormat>,
    /// `--hdv-profiles`, comma-separated.
    pub hdv_profiles: Option<String>,
    /// `--predictors`, comma-separated HDV predictors (`learned`, `constant`): a grid axis.
    pub predictors: Option<String>,
    /// `--sumocfg`, comma-separated: a campaign over these scenarios of the user's own
    /// ([`super::scenarios`]).
    pub sumocfg: Option<String>,
}
