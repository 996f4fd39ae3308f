//! The RL-PPO actor–critic: a policy network (observation → one logit per primitive) and a value
//! network (observation → expected return), separate MLPs as in the paper ("the policy and value
//! function networks both have two layers and hidden dimensions of 256").

use nalgebra::DMatrix;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::actions::ACTIONS;
use super::mlp::{Activations, Mlp};
use super::observation::OBS_DIM;

/// Hidden widths of both networks (the paper's).
pub const HIDDEN: [usize; 2] = [256, 256];

/// Both networks and their parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct ActorCritic {
    /// Shape of the policy network: observation → one logit per action.
    pub actor: Mlp,
    /// Shape of the value network: observation → one expected return.
    pub critic: Mlp,
    /// The policy network's flat parameters (see [`Mlp`] for the layout).
    pub actor_params: Vec<f32>,
    /// The value network's flat parameters.
    pub critic_params: Vec<f32>,
}

impl ActorCritic {
    /// Freshly initialised networks for observations of `obs_dim` and `actions` actions
    /// (the policy's output layer scaled by 0.01, so it starts near uniform).
    pub fn with_shape(obs_dim: usize, hidden: &[usize], actions: usize, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let actor = Mlp::new(obs_dim, hidden, actions);
        let critic = Mlp::new(obs_dim, hidden, 1);
        ActorCritic {
            actor_params: actor.init(&mut rng, 0.01),
            critic_params: critic.init(&mut rng, 1.0),
            actor,
            critic,
        }
    }

    /// The merge-scenario networks (observation [`OBS_DIM`], six primitives, [`HIDDEN`]).
    pub fn new(seed: u64) -> Self {
        Self::with_shape(OBS_DIM, &HIDDEN, ACTIONS, seed)
    }

    /// The merge-scenario networks with given weights (checked for length by the caller: the
    /// policy file's loader, a checkpoint of this build).
    pub fn with_params(actor_params: Vec<f32>, critic_params: Vec<f32>) -> Self {
        ActorCritic {
            actor: Mlp::new(OBS_DIM, &HIDDEN, ACTIONS),
            critic: Mlp::new(OBS_DIM, &HIDDEN, 1),
            actor_params,
            critic_params,
        }
    }

    /// Logits (actions × n) of the batch `obs` (obs_dim × n).
    pub fn logits(&self, obs: &DMatrix<f32>, act: &mut Activations) -> DMatrix<f32> {
        self.actor.forward(&self.actor_params, obs, act);
        act.result().clone()
    }

    /// Values (one per column of `obs`).
    pub fn values(&self, obs: &DMatrix<f32>, act: &mut Activations) -> Vec<f32> {
        self.critic.forward(&self.critic_params, obs, act);
        act.result().iter().copied().collect()
    }
}

/// Log-probabilities of the actions under `logits`, the masked ones −∞ (at least one action
/// must be allowed).
pub fn masked_log_softmax(logits: &[f32], mask: &[bool]) -> Vec<f32> {
    let max = logits
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(&l, _)| l)
        .fold(f32::NEG_INFINITY, f32::max);
    let sum: f32 = logits
        .iter()
        .zip(mask)
        .filter(|(_, &m)| m)
        .map(|(&l, _)| (l - max).exp())
        .sum();
    let log_z = max + sum.ln();
    logits
        .iter()
        .zip(mask)
        .map(|(&l, &m)| if m { l - log_z } else { f32::NEG_INFINITY })
        .collect()
}

/// The action with the highest probability (ties: the first).
pub fn greedy(log_probs: &[f32]) -> usize {
    let mut best = 0;
    for (k, &l) in log_probs.iter().enumerate() {
        if l > log_probs[best] {
            best = k;
        }
    }
    best
}

/// The action a uniform draw `u` ∈ [0, 1) picks from the distribution.
pub fn sample(log_probs: &[f32], u: f64) -> usize {
    let mut acc = 0.0f64;
    let mut last = 0;
    for (k, &l) in log_probs.iter().enumerate() {
        if l == f32::NEG_INFINITY {
            continue;
        }
        acc += f64::from(l.exp());
        last = k;
        if u < acc {
            return k;
        }
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masked_softmax_sums_to_one_over_allowed() {
        let lp = masked_log_softmax(&[1.0, 2.0, 3.0], &[true, false, true]);
        assert_eq!(lp[1], f32::NEG_INFINITY);
        let total: f32 = lp.iter().map(|l| l.exp()).sum();
        assert!((total - 1.0).abs() < 1e-6);
        assert_eq!(greedy(&lp), 2);
        assert_eq!(sample(&lp, 0.0), 0);
        assert_eq!(sample(&lp, 0.999), 2);
    }

    #[test]
    fn fresh_policy_is_near_uniform() {
        let ac = ActorCritic::new(3);
        let obs = DMatrix::from_element(OBS_DIM, 2, 0.5f32);
        let mut a = Activations::default();
        let l = ac.logits(&obs, &mut a);
        let lp = masked_log_softmax(l.column(0).as_slice(), &[true; ACTIONS]);
        for x in lp {
            assert!((x.exp() - 1.0 / 6.0).abs() < 0.02, "{x}");
        }
    }
}
