//! Training b_θ (and the logistic-regression baseline) on a collected data set.
//!
//! Binary cross-entropy, Adam (lr 1e-3), minibatches of 64, early stopping on a validation split
//! of whole episodes (episode number ≡ 9 mod 10). Each minibatch is cut into fixed chunks of
//! [`TrainOptions::chunk`] samples whose gradients are computed in parallel (rayon, data
//! parallel) and then summed in chunk order, so the result is the same for any thread count and
//! deterministic for a seed.
//!
//! Lane changes are the minority (about 2 % of ramp samples, 0.1 % of main-road ones). The
//! collector thins out main-road negatives; the model is trained on the thinned data without
//! weights and its logits are corrected afterwards by the prior shift `ln(keep rate)` for the
//! main road ([`Calibration`]), which gives probabilities of the natural distribution. The
//! decision threshold of each subset is then tuned on the validation split to the best F1
//! under the natural distribution (threshold tuning, rather than class weights, keeps the
//! probabilities calibrated, which the predictor's rollout needs).

use std::time::Instant;

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::adam::Adam;
use super::dataset::Sample;
use crate::predict::calibration::Calibration;
use crate::predict::features::Subset;
use crate::predict::training_record::ratio;
pub use crate::predict::training_record::{Confusion, EpochLog, TrainOptions};

/// A model the training loop can fit: parameters in one flat `f32` vector.
pub trait Learner: Sync {
    /// Per-worker buffers.
    type Scratch: Send;

    /// Length of the flat parameter vector.
    fn n_params(&self) -> usize;

    /// Initial parameters for a seed.
    fn init(&self, rng: &mut ChaCha8Rng) -> Vec<f32>;

    /// Fresh per-worker buffers.
    fn scratch(&self) -> Self::Scratch;

    /// Adds `scale · Σ_s ∇ℓ_s` over `batch` to `grad` and returns `Σ_s ℓ_s` (binary
    /// cross-entropy of each sample's logit against its label).
    fn loss_grad(
        &self,
        params: &[f32],
        batch: &[&Sample],
        scale: f32,
        grad: &mut [f32],
        scratch: &mut Self::Scratch,
    ) -> f64;

    /// Raw logits of `batch`, appended to `out`.
    fn logits(
        &self,
        params: &[f32],
        batch: &[&Sample],
        out: &mut Vec<f32>,
        scratch: &mut Self::Scratch,
    );
}

impl Calibration {
    /// The prior shift implied by the samples' weights (the inverse keep rates of negatives).
    pub fn prior_shift(samples: &[&Sample]) -> Calibration {
        let mean_weight = |subset| {
            let (n, w) = samples
                .iter()
                .filter(|s| s.subset == subset && !s.label)
                .fold((0usize, 0.0f64), |(n, w), s| (n + 1, w + s.weight as f64));
            if n == 0 {
                1.0
            } else {
                w / n as f64
            }
        };
        let rate = |subset| {
            let (pos, all) =
                samples
                    .iter()
                    .filter(|s| s.subset == subset)
                    .fold((0.0, 0.0), |(p, a), s| {
                        let w = s.weight as f64;
                        (p + if s.label { w } else { 0.0 }, a + w)
                    });
            if all > 0.0 {
                pos / all
            } else {
                0.0
            }
        };
        Calibration {
            logit_offset_ramp: -mean_weight(Subset::Ramp).ln(),
            logit_offset_main: -mean_weight(Subset::Main).ln(),
            threshold_ramp: 0.5,
            threshold_main: 0.5,
            positive_rate_ramp: rate(Subset::Ramp),
            positive_rate_main: rate(Subset::Main),
        }
    }
}

/// Binary cross-entropy of a logit against a label, computed stably.
pub fn bce_with_logit(logit: f64, label: bool) -> f64 {
    let y = label as u8 as f64;
    logit.max(0.0) - logit * y + (-logit.abs()).exp().ln_1p()
}

