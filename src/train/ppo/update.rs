//! One PPO update: `epochs` passes over the data in shuffled minibatches, each minibatch's
//! gradient of the clipped surrogate (policy), the squared error to the GAE returns (value)
//! and the entropy bonus, clipped in norm, applied with Adam.
//!
//! Minibatch gradients are summed over a fixed number of chunks computed in parallel (rayon)
//! and added in chunk order, so the result does not depend on the number of threads.

use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::gae::advantages;
use super::{PpoSettings, Segment, Step};
use crate::policy::mlp::Activations;
use crate::policy::network::{masked_log_softmax, ActorCritic};
use crate::train::adam::Adam;

/// Chunks a minibatch is split into for the parallel gradient.
const CHUNKS: usize = 8;

/// Adam's state for both networks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Optimiser {
    /// Adam for the policy (actor) network.
    pub actor: Adam,
    /// Adam for the value (critic) network.
    pub critic: Adam,
}

impl Optimiser {
    /// Fresh moment estimates for `net`'s two networks, both with learning rate `lr`.
    pub fn new(net: &ActorCritic, lr: f32) -> Optimiser {
        Optimiser {
            actor: Adam::new(net.actor.n_params, lr),
            critic: Adam::new(net.critic.n_params, lr),
        }
    }
}

/// What an update measured (means over its minibatches).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct UpdateStats {
    /// Clipped-surrogate loss −min(ρA, clip(ρ)A), mean over the policy samples.
    pub policy_loss: f64,
    /// Squared error of the value estimate to the GAE return, mean over all samples.
    pub value_loss: f64,
    /// Entropy of the masked action distribution (nats), mean over the policy samples.
    pub entropy: f64,
    /// Mean of (ratio − 1) − log ratio: an estimate of KL(old ‖ new).
    pub approx_kl: f64,
    /// Share of policy samples whose ratio was clipped.
    pub clip_fraction: f64,
}

/// A step with its advantage and return.
struct Sample<'a> {
    step: &'a Step,
    advantage: f32,
    ret: f32,
}

/// Sums of one chunk: gradients and statistics.
struct Partial {
    actor: Vec<f32>,
    critic: Vec<f32>,
    stats: UpdateStats,
}

/// Runs one PPO update of `net` on `segments`; `rng` shuffles the minibatches.
pub fn update(
    net: &mut ActorCritic,
    opt: &mut Optimiser,
    segments: &[Segment],
    s: &PpoSettings,
    rng: &mut ChaCha8Rng,
) -> UpdateStats {
    let mut samples = Vec::new();
    for seg in segments {
        let (adv, ret) = advantages(seg, s.gamma, s.gae_lambda);
        for ((step, advantage), ret) in seg.steps.iter().zip(adv).zip(ret) {
            samples.push(Sample {
                step,
                advantage,
                ret,
            });
        }
    }
    let mut order: Vec<usize> = (0..samples.len()).collect();
    let mut total = UpdateStats::default();
    let mut batches = 0usize;
    for _ in 0..s.epochs {
        order.shuffle(rng);
        for idx in order.chunks(s.batch.max(1)) {
            let mb: Vec<&Sample> = idx.iter().map(|&k| &samples[k]).collect();
            let st = minibatch_step(net, opt, &mb, s);
            total.policy_loss += st.policy_loss;
            total.value_loss += st.value_loss;
            total.entropy += st.entropy;
            total.approx_kl += st.approx_kl;
            total.clip_fraction += st.clip_fraction;
            batches += 1;
        }
    }
    let n = batches.max(1) as f64;
    UpdateStats {
        policy_loss: total.policy_loss / n,
        value_loss: total.value_loss / n,
        entropy: total.entropy / n,
        approx_kl: total.approx_kl / n,
        clip_fraction: total.clip_fraction / n,
    }
}

/// Advantage normalisation of a minibatch: mean and standard deviation over its policy samples.
fn advantage_moments(mb: &[&Sample]) -> (f32, f32, usize) {
    let adv: Vec<f32> = mb
        .iter()
        .filter(|x| !x.step.forced)
        .map(|x| x.advantage)
        .collect();
    let n = adv.len();
    if n == 0 {
        return (0.0, 1.0, 0);
    }
    let mean = adv.iter().sum::<f32>() / n as f32;
    let var = adv.iter().map(|a| (a - mean).powi(2)).sum::<f32>() / n as f32;
    (mean, var.sqrt() + 1e-8, n)
}

