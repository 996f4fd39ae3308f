//! `bkpbs train`: fits b_θ (conditioned or not) and its logistic-regression baseline on a data
//! file and packs both into one model file.

use std::time::Instant;

use super::dataset::Dataset;
use super::gcn::GcnLearner;
use super::training_loop::{is_validation, train, EpochLog, TrainError, TrainOptions};
use crate::predict::features::FeatureLayout;
use crate::predict::gcn::Architecture;
use crate::predict::logistic::Logistic;
use crate::predict::model_file::{Baseline, ModelFile, TrainingInfo, MODEL_FORMAT, MODEL_VERSION};

/// Which of the two fits a progress line belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fitting {
    /// The network b_θ.
    Network,
    /// The logistic-regression baseline.
    Baseline,
}

impl Fitting {
    /// The fit's name in progress lines: `b_θ` or `logistic`.
    pub fn as_str(self) -> &'static str {
        match self {
            Fitting::Network => "b_θ",
            Fitting::Baseline => "logistic",
        }
    }
}

/// Trains the network and the baseline on `data` (named `data_name` in the file); the
/// caller fills in what the data was collected on (`trained_on`).
pub fn fit(
    data: &Dataset,
    data_name: &str,
    conditioned: bool,
    opts: &TrainOptions,
    mut progress: impl FnMut(Fitting, &EpochLog),
) -> Result<ModelFile, TrainError> {
    let start = Instant::now();
    let arch = Architecture::new(conditioned);
    let net = train(
        &GcnLearner { arch: arch.clone() },
        &data.samples,
        opts,
        |e| progress(Fitting::Network, e),
    )?;
    let wall_s = start.elapsed().as_secs_f64();
    let base = train(&Logistic { conditioned }, &data.samples, opts, |e| {
        progress(Fitting::Baseline, e)
    })?;
    let validation_samples = data.samples.iter().filter(|s| is_validation(s)).count();
    Ok(ModelFile {
        format: MODEL_FORMAT.into(),
        version: MODEL_VERSION,
        conditioned,
        layout: FeatureLayout::current(),
        architecture: arch,
        params: net.params,
        calibration: net.calibration,
        baseline: Baseline {
            params: base.params,
            calibration: base.calibration,
        },
        training: TrainingInfo {
            data: data_name.into(),
            train_samples: data.samples.len() - validation_samples,
            validation_samples,
            options: opts.clone(),
            best_epoch: net.best_epoch,
            wall_s,
            baseline_wall_s: base.wall_s,
            log: net.log,
        },
        trained_on: None,
    })
}
