//! Model files of b_θ: JSON (serde_json) with a format name and version, the feature layout,
//! the architecture, the trained parameters, the calibration, the logistic-regression baseline
//! trained on the same data, and how the model was trained.
//!
//! Loading checks everything against this build: a truncated file, another format version,
//! another feature layout or parameter vectors of the wrong length are errors naming the file.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

use serde::{Deserialize, Serialize};

use super::calibration::Calibration;
use super::features::{encode_a, encode_b, FeatureLayout, Observation, Subset};
use super::gcn::Architecture;
use super::infer::{Network, Workspace};
use super::logistic::Logistic;
use super::training_record::{EpochLog, TrainOptions};
use crate::config::TrainedOn;

/// The `format` field of every model file.
pub const MODEL_FORMAT: &str = "bkpbs-lane-change-model";
/// Bumped whenever the file's meaning changes.
pub const MODEL_VERSION: u32 = 1;

/// The committed conditioned model, embedded so the default works from any directory.
pub const EMBEDDED_CONDITIONED: &str = include_str!("../../models/gcn-conditioned.json");
/// The committed unconditioned model.
pub const EMBEDDED_UNCONDITIONED: &str = include_str!("../../models/gcn-unconditioned.json");

/// The logistic-regression baseline stored next to the network.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Baseline {
    /// Its weights, then the bias ([`Logistic`]'s layout).
    pub params: Vec<f32>,
    /// Its own prior shifts and thresholds.
    pub calibration: Calibration,
}

/// How a model was trained (documentation; not used for prediction).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingInfo {
    /// File name of the training data (no directory).
    pub data: String,
    /// Decision points trained on.
    pub train_samples: usize,
    /// Decision points held out for validation (whole episodes).
    pub validation_samples: usize,
    /// The training settings.
    pub options: TrainOptions,
    /// The epoch (from 1) of the lowest validation loss, whose parameters the file holds.
    pub best_epoch: usize,
    /// Wall time of training the network (s).
    pub wall_s: f64,
    /// Wall time of training the logistic-regression baseline (s).
    pub baseline_wall_s: f64,
    /// The network's figures of every epoch run.
    pub log: Vec<EpochLog>,
}

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Format tag, [`MODEL_FORMAT`].
    pub format: String,
    /// Format version, [`MODEL_VERSION`].
    pub version: u32,
    /// The model reads sequence (b), the higher-priority CAVs' planned states.
    pub conditioned: bool,
    /// The feature layout it was trained with (must equal this build's).
    pub layout: FeatureLayout,
    /// The network's layers and where their parameters are.
    pub architecture: Architecture,
    /// The network's flat parameter vector.
    pub params: Vec<f32>,
    /// The network's prior shifts and thresholds.
    pub calibration: Calibration,
    /// The logistic-regression baseline trained on the same data.
    pub baseline: Baseline,
    /// How the model was trained.
    pub training: TrainingInfo,
    /// What it was trained on: step length, scenario, seeds, commands, versions. Absent in
    /// files written before it was kept; a file is refused under another step length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trained_on: Option<TrainedOn>,
}

/// Largest parameter magnitude a model file may hold: the committed models stay below 20, and
/// weights of 1e30 (accepted once) make every probability 0 or 1 and every sum overflow.
pub const MAX_PARAMETER: f32 = 1e4;

/// Why a model file (or a `calibration.json` of the IDM predictor) cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("cannot read model file {path}: {cause}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// The text is not JSON, or not the file's fields.
    #[error("model file {path} is not valid model JSON (truncated or corrupt?): {message}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// The `format` tag is not the expected one (empty when missing).
    #[error("{path} is not a bkpbs lane-change model (format '{found}')")]
    Format {
        /// The file.
        path: PathBuf,
        /// The tag it has.
        found: String,
    },
    /// The file's format version is not the one this build reads.
    #[error("model file {path} has format version {found}; this build reads version {expected}")]
    Version {
        /// The file.
        path: PathBuf,
        /// The version it has (0 when missing).
        found: u32,
        /// The version this build reads.
        expected: u32,
    },
    /// The model was trained on another feature layout than this build's.
    #[error("model file {path} was trained on another feature layout: {what}")]
    Layout {
        /// The file.
        path: PathBuf,
        /// The file's layout and this build's.
        what: String,
    },
    /// The contents do not fit: layers, parameter counts, parameter or calibration values (for
    /// a calibration file: its HDV profile or IDM parameters).
    #[error("model file {path} has the wrong shapes: {what}")]
    Shape {
        /// The file.
        path: PathBuf,
        /// What does not fit.
        what: String,
    },
    /// The model was trained under another SUMO step length than the run's: its probabilities
    /// are per step, so they would mean something else.
    #[error(
        "model file {path} was trained at step length {trained} s, this run's scenario.dt is \
         {run} s: train one at {run} s (bkpbs collect and bkpbs train with this configuration)"
    )]
    StepLength {
        /// The file.
        path: PathBuf,
        /// Its step length (s).
        trained: f64,
        /// The run's `scenario.dt` (s).
        run: f64,
    },
    /// Writing the file failed.
    #[error(transparent)]
    Write(#[from] crate::io::WriteError),
}