/// The gradient of one minibatch, clipped, applied.
fn minibatch_step(
    net: &mut ActorCritic,
    opt: &mut Optimiser,
    mb: &[&Sample],
    s: &PpoSettings,
) -> UpdateStats {
    let (mean, sd, n_policy) = advantage_moments(mb);
    let scale = Scale {
        mean,
        sd,
        n_policy: n_policy.max(1) as f32,
        n_all: mb.len() as f32,
    };
    let chunk = mb.len().div_ceil(CHUNKS).max(1);
    let partials: Vec<Partial> = mb
        .par_chunks(chunk)
        .map(|c| chunk_gradient(net, c, s, &scale))
        .collect();
    let mut ga = vec![0.0f32; net.actor.n_params];
    let mut gc = vec![0.0f32; net.critic.n_params];
    let mut stats = UpdateStats::default();
    for p in &partials {
        add(&mut ga, &p.actor);
        add(&mut gc, &p.critic);
        stats.policy_loss += p.stats.policy_loss;
        stats.value_loss += p.stats.value_loss;
        stats.entropy += p.stats.entropy;
        stats.approx_kl += p.stats.approx_kl;
        stats.clip_fraction += p.stats.clip_fraction;
    }
    clip_norm(&mut ga, s.max_grad_norm);
    clip_norm(&mut gc, s.max_grad_norm);
    opt.actor.step(&mut net.actor_params, &ga);
    opt.critic.step(&mut net.critic_params, &gc);
    let np = f64::from(scale.n_policy);
    UpdateStats {
        policy_loss: stats.policy_loss / np,
        value_loss: stats.value_loss / f64::from(scale.n_all),
        entropy: stats.entropy / np,
        approx_kl: stats.approx_kl / np,
        clip_fraction: stats.clip_fraction / np,
    }
}

/// Normalisations shared by a minibatch's chunks.
struct Scale {
    mean: f32,
    sd: f32,
    n_policy: f32,
    n_all: f32,
}

fn add(acc: &mut [f32], x: &[f32]) {
    for (a, b) in acc.iter_mut().zip(x) {
        *a += b;
    }
}

/// Scales `g` down to norm `max` if it is longer.
fn clip_norm(g: &mut [f32], max: f32) {
    let norm = g.iter().map(|x| x * x).sum::<f32>().sqrt();
    if norm > max && norm.is_finite() {
        let k = max / norm;
        g.iter_mut().for_each(|x| *x *= k);
    }
}

/// Gradient sums (already divided by the minibatch's counts) of one chunk of samples.
fn chunk_gradient(net: &ActorCritic, c: &[&Sample], s: &PpoSettings, sc: &Scale) -> Partial {
    let dim = net.actor.inputs();
    let mut x = DMatrix::zeros(dim, c.len());
    for (j, smp) in c.iter().enumerate() {
        x.column_mut(j).copy_from_slice(&smp.step.obs);
    }
    let mut act = Activations::default();
    let logits = net.logits(&x, &mut act);
    let mut d_logits = DMatrix::zeros(logits.nrows(), c.len());
    let mut stats = UpdateStats::default();
    for (j, smp) in c.iter().enumerate() {
        if smp.step.forced {
            continue;
        }
        let a = (smp.advantage - sc.mean) / sc.sd;
        let col = policy_gradient(logits.column(j).as_slice(), smp.step, a, s, &mut stats);
        for (k, g) in col.into_iter().enumerate() {
            d_logits[(k, j)] = g / sc.n_policy;
        }
    }
    let mut actor = vec![0.0f32; net.actor.n_params];
    net.actor
        .backward(&net.actor_params, &act, &d_logits, &mut actor);
    let mut cact = Activations::default();
    let values = net.values(&x, &mut cact);
    let mut d_v = DMatrix::zeros(1, c.len());
    for (j, (smp, v)) in c.iter().zip(values).enumerate() {
        let err = v - smp.ret;
        stats.value_loss += f64::from(err * err);
        d_v[(0, j)] = s.value_coef * 2.0 * err / sc.n_all;
    }
    let mut critic = vec![0.0f32; net.critic.n_params];
    net.critic
        .backward(&net.critic_params, &cact, &d_v, &mut critic);
    Partial {
        actor,
        critic,
        stats,
    }
}

/// d(loss)/d(logits) of one policy sample (before dividing by the sample count), adding its
/// loss, entropy, KL estimate and clipping to `stats`. loss = −min(ρA, clip(ρ)A) − c·H.
fn policy_gradient(
    logits: &[f32],
    step: &Step,
    adv: f32,
    s: &PpoSettings,
    stats: &mut UpdateStats,
) -> Vec<f32> {
    let lp = masked_log_softmax(logits, &step.mask);
    let a = usize::from(step.action);
    let log_ratio = lp[a] - step.log_prob;
    let ratio = log_ratio.exp();
    let clipped = ratio.clamp(1.0 - s.clip, 1.0 + s.clip);
    let unclipped_active = ratio * adv <= clipped * adv;
    stats.policy_loss -= f64::from((ratio * adv).min(clipped * adv));
    stats.approx_kl += f64::from((ratio - 1.0) - log_ratio);
    stats.clip_fraction += f64::from(u8::from((ratio - 1.0).abs() > s.clip));
    let pi: Vec<f32> = lp.iter().map(|l| l.exp()).collect();
    let entropy: f32 = -lp
        .iter()
        .zip(&pi)
        .filter(|(l, _)| l.is_finite())
        .map(|(l, p)| p * l)
        .sum::<f32>();
    stats.entropy += f64::from(entropy);
    let d_logp = if unclipped_active { -ratio * adv } else { 0.0 };
    (0..logits.len())
        .map(|k| {
            if !step.mask[k] {
                return 0.0;
            }
            let surrogate = d_logp * (f32::from(u8::from(k == a)) - pi[k]);
            let bonus = s.entropy_coef * pi[k] * (lp[k] + entropy);
            surrogate + bonus
        })
        .collect()
}
