//! Training of b_θ's network (paper IV.D): batched forward and backward passes, generic over
//! the float type (f32 for training, f64 for the gradient check), and the network as a
//! [`Learner`]. The network's shape is [`crate::predict::gcn::Architecture`]; the allocation-free
//! single-sample pass used for prediction is [`crate::predict::infer`].

use nalgebra::{DMatrix, Dyn, RawStorage, RealField, Scalar};
use rand_chacha::ChaCha8Rng;

use super::dataset::Sample;
use super::training_loop::{bce_with_logit, Learner};
use crate::predict::features::{
    encode_a, encode_b, Observation, CAV_NODES, COLUMNS_B, FEATURES_A, FEATURES_B, NODES_A, PREVIEW,
};
use crate::predict::gcn::{sigmoid, Architecture, Dense, HIDDEN};

/// The float types the network runs in (f32 for training and prediction, f64 for checks).
pub trait Real: RealField + Copy + From<f32> {}
impl<T: RealField + Copy + From<f32>> Real for T {}

/// Encoded inputs of a batch of samples: graph (a) columns (`NODES_A` per sample) and, if
/// conditioned, sequence (b) columns (`COLUMNS_B` per sample).
#[derive(Debug, Clone)]
pub struct Inputs<T: Scalar> {
    /// Number of samples in the batch.
    pub n: usize,
    /// Graph (a) node features: `FEATURES_A` rows, `NODES_A` columns per sample.
    pub xa: DMatrix<T>,
    /// Sequence (b) node features: `FEATURES_B` rows, `COLUMNS_B` columns per sample (none if
    /// unconditioned).
    pub xb: DMatrix<T>,
}

impl<T: Real> Default for Inputs<T> {
    fn default() -> Self {
        Inputs {
            n: 0,
            xa: DMatrix::zeros(FEATURES_A, 0),
            xb: DMatrix::zeros(FEATURES_B, 0),
        }
    }
}

impl<T: Real> Inputs<T> {
    /// Encodes `obs` (reallocating only when the batch size changes).
    pub fn encode<'a>(
        &mut self,
        obs: impl ExactSizeIterator<Item = &'a Observation>,
        conditioned: bool,
    ) {
        let n = obs.len();
        resize(&mut self.xa, FEATURES_A, n * NODES_A);
        resize(
            &mut self.xb,
            FEATURES_B,
            if conditioned { n * COLUMNS_B } else { 0 },
        );
        self.n = n;
        let (sa, sb) = (FEATURES_A * NODES_A, FEATURES_B * COLUMNS_B);
        for (s, o) in obs.enumerate() {
            encode_a(o, &mut self.xa.as_mut_slice()[s * sa..(s + 1) * sa]);
            if conditioned {
                encode_b(o, &mut self.xb.as_mut_slice()[s * sb..(s + 1) * sb]);
            }
        }
    }
}

fn resize<T: Real>(m: &mut DMatrix<T>, rows: usize, cols: usize) {
    if m.shape() != (rows, cols) {
        *m = DMatrix::zeros(rows, cols);
    }
}

/// Activations of a batch, kept for the backward pass (all post-ReLU).
#[derive(Debug, Clone)]
pub struct Cache<T: Scalar> {
    ha: DMatrix<T>,
    ma: DMatrix<T>,
    ga: DMatrix<T>,
    hb: DMatrix<T>,
    mb: DMatrix<T>,
    gb: DMatrix<T>,
    /// Block B's output: the time mean of `gb`.
    hbm: DMatrix<T>,
    /// Block outputs, stacked: rows 0..64 block A, 64..128 block B.
    z: DMatrix<T>,
    a1: DMatrix<T>,
    a2: DMatrix<T>,
    /// Output logits (1 × n).
    pub logits: DMatrix<T>,
    // Backward scratch.
    dlog: DMatrix<T>,
    da2: DMatrix<T>,
    da1: DMatrix<T>,
    dz: DMatrix<T>,
    dga: DMatrix<T>,
    dma: DMatrix<T>,
    dha: DMatrix<T>,
    dgb: DMatrix<T>,
    dmb: DMatrix<T>,
    dhb: DMatrix<T>,
    /// Transposed copies for the gradient products.
    tmp: DMatrix<T>,
}

