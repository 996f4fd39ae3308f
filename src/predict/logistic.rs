//! The logistic-regression baseline: one linear unit over the same encoded features as b_θ
//! (graph (a)'s node features and, conditioned, sequence (b)'s, flattened), trained by the same
//! loop. It shows what the graph network adds over a linear model.

use rand_chacha::ChaCha8Rng;

use super::dataset::Sample;
use super::features::{encode_a, encode_b, COLUMNS_B, FEATURES_A, FEATURES_B, NODES_A};
use super::gcn::{bce_with_logit, sigmoid};
use super::train::Learner;

const LEN_A: usize = FEATURES_A * NODES_A;
const LEN_B: usize = FEATURES_B * COLUMNS_B;

/// Logistic regression on the flattened features; parameters: weights, then the bias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Logistic {
    pub conditioned: bool,
}

impl Logistic {
    /// Input length.
    pub fn inputs(&self) -> usize {
        LEN_A + if self.conditioned { LEN_B } else { 0 }
    }

    /// Writes the flattened features of `obs` into `x` (length [`Logistic::inputs`]).
    pub fn encode(&self, obs: &super::features::Observation, x: &mut [f32]) {
        encode_a(obs, &mut x[..LEN_A]);
        if self.conditioned {
            encode_b(obs, &mut x[LEN_A..]);
        }
    }

    /// The raw logit of `x` under `params`.
    pub fn logit(params: &[f32], x: &[f32]) -> f32 {
        let (w, b) = params.split_at(params.len() - 1);
        w.iter().zip(x).map(|(a, b)| a * b).sum::<f32>() + b[0]
    }
}

impl Learner for Logistic {
    type Scratch = Vec<f32>;

    fn n_params(&self) -> usize {
        self.inputs() + 1
    }

    fn init(&self, _rng: &mut ChaCha8Rng) -> Vec<f32> {
        let mut p = vec![0.0; self.n_params()];
        p[self.inputs()] = (0.02f32 / 0.98).ln();
        p
    }

    fn scratch(&self) -> Vec<f32> {
        vec![0.0; self.inputs()]
    }

    fn loss_grad(
        &self,
        params: &[f32],
        batch: &[&Sample],
        scale: f32,
        grad: &mut [f32],
        x: &mut Vec<f32>,
    ) -> f64 {
        let n = self.inputs();
        let mut loss = 0.0;
        for s in batch {
            self.encode(&s.obs, x);
            let z = Logistic::logit(params, x);
            loss += bce_with_logit(z as f64, s.label);
            let d = scale * (sigmoid(z as f64) as f32 - s.label as u8 as f32);
            for (g, &xi) in grad[..n].iter_mut().zip(x.iter()) {
                *g += d * xi;
            }
            grad[n] += d;
        }
        loss
    }

    fn logits(&self, params: &[f32], batch: &[&Sample], out: &mut Vec<f32>, x: &mut Vec<f32>) {
        for s in batch {
            self.encode(&s.obs, x);
            out.push(Logistic::logit(params, x));
        }
    }
}
