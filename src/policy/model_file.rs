//! The RL-PPO policy file (`models/rl-ppo.json`): both networks' weights, versioned, checked on
//! load like the predictor's model files (format, version, shapes, finite weights), with what
//! training produced it.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::actions::ACTIONS;
use super::mlp::Mlp;
use super::network::{ActorCritic, HIDDEN};
use super::observation::OBS_DIM;
use crate::config::TrainedOn;
use crate::planner::primitives::Primitive;

/// The largest weight magnitude a policy file may hold: trained policies stay below 100 (the
/// shipped one below 20); 3e38 passed a finiteness check and overflowed to infinity later.
pub const MAX_WEIGHT: f32 = 1e4;

/// Whether every weight is a finite number of magnitude at most [`MAX_WEIGHT`] (policy files
/// and `train-rl` checkpoints alike).
pub fn weights_in_range<'a>(weights: impl IntoIterator<Item = &'a f32>) -> bool {
    weights
        .into_iter()
        .all(|w| w.is_finite() && w.abs() <= MAX_WEIGHT)
}
/// Format tag of the policy file (its `format` field).
pub const POLICY_FORMAT: &str = "bkpbs-rl-policy";
/// Version of the policy file format this build reads and writes (its `version` field).
pub const POLICY_VERSION: u32 = 1;

/// The committed policy, embedded in the binary.
pub const EMBEDDED_POLICY: &str = include_str!("../../models/rl-ppo.json");

/// Why a policy file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum PolicyError {
    /// The file could not be read.
    #[error("cannot read policy file {path}: {cause}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        cause: std::io::Error,
    },
    /// The text is not JSON, or not the policy file's fields.
    #[error("policy file {path} is not valid JSON (truncated or corrupt?): {message}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// The `format` tag is not [`POLICY_FORMAT`] (empty when missing).
    #[error("{path} is not a bkpbs RL policy (format '{found}')")]
    Format {
        /// The file.
        path: PathBuf,
        /// The tag it has.
        found: String,
    },
    /// The file's format version is not the one this build reads.
    #[error("policy file {path} has format version {found}; this build reads version {expected}")]
    Version {
        /// The file.
        path: PathBuf,
        /// The version it has (0 when missing).
        found: u32,
        /// [`POLICY_VERSION`].
        expected: u32,
    },
    /// The networks do not fit this build: observation length, action names, hidden widths,
    /// activation, weight counts, or non-finite weights.
    #[error("policy file {path} does not fit this build: {what}")]
    Shape {
        /// The file.
        path: PathBuf,
        /// What does not fit, and what was expected.
        what: String,
    },
    /// The policy was trained under another SUMO step length than the run's: its actions
    /// last one step, so they would mean something else.
    #[error(
        "policy file {path} was trained at step length {trained} s, this run's scenario.dt is \
         {run} s: train one at {run} s (bkpbs train-rl with this configuration)"
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

/// The file's contents.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PolicyFile {
    /// Format tag, [`POLICY_FORMAT`].
    pub format: String,
    /// Format version, [`POLICY_VERSION`].
    pub version: u32,
    /// Length of the observation vector the networks take ([`OBS_DIM`]).
    pub observation_dim: usize,
    /// Primitive names, in the order of the policy's outputs.
    pub actions: Vec<String>,
    /// Hidden-layer widths of both networks ([`HIDDEN`]).
    pub hidden: Vec<usize>,
    /// Activation of the hidden layers; only `tanh` is accepted.
    pub activation: String,
    /// The policy network's flat parameters, in [`Mlp`]'s layout.
    pub actor: Vec<f32>,
    /// The value network's flat parameters, in [`Mlp`]'s layout.
    pub critic: Vec<f32>,
    /// How it was trained (steps, seed, wall time, hyper-parameters), for the record.
    pub training: serde_json::Value,
    /// What it was trained on: step length, scenario, seeds, command, versions. Absent in
    /// files written before it was kept; a file is refused under another step length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trained_on: Option<TrainedOn>,
}

impl PolicyFile {
    /// The file of `net`, trained as `training` says, on what `trained_on` says.
    pub fn of(
        net: &ActorCritic,
        training: serde_json::Value,
        trained_on: Option<TrainedOn>,
    ) -> PolicyFile {
        PolicyFile {
            format: POLICY_FORMAT.into(),
            version: POLICY_VERSION,
            observation_dim: net.actor.inputs(),
            actions: Primitive::ALL
                .iter()
                .map(|p| p.name().to_string())
                .collect(),
            hidden: HIDDEN.to_vec(),
            activation: "tanh".into(),
            actor: net.actor_params.clone(),
            critic: net.critic_params.clone(),
            training,
            trained_on,
        }
    }

