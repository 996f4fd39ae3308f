//! b_θ for prediction: one sample at a time, f32, no allocation after the workspace is made.
//!
//! The weights are nalgebra matrices copied from the trained parameter vector; the matrix-vector
//! products run over their column-major storage (vectorised over the 64 outputs, with an AVX2
//! build of the same loop picked at run time where the CPU has it — the per-element arithmetic
//! and its order are the same, so results are bitwise identical either way). Two exact
//! shortcuts save work: an absent node's embedding does not depend on the sample (it is
//! precomputed), nor does a preview step without any CAV.

use nalgebra::{DMatrix, DVector};

use super::features::{CAV_NODES, COLUMNS_B, FEATURES_A, FEATURES_B, NODES_A, PREVIEW};
use super::gcn::{Architecture, Dense, HIDDEN};

/// A dense layer's weights (out × in) and biases.
#[derive(Debug, Clone)]
struct Layer {
    w: DMatrix<f32>,
    b: DVector<f32>,
}

impl Layer {
    fn of(d: &Dense, p: &[f32]) -> Layer {
        Layer {
            w: DMatrix::from_column_slice(d.rows, d.cols, &p[d.weights()]),
            b: DVector::from_column_slice(&p[d.biases()]),
        }
    }

    /// `y0 = ReLU(W x0 + b)` and `y1 = ReLU(W x1 + b)` for a square `HIDDEN` layer.
    #[inline(always)]
    fn apply2(&self, x0: &[f32], x1: &[f32], y0: &mut [f32], y1: &mut [f32]) {
        y0.copy_from_slice(self.b.as_slice());
        y1.copy_from_slice(self.b.as_slice());
        gemv2_acc(self.w.as_slice(), x0, x1, y0, y1);
        relu_in_place(y0);
        relu_in_place(y1);
    }

    /// `y = W x + b`, then ReLU if asked.
    #[inline(always)]
    fn apply(&self, x: &[f32], y: &mut [f32], relu: bool) {
        y.copy_from_slice(self.b.as_slice());
        gemv_acc(self.w.as_slice(), self.w.nrows(), x, y);
        if relu {
            relu_in_place(y);
        }
    }
}

/// The network's weights for prediction.
#[derive(Debug, Clone)]
pub struct Network {
    /// With block B: the prediction reads sequence (b), the CAVs' planned states.
    pub conditioned: bool,
    a_embed: Layer,
    a_conv: Layer,
    b_embed: Option<Layer>,
    b_conv: Option<Layer>,
    fc1: Layer,
    fc2: Layer,
    out: Layer,
    /// Embedding of an absent neighbour node, per slot (its only feature is the slot flag).
    absent_a: DMatrix<f32>,
    /// Embedding of an absent CAV node (all features zero).
    absent_b: DVector<f32>,
    /// Block B's convolution output for a preview step without any CAV.
    empty_step: DVector<f32>,
}

/// Buffers of one prediction; the encoded inputs go into `xa` and `xb`.
#[derive(Debug, Clone)]
pub struct Workspace {
    /// Graph (a) node features, `FEATURES_A × NODES_A`, column-major.
    pub xa: DMatrix<f32>,
    /// Sequence (b) node features, `FEATURES_B × COLUMNS_B`, column-major, step-major.
    pub xb: DMatrix<f32>,
    h: DVector<f32>,
    m: DVector<f32>,
    /// Node means of the preview steps with CAVs (HIDDEN × PREVIEW).
    means: DMatrix<f32>,
    /// Graph-convolution outputs of two steps.
    g: DVector<f32>,
    z: DVector<f32>,
    a1: DVector<f32>,
    a2: DVector<f32>,
}

impl Default for Workspace {
    fn default() -> Self {
        Workspace {
            xa: DMatrix::zeros(FEATURES_A, NODES_A),
            xb: DMatrix::zeros(FEATURES_B, COLUMNS_B),
            h: DVector::zeros(HIDDEN),
            m: DVector::zeros(HIDDEN),
            means: DMatrix::zeros(HIDDEN, PREVIEW),
            g: DVector::zeros(2 * HIDDEN),
            z: DVector::zeros(2 * HIDDEN),
            a1: DVector::zeros(HIDDEN),
            a2: DVector::zeros(HIDDEN),
        }
    }
}

impl Network {
    /// From a trained parameter vector laid out by `arch`.
    pub fn new(arch: &Architecture, params: &[f32]) -> Network {
        let a_embed = Layer::of(&arch.a_embed, params);
        let b_embed = arch.b_embed.as_ref().map(|d| Layer::of(d, params));
        let b_conv = arch.b_conv.as_ref().map(|d| Layer::of(d, params));
        let mut absent_a = DMatrix::zeros(HIDDEN, NODES_A);
        for k in 1..NODES_A {
            let mut col = a_embed.b.clone();
            col += a_embed.w.column(6 + k);
            relu_in_place(col.as_mut_slice());
            absent_a.set_column(k, &col);
        }
        let (mut absent_b, mut empty_step) = (DVector::zeros(HIDDEN), DVector::zeros(HIDDEN));
        if let (Some(be), Some(bc)) = (&b_embed, &b_conv) {
            absent_b = be.b.clone();
            relu_in_place(absent_b.as_mut_slice());
            bc.apply(absent_b.as_slice(), empty_step.as_mut_slice(), true);
        }
        Network {
            conditioned: arch.conditioned,
            a_embed,
            a_conv: Layer::of(&arch.a_conv, params),
            b_embed,
            b_conv,
            fc1: Layer::of(&arch.fc1, params),
            fc2: Layer::of(&arch.fc2, params),
            out: Layer::of(&arch.out, params),
            absent_a,
            absent_b,
            empty_step,
        }
    }

