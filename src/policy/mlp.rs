//! A multilayer perceptron over one flat parameter vector: the policy's and the value
//! function's network (two hidden tanh layers of 256 in the paper's RL-PPO). Batched: every
//! column of an input matrix is one sample, so one call serves all CAVs of a step, or a
//! minibatch in training.
//!
//! The layers reuse the predictor's [`Dense`] layout (weights column-major, out × in, then the
//! biases), so the optimiser sees one slice, as for b_θ.

use nalgebra::DMatrix;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::predict::gcn::Dense;

/// The shape of a tanh MLP: input width, hidden widths, output width.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Mlp {
    /// The layers, input side first; each knows where its weights and biases sit in the flat
    /// parameter vector.
    pub layers: Vec<Dense>,
    /// Length of the flat parameter vector all layers share.
    pub n_params: usize,
}

/// The activations of one forward pass, kept for the backward pass.
#[derive(Debug, Clone, Default)]
pub struct Activations {
    /// The input, then each layer's output (after tanh for the hidden ones).
    pub outputs: Vec<DMatrix<f32>>,
}

impl Activations {
    /// The network's output (linear).
    pub fn result(&self) -> &DMatrix<f32> {
        self.outputs.last().expect("a forward pass ran")
    }
}

impl Mlp {
    /// An MLP `inputs → hidden… → outputs`.
    pub fn new(inputs: usize, hidden: &[usize], outputs: usize) -> Mlp {
        let mut offset = 0;
        let mut layers = Vec::new();
        let mut width = inputs;
        for &h in hidden.iter().chain(std::iter::once(&outputs)) {
            layers.push(Dense::new(h, width, &mut offset));
            width = h;
        }
        Mlp {
            layers,
            n_params: offset,
        }
    }

    /// Input width: the length of one sample (one column of an input matrix).
    pub fn inputs(&self) -> usize {
        self.layers[0].cols
    }

    /// Glorot-uniform weights, zero biases; the output layer's weights scaled by `out_gain`
    /// (a small gain starts a policy near uniform, as PPO implementations do).
    pub fn init(&self, rng: &mut impl Rng, out_gain: f32) -> Vec<f32> {
        let mut p = vec![0.0f32; self.n_params];
        let last = self.layers.len() - 1;
        for (k, d) in self.layers.iter().enumerate() {
            let gain = if k == last { out_gain } else { 1.0 };
            let limit = gain * (6.0 / (d.rows + d.cols) as f32).sqrt();
            for w in &mut p[d.weights()] {
                *w = rng.gen_range(-limit..=limit);
            }
        }
        p
    }

    /// Runs the batch `x` (inputs × n) through the network, keeping every layer's output.
    pub fn forward(&self, p: &[f32], x: &DMatrix<f32>, act: &mut Activations) {
        act.outputs
            .resize(self.layers.len() + 1, DMatrix::zeros(0, 0));
        act.outputs[0].clone_from(x);
        let last = self.layers.len() - 1;
        for (k, d) in self.layers.iter().enumerate() {
            let (done, rest) = act.outputs.split_at_mut(k + 1);
            let y = &mut rest[0];
            if y.shape() != (d.rows, x.ncols()) {
                *y = DMatrix::zeros(d.rows, x.ncols());
            }
            y.gemm(1.0, &d.w(p), &done[k], 0.0);
            let b = &p[d.biases()];
            for mut col in y.column_iter_mut() {
                for (v, &bi) in col.iter_mut().zip(b) {
                    *v += bi;
                    if k != last {
                        *v = v.tanh();
                    }
                }
            }
        }
    }

    /// Adds to `grad` the gradient of the loss whose derivative with respect to the network's
    /// output is `d_out` (outputs × n), for the pass recorded in `act`.
    pub fn backward(&self, p: &[f32], act: &Activations, d_out: &DMatrix<f32>, grad: &mut [f32]) {
        let mut delta = d_out.clone();
        for (k, d) in self.layers.iter().enumerate().rev() {
            let input = &act.outputs[k];
            let mut gw = d.w_mut(grad);
            gw.gemm(1.0, &delta, &input.transpose(), 1.0);
            for (g, row) in grad[d.biases()].iter_mut().zip(delta.row_iter()) {
                *g += row.sum();
            }
            if k == 0 {
                break;
            }
            let mut below = d.w(p).transpose() * &delta;
            for (b, &h) in below.iter_mut().zip(input.iter()) {
                *b *= 1.0 - h * h;
            }
            delta = below;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Loss = Σ output · c for fixed c: its gradient by backward equals central differences.
    #[test]
    fn backward_matches_finite_differences() {
        let mlp = Mlp::new(3, &[5, 4], 2);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let p = mlp.init(&mut rng, 1.0);
        let x = DMatrix::from_fn(3, 4, |i, j| (i as f32 - j as f32) * 0.3);
        let c = DMatrix::from_fn(2, 4, |i, j| 0.5 + i as f32 - 0.2 * j as f32);
        let loss = |p: &[f32]| {
            let mut a = Activations::default();
            mlp.forward(p, &x, &mut a);
            a.result().component_mul(&c).sum() as f64
        };
        let mut act = Activations::default();
        mlp.forward(&p, &x, &mut act);
        let mut grad = vec![0.0; mlp.n_params];
        mlp.backward(&p, &act, &c, &mut grad);
        for i in (0..mlp.n_params).step_by(3) {
            let (mut up, mut down) = (p.clone(), p.clone());
            up[i] += 1e-2;
            down[i] -= 1e-2;
            let numeric = (loss(&up) - loss(&down)) / 2e-2;
            assert!(
                (numeric - grad[i] as f64).abs() < 2e-3 * (1.0 + numeric.abs()),
                "param {i}: numeric {numeric}, backward {}",
                grad[i]
            );
        }
    }

    #[test]
    fn shapes_and_parameter_count() {
        let mlp = Mlp::new(74, &[256, 256], 6);
        assert_eq!(mlp.n_params, 74 * 256 + 256 + 256 * 256 + 256 + 256 * 6 + 6);
        assert_eq!((mlp.inputs(), mlp.layers[2].rows), (74, 6));
    }
}