    /// Parses and checks policy JSON; `path` only names it in errors.
    pub fn from_json(path: &Path, text: &str) -> Result<PolicyFile, PolicyError> {
        let p = || path.to_path_buf();
        #[derive(Deserialize)]
        struct Head {
            format: Option<String>,
            version: Option<u32>,
        }
        let json = |e: serde_json::Error| PolicyError::Json {
            path: p(),
            message: e.to_string(),
        };
        let head: Head = serde_json::from_str(text).map_err(json)?;
        let found = head.format.unwrap_or_default();
        if found != POLICY_FORMAT {
            return Err(PolicyError::Format { path: p(), found });
        }
        let version = head.version.unwrap_or(0);
        if version != POLICY_VERSION {
            return Err(PolicyError::Version {
                path: p(),
                found: version,
                expected: POLICY_VERSION,
            });
        }
        let file: PolicyFile = serde_json::from_str(text).map_err(json)?;
        file.check(path)?;
        Ok(file)
    }

    fn check(&self, path: &Path) -> Result<(), PolicyError> {
        let shape = |what: String| PolicyError::Shape {
            path: path.to_path_buf(),
            what,
        };
        let names: Vec<&str> = Primitive::ALL.iter().map(|p| p.name()).collect();
        if self.observation_dim != OBS_DIM || self.actions != names || self.hidden != HIDDEN {
            return Err(shape(format!(
                "observation {} / actions {:?} / hidden {:?}; expected {OBS_DIM} / {names:?} / {HIDDEN:?}",
                self.observation_dim, self.actions, self.hidden
            )));
        }
        if self.activation != "tanh" {
            return Err(shape(format!("activation '{}'", self.activation)));
        }
        let actor = Mlp::new(OBS_DIM, &HIDDEN, ACTIONS);
        let critic = Mlp::new(OBS_DIM, &HIDDEN, 1);
        if self.actor.len() != actor.n_params || self.critic.len() != critic.n_params {
            return Err(shape(format!(
                "{} actor and {} critic weights; expected {} and {}",
                self.actor.len(),
                self.critic.len(),
                actor.n_params,
                critic.n_params
            )));
        }
        if !weights_in_range(self.actor.iter().chain(&self.critic)) {
            return Err(shape(format!(
                "a weight is not a finite number of magnitude at most {MAX_WEIGHT:e} (trained \
                 policies stay below 100; larger ones overflow the network's sums)"
            )));
        }
        Ok(())
    }

    /// Reads and checks a policy file.
    pub fn read(path: &Path) -> Result<PolicyFile, PolicyError> {
        let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Model)
            .map_err(|cause| PolicyError::Read {
                path: path.to_path_buf(),
                cause,
            })?;
        PolicyFile::from_json(path, &text)
    }

    /// Writes the file atomically.
    pub fn write(&self, path: &Path) -> Result<(), PolicyError> {
        let text = serde_json::to_string(self).expect("a policy serialises");
        crate::io::write_atomic(path, text.as_bytes())?;
        Ok(())
    }

    /// The networks.
    pub fn networks(&self) -> ActorCritic {
        ActorCritic::with_params(self.actor.clone(), self.critic.clone())
    }
}

/// Where the embedded policy is said to come from.
pub const EMBEDDED_POLICY_SOURCE: &str = "embedded:rl-ppo.json";

/// The policy file at `path`, or the embedded one, checked to be trained under the step length
/// `dt` (s) where it records one.
///
/// # Errors
/// A file that cannot be read or used, or [`PolicyError::StepLength`].
pub fn load_file(path: Option<&Path>, dt: f64) -> Result<PolicyFile, PolicyError> {
    let (file, source) = match path {
        Some(p) => (PolicyFile::read(p)?, p),
        None => {
            let source = Path::new(EMBEDDED_POLICY_SOURCE);
            (PolicyFile::from_json(source, EMBEDDED_POLICY)?, source)
        }
    };
    match &file.trained_on {
        Some(t) if !t.fits_step_length(dt) => Err(PolicyError::StepLength {
            path: source.to_path_buf(),
            trained: t.step_length_s,
            run: dt,
        }),
        _ => Ok(file),
    }
}

/// The networks of the policy at `path`, or of the embedded one, for a run of step length `dt`.
///
/// # Errors
/// As [`load_file`].
pub fn load(path: Option<&Path>, dt: f64) -> Result<ActorCritic, PolicyError> {
    load_file(path, dt).map(|f| f.networks())
}
