//! The predictor b_θ's subcommands: `collect` data, `train` on it, `eval-predictor` and
//! `bench-predictor`.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use bkpbs::config::Config;
use bkpbs::train::collect::CollectPlan;
use bkpbs::train::commands::{self, EvalData};
use bkpbs::train::training_loop::TrainOptions;

use super::scenario::{load_config, ScenarioArgs};

#[derive(Args)]
pub struct CollectArgs {
    /// Episodes to run.
    #[arg(long)]
    episodes: usize,
    /// Data file to write (e.g. data/train.bin).
    #[arg(long)]
    out: PathBuf,
    /// First seed [default: 10000].
    #[arg(long)]
    seed_base: Option<u64>,
    /// CAV rollout policies, cycled over the episodes [default: idm-mobil,bk-mastar].
    #[arg(long, value_delimiter = ',')]
    planners: Option<Vec<String>>,
    /// CAV penetrations α, cycled [default: 0.2,0.4,0.6,0.8].
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    alphas: Option<Vec<f64>>,
    /// Arrival rates λ (veh/h), cycled [default: 2500,3000].
    #[arg(long = "lambdas", value_delimiter = ',', allow_hyphen_values = true)]
    lambdas: Option<Vec<f64>>,
    /// Episode length in steps [default: 400].
    #[arg(long)]
    steps: Option<u32>,
    /// Probability of keeping a main-road sample without a lane change [default: 0.1].
    #[arg(long, allow_negative_numbers = true)]
    main_negative_keep: Option<f64>,
    /// TOML file with scenario settings (α, λ, seed and steps are set per episode).
    #[arg(long)]
    config: Option<PathBuf>,
    /// HDV driver profile of the episodes (overrides the config's hdv.profile).
    #[arg(long, value_name = "NAME")]
    hdv_profile: Option<String>,
    /// SUMO network of the episodes (overrides the config's scenario.net_file).
    #[arg(long, value_name = "FILE", conflicts_with = "sumocfg")]
    net: Option<PathBuf>,
    /// A SUMO configuration of your own (.sumocfg): its routes are the episodes' demand (no
    /// --lambdas) and each merge region's scenes give samples.
    #[arg(long, value_name = "FILE", conflicts_with = "lambdas")]
    sumocfg: Option<PathBuf>,
}

/// A checked collection: the base configuration, the episodes' plan and the data file.
pub struct Collect {
    base: Config,
    plan: CollectPlan,
    out: PathBuf,
}

impl CollectArgs {
    /// Loads the base configuration and fills the plan's unset flags with the library defaults.
    pub fn resolve(self) -> Result<Collect> {
        let (profile, net, sumocfg) = (self.hdv_profile, self.net, self.sumocfg);
        let base = load_config(self.config.as_deref(), |c| {
            if let Some(p) = profile {
                c.hdv.profile = p;
            }
            if net.is_some() {
                c.scenario.net_file = net;
            }
            if sumocfg.is_some() {
                c.scenario.sumocfg = sumocfg;
            }
        })?;
        // A scenario's routes are its demand: no λ.
        let own_demand = base.scenario.sumocfg.is_some();
        bkpbs::sumo::frame::scenario_road(&base.scenario)?;
        let d = CollectPlan::default();
        let plan = CollectPlan {
            episodes: self.episodes,
            seed_base: self.seed_base.unwrap_or(d.seed_base),
            planners: self.planners.unwrap_or(d.planners),
            alphas: self.alphas.unwrap_or(d.alphas),
            lambdas: match own_demand {
                true => Vec::new(),
                false => self.lambdas.unwrap_or(d.lambdas),
            },
            steps: self.steps.unwrap_or(d.steps),
            main_negative_keep: self.main_negative_keep.unwrap_or(d.main_negative_keep),
        };
        Ok(Collect {
            base,
            plan,
            out: self.out,
        })
    }
}

/// Runs the plan's episodes, writes the data file and prints what it holds.
pub fn collect(c: Collect) -> Result<()> {
    print!("{}", commands::run_collect(&c.base, &c.plan, &c.out)?);
    Ok(())
}

