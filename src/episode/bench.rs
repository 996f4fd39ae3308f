//! Overhead benchmark: the same episode with SUMO alone and with controllers, measured
//! side by side in one run so the ratio survives a noisy machine.

use std::time::Instant;

use crate::config::Config;
use crate::episode::demand;
use crate::episode::metrics::percentile;
use crate::episode::{self, EpisodeError};
use crate::sumo::files::EpisodeInput;
use crate::sumo::Simulation;

/// One row of the benchmark table; each figure is the median over the repeats.
#[derive(Debug, Clone, Default)]
pub struct BenchRow {
    pub what: String,
    /// Wall time of the stepping loop per step (ms).
    pub ms_per_step: f64,
    /// Planning time per step: median, 99th percentile and maximum over the episode's steps (ms).
    pub plan_ms_median: f64,
    pub plan_ms_p99: f64,
    pub plan_ms_max: f64,
    /// Nodes expanded per step, all CAVs together.
    pub nodes_per_step: f64,
    /// The safety shield's part of the planning time per step: median and maximum (ms).
    pub shield_ms_median: f64,
    pub shield_ms_max: f64,
}

/// SUMO stepping the episode's demand (as a plain route file, inserted by SUMO itself) with
/// nobody reading or commanding: the floor.
pub fn sumo_alone_ms_per_step(config: &Config) -> Result<f64, EpisodeError> {
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
    let mut sim = Simulation::start(&args).map_err(|cause| EpisodeError::Start {
        net: input.net.clone(),
        cause,
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

/// Runs SUMO alone and each planner `repeats` times, interleaved, and reports medians.
pub fn run(
    config: &Config,
    planners: &[String],
    repeats: usize,
) -> Result<Vec<BenchRow>, EpisodeError> {
    let mut alone = Vec::new();
    let mut samples: Vec<Vec<[f64; 7]>> = vec![Vec::new(); planners.len()];
    for _ in 0..repeats.max(1) {
        alone.push(sumo_alone_ms_per_step(config)?);
        for (k, name) in planners.iter().enumerate() {
            let r = episode::run(config, name)?;
            let t = &r.timing;
            let nodes = r.summary.plan_stats.nodes_expanded as f64 / config.scenario.steps as f64;
            samples[k].push([
                t.episode_ms_per_step,
                t.plan_ms_median,
                t.plan_ms_p99,
                t.plan_ms_max,
                nodes,
                t.shield_ms_median,
                t.shield_ms_max,
            ]);
        }
    }
    let mut rows = vec![BenchRow {
        what: "sumo-alone".into(),
        ms_per_step: percentile(&mut alone, 50.0),
        ..BenchRow::default()
    }];
    for (name, runs) in planners.iter().zip(samples) {
        let median =
            |i: usize| percentile(&mut runs.iter().map(|r| r[i]).collect::<Vec<_>>(), 50.0);
        rows.push(BenchRow {
            what: name.clone(),
            ms_per_step: median(0),
            plan_ms_median: median(1),
            plan_ms_p99: median(2),
            plan_ms_max: median(3),
            nodes_per_step: median(4),
            shield_ms_median: median(5),
            shield_ms_max: median(6),
        });
    }
    Ok(rows)
}

/// The table as text: one row per run, with its ratio to SUMO alone.
pub fn table(rows: &[BenchRow]) -> String {
    let base = rows.first().map_or(1.0, |r| r.ms_per_step);
    let mut out = format!(
        "{:<12} {:>10} {:>8} {:>12} {:>10} {:>10} {:>11} {:>13} {:>11}\n",
        "run",
        "ms/step",
        "ratio",
        "plan median",
        "plan p99",
        "plan max",
        "nodes/step",
        "shield median",
        "shield max"
    );
    for r in rows {
        out += &format!(
            "{:<12} {:>10.4} {:>7.2}x {:>12.4} {:>10.4} {:>10.4} {:>11.1} {:>13.4} {:>11.4}\n",
            r.what,
            r.ms_per_step,
            r.ms_per_step / base,
            r.plan_ms_median,
            r.plan_ms_p99,
            r.plan_ms_max,
            r.nodes_per_step,
            r.shield_ms_median,
            r.shield_ms_max
        );
    }
    out += "(ms; planning figures are per step for all CAVs together, the shield's part of it \
            apart, medians over the repeats)\n";
    out
}
