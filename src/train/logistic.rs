//! Training of the logistic-regression baseline ([`Logistic`]) by the same loop as b_θ.

use rand_chacha::ChaCha8Rng;

use super::dataset::Sample;
use super::training_loop::{bce_with_logit, Learner};
use crate::predict::gcn::sigmoid;
use crate::predict::logistic::Logistic;

impl Learner for Logistic {
    type Scratch = Vec<f32>;

    fn n_params(&self) -> usize {
        Logistic::n_params(self)
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
