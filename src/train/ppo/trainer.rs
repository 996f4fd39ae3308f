//! `bkpbs train-rl`: PPO on SUMO episodes until a budget of environment steps (CAV decisions),
//! with a learning curve, checkpoints after every update, and resumption from the last one.
//!
//! Everything random derives from the seed and the update's number (the episodes' seeds, α and
//! λ, the action sampling, the minibatch shuffling), and rollouts come back in request order,
//! so a run is the same for a seed whatever the number of workers or threads, and a resumed
//! run continues exactly as an uninterrupted one.

use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::reward::RewardSettings;
use super::rollout::RolloutStats;
use super::update::{update, Optimiser, UpdateStats};
use super::workers::{Acting, Pool, PoolError, RolloutRequest};
use super::PpoSettings;
use crate::config::Config;
use crate::policy::model_file::{PolicyError, PolicyFile};
use crate::policy::network::ActorCritic;

/// What a training run is; stored in its checkpoint, so a resumed run keeps it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainSettings {
    /// Environment steps (CAV decisions) to train for.
    pub steps: u64,
    /// Seed of the initial weights, the action sampling and the minibatch shuffling.
    pub seed: u64,
    /// SUMO episodes per update.
    pub episodes_per_update: usize,
    /// α and λ of the training episodes, cycled (the paper's grid).
    pub alphas: Vec<f64>,
    /// Arrival rates λ (veh/h) of the training episodes, cycled more slowly than α.
    pub lambdas: Vec<f64>,
    /// First episode seed (far from the evaluation seeds 0…).
    pub seed_base: u64,
    /// PPO's hyper-parameters.
    pub ppo: PpoSettings,
    /// The reward's terms and weights.
    pub reward: RewardSettings,
    /// Train with one CAV among HDVs per episode (the paper's set-up) instead of every CAV.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub single_cav: bool,
}

impl Default for TrainSettings {
    fn default() -> Self {
        TrainSettings {
            steps: 10_000_000,
            seed: 1,
            episodes_per_update: 4,
            alphas: vec![0.4, 0.5, 0.6, 0.7, 0.8],
            lambdas: vec![2500.0, 3000.0],
            seed_base: 1_000_000,
            ppo: PpoSettings::default(),
            reward: RewardSettings::default(),
            single_cav: false,
        }
    }
}

/// One row of `learning_curve.csv`: the sampled episodes of one update and the update itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurveRow {
    /// Updates done, counting this one.
    pub update: u64,
    /// Environment steps after this update's episodes.
    pub env_steps: u64,
    /// Episodes sampled for this update.
    pub episodes: u64,
    /// Mean undiscounted return per CAV of those episodes.
    pub mean_return: f64,
    /// Share of their CAVs removed in a collision.
    pub collision_rate: f64,
    /// Mean CAV speed over their decisions (m/s).
    pub mean_speed: f64,
    /// Mean clipped-surrogate policy loss over the update's minibatches.
    pub policy_loss: f64,
    /// Mean squared error of the value network to the GAE returns.
    pub value_loss: f64,
    /// Mean entropy of the policy (nats).
    pub entropy: f64,
    /// Mean estimate of KL(old ‖ new) over the minibatches.
    pub approx_kl: f64,
    /// Share of policy samples whose probability ratio was clipped.
    pub clip_fraction: f64,
}

/// Everything needed to continue a run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Always `bkpbs-rl-checkpoint-1`: what the file is.
    pub format: String,
    /// What the run is (the budget `steps` may grow on resumption).
    pub settings: TrainSettings,
    /// The base scenario configuration of the episodes.
    pub config: Config,
    /// Updates done.
    pub updates: u64,
    /// Environment steps (CAV decisions) done.
    pub env_steps: u64,
    /// Wall time of the rollouts and updates so far (s).
    pub wall_s: f64,
    /// The policy network's weights.
    pub actor: Vec<f32>,
    /// The value network's weights.
    pub critic: Vec<f32>,
    /// Adam's state for both networks.
    pub optimiser: Optimiser,
    /// The learning curve so far, one row per update.
    pub curve: Vec<CurveRow>,
}

impl Checkpoint {
    /// The networks with the checkpoint's weights.
    pub fn networks(&self) -> ActorCritic {
        ActorCritic::with_params(self.actor.clone(), self.critic.clone())
    }

    /// Episode number `k` of a sequence (training or evaluation) with demand seed `seed`: α and
    /// λ cycled over the settings' grid, α fastest.
    pub fn episode(&self, k: u64, seed: u64) -> Config {
        let s = &self.settings;
        let (na, nl) = (s.alphas.len() as u64, s.lambdas.len() as u64);
        let mut c = self.config.clone();
        c.scenario.alpha = s.alphas[(k % na) as usize];
        c.scenario.lambda = s.lambdas[((k / na) % nl) as usize];
        c.scenario.seed = seed;
        c
    }
}

