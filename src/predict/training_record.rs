//! What a model file records of how it was trained: the settings and each epoch's figures.
//! The training loop (`crate::train`) fills them in; they live here because the model file,
//! which the runtime predictor reads, carries them.

use serde::{Deserialize, Serialize};

/// Settings of one training run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainOptions {
    /// Most epochs (early stopping usually ends sooner).
    pub epochs: usize,
    /// Samples per minibatch.
    pub batch: usize,
    /// Adam learning rate.
    pub lr: f32,
    /// Seed of the initial parameters and of the shuffling of the training samples.
    pub seed: u64,
    /// Stop after this many epochs without a better validation loss.
    pub patience: usize,
    /// Worker threads for the gradient chunks.
    pub threads: usize,
    /// Samples per gradient chunk (fixed, so results do not depend on `threads`).
    pub chunk: usize,
}

impl Default for TrainOptions {
    fn default() -> Self {
        TrainOptions {
            epochs: 40,
            batch: 64,
            lr: 1e-3,
            seed: 1,
            patience: 5,
            threads: 2,
            chunk: 16,
        }
    }
}

/// Counts of a binary classification, weighted (a sample counts its weight).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Confusion {
    /// True positives: lane changes predicted as such.
    pub tp: f64,
    /// False positives: lane changes predicted where none started.
    pub fp: f64,
    /// True negatives: no lane change, none predicted.
    pub tn: f64,
    /// False negatives: lane changes missed.
    pub fn_: f64,
}

impl Confusion {
    /// Counts one sample of weight `weight`, `predicted` and `actual` being "lane change".
    pub fn add(&mut self, predicted: bool, actual: bool, weight: f64) {
        match (predicted, actual) {
            (true, true) => self.tp += weight,
            (true, false) => self.fp += weight,
            (false, false) => self.tn += weight,
            (false, true) => self.fn_ += weight,
        }
    }

    /// Total weight counted.
    pub fn total(&self) -> f64 {
        self.tp + self.fp + self.tn + self.fn_
    }

    /// Share of the weight classified correctly (0 when empty).
    pub fn accuracy(&self) -> f64 {
        ratio(self.tp + self.tn, self.total())
    }

    /// Share of the predicted lane changes that were lane changes (0 when none predicted).
    pub fn precision(&self) -> f64 {
        ratio(self.tp, self.tp + self.fp)
    }

    /// Share of the lane changes that were predicted (0 when there were none).
    pub fn recall(&self) -> f64 {
        ratio(self.tp, self.tp + self.fn_)
    }

    /// F1 score: the harmonic mean of precision and recall (0 when undefined).
    pub fn f1(&self) -> f64 {
        ratio(2.0 * self.tp, 2.0 * self.tp + self.fp + self.fn_)
    }
}

pub(crate) fn ratio(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        a / b
    } else {
        0.0
    }
}

/// One epoch's figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EpochLog {
    /// Epoch number, from 1.
    pub epoch: usize,
    /// Mean binary cross-entropy of the raw logits over the training samples (thinned data).
    pub train_loss: f64,
    /// The same over the validation samples, after the epoch; early stopping watches it.
    pub val_loss: f64,
    /// Validation figures of the ramp subset at its best-F1 threshold of this epoch (weighted
    /// back to the natural distribution).
    pub val_ramp: Confusion,
    /// The same for the main-road subset.
    pub val_main: Confusion,
    /// Wall time of the epoch, training and validation (s).
    pub seconds: f64,
}

impl std::fmt::Display for EpochLog {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "epoch {:>3}: train loss {:.5}, val loss {:.5} | ramp acc {:.1}% recall {:.1}% F1 {:.3} | main acc {:.2}% recall {:.1}% F1 {:.3} | {:.1} s",
            self.epoch,
            self.train_loss,
            self.val_loss,
            100.0 * self.val_ramp.accuracy(),
            100.0 * self.val_ramp.recall(),
            self.val_ramp.f1(),
            100.0 * self.val_main.accuracy(),
            100.0 * self.val_main.recall(),
            self.val_main.f1(),
            self.seconds
        )
    }
}