/// Whether a sample belongs to the validation split (whole episodes, one in ten).
pub fn is_validation(s: &Sample) -> bool {
    s.episode % 10 == 9
}

/// The threshold on calibrated probabilities with the best weighted F1 over `scored`
/// (probability, label, weight), and that F1. Candidates are the scores themselves; ties go to
/// the higher threshold.
pub fn best_f1_threshold(scored: &mut [(f64, bool, f64)]) -> (f64, f64) {
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    let positives: f64 = scored.iter().filter(|s| s.1).map(|s| s.2).sum();
    let (mut tp, mut fp) = (0.0, 0.0);
    let (mut best, mut best_t) = (0.0, 0.5);
    let mut i = 0;
    while i < scored.len() {
        let t = scored[i].0;
        while i < scored.len() && scored[i].0 == t {
            if scored[i].1 {
                tp += scored[i].2;
            } else {
                fp += scored[i].2;
            }
            i += 1;
        }
        let f1 = ratio(2.0 * tp, tp + fp + positives);
        if f1 > best {
            best = f1;
            best_t = t;
        }
    }
    (best_t, best)
}

/// What a training run produced.
#[derive(Debug, Clone)]
pub struct Trained {
    /// The parameters of the epoch with the lowest validation loss.
    pub params: Vec<f32>,
    /// Calibration on the validation split with those parameters, best-F1 thresholds per subset.
    pub calibration: Calibration,
    /// One entry per epoch run.
    pub log: Vec<EpochLog>,
    /// The epoch whose parameters were kept (1-based).
    pub best_epoch: usize,
    /// Wall time of the whole run (s).
    pub wall_s: f64,
}

/// Why training could not run.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// No sample outside the validation split; the number of samples the data has.
    #[error("no training samples (the data has {0} samples, all in the validation split?)")]
    NoTrainingData(usize),
    /// No sample in the validation split (episodes numbered 9, 19, …).
    #[error("no validation samples: the data needs episodes numbered 9, 19, … (collect at least 10 episodes)")]
    NoValidationData,
    /// The thread pool could not be built: threads asked for, and the error.
    #[error("cannot start {0} training threads: {1}")]
    Threads(usize, String),
    /// An option that cannot work (zero epochs, batch, chunk or threads).
    #[error("invalid training option: {0}")]
    Options(String),
}