impl<T: Real> Default for Cache<T> {
    fn default() -> Self {
        let z = || DMatrix::zeros(0, 0);
        Cache {
            ha: z(),
            ma: z(),
            ga: z(),
            hb: z(),
            mb: z(),
            gb: z(),
            hbm: z(),
            z: z(),
            a1: z(),
            a2: z(),
            logits: z(),
            dlog: z(),
            da2: z(),
            da1: z(),
            dz: z(),
            dga: z(),
            dma: z(),
            dha: z(),
            dgb: z(),
            dmb: z(),
            dhb: z(),
            tmp: z(),
        }
    }
}

/// `y = W x + b` for every column of `x`, then ReLU if asked.
fn affine<T: Real>(d: &Dense, p: &[T], x: &DMatrix<T>, y: &mut DMatrix<T>, relu: bool) {
    resize(y, d.rows, x.ncols());
    y.gemm(T::one(), &d.w(p), x, T::zero());
    let b = &p[d.biases()];
    for mut col in y.column_iter_mut() {
        for (v, &bi) in col.iter_mut().zip(b) {
            *v += bi;
            if relu && *v < T::zero() {
                *v = T::zero();
            }
        }
    }
}

/// `dst[:, j]` = mean of `src` columns `j·g .. (j+1)·g`.
fn mean_groups<T: Real>(src: &DMatrix<T>, g: usize, dst: &mut DMatrix<T>) {
    let m = src.ncols() / g;
    resize(dst, src.nrows(), m);
    let inv = T::one() / T::from(g as f32);
    for j in 0..m {
        let mut out = dst.column_mut(j);
        out.fill(T::zero());
        for k in 0..g {
            out += src.column(j * g + k);
        }
        out *= inv;
    }
}

/// The gradient flowing into a group mean, masked by the ReLU of the grouped activations:
/// `dst[:, j·g + k] = src[:, j] / g` where `act[:, j·g + k] > 0`, else 0.
fn spread_masked<T: Real, S>(
    src: &nalgebra::Matrix<T, Dyn, Dyn, S>,
    g: usize,
    act: &DMatrix<T>,
    dst: &mut DMatrix<T>,
) where
    S: RawStorage<T, Dyn, Dyn>,
{
    resize(dst, act.nrows(), act.ncols());
    let inv = T::one() / T::from(g as f32);
    for c in 0..act.ncols() {
        let s = src.column(c / g);
        let a = act.column(c);
        let mut d = dst.column_mut(c);
        for r in 0..act.nrows() {
            d[r] = if a[r] > T::zero() {
                s[r] * inv
            } else {
                T::zero()
            };
        }
    }
}

/// Zeroes the gradient where the ReLU output was zero.
fn mask<T: Real>(d: &mut DMatrix<T>, act: &DMatrix<T>) {
    for (g, &a) in d.iter_mut().zip(act.iter()) {
        if a <= T::zero() {
            *g = T::zero();
        }
    }
}

/// Accumulates a dense layer's gradient: `dW += dy xᵀ`, `db += Σ_columns dy`. (Transposes
/// are copied into `scratch`: nalgebra's small-matrix fallback mishandles strided views.)
fn accumulate<T: Real>(
    d: &Dense,
    grad: &mut [T],
    dy: &DMatrix<T>,
    x: &DMatrix<T>,
    scratch: &mut DMatrix<T>,
) {
    resize(scratch, x.ncols(), x.nrows());
    x.transpose_to(scratch);
    d.w_mut(grad).gemm(T::one(), dy, &*scratch, T::one());
    let gb = &mut grad[d.biases()];
    for col in dy.column_iter() {
        for (g, &v) in gb.iter_mut().zip(col.iter()) {
            *g += v;
        }
    }
}

