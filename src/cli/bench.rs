//! `bkpbs bench`: SUMO alone against the same episode with each controller.

use anyhow::Result;
use clap::Args;

use bkpbs::config::Config;
use bkpbs::controller::PlannerKind;
use bkpbs::episode::bench;

use super::scenario::ScenarioArgs;

#[derive(Args)]
pub struct BenchArgs {
    /// Controllers to time next to SUMO alone [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    planners: Vec<PlannerKind>,
    /// Repeats per row (medians are reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Thread counts to plan with, one row each (default: 1 and every core).
    #[arg(long, value_delimiter = ',')]
    threads: Vec<usize>,
    #[command(flatten)]
    scenario: ScenarioArgs,
}

/// A checked benchmark: every planner exists for this configuration.
pub struct Bench {
    config: Config,
    planners: Vec<String>,
    threads: Vec<usize>,
    repeats: usize,
}

impl BenchArgs {
    /// Refuses an unknown planner, a thread count of 0 or a network that is no merge before
    /// any of the rows is timed.
    pub fn resolve(self) -> Result<Bench> {
        let config = self.scenario.resolve()?;
        let mut planners = self.planners;
        if planners.is_empty() {
            planners = PlannerKind::ALL.to_vec();
        }
        for p in &planners {
            p.check(&config)?;
        }
        bkpbs::sumo::frame::scenario_roads(&config.scenario)?;
        for &t in &self.threads {
            bkpbs::io::cores::check("--threads", t).map_err(anyhow::Error::msg)?;
        }
        let cores = bkpbs::io::cores::available();
        let mut threads = self.threads;
        if threads.is_empty() {
            threads = if cores > 1 { vec![1, cores] } else { vec![1] };
        }
        Ok(Bench {
            config,
            planners: planners.iter().map(|p| p.name().to_string()).collect(),
            threads,
            repeats: self.repeats,
        })
    }
}

/// Prints the settings, then the table of timings.
pub fn run(b: Bench) -> Result<()> {
    let s = &b.config.scenario;
    let net = s
        .sumocfg
        .as_ref()
        .or(s.net_file.as_ref())
        .map_or("the embedded network".to_string(), |p| {
            p.display().to_string()
        });
    println!(
        "bench: α={} λ={} seed={} steps={} repeats={} threads={:?} on {net}",
        s.alpha, s.lambda, s.seed, s.steps, b.repeats, b.threads
    );
    let rows = bench::run(&b.config, &b.planners, &b.threads, b.repeats)?;
    print!("{}", bench::table(&rows));
    Ok(())
}
