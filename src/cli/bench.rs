//! `bkpbs bench`: SUMO alone against the same episode with each controller.

use anyhow::Result;
use clap::Args;

use bkpbs::config::Config;
use bkpbs::controller;
use bkpbs::episode::bench;

use super::scenario::ScenarioArgs;

#[derive(Args)]
pub struct BenchArgs {
    /// Controllers to time next to SUMO alone.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "sumo,idm-mobil,bk-mastar,bk-pbs,rl-ppo"
    )]
    planners: Vec<String>,
    /// Repeats per row (medians are reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    #[command(flatten)]
    scenario: ScenarioArgs,
}

/// A checked benchmark: every planner exists for this configuration.
pub struct Bench {
    config: Config,
    planners: Vec<String>,
    repeats: usize,
}

impl BenchArgs {
    /// Refuses an unknown planner before any of the rows is timed.
    pub fn resolve(self) -> Result<Bench> {
        let config = self.scenario.resolve()?;
        for p in &self.planners {
            controller::check(p, &config)?;
        }
        Ok(Bench {
            config,
            planners: self.planners,
            repeats: self.repeats,
        })
    }
}

/// Prints the settings, then the table of timings.
pub fn run(b: Bench) -> Result<()> {
    let s = &b.config.scenario;
    println!(
        "bench: α={} λ={} seed={} steps={} repeats={}",
        s.alpha, s.lambda, s.seed, s.steps, b.repeats
    );
    let rows = bench::run(&b.config, &b.planners, b.repeats)?;
    print!("{}", bench::table(&rows));
    Ok(())
}