/// `out = Wᵀ dy`: the gradient flowing back through a dense layer (before its input's ReLU).
fn back<T: Real>(
    d: &Dense,
    p: &[T],
    dy: &DMatrix<T>,
    out: &mut DMatrix<T>,
    scratch: &mut DMatrix<T>,
) {
    resize(scratch, d.cols, d.rows);
    d.w(p).transpose_to(scratch);
    resize(out, d.cols, dy.ncols());
    out.gemm(T::one(), &*scratch, dy, T::zero());
}

/// Forward pass of a batch; the logits end up in `cache.logits` (1 × n).
pub fn forward<T: Real>(arch: &Architecture, p: &[T], x: &Inputs<T>, c: &mut Cache<T>) {
    let n = x.n;
    affine(&arch.a_embed, p, &x.xa, &mut c.ha, true);
    mean_groups(&c.ha, NODES_A, &mut c.ma);
    affine(&arch.a_conv, p, &c.ma, &mut c.ga, true);
    resize(&mut c.z, arch.fc1.cols, n);
    c.z.rows_mut(0, HIDDEN).copy_from(&c.ga);
    if let (Some(be), Some(bc)) = (&arch.b_embed, &arch.b_conv) {
        affine(be, p, &x.xb, &mut c.hb, true);
        mean_groups(&c.hb, CAV_NODES, &mut c.mb);
        affine(bc, p, &c.mb, &mut c.gb, true);
        mean_groups(&c.gb, PREVIEW, &mut c.hbm);
        c.z.rows_mut(HIDDEN, HIDDEN).copy_from(&c.hbm);
    }
    affine(&arch.fc1, p, &c.z, &mut c.a1, true);
    affine(&arch.fc2, p, &c.a1, &mut c.a2, true);
    affine(&arch.out, p, &c.a2, &mut c.logits, false);
}

/// Backward pass after [`forward`]: adds `Σ_s dlogit_s ∂logit_s/∂θ` to `grad`, where
/// `dlogits` holds ∂loss/∂logit per sample.
pub fn backward<T: Real>(
    arch: &Architecture,
    p: &[T],
    x: &Inputs<T>,
    c: &mut Cache<T>,
    dlogits: &[T],
    grad: &mut [T],
) {
    let n = x.n;
    resize(&mut c.dlog, 1, n);
    c.dlog.as_mut_slice().copy_from_slice(dlogits);
    accumulate(&arch.out, grad, &c.dlog, &c.a2, &mut c.tmp);
    back(&arch.out, p, &c.dlog, &mut c.da2, &mut c.tmp);
    mask(&mut c.da2, &c.a2);
    accumulate(&arch.fc2, grad, &c.da2, &c.a1, &mut c.tmp);
    back(&arch.fc2, p, &c.da2, &mut c.da1, &mut c.tmp);
    mask(&mut c.da1, &c.a1);
    accumulate(&arch.fc1, grad, &c.da1, &c.z, &mut c.tmp);
    back(&arch.fc1, p, &c.da1, &mut c.dz, &mut c.tmp);
    // Block A.
    resize(&mut c.dga, HIDDEN, n);
    c.dga.copy_from(&c.dz.rows(0, HIDDEN));
    mask(&mut c.dga, &c.ga);
    accumulate(&arch.a_conv, grad, &c.dga, &c.ma, &mut c.tmp);
    back(&arch.a_conv, p, &c.dga, &mut c.dma, &mut c.tmp);
    spread_masked(&c.dma, NODES_A, &c.ha, &mut c.dha);
    accumulate(&arch.a_embed, grad, &c.dha, &x.xa, &mut c.tmp);
    // Block B: its output is the time mean of the per-step graph convolutions.
    if let (Some(be), Some(bc)) = (&arch.b_embed, &arch.b_conv) {
        spread_masked(&c.dz.rows(HIDDEN, HIDDEN), PREVIEW, &c.gb, &mut c.dgb);
        accumulate(bc, grad, &c.dgb, &c.mb, &mut c.tmp);
        back(bc, p, &c.dgb, &mut c.dmb, &mut c.tmp);
        spread_masked(&c.dmb, CAV_NODES, &c.hb, &mut c.dhb);
        accumulate(be, grad, &c.dhb, &x.xb, &mut c.tmp);
    }
}

