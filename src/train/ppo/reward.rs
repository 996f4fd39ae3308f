//! The reward of the RL-PPO merge policy (docs/src/python-and-rl.md): per CAV and step, the paper's two
//! terms (tracking a target speed, avoiding collision) and two this project adds.

use serde::{Deserialize, Serialize};

/// The reward's weights.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RewardSettings {
    /// Target speed (m/s): the step's reward is 1 − |v − target| / target.
    pub target_speed: f64,
    /// Paid once, on a collision (which ends the CAV's episode).
    pub collision_penalty: f64,
    /// Per step on the merge lane, growing linearly from 0 at the middle of the merge zone to
    /// this at its end: a ramp CAV must merge before the lane ends, and the speed term alone
    /// makes waiting at the end nearly free.
    pub merge_deadline_penalty: f64,
    /// Per lane change started: without it the policy weaves for nothing.
    pub lane_change_cost: f64,
}

impl Default for RewardSettings {
    fn default() -> Self {
        RewardSettings {
            target_speed: 35.0,
            collision_penalty: 20.0,
            merge_deadline_penalty: 1.0,
            lane_change_cost: 0.05,
        }
    }
}

impl RewardSettings {
    /// Reward of a step that ended at `speed`, on the merge lane at `merge_progress` (share of
    /// the zone driven) if there, after starting a lane change if `changed`.
    pub fn step(&self, speed: f64, merge_progress: Option<f64>, changed: bool) -> f64 {
        let tracking = 1.0 - ((speed - self.target_speed).abs() / self.target_speed).min(1.0);
        let deadline = merge_progress.map_or(0.0, |xi| {
            self.merge_deadline_penalty * ((xi - 0.5) / 0.5).clamp(0.0, 1.0)
        });
        let change = if changed { self.lane_change_cost } else { 0.0 };
        tracking - deadline - change
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms() {
        let r = RewardSettings::default();
        assert_eq!(r.step(35.0, None, false), 1.0);
        assert!((r.step(17.5, None, false) - 0.5).abs() < 1e-12);
        assert!((r.step(35.0, Some(0.75), false) - 0.5).abs() < 1e-12);
        assert_eq!(r.step(35.0, Some(0.4), true), 0.95);
        assert_eq!(r.step(0.0, Some(1.2), false), -1.0);
    }
}
