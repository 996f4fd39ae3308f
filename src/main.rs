//! The `bkpbs` command line: parses, dispatches to the library, prints one error line on failure.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use bkpbs::config::{Config, PredictorKind};
use bkpbs::episode::{bench, demand, output};
use bkpbs::sumo::files as sumo_files;
use bkpbs::{campaign, report};
use bkpbs::{controller, episode, train};

#[derive(Parser)]
#[command(
    name = "bkpbs",
    version,
    about = "BK-PBS merge coordination co-simulated with SUMO"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run one episode and write episode.csv, vehicles.csv, collisions.csv and timing.csv.
    Episode(EpisodeArgs),
    /// Show the configuration (defaults = the paper's) or the SUMO vehicle types it implies.
    Config(ConfigArgs),
    /// Time SUMO alone against the same episode with controllers, side by side.
    Bench(BenchArgs),
    /// Write an episode's demand as a SUMO route file (e.g. to watch it in sumo-gui).
    Demand(DemandArgs),
    /// Run (or resume) the planners × α × λ × seeds grid in worker processes, then report.
    Campaign(CampaignArgs),
    /// Tables and figures from one or more campaign directories (several: shards, merged).
    Report(ReportArgs),
    /// Collect lane-change data for the predictor b_θ from SUMO episodes.
    Collect(CollectArgs),
    /// Train b_θ (and its logistic-regression baseline) on collected data.
    Train(TrainArgs),
    /// Evaluate b_θ like the paper's tables I–II, next to two baselines.
    EvalPredictor(EvalPredictorArgs),
    /// Time b_θ: one prediction, and all HDVs of a dense scene per step.
    BenchPredictor(BenchPredictorArgs),
    /// Internal: run episodes sent by a campaign on stdin (one JSON line each).
    #[command(hide = true)]
    Worker,
}

#[derive(Args)]
struct CampaignArgs {
    /// TOML file with a [campaign] table and optionally scenario settings.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Results directory; re-running the same command resumes it.
    #[arg(long)]
    out: PathBuf,
    /// Planners, comma-separated [default: all].
    #[arg(long)]
    planners: Option<String>,
    /// CAV penetrations α, comma-separated [default: 0.4,0.5,0.6,0.7,0.8].
    #[arg(long, allow_hyphen_values = true)]
    alphas: Option<String>,
    /// Arrival rates λ (veh/h), comma-separated [default: 2500,3000].
    #[arg(long, allow_hyphen_values = true)]
    lambdas: Option<String>,
    /// Seeds per cell [default: 5].
    #[arg(long)]
    seeds: Option<u64>,
    /// First seed [default: 0].
    #[arg(long)]
    seed_base: Option<u64>,
    /// Episode length in steps [default: 400].
    #[arg(long)]
    steps: Option<u32>,
    /// Worker processes [default: number of cores].
    #[arg(long)]
    workers: Option<usize>,
    /// Run only slice k of n (1-based; cell i of the grid belongs to slice i mod n + 1).
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
}

