//! Overhead benchmark: the same episode with SUMO alone and with controllers, measured
//! side by side in one run so the ratio survives a noisy machine.

use std::time::Instant;

use crate::config::Config;
use crate::controller;
use crate::demand;
use crate::episode::{self, EpisodeError};
use crate::metrics::percentile;
use crate::sumo::Simulation;
use crate::sumo_files::EpisodeInput;

/// One row of the benchmark table.
#[derive(Debug, Clone)]
pub struct BenchRow {
    pub what: String,
    /// Median over repeats of the stepping loop's wall time per step (ms).
    pub ms_per_step: f64,
    /// Median over repeats of the time inside the planner per step (ms).
    pub plan_ms_per_step: f64,
}

/// SUMO stepping the episode's demand (as a plain route file, inserted by SUMO itself) with
/// nobody reading or commanding: the floor.
pub fn sumo_alone_ms_per_step(config: &Config) -> Result<f64, EpisodeError> {
    let planned = demand::generate(config);
    let input = EpisodeInput::write(config)?;
    let demand_file = tempfile::Builder::new()
        .suffix(".rou.xml")
        .tempfile()
        .and_then(|f| {
            std::fs::write(f.path(), demand::route_file(&planned))?;
            Ok(f)
        })
        .map_err(|source| crate::sumo_files::InputError::Write {
            path: std::env::temp_dir(),
            source,
        })?;
    let args = crate::sumo_files::command_line(
        config,
        &input.net,
        &input.vehicle_types,
        demand_file.path(),
    );
    let mut sim = Simulation::start(&args).map_err(|source| EpisodeError::Start {
        net: input.net.clone(),
        source,
    })?;
    let start = Instant::now();
    for step in 0..config.scenario.steps {
        sim.step().map_err(|source| EpisodeError::Step {
            step,
            time: step as f64 * config.scenario.dt,
            source,
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
    let mut per_planner: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); planners.len()];
    for _ in 0..repeats.max(1) {
        alone.push(sumo_alone_ms_per_step(config)?);
        for (k, name) in planners.iter().enumerate() {
            let mut c = controller::by_name(name, config)?;
            let r = episode::run(config, c.as_mut())?;
            per_planner[k].0.push(r.timing.episode_ms_per_step);
            per_planner[k]
                .1
                .push(r.timing.plan_ms_total / config.scenario.steps as f64);
        }
    }
    let mut rows = vec![BenchRow {
        what: "sumo-alone".into(),
        ms_per_step: percentile(&mut alone, 50.0),
        plan_ms_per_step: 0.0,
    }];
    for (name, (mut ep, mut plan)) in planners.iter().zip(per_planner) {
        rows.push(BenchRow {
            what: name.clone(),
            ms_per_step: percentile(&mut ep, 50.0),
            plan_ms_per_step: percentile(&mut plan, 50.0),
        });
    }
    Ok(rows)
}

/// The table as text: one row per configuration, with its ratio to SUMO alone.
pub fn table(rows: &[BenchRow]) -> String {
    let base = rows.first().map_or(1.0, |r| r.ms_per_step);
    let mut out = format!(
        "{:<14} {:>12} {:>12} {:>14}\n",
        "run", "ms/step", "plan ms/step", "ratio to sumo"
    );
    for r in rows {
        out += &format!(
            "{:<14} {:>12.4} {:>12.4} {:>13.2}x\n",
            r.what,
            r.ms_per_step,
            r.plan_ms_per_step,
            r.ms_per_step / base
        );
    }
    out
}