impl ModelFile {
    /// Parses and checks model JSON; `path` only names the file in errors.
    pub fn from_json(path: &Path, text: &str) -> Result<ModelFile, ModelError> {
        let p = || path.to_path_buf();
        // Read the version first, so an old or new file says so rather than failing on a field.
        #[derive(Deserialize)]
        struct Head {
            format: Option<String>,
            version: Option<u32>,
        }
        let head: Head = serde_json::from_str(text).map_err(|e| ModelError::Json {
            path: p(),
            message: e.to_string(),
        })?;
        let format = head.format.unwrap_or_default();
        if format != MODEL_FORMAT {
            return Err(ModelError::Format {
                path: p(),
                found: format,
            });
        }
        let version = head.version.unwrap_or(0);
        if version != MODEL_VERSION {
            return Err(ModelError::Version {
                path: p(),
                found: version,
                expected: MODEL_VERSION,
            });
        }
        let m: ModelFile = serde_json::from_str(text).map_err(|e| ModelError::Json {
            path: p(),
            message: e.to_string(),
        })?;
        m.check(path)?;
        Ok(m)
    }

    /// The file fits this build: its feature layout, its layers, its parameter counts, finite
    /// and bounded parameters and calibration.
    fn check(&self, path: &Path) -> Result<(), ModelError> {
        self.check_layout(path)?;
        let shape = |what: String| ModelError::Shape {
            path: path.to_path_buf(),
            what,
        };
        self.check_shapes().map_err(shape)?;
        if self
            .params
            .iter()
            .chain(&self.baseline.params)
            .any(|x| !x.is_finite() || x.abs() > MAX_PARAMETER)
        {
            return Err(shape(format!(
                "a parameter is not a finite number of magnitude at most {MAX_PARAMETER:e} \
                 (trained models stay below 100; larger ones saturate every probability)"
            )));
        }
        for c in [&self.calibration, &self.baseline.calibration] {
            let ok = |t: f64| t > 0.0 && t <= 1.0;
            if !ok(c.threshold_ramp)
                || !ok(c.threshold_main)
                || !c.logit_offset_ramp.is_finite()
                || !c.logit_offset_main.is_finite()
            {
                return Err(shape(format!("calibration out of range: {c:?}")));
            }
        }
        Ok(())
    }

    /// The node features the file was trained on are this build's.
    fn check_layout(&self, path: &Path) -> Result<(), ModelError> {
        let current = FeatureLayout::current();
        if self.layout == current {
            return Ok(());
        }
        Err(ModelError::Layout {
            path: path.to_path_buf(),
            what: format!(
                "file has {} × {} node features (a) and {} × {} × {} (b), this build {} × {} and {} × {} × {}",
                self.layout.nodes_a,
                self.layout.features_a,
                self.layout.preview,
                self.layout.cav_nodes,
                self.layout.features_b,
                current.nodes_a,
                current.features_a,
                current.preview,
                current.cav_nodes,
                current.features_b
            ),
        })
    }

    /// The network's layers and both parameter counts are this build's; the error says which
    /// differs.
    fn check_shapes(&self) -> Result<(), String> {
        let arch = Architecture::new(self.conditioned);
        if self.architecture != arch {
            return Err(format!(
                "its layers differ from this build's {} network",
                if self.conditioned {
                    "conditioned"
                } else {
                    "unconditioned"
                }
            ));
        }
        if self.params.len() != arch.n_params {
            return Err(format!(
                "{} network parameters, the architecture needs {}",
                self.params.len(),
                arch.n_params
            ));
        }
        let lr = Logistic {
            conditioned: self.conditioned,
        };
        if self.baseline.params.len() != lr.n_params() {
            return Err(format!(
                "{} baseline parameters, the logistic regression needs {}",
                self.baseline.params.len(),
                lr.n_params()
            ));
        }
        Ok(())
    }

