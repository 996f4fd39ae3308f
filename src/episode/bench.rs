//! Overhead benchmark: the same episode with SUMO alone and with controllers, measured
//! side by side in one run so the ratio survives a noisy machine.

use std::time::Instant;

use crate::config::Config;
use crate::episode::demand;
use crate::episode::metrics::percentile;
use crate::episode::{self, sumocfg, EpisodeError};
use crate::sumo::files::EpisodeInput;
use crate::sumo::Simulation;

/// One row of the benchmark table; each figure is the median over the repeats.
#[derive(Debug, Clone, Default)]
pub struct BenchRow {
    /// What ran: `sumo-alone`, or the planner's name (with ` ×N` for N threads when several
    /// thread counts are compared).
    pub what: String,
    /// Wall time of the stepping loop per step (ms).
    pub ms_per_step: f64,
    /// Planning time per step, median over the episode's steps (ms).
    pub plan_ms_median: f64,
    /// Planning time per step, 99th percentile over the episode's steps (ms).
    pub plan_ms_p99: f64,
    /// Planning time per step, maximum over the episode's steps (ms).
    pub plan_ms_max: f64,
    /// Nodes expanded per step, all CAVs together.
    pub nodes_per_step: f64,
    /// The safety shield's part of the planning time per step, median over the steps (ms).
    pub shield_ms_median: f64,
    /// The safety shield's part of the planning time per step, maximum over the steps (ms).
    pub shield_ms_max: f64,
    /// Vehicles on the section per step, on average.
    pub vehicles_per_step: f64,
    /// CAVs on the section per step, on average.
    pub cavs_per_step: f64,
}

/// A rayon pool of `threads` threads for the planners.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

/// One timed episode of `planner` on a rayon pool of `threads` threads: the row's figures
/// (on a scenario, planning per step is every region's together).
fn timed_episode(config: &Config, planner: &str, threads: usize) -> Result<[f64; 9], EpisodeError> {
    let r = pool(threads).install(|| episode::ran::run(config, planner))?;
    let t = r.timing();
    let steps = config.scenario.steps as f64;
    Ok([
        t.episode_ms_per_step,
        t.plan_ms_median,
        t.plan_ms_p99,
        t.plan_ms_max,
        r.summary().plan_stats.nodes_expanded as f64 / steps,
        t.shield_ms_median,
        t.shield_ms_max,
        r.vehicles_per_step(),
        r.cavs_per_step(),
    ])
}

/// SUMO stepping the episode's demand (as a plain route file, inserted by SUMO itself), or the
/// user's scenario with bkpbs's options, with nobody reading or commanding: the floor.
pub fn sumo_alone_ms_per_step(config: &Config) -> Result<f64, EpisodeError> {
    if config.scenario.sumocfg.is_some() {
        return sumocfg::sumo_alone_ms_per_step(config);
    }
    let road = crate::sumo::frame::scenario_road(&config.scenario)?;
    let planned = demand::generate(config, &road);
    let input = EpisodeInput::write(config, &road)?;
    let demand_file = tempfile::Builder::new()
        .suffix(".rou.xml")
        .tempfile()
        .and_then(|f| {
            std::fs::write(f.path(), demand::route_file(&road, &planned))?;
            Ok(f)
        })
        .map_err(|cause| crate::sumo::files::InputError::Write {
            path: std::env::temp_dir(),
            cause,
        })?;
    let args = crate::sumo::files::command_line(
        config,
        &input.net,
        &input.vehicle_types,
        demand_file.path(),
    );
    let mut sim = Simulation::start(&args, config.sumo.stall_limit()).map_err(|cause| {
        EpisodeError::Start {
            net: input.net.clone(),
            cause,
        }
    })?;
    let start = Instant::now();
    for step in 0..config.scenario.steps {
        sim.step().map_err(|cause| EpisodeError::Step {
            step,
            time: step as f64 * config.scenario.dt,
            cause,
        })?;
    }
    let ms = start.elapsed().as_secs_f64() * 1e3 / config.scenario.steps as f64;
    let _ = sim.close();
    Ok(ms)
}

/// Runs SUMO alone and each planner `repeats` times, interleaved, once per thread count of
/// `threads` (rayon's pool for the planner), and reports medians.
pub fn run(
    config: &Config,
    planners: &[String],
    threads: &[usize],
    repeats: usize,
) -> Result<Vec<BenchRow>, EpisodeError> {
    let runs: Vec<(String, usize)> = planners
        .iter()
        .flat_map(|p| threads.iter().map(move |&t| (p.clone(), t)))
        .collect();
    let mut alone = Vec::new();
    let mut samples: Vec<Vec<[f64; 9]>> = vec![Vec::new(); runs.len()];
    for _ in 0..repeats.max(1) {
        alone.push(sumo_alone_ms_per_step(config)?);
        for (k, (name, t)) in runs.iter().enumerate() {
            samples[k].push(timed_episode(config, name, *t)?);
        }
    }
    let mut rows = vec![BenchRow {
        what: "sumo-alone".into(),
        ms_per_step: percentile(&mut alone, 50.0),
        ..BenchRow::default()
    }];
    for ((name, t), runs) in runs.iter().zip(samples) {
        let median =
            |i: usize| percentile(&mut runs.iter().map(|r| r[i]).collect::<Vec<_>>(), 50.0);
        let what = if threads.len() > 1 {
            format!("{name} ×{t}")
        } else {
            name.clone()
        };
        rows.push(BenchRow {
            what,
            ms_per_step: median(0),
            plan_ms_median: median(1),
            plan_ms_p99: median(2),
            plan_ms_max: median(3),
            nodes_per_step: median(4),
            shield_ms_median: median(5),
            shield_ms_max: median(6),
            vehicles_per_step: median(7),
            cavs_per_step: median(8),
        });
    }
    Ok(rows)
}

/// The table as text: one row per run, with its ratio to SUMO alone.
pub fn table(rows: &[BenchRow]) -> String {
    let base = rows.first().map_or(1.0, |r| r.ms_per_step);
    let mut out = format!(
        "{:<14} {:>10} {:>8} {:>12} {:>10} {:>10} {:>11} {:>13} {:>11} {:>9} {:>6}\n",
        "run",
        "ms/step",
        "ratio",
        "plan median",
        "plan p99",
        "plan max",
        "nodes/step",
        "shield median",
        "shield max",
        "veh/step",
        "CAVs"
    );
    for r in rows {
        out += &format!(
            "{:<14} {:>10.4} {:>7.2}x {:>12.4} {:>10.4} {:>10.4} {:>11.1} {:>13.4} {:>11.4} {:>9.1} {:>6.1}\n",
            r.what,
            r.ms_per_step,
            r.ms_per_step / base,
            r.plan_ms_median,
            r.plan_ms_p99,
            r.plan_ms_max,
            r.nodes_per_step,
            r.shield_ms_median,
            r.shield_ms_max,
            r.vehicles_per_step,
            r.cavs_per_step
        );
    }
    out += "(ms; planning figures are per step for all CAVs together, the shield's part of it \
            apart, medians over the repeats; ×N: the planner on N threads; veh/step and CAVs: on \
            the section per step, on average; on a scenario of your own, in its regions, planning \
            and nodes all regions together)\n";
    out
}
