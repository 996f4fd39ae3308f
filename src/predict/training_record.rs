//! What a model file records of how it was trained: the settings and each epoch's figures.
//! The training loop (`crate::train`) fills them in; they live here because the model file,
//! which the runtime predictor reads, carries them.

use serde::{Deserialize, Serialize};

/// Settings of one training run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainOptions {
    /// Most epochs (early stopping usually ends sooner).
    pub epochs: usize,
    pub batch: usize,
    pub lr: f32,
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
    pub tp: f64,
    pub fp: f64,
    pub tn: f64,
    pub fn_: f64,
}

impl Confusion {
    pub fn add(&mut self, predicted: bool, actual: bool, weight: f64) {
        match (predicted, actual) {
            (true, true) => self.tp += weight,
            (true, false) => self.fp += weight,
            (false, false) => self.tn += weight,
            (false, true) => self.fn_ += weight,
        }
    }

    pub fn total(&self) -> f64 {
        self.tp + self.fp + self.tn + self.fn_
    }

    pub fn accuracy(&self) -> f64 {
        ratio(self.tp + self.tn, self.total())
    }

    pub fn precision(&self) -> f64 {
        ratio(self.tp, self.tp + self.fp)
    }

    pub fn recall(&self) -> f64 {
        ratio(self.tp, self.tp + self.fn_)
    }

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
    pub epoch: usize,
    pub train_loss: f64,
    pub val_loss: f64,
    /// Validation figures at the best-F1 thresholds of this epoch (natural distribution).
    pub val_ramp: Confusion,
    pub val_main: Confusion,
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