    /// The raw logit of the inputs encoded in `ws.xa` (and, conditioned, `ws.xb`).
    pub fn logit(&self, ws: &mut Workspace) -> f32 {
        self.block_a(ws);
        if let (Some(be), Some(bc)) = (&self.b_embed, &self.b_conv) {
            let (_, zb) = ws.z.as_mut_slice().split_at_mut(HIDDEN);
            zb.fill(0.0);
            let busy = step_means(
                self,
                be,
                ws.xb.as_slice(),
                ws.means.as_mut_slice(),
                ws.h.as_mut_slice(),
                zb,
            );
            convolve_means(
                bc,
                &ws.means.as_slice()[..busy * HIDDEN],
                ws.g.as_mut_slice(),
                zb,
            );
            scale(zb, 1.0 / PREVIEW as f32);
        }
        let zlen = if self.conditioned { 2 * HIDDEN } else { HIDDEN };
        let a1 = ws.a1.as_mut_slice();
        let a2 = ws.a2.as_mut_slice();
        self.fc1.apply(&ws.z.as_slice()[..zlen], a1, true);
        self.fc2.apply(a1, a2, true);
        let mut o = [0.0f32];
        self.out.apply(a2, &mut o, false);
        o[0]
    }

    /// Block A into the first half of `ws.z`: node embeddings, their mean (the normalised
    /// fully connected propagation), the graph convolution.
    #[inline]
    fn block_a(&self, ws: &mut Workspace) {
        let h = ws.h.as_mut_slice();
        let m = ws.m.as_mut_slice();
        m.fill(0.0);
        for (k, x) in ws.xa.as_slice().chunks_exact(FEATURES_A).enumerate() {
            if k > 0 && x[0] == 0.0 {
                add(m, &self.absent_a.as_slice()[k * HIDDEN..(k + 1) * HIDDEN]);
            } else {
                self.a_embed.apply(x, h, true);
                add(m, h);
            }
        }
        scale(m, 1.0 / NODES_A as f32);
        self.a_conv
            .apply(m, &mut ws.z.as_mut_slice()[..HIDDEN], true);
    }
}

/// Block B, first half: the node mean of each preview step with CAVs into `means` (in order;
/// returns how many), while a step without CAVs adds its precomputed output to `zb` at once.
/// The means are gathered first so that the graph convolution can run on two steps at a time.
#[inline]
fn step_means(
    net: &Network,
    be: &Layer,
    xb: &[f32],
    means: &mut [f32],
    h: &mut [f32],
    zb: &mut [f32],
) -> usize {
    let mut busy = 0;
    for step in xb.chunks_exact(FEATURES_B * CAV_NODES) {
        if step.chunks_exact(FEATURES_B).all(|x| x[0] == 0.0) {
            add(zb, net.empty_step.as_slice());
            continue;
        }
        let m = &mut means[busy * HIDDEN..(busy + 1) * HIDDEN];
        m.fill(0.0);
        for x in step.chunks_exact(FEATURES_B) {
            if x[0] == 0.0 {
                add(m, net.absent_b.as_slice());
            } else {
                be.apply(x, h, true);
                add(m, h);
            }
        }
        scale(m, 1.0 / CAV_NODES as f32);
        busy += 1;
    }
    busy
}

/// Block B, second half: the graph convolution of each step mean, added into `zb`, two steps
/// at a time (each weight column loaded once for both); `g` holds two outputs.
#[inline]
fn convolve_means(bc: &Layer, means: &[f32], g: &mut [f32], zb: &mut [f32]) {
    let mut pairs = means.chunks_exact(2 * HIDDEN);
    for pair in &mut pairs {
        let (m0, m1) = pair.split_at(HIDDEN);
        let (g0, g1) = g.split_at_mut(HIDDEN);
        bc.apply2(m0, m1, g0, g1);
        add(zb, g0);
        add(zb, g1);
    }
    let rest = pairs.remainder();
    if !rest.is_empty() {
        bc.apply(rest, &mut g[..HIDDEN], true);
        add(zb, &g[..HIDDEN]);
    }
}

#[inline(always)]
fn scale(y: &mut [f32], f: f32) {
    for v in y {
        *v *= f;
    }
}

#[inline(always)]
fn add(y: &mut [f32], x: &[f32]) {
    for (a, b) in y.iter_mut().zip(x) {
        *a += b;
    }
}