/// The network as a [`Learner`] (training runs in f32).
#[derive(Debug, Clone)]
pub struct GcnLearner {
    /// The network's shape (conditioned or not) and parameter layout.
    pub arch: Architecture,
}

/// Per-worker buffers of [`GcnLearner`].
#[derive(Debug, Default)]
pub struct GcnScratch {
    inputs: Inputs<f32>,
    cache: Cache<f32>,
    dlogits: Vec<f32>,
}

impl Learner for GcnLearner {
    type Scratch = GcnScratch;

    fn n_params(&self) -> usize {
        self.arch.n_params
    }

    fn init(&self, rng: &mut ChaCha8Rng) -> Vec<f32> {
        self.arch.init(rng)
    }

    fn scratch(&self) -> GcnScratch {
        GcnScratch::default()
    }

    fn loss_grad(
        &self,
        params: &[f32],
        batch: &[&Sample],
        scale: f32,
        grad: &mut [f32],
        s: &mut GcnScratch,
    ) -> f64 {
        s.inputs
            .encode(batch.iter().map(|b| &b.obs), self.arch.conditioned);
        forward(&self.arch, params, &s.inputs, &mut s.cache);
        s.dlogits.clear();
        let mut loss = 0.0;
        for (b, &z) in batch.iter().zip(s.cache.logits.iter()) {
            loss += bce_with_logit(z as f64, b.label);
            let y = b.label as u8 as f32;
            s.dlogits.push(scale * (sigmoid(z as f64) as f32 - y));
        }
        backward(
            &self.arch,
            params,
            &s.inputs,
            &mut s.cache,
            &s.dlogits,
            grad,
        );
        loss
    }

    fn logits(&self, params: &[f32], batch: &[&Sample], out: &mut Vec<f32>, s: &mut GcnScratch) {
        s.inputs
            .encode(batch.iter().map(|b| &b.obs), self.arch.conditioned);
        forward(&self.arch, params, &s.inputs, &mut s.cache);
        out.extend(s.cache.logits.iter());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalised_adjacency_of_a_fully_connected_graph_is_the_mean() {
        // D^-1/2 (A + I) D^-1/2 with A the complete graph: every degree (with self-loop) is n.
        for n in [1usize, 4, 7] {
            let a_plus_i = DMatrix::<f64>::from_element(n, n, 1.0);
            let deg: Vec<f64> = (0..n).map(|i| a_plus_i.row(i).sum()).collect();
            let norm = DMatrix::from_fn(n, n, |i, j| a_plus_i[(i, j)] / (deg[i] * deg[j]).sqrt());
            let h = DMatrix::from_fn(n, 3, |i, j| (i * 3 + j) as f64 * 0.7 - 1.0);
            let prop = &norm * &h;
            let mut mean_rows = DMatrix::zeros(0, 0);
            // mean_groups works on columns: nodes are columns there.
            mean_groups(&h.transpose(), n, &mut mean_rows);
            for i in 0..n {
                for j in 0..3 {
                    assert!((prop[(i, j)] - mean_rows[(j, 0)]).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn parameter_counts() {
        let u = Architecture::new(false);
        let c = Architecture::new(true);
        assert_eq!(u.n_params, 64 * 21 + 64 * 65 + 64 * 65 + 64 * 65 + 65);
        assert_eq!(
            c.n_params - u.n_params,
            64 * 7 + 64 * 65 + 64 * 64 // block B, and fc1's extra 64 inputs
        );
    }
}
