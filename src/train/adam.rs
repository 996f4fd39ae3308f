//! The Adam optimiser (Kingma & Ba), over one flat parameter vector.

/// Adam's moment estimates and settings.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Adam {
    /// Step size (learning rate).
    pub lr: f32,
    /// Decay rate of the first-moment (mean) estimate, β₁.
    pub beta1: f32,
    /// Decay rate of the second-moment (uncentred variance) estimate, β₂.
    pub beta2: f32,
    /// Added to the denominator's square root so near-zero variances do not blow the step up, ε.
    pub eps: f32,
    m: Vec<f32>,
    v: Vec<f32>,
    t: i32,
}

impl Adam {
    /// With the usual β₁ = 0.9, β₂ = 0.999, ε = 1e-8.
    pub fn new(n_params: usize, lr: f32) -> Adam {
        Adam {
            lr,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
            m: vec![0.0; n_params],
            v: vec![0.0; n_params],
            t: 0,
        }
    }

    /// One update of `params` against the gradient `grad` of the loss.
    pub fn step(&mut self, params: &mut [f32], grad: &[f32]) {
        self.t += 1;
        let c1 = 1.0 - self.beta1.powi(self.t);
        let c2 = 1.0 - self.beta2.powi(self.t);
        let step = self.lr * c2.sqrt() / c1;
        for (((p, &g), m), v) in params
            .iter_mut()
            .zip(grad)
            .zip(&mut self.m)
            .zip(&mut self.v)
        {
            *m = self.beta1 * *m + (1.0 - self.beta1) * g;
            *v = self.beta2 * *v + (1.0 - self.beta2) * g * g;
            *p -= step * *m / (v.sqrt() + self.eps * c2.sqrt());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimises_a_quadratic() {
        // f(x) = Σ (x_i − i)², gradient 2 (x_i − i).
        let mut x = vec![5.0f32; 4];
        let mut adam = Adam::new(4, 0.05);
        for _ in 0..2000 {
            let g: Vec<f32> = x
                .iter()
                .enumerate()
                .map(|(i, &v)| 2.0 * (v - i as f32))
                .collect();
            adam.step(&mut x, &g);
        }
        for (i, v) in x.iter().enumerate() {
            assert!((v - i as f32).abs() < 1e-2, "{x:?}");
        }
    }
}
