//! The logistic-regression baseline: one linear unit over the same encoded features as b_θ
//! (graph (a)'s node features and, conditioned, sequence (b)'s, flattened), trained by the same
//! loop (its [`crate::train::training_loop::Learner`] impl is in `train/logistic.rs`). It shows
//! what the graph network adds over a linear model.

use super::features::{encode_a, encode_b, COLUMNS_B, FEATURES_A, FEATURES_B, NODES_A};

const LEN_A: usize = FEATURES_A * NODES_A;
const LEN_B: usize = FEATURES_B * COLUMNS_B;

/// Logistic regression on the flattened features; parameters: weights, then the bias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Logistic {
    /// Also reads sequence (b) (the CAV preview), flattened after graph (a).
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

    /// Parameter count: one weight per input, then the bias.
    pub fn n_params(&self) -> usize {
        self.inputs() + 1
    }

    /// The raw logit of `x` under `params`.
    pub fn logit(params: &[f32], x: &[f32]) -> f32 {
        let (w, b) = params.split_at(params.len() - 1);
        w.iter().zip(x).map(|(a, b)| a * b).sum::<f32>() + b[0]
    }
}