#[derive(Args)]
struct ReportArgs {
    /// Campaign directories (several are merged).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Where to write [default: the first directory].
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Writes a report and prints its tables and where the files are.
fn print_report(dirs: &[PathBuf], out: Option<&std::path::Path>) -> Result<()> {
    let r = report::run(dirs, out)?;
    print!("{}", r.markdown);
    println!(
        "results in {}: episodes.csv, vehicles.csv, timings.csv, failures.csv",
        r.out.display()
    );
    println!("tables and figures:");
    for p in report::highlights(&r) {
        println!("  {}", p.display());
    }
    Ok(())
}

/// Scenario flags shared by the subcommands that run SUMO; each overrides the config file.
#[derive(Args)]
struct ScenarioArgs {
    /// TOML file with settings; unset fields keep the paper's defaults.
    #[arg(long)]
    config: Option<PathBuf>,
    /// CAV penetration α in [0, 1].
    #[arg(long)]
    alpha: Option<f64>,
    /// Arrival rate λ (veh/h).
    #[arg(long = "lambda")]
    lambda: Option<f64>,
    /// Seed of the demand and of the HDVs' merge decisions.
    #[arg(long)]
    seed: Option<u64>,
    /// Episode length in steps (default 400 of 0.2 s).
    #[arg(long)]
    steps: Option<u32>,
    /// Network file to use instead of the embedded merge network.
    #[arg(long)]
    net: Option<PathBuf>,
    /// Let SUMO print its warnings.
    #[arg(long)]
    verbose: bool,
}

impl ScenarioArgs {
    /// The validated configuration: file (or defaults), then flags.
    fn resolve(&self) -> Result<Config> {
        let mut c = match &self.config {
            Some(p) => Config::from_file(p)?,
            None => Config::default(),
        };
        let s = &mut c.scenario;
        if let Some(a) = self.alpha {
            s.alpha = a;
        }
        if let Some(l) = self.lambda {
            s.lambda = l;
        }
        if let Some(seed) = self.seed {
            s.seed = seed;
        }
        if let Some(n) = self.steps {
            s.steps = n;
        }
        if let Some(n) = &self.net {
            s.net_file = Some(n.clone());
        }
        c.sumo.verbose |= self.verbose;
        c.validate()?;
        Ok(c)
    }
}

#[derive(Args)]
struct EpisodeArgs {
    /// Controller of the CAVs: sumo, idm-mobil, bk-mastar or bk-pbs.
    #[arg(long, default_value = "bk-pbs")]
    planner: String,
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Directory for the CSV files [default: out/<planner>_a<α>_l<λ>_s<seed>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// HDV predictor of the planners (overrides predictor.kind of the config).
    #[arg(long, value_parser = ["learned", "constant"])]
    predictor: Option<String>,
}

#[derive(Args)]
struct CollectArgs {
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
    #[arg(long, value_delimiter = ',')]
    alphas: Option<Vec<f64>>,
    /// Arrival rates λ (veh/h), cycled [default: 2500,3000].
    #[arg(long = "lambdas", value_delimiter = ',')]
    lambdas: Option<Vec<f64>>,
    /// Episode length in steps [default: 400].
    #[arg(long)]
    steps: Option<u32>,
    /// Probability of keeping a main-road sample without a lane change [default: 0.1].
    #[arg(long)]
    main_negative_keep: Option<f64>,
    /// TOML file with scenario settings (α, λ, seed and steps are set per episode).
    #[arg(long)]
    config: Option<PathBuf>,
}

#[derive(Args)]
struct TrainArgs {
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

#[derive(Args)]
struct EvalPredictorArgs {
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
    /// Fresh evaluation episodes to collect.
    #[arg(long, default_value_t = 500, conflicts_with = "data")]
    episodes: usize,
    /// Seed of the draw of the 4000 + 4000 samples.
    #[arg(long, default_value_t = 1)]
    draw_seed: u64,
}

#[derive(Args)]
struct BenchPredictorArgs {
    #[command(flatten)]
    scenario: ScenarioArgs,
}

#[derive(Args)]
struct ConfigArgs {
    /// Print the full configuration as TOML.
    #[arg(long, conflicts_with = "vtypes")]
    print: bool,
    /// Print the SUMO vehicle-type file the configuration implies.
    #[arg(long)]
    vtypes: bool,
    /// Start from this file instead of the defaults.
    #[arg(long)]
    config: Option<PathBuf>,
}

#[derive(Args)]
struct BenchArgs {
    /// Controllers to time next to SUMO alone.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "sumo,idm-mobil,bk-mastar,bk-pbs"
    )]
    planners: Vec<String>,
    /// Repeats per row (medians are reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    #[command(flatten)]
    scenario: ScenarioArgs,
}

#[derive(Args)]
struct DemandArgs {
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Route file to write.
    #[arg(long)]
    out: PathBuf,
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Episode(a) => {
            let mut config = a.scenario.resolve()?;
            if let Some(p) = &a.predictor {
                config.predictor.kind = match p.as_str() {
                    "learned" => PredictorKind::Learned,
                    _ => PredictorKind::Constant,
                };
            }
            controller::check(&a.planner, &config)?;
            let s = &config.scenario;
            let out = a.out.unwrap_or_else(|| {
                PathBuf::from(format!(
                    "out/{}_a{}_l{}_s{}",
                    a.planner, s.alpha, s.lambda, s.seed
                ))
            });
            let result = episode::run(&config, &a.planner)?;
            result.write(&out).with_context(|| {
                format!(
                    "episode finished but its results could not be saved in {}",
                    out.display()
                )
            })?;
            let m = &result.summary;
            println!(
                "{} α={} λ={} seed={}: inserted {}, arrived {}, crashed {} (controllable rate {:.4}), mean delay {} s",
                m.planner,
                m.alpha,
                m.lambda,
                m.seed,
                m.inserted,
                m.arrived,
                m.crashed,
                m.controllable_collision_rate,
                m.mean_delay_s.map_or("n/a".into(), |d| format!("{d:.2}"))
            );
            println!("results: {}", out.join("episode.csv").display());
        }
        Command::Config(a) => {
            let config = match &a.config {
                Some(p) => Config::from_file(p)?,
                None => Config::default(),
            };
            if a.vtypes {
                print!("{}", sumo_files::vehicle_types(&config));
            } else {
                print!("{}", config.to_toml());
            }
        }
        Command::Demand(a) => {
            let config = a.scenario.resolve()?;
            let planned = demand::generate(&config);
            output::write_atomic(&a.out, demand::route_file(&planned).as_bytes())?;
            println!("{} vehicles written to {}", planned.len(), a.out.display());
        }
        Command::Bench(a) => {
            let config = a.scenario.resolve()?;
            for p in &a.planners {
                controller::check(p, &config)?;
            }
            let s = &config.scenario;
            println!(
                "bench: α={} λ={} seed={} steps={} repeats={}",
                s.alpha, s.lambda, s.seed, s.steps, a.repeats
            );
            let rows = bench::run(&config, &a.planners, a.repeats)?;
            print!("{}", bench::table(&rows));
        }
        Command::Campaign(a) => {
            let settings = campaign::Settings::resolve(
                a.config.as_deref(),
                &campaign::Overrides {
                    planners: a.planners,
                    alphas: a.alphas,
                    lambdas: a.lambdas,
                    seeds: a.seeds,
                    seed_base: a.seed_base,
                    steps: a.steps,
                    workers: a.workers,
                    shard: a.shard,
                },
            )?;
            let exe = std::env::current_exe().context("cannot locate the bkpbs binary")?;
            let done = campaign::run(&settings, &a.out, &exe)?;
            if done.collected > 0 {
                print_report(std::slice::from_ref(&a.out), None)?;
            }
            if done.failed > 0 {
                anyhow::bail!(
                    "{} of {} episodes failed (see {})",
                    done.failed,
                    done.shard,
                    a.out.join("failures.csv").display()
                );
            }
        }
        Command::Report(a) => print_report(&a.dirs, a.out.as_deref())?,
        Command::Collect(a) => {
            let base = match &a.config {
                Some(p) => Config::from_file(p)?,
                None => Config::default(),
            };
            let d = train::collect::CollectPlan::default();
            let plan = train::collect::CollectPlan {
                episodes: a.episodes,
                seed_base: a.seed_base.unwrap_or(d.seed_base),
                planners: a.planners.unwrap_or(d.planners),
                alphas: a.alphas.unwrap_or(d.alphas),
                lambdas: a.lambdas.unwrap_or(d.lambdas),
                steps: a.steps.unwrap_or(d.steps),
                main_negative_keep: a.main_negative_keep.unwrap_or(d.main_negative_keep),
            };
            print!("{}", train::commands::run_collect(&base, &plan, &a.out)?);
        }
        Command::Train(a) => {
            let opts = train::train::TrainOptions {
                epochs: a.epochs,
                seed: a.seed,
                threads: a.threads,
                patience: a.patience,
                ..Default::default()
            };
            let conditioned = !a.unconditioned;
            print!(
                "{}",
                train::commands::run_train(&a.data, &a.out, conditioned, &opts)?
            );
        }
        Command::EvalPredictor(a) => {
            let data = match a.data {
                Some(p) => train::commands::EvalData::File(p),
                None => train::commands::EvalData::fresh(a.episodes, a.seed_base),
            };
            let r = train::commands::run_eval(
                &Config::default(),
                a.model.as_deref(),
                a.unconditioned,
                &data,
                a.draw_seed,
            )?;
            print!("{}", r.to_text());
        }
        Command::BenchPredictor(a) => {
            let config = a.scenario.resolve()?;
            print!("{}", train::commands::run_bench(&config)?);
        }
        Command::Worker => campaign::worker::serve_stdio()?,
    }
    Ok(())
}

fn main() -> ExitCode {
    // Die quietly on a closed pipe (`bkpbs … | head`), as command-line tools do.
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
