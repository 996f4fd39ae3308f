//! `bkpbs train-rl`: train the RL-PPO policy on SUMO episodes (resumable), then compare it with
//! a random and an idle policy on held-out episodes.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use bkpbs::config::Config;
use bkpbs::train::ppo::evaluate;
use bkpbs::train::ppo::rollout::RolloutStats;
use bkpbs::train::ppo::trainer::{self, Checkpoint, RunFiles, TrainSettings};
use bkpbs::train::ppo::workers::{Pool, PoolError};

use super::scenario::{check_own_scenario, load_config};

#[derive(Args)]
pub struct TrainRlArgs {
    /// Run directory: checkpoint.json, learning_curve.csv/.png, policy.json, evaluation.csv.
    /// Re-running the same command resumes from the checkpoint.
    #[arg(long)]
    out: PathBuf,
    /// Environment steps (CAV decisions) to train for; a larger value extends a finished run.
    #[arg(long, default_value_t = 10_000_000)]
    steps: u64,
    /// Seed of the initial weights, the episodes and the sampling.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Train with one CAV among HDVs per episode (the paper's "single CAV environment")
    /// instead of every CAV acting with the shared policy; about one decision per SUMO step.
    #[arg(long)]
    single_cav: bool,
    /// SUMO episodes per PPO update.
    #[arg(long, default_value_t = 4)]
    episodes_per_update: usize,
    /// Worker processes running the episodes [default: number of cores].
    #[arg(long)]
    workers: Option<usize>,
    /// Threads of the PPO update (the result does not depend on it) [default: number of cores].
    #[arg(long)]
    threads: Option<usize>,
    /// Held-out episodes (seeds 0, 1, …, α and λ cycled over the paper's grid) on which the
    /// trained, a random and an idle policy are compared at the end (0: none).
    #[arg(long, default_value_t = 20)]
    eval_episodes: u64,
    /// TOML file with scenario settings (α, λ and seed are set per episode).
    #[arg(long)]
    config: Option<PathBuf>,
    /// A SUMO configuration of your own (.sumocfg; overrides the config's scenario.sumocfg):
    /// train on its routes and vehicle types, every merge region's CAVs acting (α and the
    /// seed set per episode; λ does not apply).
    #[arg(long, value_name = "FILE")]
    sumocfg: Option<PathBuf>,
}

/// The most SUMO episodes per PPO update.
const MAX_EPISODES_PER_UPDATE: usize = 1000;
/// The most held-out evaluation episodes.
const MAX_EVAL_EPISODES: u64 = 100_000;

/// A checked training run.
pub struct TrainRl {
    files: RunFiles,
    settings: TrainSettings,
    config: Config,
    workers: usize,
    eval_episodes: u64,
}