/// Fits `learner` to the training split of `samples`, stopping early on the validation split;
/// `progress` sees every epoch.
pub fn train<L: Learner>(
    learner: &L,
    samples: &[Sample],
    opts: &TrainOptions,
    mut progress: impl FnMut(&EpochLog),
) -> Result<Trained, TrainError> {
    check_options(opts)?;
    let start = Instant::now();
    let (val, tr) = split(samples)?;
    let mut run = TrainingRun::new(learner, tr, opts)?;
    let calib = Calibration::prior_shift(&run.tr);
    let mut log = Vec::new();
    let (mut best, mut best_loss, mut best_epoch) = (run.params.clone(), f64::INFINITY, 0);
    let mut eval_scratch = learner.scratch();
    for epoch in 1..=opts.epochs {
        let t0 = Instant::now();
        let loss_sum = run.epoch();
        let (val_loss, val_ramp, val_main, _) =
            validate(learner, &run.params, &val, &calib, &mut eval_scratch);
        let entry = EpochLog {
            epoch,
            train_loss: loss_sum / run.tr.len() as f64,
            val_loss,
            val_ramp,
            val_main,
            seconds: t0.elapsed().as_secs_f64(),
        };
        progress(&entry);
        log.push(entry);
        if val_loss < best_loss {
            best_loss = val_loss;
            best_epoch = epoch;
            best.copy_from_slice(&run.params);
        } else if epoch - best_epoch >= opts.patience {
            break;
        }
    }
    let (_, _, _, calibration) = validate(learner, &best, &val, &calib, &mut eval_scratch);
    Ok(Trained {
        params: best,
        calibration,
        log,
        best_epoch,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// Rejects options under which the loop could not make progress (zero-sized batches, chunks,
/// thread pools or runs).
fn check_options(opts: &TrainOptions) -> Result<(), TrainError> {
    if opts.batch == 0 || opts.chunk == 0 || opts.threads == 0 || opts.epochs == 0 {
        return Err(TrainError::Options(format!(
            "epochs {}, batch {}, chunk {} and threads {} must be positive",
            opts.epochs, opts.batch, opts.chunk, opts.threads
        )));
    }
    Ok(())
}

/// The validation and the training split of `samples`, neither of which may be empty.
fn split(samples: &[Sample]) -> Result<(Vec<&Sample>, Vec<&Sample>), TrainError> {
    let (val, tr): (Vec<&Sample>, Vec<&Sample>) = samples.iter().partition(|s| is_validation(s));
    if tr.is_empty() {
        return Err(TrainError::NoTrainingData(samples.len()));
    }
    if val.is_empty() {
        return Err(TrainError::NoValidationData);
    }
    Ok((val, tr))
}

/// A training run between epochs: the parameters, the optimiser, the random stream (seeded once,
/// drawn by the initialisation and then by each epoch's shuffle) and the reused buffers.
struct TrainingRun<'a, L: Learner> {
    learner: &'a L,
    opts: &'a TrainOptions,
    /// The training split.
    tr: Vec<&'a Sample>,
    rng: ChaCha8Rng,
    params: Vec<f32>,
    adam: Adam,
    gradient: Gradient<L>,
    /// Indices into `tr`, shuffled each epoch.
    order: Vec<usize>,
    batch: Vec<&'a Sample>,
}

impl<'a, L: Learner> TrainingRun<'a, L> {
    /// Parameters initialised from `opts.seed`, and buffers for `opts.batch`.
    fn new(
        learner: &'a L,
        tr: Vec<&'a Sample>,
        opts: &'a TrainOptions,
    ) -> Result<TrainingRun<'a, L>, TrainError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(opts.threads)
            .build()
            .map_err(|e| TrainError::Threads(opts.threads, e.to_string()))?;
        let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
        let params = learner.init(&mut rng);
        let adam = Adam::new(params.len(), opts.lr);
        let chunks_per_batch = opts.batch.div_ceil(opts.chunk);
        let gradient = Gradient {
            pool,
            workers: (0..chunks_per_batch)
                .map(|_| (learner.scratch(), vec![0.0; params.len()], 0.0))
                .collect(),
            sum: vec![0.0f32; params.len()],
        };
        Ok(TrainingRun {
            learner,
            opts,
            order: (0..tr.len()).collect(),
            tr,
            rng,
            params,
            adam,
            gradient,
            batch: Vec::with_capacity(opts.batch),
        })
    }

    /// One pass over the training split in shuffled minibatches, one Adam step each; returns
    /// the summed training loss.
    fn epoch(&mut self) -> f64 {
        self.order.shuffle(&mut self.rng);
        let mut loss_sum = 0.0;
        for ids in self.order.chunks(self.opts.batch) {
            self.batch.clear();
            self.batch.extend(ids.iter().map(|&i| self.tr[i]));
            self.gradient.compute(
                self.learner,
                &self.params,
                &self.batch,
                self.opts.chunk,
                &mut loss_sum,
            );
            self.adam.step(&mut self.params, &self.gradient.sum);
        }
        loss_sum
    }
}

/// The mean gradient of a minibatch, computed in fixed chunks on a thread pool and summed in
/// chunk order, so the result does not depend on the number of threads.
struct Gradient<L: Learner> {
    pool: rayon::ThreadPool,
    /// Per chunk of a minibatch: scratch, gradient and loss.
    workers: Vec<(L::Scratch, Vec<f32>, f64)>,
    /// The minibatch's gradient.
    sum: Vec<f32>,
}

impl<L: Learner> Gradient<L> {
    /// Sets `sum` to the mean gradient of `batch` at `params` and adds each chunk's summed loss
    /// to `loss_sum`, in chunk order.
    fn compute(
        &mut self,
        learner: &L,
        params: &[f32],
        batch: &[&Sample],
        chunk: usize,
        loss_sum: &mut f64,
    ) {
        let scale = 1.0 / batch.len() as f32;
        let chunks: Vec<&[&Sample]> = batch.chunks(chunk).collect();
        let used = chunks.len();
        let workers = &mut self.workers[..used];
        self.pool.install(|| {
            workers
                .par_iter_mut()
                .zip(chunks.par_iter())
                .for_each(|((scratch, g, loss), part)| {
                    g.iter_mut().for_each(|x| *x = 0.0);
                    *loss = learner.loss_grad(params, part, scale, g, scratch);
                });
        });
        self.sum.iter_mut().for_each(|x| *x = 0.0);
        for (_, g, loss) in &self.workers[..used] {
            for (a, b) in self.sum.iter_mut().zip(g) {
                *a += b;
            }
            *loss_sum += loss;
        }
    }
}

/// Validation loss (on the thinned data, like the training loss), the confusion of each subset
/// at its best-F1 threshold (natural distribution), and the calibration with those thresholds.
fn validate<L: Learner>(
    learner: &L,
    params: &[f32],
    val: &[&Sample],
    calib: &Calibration,
    scratch: &mut L::Scratch,
) -> (f64, Confusion, Confusion, Calibration) {
    let mut logits = Vec::with_capacity(val.len());
    for part in val.chunks(256) {
        learner.logits(params, part, &mut logits, scratch);
    }
    let loss = val
        .iter()
        .zip(&logits)
        .map(|(s, &z)| bce_with_logit(z as f64, s.label))
        .sum::<f64>()
        / val.len() as f64;
    let mut out = *calib;
    let mut conf = [Confusion::default(); 2];
    for subset in [Subset::Ramp, Subset::Main] {
        let mut scored: Vec<(f64, bool, f64)> = val
            .iter()
            .zip(&logits)
            .filter(|(s, _)| s.subset == subset)
            .map(|(s, &z)| {
                (
                    calib.probability(z as f64, subset),
                    s.label,
                    s.weight as f64,
                )
            })
            .collect();
        let (t, _) = best_f1_threshold(&mut scored);
        let c = &mut conf[subset.code() as usize];
        for &(p, y, w) in &scored {
            c.add(p >= t, y, w);
        }
        match subset {
            Subset::Ramp => out.threshold_ramp = t,
            Subset::Main => out.threshold_main = t,
        }
    }
    (loss, conf[0], conf[1], out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn best_threshold_separates_when_possible() {
        let mut s = vec![
            (0.9, true, 1.0),
            (0.8, true, 1.0),
            (0.3, false, 1.0),
            (0.2, false, 10.0),
        ];
        let (t, f1) = best_f1_threshold(&mut s);
        assert_eq!((t, f1), (0.8, 1.0));
        // A heavy negative above the positives pushes the threshold up.
        let mut s = vec![(0.9, true, 1.0), (0.8, false, 10.0), (0.7, true, 1.0)];
        let (t, f1) = best_f1_threshold(&mut s);
        assert_eq!(t, 0.9);
        assert!((f1 - 2.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn confusion_figures() {
        let mut c = Confusion::default();
        c.add(true, true, 1.0);
        c.add(true, false, 1.0);
        c.add(false, false, 7.0);
        c.add(false, true, 1.0);
        assert_eq!(c.accuracy(), 0.8);
        assert_eq!(c.precision(), 0.5);
        assert_eq!(c.recall(), 0.5);
        assert_eq!(c.f1(), 0.5);
    }
}
