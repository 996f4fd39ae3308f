//! The network of b_θ (paper IV.D): two GCN blocks, two fully connected layers, a sigmoid.
//!
//! Block A reads graph (a) (the HDV and its neighbours); block B, with shared weights, reads each
//! graph of sequence (b) (the CAVs near it over the preview horizon), and its outputs are
//! averaged over time. Both graphs are fully connected with self-loops, and the GCN propagation
//! uses the symmetric normalisation D^-½ (A + I) D^-½ — which, for a fully connected graph of n
//! nodes, is exactly the matrix with every entry 1/n: every node receives the mean of all nodes.
//! A graph convolution applied to the raw features would therefore only see the feature mean
//! and forget which neighbour is where, so each block first embeds every node with a shared
//! layer (64, ReLU), then applies the graph convolution (64, ReLU) and reads the graph out by its
//! (identical) node mean. The concatenated block outputs pass two fully connected layers of 64
//! (ReLU) and a single output unit; σ(output) = P(lane change at the next step).
//! The unconditioned variant has no block B.
//!
//! All parameters live in one flat vector (so the optimiser sees one slice); [`Architecture`]
//! knows where each layer's weights (column-major, out × in) and biases are. This module holds
//! that shape; the allocation-free single-sample pass for prediction is in [`super::infer`],
//! and the batched forward and backward passes used for training are in `crate::train::gcn`.

use nalgebra::{DMatrixView, DMatrixViewMut, RealField, Scalar};
use rand::Rng;
use serde::{Deserialize, Serialize};

use super::features::{FEATURES_A, FEATURES_B};

/// Width of every hidden layer (the paper's 64).
pub const HIDDEN: usize = 64;

/// A dense layer's place in the parameter vector: weights (rows × cols, column-major), then
/// biases (rows).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Dense {
    /// Output width (rows of the weight matrix, number of biases).
    pub rows: usize,
    /// Input width (columns of the weight matrix).
    pub cols: usize,
    /// Index of the layer's first weight in the parameter vector.
    pub offset: usize,
}

impl Dense {
    /// A `rows × cols` layer placed at `*offset`, which it advances past its weights and biases
    /// (so consecutive calls lay the layers out one after another).
    pub fn new(rows: usize, cols: usize, offset: &mut usize) -> Dense {
        let d = Dense {
            rows,
            cols,
            offset: *offset,
        };
        *offset += rows * (cols + 1);
        d
    }

    /// Range of the weights in the parameter vector.
    pub fn weights(&self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.rows * self.cols
    }

    /// Range of the biases in the parameter vector.
    pub fn biases(&self) -> std::ops::Range<usize> {
        let w = self.offset + self.rows * self.cols;
        w..w + self.rows
    }

    /// The weights as a matrix view.
    pub fn w<'a, T: Scalar>(&self, p: &'a [T]) -> DMatrixView<'a, T> {
        DMatrixView::from_slice(&p[self.weights()], self.rows, self.cols)
    }

    /// The weights as a mutable matrix view.
    pub fn w_mut<'a, T: Scalar>(&self, p: &'a mut [T]) -> DMatrixViewMut<'a, T> {
        DMatrixViewMut::from_slice(&mut p[self.weights()], self.rows, self.cols)
    }
}

/// The layers of b_θ and where their parameters are.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Architecture {
    /// With block B (sequence (b) of higher-priority CAV states).
    pub conditioned: bool,
    /// Block A's node embedding (graph (a)'s node features → [`HIDDEN`], ReLU).
    pub a_embed: Dense,
    /// Block A's graph convolution ([`HIDDEN`] → [`HIDDEN`], ReLU).
    pub a_conv: Dense,
    /// Block B's node embedding (conditioned only), shared over the preview steps.
    pub b_embed: Option<Dense>,
    /// Block B's graph convolution (conditioned only), shared over the preview steps.
    pub b_conv: Option<Dense>,
    /// First fully connected layer: the concatenated block outputs → [`HIDDEN`], ReLU.
    pub fc1: Dense,
    /// Second fully connected layer ([`HIDDEN`] → [`HIDDEN`], ReLU).
    pub fc2: Dense,
    /// The output unit: the raw lane-change logit.
    pub out: Dense,
    /// Length of the flat parameter vector.
    pub n_params: usize,
}

impl Architecture {
    /// The layout of the conditioned (with block B) or unconditioned network.
    pub fn new(conditioned: bool) -> Architecture {
        let mut o = 0;
        let a_embed = Dense::new(HIDDEN, FEATURES_A, &mut o);
        let a_conv = Dense::new(HIDDEN, HIDDEN, &mut o);
        let (b_embed, b_conv) = if conditioned {
            (
                Some(Dense::new(HIDDEN, FEATURES_B, &mut o)),
                Some(Dense::new(HIDDEN, HIDDEN, &mut o)),
            )
        } else {
            (None, None)
        };
        let concat = if conditioned { 2 * HIDDEN } else { HIDDEN };
        let fc1 = Dense::new(HIDDEN, concat, &mut o);
        let fc2 = Dense::new(HIDDEN, HIDDEN, &mut o);
        let out = Dense::new(1, HIDDEN, &mut o);
        Architecture {
            conditioned,
            a_embed,
            a_conv,
            b_embed,
            b_conv,
            fc1,
            fc2,
            out,
            n_params: o,
        }
    }

    /// Every layer, in parameter order.
    pub fn layers(&self) -> Vec<Dense> {
        let mut v = vec![self.a_embed, self.a_conv];
        v.extend(self.b_embed);
        v.extend(self.b_conv);
        v.extend([self.fc1, self.fc2, self.out]);
        v
    }

    /// He-uniform weights for the ReLU layers, Glorot for the output, zero biases except the
    /// output's, which starts at the log-odds of a 2 % lane-change rate.
    pub fn init<T: RealField + Copy>(&self, rng: &mut impl Rng) -> Vec<T> {
        let mut p = vec![T::zero(); self.n_params];
        for d in self.layers() {
            let limit = if d == self.out {
                (6.0 / (d.rows + d.cols) as f64).sqrt()
            } else {
                (6.0 / d.cols as f64).sqrt()
            };
            for w in &mut p[d.weights()] {
                *w = nalgebra::convert(rng.gen_range(-limit..limit));
            }
        }
        p[self.out.biases().start] = nalgebra::convert((0.02f64 / 0.98).ln());
        p
    }
}

/// The logistic function.
pub fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}