impl TrainRlArgs {
    pub fn resolve(self) -> Result<TrainRl> {
        let sumocfg = self.sumocfg;
        let config = load_config(self.config.as_deref(), |c| {
            if sumocfg.is_some() {
                c.scenario.sumocfg = sumocfg;
            }
        })?;
        // Read before any worker starts: a bad scenario is one line, not a failed rollout.
        check_own_scenario(&config)?;
        if self.steps == 0 || self.episodes_per_update == 0 {
            anyhow::bail!("--steps and --episodes-per-update must be positive");
        }
        // Each episode of an update keeps its rollout in memory until the update, and each
        // held-out episode is set up before the first runs: beyond these a run would only
        // exhaust memory (the paper uses 4 and 20).
        if self.episodes_per_update > MAX_EPISODES_PER_UPDATE {
            anyhow::bail!(
                "--episodes-per-update {}: at most {MAX_EPISODES_PER_UPDATE} (every rollout of \
                 an update is held in memory)",
                self.episodes_per_update
            );
        }
        if self.eval_episodes > MAX_EVAL_EPISODES {
            anyhow::bail!(
                "--eval-episodes {}: at most {MAX_EVAL_EPISODES}",
                self.eval_episodes
            );
        }
        let cores = bkpbs::io::cores::available();
        let threads = self.threads.unwrap_or(cores);
        bkpbs::io::cores::check("--threads", threads).map_err(anyhow::Error::msg)?;
        if let Some(w) = self.workers {
            bkpbs::io::cores::check("--workers", w).map_err(anyhow::Error::msg)?;
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .context("cannot start the update threads")?;
        bkpbs::io::ensure_writable_dir(&self.out)?;
        Ok(TrainRl {
            files: RunFiles { dir: self.out },
            settings: TrainSettings {
                steps: self.steps,
                seed: self.seed,
                episodes_per_update: self.episodes_per_update,
                single_cav: self.single_cav,
                ..TrainSettings::default()
            },
            config,
            workers: self.workers.unwrap_or(cores),
            eval_episodes: self.eval_episodes,
        })
    }
}

/// Trains to the budget (or resumes), writes the policy and the curve, evaluates.
pub fn run(t: TrainRl) -> Result<()> {
    let mut ck = trainer::start_or_resume(&t.files, t.settings.clone(), t.config.clone())?;
    let mut pool = Pool::start(t.workers)?;
    if ck.updates > 0 {
        eprintln!(
            "train-rl: resuming after update {} ({} steps)",
            ck.updates, ck.env_steps
        );
    }
    while ck.env_steps < ck.settings.steps {
        match trainer::one_update(&mut ck, &mut pool, &t.files) {
            Ok(report) => {
                trainer::save(&ck, &t.files)?;
                log_update(&t.files, &ck, &report)?;
            }
            Err(trainer::TrainError::Pool(PoolError::Interrupted(signal))) => {
                eprintln!(
                    "train-rl: stopped; {} updates kept in {} (the same command resumes)",
                    ck.updates,
                    t.files.checkpoint().display()
                );
                anyhow::bail!("interrupted by {}", bkpbs::io::interrupt::name(signal));
            }
            Err(e) => return Err(e.into()),
        }
    }
    finish(&t, &ck, &mut pool)
}

/// A progress line and a `timings.csv` row (wall times differ run to run, so they stay out of
/// the learning curve).
fn log_update(files: &RunFiles, ck: &Checkpoint, r: &trainer::UpdateReport) -> Result<()> {
    let rate = ck.env_steps as f64 / ck.wall_s.max(1e-9);
    let left = ck.settings.steps.saturating_sub(ck.env_steps) as f64 / rate.max(1e-9);
    eprintln!(
        "train-rl: update {} | {} steps ({:.1} %) | return {:.2} | collisions {:.2} % | speed {:.1} m/s | {:.0} steps/s (rollout {:.1} s, update {:.1} s) | {:.0} min left",
        ck.updates,
        ck.env_steps,
        100.0 * ck.env_steps as f64 / ck.settings.steps as f64,
        r.row.mean_return,
        100.0 * r.row.collision_rate,
        r.row.mean_speed,
        rate,
        r.rollout_s,
        r.update_s,
        left / 60.0
    );
    let path = files.timings();
    let new = !path.exists();
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    if new {
        writeln!(f, "update,env_steps,rollout_s,update_s")?;
    }
    writeln!(
        f,
        "{},{},{:.3},{:.3}",
        ck.updates, ck.env_steps, r.rollout_s, r.update_s
    )?;
    Ok(())
}

/// Writes the policy, evaluates it, and draws the learning curve with the reference levels.
fn finish(t: &TrainRl, ck: &Checkpoint, pool: &mut Pool) -> Result<()> {
    trainer::policy_file(ck)?.write(&t.files.policy())?;
    println!(
        "policy: {} ({} steps, {} updates, {:.0} s of training)",
        t.files.policy().display(),
        ck.env_steps,
        ck.updates,
        ck.wall_s
    );
    let rows = if t.eval_episodes == 0 {
        Vec::new()
    } else {
        evaluate_policy(t, ck, pool)?
    };
    let fig = bkpbs::report::learning_curve::figure(&ck.curve, &rows).render()?;
    bkpbs::io::write_atomic(&t.files.dir.join("learning_curve.png"), &fig.png)?;
    bkpbs::io::write_atomic(&t.files.dir.join("learning_curve.svg"), fig.svg.as_bytes())?;
    Ok(())
}

/// The trained, a random and an idle policy on the held-out episodes: `evaluation.csv`.
fn evaluate_policy(
    t: &TrainRl,
    ck: &Checkpoint,
    pool: &mut Pool,
) -> Result<Vec<(&'static str, RolloutStats)>> {
    let s = &ck.settings;
    let configs: Vec<Config> = (0..t.eval_episodes).map(|k| ck.episode(k, k)).collect();
    let rows = evaluate::compare(pool, &t.files.policy(), &configs, &s.reward)?;
    let text = evaluation_csv(&rows);
    bkpbs::io::write_atomic(&t.files.dir.join("evaluation.csv"), text.as_bytes())?;
    print!("{text}");
    Ok(rows)
}

fn evaluation_csv(rows: &[(&str, RolloutStats)]) -> String {
    let mut out = String::from("policy,episodes,cavs,mean_return,collision_rate,mean_speed_mps\n");
    for (name, s) in rows {
        out.push_str(&format!(
            "{name},{},{},{:.4},{:.5},{:.3}\n",
            s.episodes,
            s.agents,
            s.mean_return(),
            s.collision_rate(),
            s.mean_speed()
        ));
    }
    out
}
