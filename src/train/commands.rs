//! The predictor's subcommands (`collect`, `train`, `eval-predictor`, `bench-predictor`): the
//! binary parses the flags into these option structs and calls one function; progress goes to
//! stderr (a bar when it is a terminal), results to stdout.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

use super::collect::{collect, meta_of, CollectError, CollectPlan, EVAL_SEED_BASE};
use super::dataset::{DataError, Dataset};
use super::eval::{evaluate, EvalReport};
use super::fit::{fit, Fitting};
use super::training_loop::{TrainError, TrainOptions};
use crate::config::Config;
use crate::episode::EpisodeError;
use crate::predict::learned::Learned;
use crate::predict::model_file::{LaneChangeModel, ModelError};

/// Why a predictor command failed.
#[derive(Debug, thiserror::Error)]
pub enum CommandError {
    /// The data file could not be read or written.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The model file could not be read, written or checked.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Collecting the data failed.
    #[error(transparent)]
    Collect(#[from] CollectError),
    /// Training failed.
    #[error(transparent)]
    Train(#[from] TrainError),
    /// An evaluation or benchmark episode failed.
    #[error(transparent)]
    Episode(#[from] EpisodeError),
}

/// A progress bar on a terminal, nothing otherwise (callers then print lines).
fn bar(len: u64, what: &str) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let b = ProgressBar::new(len);
    b.set_style(
        ProgressStyle::with_template(&format!(
            "{what} [{{bar:30}}] {{pos}}/{{len}} {{msg}} (eta {{eta}})"
        ))
        .expect("valid template")
        .progress_chars("=> "),
    );
    Some(b)
}

/// `bkpbs collect`: runs the plan's episodes and writes the data file; returns the summary.
pub fn run_collect(base: &Config, plan: &CollectPlan, out: &Path) -> Result<String, CommandError> {
    let start = Instant::now();
    let pb = bar(plan.episodes as u64, "collect");
    let data = collect(base, plan, |done, stats| match &pb {
        Some(b) => {
            b.set_position(done as u64);
            b.set_message(format!(
                "{} + {} ramp, {} + {} main samples",
                stats.ramp_negative, stats.ramp_positive, stats.main_negative, stats.main_positive
            ));
        }
        None if done % 20 == 0 || done == plan.episodes => {
            eprintln!("collect: {done}/{} episodes: {stats}", plan.episodes)
        }
        None => {}
    })?;
    if let Some(b) = pb {
        b.finish_and_clear();
    }
    data.write(out)?;
    let stats = meta_of(&data)
        .map(|m| m.stats.to_string())
        .unwrap_or_default();
    let bytes = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    Ok(format!(
        "{stats}\nwrote {} samples ({:.1} MB) to {} in {:.0} s\n",
        data.samples.len(),
        bytes as f64 / 1e6,
        out.display(),
        start.elapsed().as_secs_f64()
    ))
}

/// `bkpbs train`: fits b_θ and the baseline on `data` and writes the model file.
pub fn run_train(
    data_path: &Path,
    out: &Path,
    conditioned: bool,
    opts: &TrainOptions,
) -> Result<String, CommandError> {
    let data = Dataset::read(data_path)?;
    let name = data_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    eprintln!(
        "train: {} samples from {} ({}), {} threads",
        data.samples.len(),
        data_path.display(),
        if conditioned {
            "conditioned"
        } else {
            "unconditioned"
        },
        opts.threads
    );
    let pb = bar(opts.epochs as u64, "train");
    let mut model = fit(&data, &name, conditioned, opts, |what, e| {
        let line = format!("{}: {e}", what.as_str());
        match (&pb, what) {
            (Some(b), Fitting::Network) => {
                b.set_position(e.epoch as u64);
                b.println(line);
            }
            (Some(b), Fitting::Baseline) => b.println(line),
            (None, _) => eprintln!("{line}"),
        }
    })?;
    if let Some(b) = pb {
        b.finish_and_clear();
    }
    model.trained_on = trained_on_of(&data, data_path, opts.seed);
    model.write(out)?;
    let c = &model.calibration;
    Ok(format!(
        "b_θ: best epoch {} of {}, {:.0} s; baseline {:.0} s; thresholds ramp {:.3}, main {:.3}; written to {}\n",
        model.training.best_epoch,
        model.training.log.len(),
        model.training.wall_s,
        model.training.baseline_wall_s,
        c.threshold_ramp,
        c.threshold_main,
        out.display()
    ))
}

/// The model's record of what it was trained on: the data's, carried on; none (said on
/// stderr) when the data file predates the record.
fn trained_on_of(data: &Dataset, path: &Path, seed: u64) -> Option<crate::config::TrainedOn> {
    let record = meta_of(data).and_then(|m| m.trained_on);
    if record.is_none() {
        eprintln!(
            "warning: data file {} does not record what it was collected on (written before \
             bkpbs kept it): the model will not record it either",
            path.display()
        );
    }
    record.map(|r| super::provenance::of_training(&r, seed))
}

/// Where `eval-predictor` gets its data.
#[derive(Debug, Clone)]
pub enum EvalData {
    /// Samples read from this data file.
    File(PathBuf),
    /// Fresh episodes from this plan (seeds never used in training by default).
    Collect(CollectPlan),
}

impl EvalData {
    /// Fresh data: `episodes` episodes from `seed_base` (default [`EVAL_SEED_BASE`]); on a
    /// scenario of the user's own (`own_demand`) without λ, its routes being its demand.
    pub fn fresh(episodes: usize, seed_base: Option<u64>, own_demand: bool) -> EvalData {
        let d = CollectPlan::default();
        EvalData::Collect(CollectPlan {
            episodes,
            seed_base: seed_base.unwrap_or(EVAL_SEED_BASE),
            lambdas: if own_demand {
                Vec::new()
            } else {
                d.lambdas.clone()
            },
            ..d
        })
    }
}

/// `bkpbs eval-predictor`: the model (`None`: the embedded conditioned one, or the unconditioned
/// one if `unconditioned`) on the data; returns the report.
pub fn run_eval(
    base: &Config,
    model: Option<&Path>,
    unconditioned: bool,
    data: &EvalData,
    seed: u64,
) -> Result<EvalReport, CommandError> {
    let model = match model {
        Some(p) => std::sync::Arc::new(LaneChangeModel::load(p)?),
        None => LaneChangeModel::embedded(!unconditioned),
    };
    let data = match data {
        EvalData::File(p) => {
            let d = Dataset::read(p)?;
            // Samples of another step length are other per-step probabilities.
            let recorded = meta_of(&d).and_then(|m| m.trained_on);
            model.check_step_length(recorded.map_or(base.scenario.dt, |t| t.step_length_s))?;
            d
        }
        EvalData::Collect(plan) => {
            model.check_step_length(base.scenario.dt)?;
            let pb = bar(plan.episodes as u64, "collect evaluation data");
            let d = collect(base, plan, |done, _| {
                if let Some(b) = &pb {
                    b.set_position(done as u64);
                }
            })?;
            if let Some(b) = pb {
                b.finish_and_clear();
            }
            eprintln!(
                "evaluation data: {} episodes from seed {} ({} samples)",
                plan.episodes,
                plan.seed_base,
                d.samples.len()
            );
            d
        }
    };
    Ok(evaluate(&model, &data, seed))
}

/// `bkpbs bench-predictor`: the benchmark episode of `config` with the configured models.
pub fn run_bench(config: &Config) -> Result<String, CommandError> {
    let mut c = config.clone();
    c.predictor.kind = crate::config::PredictorKind::Learned;
    let p = &c.predictor;
    let load = |path: &Option<PathBuf>, conditioned| -> Result<_, ModelError> {
        let model = match path {
            Some(p) => std::sync::Arc::new(LaneChangeModel::load(p)?),
            None => LaneChangeModel::embedded(conditioned),
        };
        model.check_step_length(c.scenario.dt)?;
        Ok(model)
    };
    let learned = Learned::with_models(
        &c,
        load(&p.conditioned_model, true)?,
        load(&p.unconditioned_model, false)?,
    );
    let s = &c.scenario;
    let r = super::bench::run(&c, &learned)?;
    Ok(format!(
        "bench-predictor: α={} λ={} seed={} steps={}, CAVs by idm-mobil\n{}",
        s.alpha,
        s.lambda,
        s.seed,
        s.steps,
        r.to_text()
    ))
}