#[derive(Args)]
pub struct TrainArgs {
    /// Data file from `bkpbs collect`.
    #[arg(long)]
    data: PathBuf,
    /// Model file to write (JSON).
    #[arg(long)]
    out: PathBuf,
    /// Train the conditioned model (with the CAV-trajectory input); the default.
    #[arg(long, conflicts_with = "unconditioned")]
    conditioned: bool,
    /// Train the unconditioned model (BK-M-A*, the PBS root).
    #[arg(long)]
    unconditioned: bool,
    /// Most epochs (early stopping on the validation split usually ends sooner).
    #[arg(long, default_value_t = 40)]
    epochs: usize,
    /// Seed of the initialisation and the shuffling.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (results do not depend on it).
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Epochs without a better validation loss before stopping.
    #[arg(long, default_value_t = 5)]
    patience: usize,
}

/// A training run: which model, from which data, with which options.
pub struct Training {
    data: PathBuf,
    out: PathBuf,
    conditioned: bool,
    options: TrainOptions,
}

impl TrainArgs {
    /// Refuses a thread count of 0 or beyond the machine's (clap already refuses
    /// `--conditioned` with `--unconditioned`).
    pub fn resolve(self) -> Result<Training> {
        bkpbs::io::cores::check("--threads", self.threads).map_err(anyhow::Error::msg)?;
        Ok(Training {
            data: self.data,
            out: self.out,
            conditioned: !self.unconditioned,
            options: TrainOptions {
                epochs: self.epochs,
                seed: self.seed,
                threads: self.threads,
                patience: self.patience,
                ..Default::default()
            },
        })
    }
}

/// Trains, writes the model file and prints the training log.
pub fn train(t: Training) -> Result<()> {
    let log = commands::run_train(&t.data, &t.out, t.conditioned, &t.options)?;
    print!("{log}");
    Ok(())
}

#[derive(Args)]
pub struct EvalPredictorArgs {
    /// Model file [default: the embedded conditioned model].
    #[arg(long)]
    model: Option<PathBuf>,
    /// Without --model: evaluate the embedded unconditioned model instead.
    #[arg(long, conflicts_with = "model")]
    unconditioned: bool,
    /// Data file from `bkpbs collect` [default: collect fresh episodes].
    #[arg(long)]
    data: Option<PathBuf>,
    /// First seed of fresh evaluation episodes [default: 90000, never used in training].
    #[arg(long, conflicts_with = "data")]
    seed_base: Option<u64>,
    /// Fresh evaluation episodes to collect (at least 1).
    #[arg(long, default_value_t = 500, conflicts_with = "data",
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    episodes: usize,
    /// Seed of the draw of the 4000 + 4000 samples.
    #[arg(long, default_value_t = 1)]
    draw_seed: u64,
    /// Fresh evaluation episodes on a SUMO configuration of your own (.sumocfg), its routes
    /// their demand [default: the paper's merge and demand].
    #[arg(long, value_name = "FILE", conflicts_with = "data")]
    sumocfg: Option<PathBuf>,
}

/// An evaluation: which model on which data.
pub struct Evaluation {
    base: Config,
    model: Option<PathBuf>,
    unconditioned: bool,
    data: EvalData,
    draw_seed: u64,
}

impl EvalPredictorArgs {
    /// The evaluation's configuration (the paper's, or its scenario of your own, checked) and
    /// data.
    pub fn resolve(self) -> Result<Evaluation> {
        let mut base = Config::default();
        if let Some(cfg) = self.sumocfg {
            base.scenario.sumocfg = Some(cfg);
            bkpbs::sumo::frame::scenario_road(&base.scenario)?;
        }
        let data = match self.data {
            Some(p) => EvalData::File(p),
            None => {
                let own_demand = base.scenario.sumocfg.is_some();
                EvalData::fresh(self.episodes, self.seed_base, own_demand)
            }
        };
        Ok(Evaluation {
            base,
            model: self.model,
            unconditioned: self.unconditioned,
            data,
            draw_seed: self.draw_seed,
        })
    }
}

/// Evaluates the model on the paper's default scenario (or the one given) and prints the
/// tables.
pub fn eval_predictor(e: Evaluation) -> Result<()> {
    let report = commands::run_eval(
        &e.base,
        e.model.as_deref(),
        e.unconditioned,
        &e.data,
        e.draw_seed,
    )?;
    print!("{}", report.to_text());
    Ok(())
}

#[derive(Args)]
pub struct BenchPredictorArgs {
    #[command(flatten)]
    scenario: ScenarioArgs,
}

impl BenchPredictorArgs {
    /// The benchmark episode's configuration.
    pub fn resolve(&self) -> Result<Config> {
        self.scenario.resolve()
    }
}

/// Times the learned predictor on the configured scenario and prints the timings.
pub fn bench_predictor(config: Config) -> Result<()> {
    print!("{}", commands::run_bench(&config)?);
    Ok(())
}