const CHECKPOINT_FORMAT: &str = "bkpbs-rl-checkpoint-1";

/// Why training stopped.
#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// The rollout workers failed.
    #[error(transparent)]
    Pool(#[from] PoolError),
    /// A policy file could not be written.
    #[error(transparent)]
    Policy(#[from] PolicyError),
    /// The checkpoint or the learning curve could not be written.
    #[error(transparent)]
    Write(#[from] crate::io::WriteError),
    /// The checkpoint exists but cannot be used: unreadable, not JSON, another format, or
    /// networks of other shapes than this build's.
    #[error("cannot read checkpoint {path}: {message}")]
    Checkpoint {
        /// The checkpoint file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The scenario configuration is invalid.
    #[error("{0}")]
    Config(#[from] crate::config::ConfigError),
    /// The checkpoint's settings or configuration differ from those given (the budget aside).
    #[error(
        "checkpoint {0} was made with other settings (seed, episodes per update or scenario \
         configuration): resume with the same ones, or train into another directory"
    )]
    OtherSettings(PathBuf),
    /// A file of the scenario could not be read for the policy's record of it.
    #[error(transparent)]
    Scenario(#[from] crate::sumo::sumocfg::SumoConfigError),
}

/// The files of a run directory.
pub struct RunFiles {
    /// The run directory.
    pub dir: PathBuf,
}

impl RunFiles {
    /// `checkpoint.json`: the [`Checkpoint`] after the last update.
    pub fn checkpoint(&self) -> PathBuf {
        self.dir.join("checkpoint.json")
    }
    /// `learning_curve.csv`: one [`CurveRow`] per update.
    pub fn curve(&self) -> PathBuf {
        self.dir.join("learning_curve.csv")
    }
    /// `timings.csv`: wall times of each update's rollouts and PPO step.
    pub fn timings(&self) -> PathBuf {
        self.dir.join("timings.csv")
    }
    /// `policy.json`: the trained policy.
    pub fn policy(&self) -> PathBuf {
        self.dir.join("policy.json")
    }
    /// The policy the workers act with during an update.
    pub fn acting(&self) -> PathBuf {
        self.dir.join("acting-policy.json")
    }
}

/// A resumed checkpoint's own consistency: weights as a policy file's (finite, bounded), one
/// learning-curve row per update, a finite wall time. An `updates = 1e18` or weights of 3e38
/// once passed and failed later without naming the file.
fn check_progress(ck: &Checkpoint) -> Result<(), String> {
    use crate::policy::model_file::{weights_in_range, MAX_WEIGHT};
    if !weights_in_range(ck.actor.iter().chain(&ck.critic)) {
        return Err(format!(
            "a weight is not a finite number of magnitude at most {MAX_WEIGHT:e}"
        ));
    }
    if ck.updates != ck.curve.len() as u64 {
        return Err(format!(
            "it counts {} updates but its learning curve has {} rows",
            ck.updates,
            ck.curve.len()
        ));
    }
    if !(ck.wall_s.is_finite() && ck.wall_s >= 0.0) {
        return Err(format!(
            "wall_s {} is not a finite, non-negative time",
            ck.wall_s
        ));
    }
    Ok(())
}

/// A fresh run's checkpoint, or the one in `files` when resuming.
pub fn start_or_resume(
    files: &RunFiles,
    settings: TrainSettings,
    config: Config,
) -> Result<Checkpoint, TrainError> {
    let path = files.checkpoint();
    if path.exists() {
        let bad = |message: String| TrainError::Checkpoint {
            path: path.clone(),
            message,
        };
        let text = crate::io::bounded::read_text(&path, crate::io::bounded::FileKind::Model)
            .map_err(|e| bad(e.to_string()))?;
        let mut ck: Checkpoint = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        if ck.format != CHECKPOINT_FORMAT {
            return Err(bad(format!("format '{}'", ck.format)));
        }
        let shape = ActorCritic::new(0);
        if ck.actor.len() != shape.actor.n_params || ck.critic.len() != shape.critic.n_params {
            return Err(bad(
                "its networks have other shapes than this build's".into()
            ));
        }
        check_progress(&ck).map_err(bad)?;
        ck.settings.steps = settings.steps; // the budget may be extended
        if ck.settings != settings || ck.config != config {
            return Err(TrainError::OtherSettings(path));
        }
        return Ok(ck);
    }
    config.validate()?;
    let net = ActorCritic::new(settings.seed);
    Ok(Checkpoint {
        format: CHECKPOINT_FORMAT.into(),
        optimiser: Optimiser::new(&net, settings.ppo.learning_rate),
        actor: net.actor_params,
        critic: net.critic_params,
        settings,
        config,
        updates: 0,
        env_steps: 0,
        wall_s: 0.0,
        curve: Vec::new(),
    })
}

/// The requests of update `u`: its episodes' α, λ, seeds and sampling seeds.
pub fn requests(ck: &Checkpoint, u: u64, policy: &Path) -> Vec<RolloutRequest> {
    let s = &ck.settings;
    (0..s.episodes_per_update)
        .map(|j| {
            let g = u * s.episodes_per_update as u64 + j as u64;
            RolloutRequest {
                index: j,
                config: ck.episode(g, s.seed_base + g),
                policy: policy.to_path_buf(),
                acting: Acting::Sample(mix(s.seed, g)),
                reward: s.reward.clone(),
                single_cav: s.single_cav,
            }
        })
        .collect()
}

/// A seed from two numbers (SplitMix64 of their combination).
pub fn mix(a: u64, b: u64) -> u64 {
    let mut z = a
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(b)
        .wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// How one update went, for progress lines and timings.
pub struct UpdateReport {
    /// The update's learning-curve row.
    pub row: CurveRow,
    /// Wall time of the update's rollouts (s).
    pub rollout_s: f64,
    /// Wall time of the PPO step on them (s).
    pub update_s: f64,
}

/// Runs one update: rollouts in the pool, then PPO on them; advances the checkpoint.
pub fn one_update(
    ck: &mut Checkpoint,
    pool: &mut Pool,
    files: &RunFiles,
) -> Result<UpdateReport, TrainError> {
    let u = ck.updates;
    let mut net = ck.networks();
    PolicyFile::of(&net, serde_json::Value::Null, None).write(&files.acting())?;
    let t0 = Instant::now();
    let rollouts = pool.run(requests(ck, u, &files.acting()))?;
    let rollout_s = t0.elapsed().as_secs_f64();
    let mut stats = RolloutStats::default();
    let mut segments = Vec::new();
    for r in rollouts {
        stats.add(&r.stats);
        segments.extend(r.segments);
    }
    let t1 = Instant::now();
    let mut rng = ChaCha8Rng::seed_from_u64(mix(ck.settings.seed ^ 0x5EED, u));
    let st: UpdateStats = update(
        &mut net,
        &mut ck.optimiser,
        &segments,
        &ck.settings.ppo,
        &mut rng,
    );
    let update_s = t1.elapsed().as_secs_f64();
    ck.actor = net.actor_params;
    ck.critic = net.critic_params;
    ck.updates += 1;
    ck.env_steps += stats.steps;
    ck.wall_s += rollout_s + update_s;
    let row = CurveRow {
        update: ck.updates,
        env_steps: ck.env_steps,
        episodes: stats.episodes,
        mean_return: stats.mean_return(),
        collision_rate: stats.collision_rate(),
        mean_speed: stats.mean_speed(),
        policy_loss: st.policy_loss,
        value_loss: st.value_loss,
        entropy: st.entropy,
        approx_kl: st.approx_kl,
        clip_fraction: st.clip_fraction,
    };
    ck.curve.push(row.clone());
    Ok(UpdateReport {
        row,
        rollout_s,
        update_s,
    })
}

/// Writes the checkpoint and the learning curve (atomically, each).
pub fn save(ck: &Checkpoint, files: &RunFiles) -> Result<(), TrainError> {
    let text = serde_json::to_string(ck).expect("a checkpoint serialises");
    crate::io::write_atomic(&files.checkpoint(), text.as_bytes())?;
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in &ck.curve {
        w.serialize(row).expect("a curve row serialises");
    }
    let bytes = w.into_inner().expect("in-memory CSV");
    crate::io::write_atomic(&files.curve(), &bytes)?;
    Ok(())
}

/// The trained policy file of a checkpoint, with its record of what it was trained on.
///
/// # Errors
/// A file of the scenario that cannot be read for the record.
pub fn policy_file(ck: &Checkpoint) -> Result<PolicyFile, TrainError> {
    let net = ck.networks();
    let training = serde_json::json!({
        "algorithm": "PPO (clipped, GAE), every CAV of an episode acting with the shared policy",
        "env_steps": ck.env_steps,
        "updates": ck.updates,
        "settings": ck.settings,
    });
    Ok(PolicyFile::of(&net, training, Some(trained_on(ck)?)))
}

/// What the checkpoint's episodes were: its scenario and step, the seeds of every training
/// episode so far, and the training seed.
fn trained_on(ck: &Checkpoint) -> Result<crate::config::TrainedOn, TrainError> {
    use crate::train::provenance::{of_episodes, seed_range};
    let s = &ck.settings;
    let episodes = ck.updates * s.episodes_per_update as u64;
    let mut r = of_episodes(&ck.config, seed_range(s.seed_base, episodes), episodes)?;
    r.training_seed = s.seed.to_string();
    Ok(r)
}