#[inline(always)]
fn relu_in_place(y: &mut [f32]) {
    for v in y {
        *v = v.max(0.0);
    }
}

/// `y += W x` with `W` column-major (`rows` × `x.len()`). Products are fused multiply-adds
/// (`f32::mul_add`), so every build computes the same bits: the AVX-512 and AVX2 builds use
/// the CPU's FMA instructions, the portable one the exact software fused multiply-add.
fn gemv_acc(w: &[f32], rows: usize, x: &[f32], y: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX-512F and FMA (checked just above).
            unsafe { gemv_acc_avx512(w, rows, x, y) };
            return;
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            unsafe { gemv_acc_avx2(w, rows, x, y) };
            return;
        }
    }
    gemv_acc_portable(w, rows, x, y);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
unsafe fn gemv_acc_avx512(w: &[f32], rows: usize, x: &[f32], y: &mut [f32]) {
    gemv_acc_portable(w, rows, x, y)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn gemv_acc_avx2(w: &[f32], rows: usize, x: &[f32], y: &mut [f32]) {
    gemv_acc_portable(w, rows, x, y)
}

/// `y0 += W x0` and `y1 += W x1` for `HIDDEN` rows, each column of `W` loaded once; the same
/// fused multiply-adds in the same order on every build.
fn gemv2_acc(w: &[f32], x0: &[f32], x1: &[f32], y0: &mut [f32], y1: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX-512F and FMA (checked just above).
            unsafe { gemv2_acc_avx512(w, x0, x1, y0, y1) };
            return;
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            unsafe { gemv2_acc_avx2(w, x0, x1, y0, y1) };
            return;
        }
    }
    gemv2_acc_portable(w, x0, x1, y0, y1);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
unsafe fn gemv2_acc_avx512(w: &[f32], x0: &[f32], x1: &[f32], y0: &mut [f32], y1: &mut [f32]) {
    gemv2_acc_portable(w, x0, x1, y0, y1)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn gemv2_acc_avx2(w: &[f32], x0: &[f32], x1: &[f32], y0: &mut [f32], y1: &mut [f32]) {
    gemv2_acc_portable(w, x0, x1, y0, y1)
}

#[inline(always)]
fn gemv2_acc_portable(w: &[f32], x0: &[f32], x1: &[f32], y0: &mut [f32], y1: &mut [f32]) {
    let mut a0 = [0.0f32; HIDDEN];
    let mut a1 = [0.0f32; HIDDEN];
    a0.copy_from_slice(&y0[..HIDDEN]);
    a1.copy_from_slice(&y1[..HIDDEN]);
    for ((col, &u), &v) in w.chunks_exact(HIDDEN).zip(x0).zip(x1) {
        let col: &[f32; HIDDEN] = col.try_into().expect("HIDDEN");
        for i in 0..HIDDEN {
            a0[i] = col[i].mul_add(u, a0[i]);
            a1[i] = col[i].mul_add(v, a1[i]);
        }
    }
    y0[..HIDDEN].copy_from_slice(&a0);
    y1[..HIDDEN].copy_from_slice(&a1);
}

#[inline(always)]
fn gemv_acc_portable(w: &[f32], rows: usize, x: &[f32], y: &mut [f32]) {
    if rows == HIDDEN {
        // Fixed-size accumulators stay in vector registers; two of them (even and odd columns)
        // so that consecutive fused multiply-adds do not wait for each other. No skipping of
        // zero inputs: a data-dependent branch costs more than it saves.
        let mut even = [0.0f32; HIDDEN];
        let mut odd = [0.0f32; HIDDEN];
        even.copy_from_slice(&y[..HIDDEN]);
        let mut cols = w.chunks_exact(2 * HIDDEN).zip(x.chunks_exact(2));
        for (pair, xs) in &mut cols {
            let (c0, c1) = pair.split_at(HIDDEN);
            let c0: &[f32; HIDDEN] = c0.try_into().expect("HIDDEN");
            let c1: &[f32; HIDDEN] = c1.try_into().expect("HIDDEN");
            for i in 0..HIDDEN {
                even[i] = c0[i].mul_add(xs[0], even[i]);
                odd[i] = c1[i].mul_add(xs[1], odd[i]);
            }
        }
        if x.len() % 2 == 1 && w.len() >= x.len() * HIDDEN {
            let j = x.len() - 1;
            let c: &[f32; HIDDEN] = w[j * HIDDEN..(j + 1) * HIDDEN].try_into().expect("HIDDEN");
            for i in 0..HIDDEN {
                even[i] = c[i].mul_add(x[j], even[i]);
            }
        }
        for i in 0..HIDDEN {
            y[i] = even[i] + odd[i];
        }
        return;
    }
    let y = &mut y[..rows];
    for (col, &xj) in w.chunks_exact(rows).zip(x) {
        for (yi, &wi) in y.iter_mut().zip(col) {
            *yi = wi.mul_add(xj, *yi);
        }
    }
}
