//! `bkpbs campaign` and its hidden `worker`: the grid of episodes run in worker processes.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use bkpbs::campaign::{self, Overrides, Settings};
use bkpbs::config::TrajectoryFormat;
use bkpbs::report::episode_plots;

use super::report::print_report;
use super::scenario::TrajectoryArgs;

#[derive(Args)]
pub struct CampaignArgs {
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
    /// Scenarios of your own (.sumocfg), comma-separated: a campaign over them (planners ×
    /// scenarios × α × seeds; each brings its demand, and runs its own interval unless --steps).
    #[arg(long, value_name = "FILES")]
    sumocfg: Option<String>,
    /// Arrival rates λ (veh/h), comma-separated [default: 2500,3000].
    #[arg(long, allow_hyphen_values = true)]
    lambdas: Option<String>,
    /// HDV driver profiles, comma-separated: a grid axis [default: the config's hdv.profile,
    /// sumo-safe].
    #[arg(long, value_name = "NAMES")]
    hdv_profiles: Option<String>,
    /// HDV predictors of the planners, comma-separated (learned, constant): a grid axis; the
    /// report then compares `bk-pbs+learned` with `bk-pbs+constant` [default: the config's
    /// predictor.kind, no axis].
    #[arg(long, value_name = "NAMES")]
    predictors: Option<String>,
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
    /// Wall-clock limit of one episode in seconds; a longer one is stopped and recorded in
    /// failures.csv [default: none].
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    episode_timeout: Option<f64>,
    #[command(flatten)]
    trajectories: TrajectoryArgs,
    /// Also draw each finished cell's time–space diagram and speed field (`bkpbs plot`);
    /// implies --trajectories.
    #[arg(long)]
    plots: bool,
}

/// A checked campaign: the grid, shard and scenario settings, and where results go.
pub struct Campaign {
    settings: Box<Settings>,
    out: PathBuf,
    plots: bool,
}

impl CampaignArgs {
    /// Resolves the file and the flags through the library, which parses the list flags itself
    /// so that its errors name the flag.
    pub fn resolve(self) -> Result<Campaign> {
        let overrides = Overrides {
            planners: self.planners,
            alphas: self.alphas,
            lambdas: self.lambdas,
            hdv_profiles: self.hdv_profiles,
            predictors: self.predictors,
            seeds: self.seeds,
            seed_base: self.seed_base,
            steps: self.steps,
            workers: self.workers,
            shard: self.shard,
            episode_timeout: self.episode_timeout,
            trajectories: self
                .trajectories
                .format()
                .or(self.plots.then_some(TrajectoryFormat::Csv)),
            sumocfg: self.sumocfg,
        };
        let settings = Settings::resolve(self.config.as_deref(), &overrides)?;
        if self.plots && settings.config.output.trajectories != TrajectoryFormat::Csv {
            anyhow::bail!(
                "--plots draws from trajectories.csv: it needs --trajectories-format csv"
            );
        }
        Ok(Campaign {
            settings: Box::new(settings),
            out: self.out,
            plots: self.plots,
        })
    }
}

/// Runs the shard with workers of this very binary, reports what was collected, and fails if
/// any episode failed (after the report, so the finished ones are not lost from view).
pub fn run(c: Campaign) -> Result<()> {
    let exe = std::env::current_exe().context("cannot locate the bkpbs binary")?;
    let s = c.settings.as_ref();
    say_before_the_run(s)?;
    let done = campaign::run(s, &c.out, &exe)?;
    if done.collected > 0 {
        print_report(std::slice::from_ref(&c.out), None, false, &[])?;
    }
    if c.plots && done.interrupted.is_none() {
        let drawn = episode_plots::plot_cells(&c.out, s)?;
        println!(
            "plots: time–space diagram and speed field of {} cells (in each cell's directory){}",
            drawn.plotted,
            match drawn.without_trajectories {
                0 => String::new(),
                n => format!("; {n} cells finished earlier without trajectories are not drawn"),
            }
        );
    }
    if let Some(signal) = done.interrupted {
        anyhow::bail!(
            "interrupted by {}: {} of {} episodes of this shard finished (see {}); rerun the same command to resume",
            bkpbs::io::interrupt::name(signal),
            done.shard - done.failed,
            done.shard,
            c.out.join("episodes.csv").display()
        );
    }
    if done.failed > 0 {
        anyhow::bail!(
            "{} of {} episodes failed (see {})",
            done.failed,
            done.shard,
            c.out.join("failures.csv").display()
        );
    }
    Ok(())
}

/// Before the run, for each scenario of the campaign (the paper's demand: its one): one line
/// per merge region left to SUMO's drivers, as an episode on it says at its start (its results
/// are SUMO's own there), and the warnings of learned files trained on another scenario.
fn say_before_the_run(s: &Settings) -> Result<()> {
    let scenarios: Vec<Option<&std::path::PathBuf>> = match s.table.scenarios.is_empty() {
        true => vec![None],
        false => s.table.scenarios.iter().map(Some).collect(),
    };
    for cfg in scenarios {
        let mut config = s.config.clone();
        if let Some(cfg) = cfg {
            config.scenario.sumocfg = Some(cfg.clone());
            for line in bkpbs::sumo::frame::scenario_left_to_sumo(&config.scenario)? {
                println!("campaign: {}: {line}", cfg.display());
            }
        }
        say_model_warnings(&config, &s.table.planners);
    }
    Ok(())
}

/// The warnings of learned files the `planners` use under `config` that were trained on
/// another scenario, each once, before the campaign runs (its episodes print none), on
/// stdout with the campaign's other lines (stderr is for its one `error:` line).
fn say_model_warnings(config: &bkpbs::config::Config, planners: &[String]) {
    let mut said = std::collections::BTreeSet::new();
    for planner in planners {
        // A file that cannot be used is reported when its episodes build the planner.
        let used = bkpbs::episode::models_used::models_used(config, planner).unwrap_or_default();
        for line in bkpbs::episode::models_used::other_scenario_warnings(config, &used) {
            if said.insert(line.clone()) {
                println!("campaign: {line}");
            }
        }
    }
}

/// Serves a campaign's episode requests on stdin until it closes.
pub fn worker() -> Result<()> {
    campaign::worker::serve_stdio()?;
    Ok(())
}
