//! Campaigns over scenarios of the user's own (`bkpbs campaign --sumocfg A.sumocfg,B.sumocfg`):
//! every episode of a planners × scenarios × α × seeds grid, run in the same worker processes
//! as the paper's campaigns, resumable and shardable the same way, collected into one set of
//! CSV files.
//!
//! Layout of a campaign directory `<out>`:
//!
//! ```text
//! campaign.toml                                  the settings; a re-run must agree
//! episodes/<planner>/<scenario>/a<α>_s<seed>/     the files of `bkpbs episode --sumocfg`
//!     (+ settings.toml), or error.txt
//! episodes.csv regions.csv vehicles.csv timings.csv failures.csv   collected, grid order
//! report/                                        per-region paired comparisons
//! ```
//!
//! Modules: [`grid`] (cells and their order), [`settings`] (file and flags), [`collect`]
//! (resume state, gathering). `--trajectories` writes each cell's region trajectories
//! (`trajectories/<region>/`, as `bkpbs episode --sumocfg`), which `--plots` draws. Not yet: the
//! claim that lets two runs with other settings share a directory safely (run one such campaign
//! per directory at a time).

pub mod collect;
pub mod grid;
pub mod merge;
pub mod settings;

use std::path::Path;
use std::time::Instant;

use super::worker::{self, Request};
use super::{pool, run_requests, CampaignError, RunSummary, SETTINGS_FILE};
pub use collect::ScenarioResults;
pub use grid::{ScenarioCell, ScenarioGrid};
pub use settings::{is_scenario_campaign, ScenarioSettings, ScenarioTable};

/// The unfinished episodes of a run, and how many of its shard were done.
#[derive(Debug, Clone)]
pub struct ScenarioPlan {
    /// Unfinished cells of the shard, in grid order.
    pub requests: Vec<Request>,
    /// Cells in this run's shard.
    pub shard_size: usize,
    /// Cells of the shard found finished.
    pub already_done: usize,
}

/// Readies `out` (its `campaign.toml` must agree with `settings`, and is then written) and
/// lists the shard's unfinished episodes.
///
/// # Errors
/// `out` holds a campaign of other settings, or collected episodes outside this grid (which
/// collecting it would drop), or `campaign.toml` cannot be written.
pub fn prepare(settings: &ScenarioSettings, out: &Path) -> Result<ScenarioPlan, CampaignError> {
    let path = out.join(SETTINGS_FILE);
    if path.exists() {
        let earlier = ScenarioSettings::from_campaign_file(&path)?;
        if let Some(key) = settings.difference(&earlier) {
            return Err(CampaignError::OtherSettings {
                dir: out.to_path_buf(),
                key,
            });
        }
    }
    let dropped = collect::recorded_outside(out, &settings.grid);
    if let Some(first) = dropped.first() {
        return Err(CampaignError::WouldDrop {
            dir: out.to_path_buf(),
            count: dropped.len(),
            first: first.clone(),
        });
    }
    crate::io::ensure_writable_dir(out)?;
    crate::io::write_atomic(&path, settings.to_toml().as_bytes())?;
    worker::remove_stale_temporaries(out);
    let mut shard_size = 0;
    let mut requests = Vec::new();
    for (position, cell) in settings.grid.cells().iter().enumerate() {
        if !settings.shard.contains(position) {
            continue;
        }
        shard_size += 1;
        match collect::cell_state(out, settings, cell) {
            collect::CellState::Done(_) => continue,
            collect::CellState::Stale(why) => println!("campaign: {cell} runs again: {why}"),
            collect::CellState::NotRun => {}
        }
        requests.push(Request {
            position,
            planner: cell.planner.clone(),
            dir: collect::cell_dir(out, cell),
            config: settings.episode_config(cell),
        });
    }
    Ok(ScenarioPlan {
        already_done: shard_size - requests.len(),
        requests,
        shard_size,
    })
}

/// Gathers the finished cells into the collected files and returns them.
///
/// # Errors
/// A collected file cannot be written.
pub fn collect(settings: &ScenarioSettings, out: &Path) -> Result<ScenarioResults, CampaignError> {
    let results = collect::collect(out, settings);
    results.write(out)?;
    Ok(results)
}

/// Runs (or resumes) the campaign in `out` with worker processes of `exe`, then collects.
///
/// # Errors
/// As [`prepare`] and [`collect`]; failed episodes are counted in the summary, not errors.
pub fn run(
    settings: &ScenarioSettings,
    out: &Path,
    exe: &Path,
) -> Result<RunSummary, CampaignError> {
    let start = Instant::now();
    let plan = prepare(settings, out)?;
    let g = &settings.grid;
    println!(
        "campaign: {} planners × {} scenarios × {} α × {} seeds = {} episodes; shard {}: {}; already done: {}; to run: {}; workers: {}",
        g.planners.len(),
        g.scenarios.len(),
        g.alphas.len(),
        g.seeds.len(),
        g.len(),
        settings.shard,
        plan.shard_size,
        plan.already_done,
        plan.requests.len(),
        settings.workers.min(plan.requests.len()),
    );
    let names: Vec<String> = g.cells().iter().map(|c| c.to_string()).collect();
    let options = pool::PoolOptions {
        workers: settings.workers,
        episode_timeout: settings.episode_timeout,
    };
    let (ran, failed_now) = run_requests(&names, options, exe, plan.requests);
    let results = collect(settings, out)?;
    let summary = RunSummary {
        grid: g.len(),
        shard: plan.shard_size,
        already_done: plan.already_done,
        ran,
        failed: results.failures.len(),
        collected: results.episodes.len(),
        wall_s: start.elapsed().as_secs_f64(),
        interrupted: crate::io::interrupt::requested(),
    };
    println!(
        "campaign: ran {ran} episodes ({failed_now} failed) in {:.1} s; {} episodes collected in {}",
        summary.wall_s,
        summary.collected,
        out.join("episodes.csv").display()
    );
    Ok(summary)
}