    /// Reads and checks a model file.
    pub fn read(path: &Path) -> Result<ModelFile, ModelError> {
        let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Model)
            .map_err(|cause| ModelError::Read {
                path: path.to_path_buf(),
                cause,
            })?;
        ModelFile::from_json(path, &text)
    }

    /// Writes the file atomically.
    pub fn write(&self, path: &Path) -> Result<(), ModelError> {
        let text = serde_json::to_string(self).expect("a model serialises");
        crate::io::write_atomic(path, text.as_bytes())?;
        Ok(())
    }
}

/// A loaded model ready to predict: the network in f32 and its calibration.
#[derive(Debug, Clone)]
pub struct LaneChangeModel {
    /// Where it came from (a path, or `embedded:<name>`).
    pub source: String,
    /// The model file, as read.
    pub file: ModelFile,
    network: Network,
}

impl LaneChangeModel {
    /// The model of `file`, whose shapes must fit this build (as [`ModelFile::read`] checks),
    /// named `source` in messages and results.
    pub fn new(source: String, file: ModelFile) -> LaneChangeModel {
        let network = Network::new(&file.architecture, &file.params);
        LaneChangeModel {
            source,
            file,
            network,
        }
    }

    /// Loads a model file.
    pub fn load(path: &Path) -> Result<LaneChangeModel, ModelError> {
        Ok(LaneChangeModel::new(
            path.display().to_string(),
            ModelFile::read(path)?,
        ))
    }

    /// The committed model embedded in the binary (parsed once per process).
    pub fn embedded(conditioned: bool) -> Arc<LaneChangeModel> {
        static COND: OnceLock<Arc<LaneChangeModel>> = OnceLock::new();
        static UNCOND: OnceLock<Arc<LaneChangeModel>> = OnceLock::new();
        let (cell, text, name) = if conditioned {
            (&COND, EMBEDDED_CONDITIONED, "gcn-conditioned.json")
        } else {
            (&UNCOND, EMBEDDED_UNCONDITIONED, "gcn-unconditioned.json")
        };
        cell.get_or_init(|| {
            let path = PathBuf::from(format!("models/{name}"));
            let file = ModelFile::from_json(&path, text)
                .expect("the embedded model passed its checks when it was committed");
            Arc::new(LaneChangeModel::new(format!("embedded:{name}"), file))
        })
        .clone()
    }

    /// Refuses the model under a step length `dt` (s) other than the one it was trained at;
    /// a file without a record of it is taken as it is.
    ///
    /// # Errors
    /// [`ModelError::StepLength`], naming the file and both step lengths.
    pub fn check_step_length(&self, dt: f64) -> Result<(), ModelError> {
        match &self.file.trained_on {
            Some(t) if !t.fits_step_length(dt) => Err(ModelError::StepLength {
                path: self.source.clone().into(),
                trained: t.step_length_s,
                run: dt,
            }),
            _ => Ok(()),
        }
    }

    /// The model reads sequence (b), the higher-priority CAVs' planned states.
    pub fn conditioned(&self) -> bool {
        self.file.conditioned
    }

    /// The raw logit of `obs` (encodes it into `ws`).
    pub fn logit(&self, obs: &Observation, ws: &mut Workspace) -> f32 {
        encode_a(obs, ws.xa.as_mut_slice());
        if self.file.conditioned {
            encode_b(obs, ws.xb.as_mut_slice());
        }
        self.network.logit(ws)
    }

    /// P(lane change at the next step), calibrated to the natural frequency of lane changes.
    pub fn probability(&self, obs: &Observation, ws: &mut Workspace) -> f64 {
        let subset = Subset::of_lane(obs.ego.lane as i32);
        self.file
            .calibration
            .probability(self.logit(obs, ws) as f64, subset)
    }

    /// The baseline's raw logit of `obs` (`x` is a buffer of the baseline's input length).
    pub fn baseline_logit(&self, obs: &Observation, x: &mut Vec<f32>) -> f32 {
        let lr = Logistic {
            conditioned: self.file.conditioned,
        };
        x.resize(lr.inputs(), 0.0);
        lr.encode(obs, x);
        Logistic::logit(&self.file.baseline.params, x)
    }
}
