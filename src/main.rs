//! The `bkpbs` command line: parses, dispatches to the library, prints one error line on failure.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use bkpbs::config::Config;
use bkpbs::{bench, controller, demand, episode, output, sumo_files};

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
    /// Controller of the CAVs (one of: sumo, idm-mobil).
    #[arg(long, default_value = "idm-mobil")]
    planner: String,
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Directory for the CSV files [default: out/<planner>_a<α>_l<λ>_s<seed>].
    #[arg(long)]
    out: Option<PathBuf>,
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
        default_value = "sumo,idm-mobil,bk-mastar"
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
            let config = a.scenario.resolve()?;
            let mut ctl = controller::by_name(&a.planner, &config)?;
            let s = &config.scenario;
            let out = a.out.unwrap_or_else(|| {
                PathBuf::from(format!(
                    "out/{}_a{}_l{}_s{}",
                    a.planner, s.alpha, s.lambda, s.seed
                ))
            });
            let result = episode::run(&config, ctl.as_mut())?;
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
                controller::by_name(p, &config)?;
            }
            let s = &config.scenario;
            println!(
                "bench: α={} λ={} seed={} steps={} repeats={}",
                s.alpha, s.lambda, s.seed, s.steps, a.repeats
            );
            let rows = bench::run(&config, &a.planners, a.repeats)?;
            print!("{}", bench::table(&rows));
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
