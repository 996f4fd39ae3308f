//! The subcommands of the `bkpbs` binary, each in two stages: its clap flags are resolved into
//! checked options (bad values and combinations stop there, before any work), then one short
//! function runs it through the library. `main.rs` only parses and dispatches.

pub mod bench;
pub mod calibrate;
pub mod campaign;
pub mod config;
pub mod demand;
pub mod episode;
pub mod explain;
pub mod network;
pub mod plot;
pub mod report;
pub mod scenario;
pub mod train;
pub mod train_rl;

use clap::{Parser, Subcommand};

/// The whole command line.
#[derive(Parser)]
#[command(
    name = "bkpbs",
    // The commit it was built from and the SUMO it was built against (and will run: another
    // is refused).
    version = concat!(
        env!("CARGO_PKG_VERSION"),
        " (commit ",
        env!("BKPBS_COMMIT"),
        ", SUMO ",
        env!("BKPBS_SUMO_VERSION"),
        ")"
    ),
    about = "BK-PBS merge coordination co-simulated with SUMO"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// One variant per subcommand; the doc comments are the help texts clap shows.
#[derive(Subcommand)]
pub enum Command {
    /// Run one episode and write episode.csv, vehicles.csv, collisions.csv and timing.csv
    /// (and trace.jsonl with --trace, trajectories.csv with --trajectories).
    Episode(episode::EpisodeArgs),
    /// Tell the story of each collision of a traced episode (`episode --trace`), step by step.
    Explain(explain::ExplainArgs),
    /// Draw an episode's time–space diagram and speed field (from `episode --trajectories`).
    Plot(plot::PlotArgs),
    /// The merge layout found in a SUMO network: main carriageway, on-ramps with their
    /// acceleration lanes, off-ramps (what `--net` of episode, campaign and bench will run).
    Network(network::NetworkArgs),
    /// Show the configuration (defaults = the paper's) or the SUMO vehicle types it implies.
    Config(config::ConfigArgs),
    /// Time SUMO alone against the same episode with controllers, side by side.
    Bench(bench::BenchArgs),
    /// Write an episode's demand as a SUMO route file (e.g. to watch it in sumo-gui).
    Demand(demand::DemandArgs),
    /// Run (or resume) the planners × α × λ × seeds grid in worker processes, then report.
    Campaign(campaign::CampaignArgs),
    /// Tables and figures from one or more campaign directories (several: shards, merged).
    Report(report::ReportArgs),
    /// Collect lane-change data for the predictor b_θ from SUMO episodes.
    Collect(train::CollectArgs),
    /// Train b_θ (and its logistic-regression baseline) on collected data.
    Train(train::TrainArgs),
    /// Evaluate b_θ like the paper's tables I–II, next to two baselines.
    EvalPredictor(train::EvalPredictorArgs),
    /// Time b_θ: one prediction, and all HDVs of a dense scene per step.
    BenchPredictor(train::BenchPredictorArgs),
    /// Fit an IDM to the HDVs SUMO drives under a driver profile and compare it with constant
    /// speed on held-out episodes.
    Calibrate(calibrate::CalibrateArgs),
    /// Train the RL-PPO policy with PPO on SUMO episodes (resumable), then compare it with a
    /// random and an idle policy on held-out episodes.
    TrainRl(train_rl::TrainRlArgs),
    /// Internal: run RL rollouts sent by `train-rl` on stdin (one JSON line each).
    #[command(hide = true)]
    RlWorker,
    /// Internal: run episodes sent by a campaign on stdin (one JSON line each).
    #[command(hide = true)]
    Worker,
}
