//! Proximal Policy Optimisation (Schulman et al. 2017) for the RL-PPO baseline: clipped
//! surrogate objective, generalised advantage estimation (GAE), separate policy and value
//! networks trained with Adam. The algorithm is independent of where experience comes from:
//! SUMO episodes ([`rollout`], gathered by worker processes in [`workers`]) for the merge
//! policy, a point mass in the tests.

pub mod env;
pub mod evaluate;
pub mod gae;
pub mod reward;
pub mod rollout;
pub mod trainer;
pub mod update;
#[doc(hidden)] // the rollout worker processes of `train-rl`
pub mod workers;

#[cfg(test)]
mod point_mass;

use serde::{Deserialize, Serialize};

/// One agent step of experience.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Step {
    /// The observation the policy acted on.
    pub obs: Vec<f32>,
    /// Allowed actions.
    pub mask: Vec<bool>,
    /// The primitive chosen (index into the action space).
    pub action: u8,
    /// Log-probability of `action` under the policy that acted.
    pub log_prob: f32,
    /// The value network's estimate at `obs` when acting.
    pub value: f32,
    /// Reward of the transition to the next step.
    pub reward: f32,
    /// No choice was made (a lane change under way): trains the value network only.
    pub forced: bool,
}

/// One agent's consecutive steps, up to the end of its episode or of the data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// The steps, in order.
    pub steps: Vec<Step>,
    /// It ended for good (a collision): nothing follows the last step.
    pub terminal: bool,
    /// Otherwise the value of the state after the last step (the episode went on).
    pub bootstrap: f32,
}

/// PPO's hyper-parameters; the defaults are the paper's where it gives them (learning rate,
/// discount, batch, epochs) and Stable-Baselines3's otherwise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PpoSettings {
    /// Adam's step size, for both networks.
    pub learning_rate: f32,
    /// Discount γ.
    pub gamma: f32,
    /// GAE's λ.
    pub gae_lambda: f32,
    /// Clip range ε of the probability ratio.
    pub clip: f32,
    /// Passes over each update's data.
    pub epochs: usize,
    /// Minibatch size.
    pub batch: usize,
    /// Weight of the value loss.
    pub value_coef: f32,
    /// Weight of the entropy bonus.
    pub entropy_coef: f32,
    /// Largest gradient norm of each network per minibatch.
    pub max_grad_norm: f32,
}

impl Default for PpoSettings {
    fn default() -> Self {
        PpoSettings {
            learning_rate: 1e-3,
            gamma: 0.95,
            gae_lambda: 0.95,
            clip: 0.2,
            epochs: 10,
            batch: 512,
            value_coef: 0.5,
            entropy_coef: 0.0,
            max_grad_norm: 0.5,
        }
    }
}
