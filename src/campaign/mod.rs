//! Experiment campaigns: every episode of a planners × HDV profiles × α × λ × seeds grid, run
//! in parallel worker processes, resumable after any interruption, collected into one set of CSV
//! files.
//!
//! Layout of a campaign directory `<out>`:
//!
//! ```text
//! campaign.toml                      the settings (grid and scenario); a re-run must agree
//! episodes/<planner>/[hdv-<profile>/]a<α>_l<λ>_s<seed>/   (hdv-<profile>/: a profile other than sumo-safe)
//!     episode.csv vehicles.csv collisions.csv timing.csv settings.toml [sumo.log]   a finished cell
//!     error.txt                                                       a failed one
//! episodes.csv vehicles.csv timings.csv failures.csv                  collected, grid order
//! report/                                                             tables and figures
//! ```
//!
//! Modules: [`grid`] (cells, order, shards), [`settings`] (file and flags), [`claim`] (one
//! set of settings per directory at a time), [`worker`] and
//! [`pool`] (the two ends of the worker processes), [`collect`] (resume state, gathering),
//! [`results`] (the collected files), [`tasks`] (the same run for other schedulers),
//! [`scenarios`] (the grid over scenarios of the user's own, `--sumocfg`).

mod checks;
pub mod claim;
pub mod collect;
pub mod comparison;
pub mod grid;
#[doc(hidden)] // worker-process plumbing: the campaign runs it, a library user never does
pub mod pool;
pub mod results;
pub mod scenarios;
pub mod settings;
pub mod table;
pub mod tasks;
pub mod validate;
#[doc(hidden)] // the worker processes' protocol (`bkpbs worker`, the Ray runner)
pub mod worker;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::io::WriteError;
use results::ResultsError;
pub use settings::{Overrides, Settings, SettingsError};
use worker::Outcome;

/// Name of the settings file in a campaign directory.
pub const SETTINGS_FILE: &str = "campaign.toml";

/// Why a campaign could not run (failed episodes are not errors: see [`RunSummary`]).
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// The campaign settings (file or flags) are unusable.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The output directory already holds a campaign whose scenario settings differ, so its
    /// finished episodes could not be resumed into this one.
    #[error(
        "{dir} holds a campaign with other settings ({key} differs); use another --out or remove it"
    )]
    OtherSettings {
        /// The campaign directory (`--out`).
        dir: PathBuf,
        /// The first differing setting, dotted (`scenario.dt`, `campaign.steps`, …).
        key: String,
    },
    /// Another campaign with other settings is running in the directory.
    #[error(
        "{dir} is in use by a running campaign with other settings ({key} differs); wait for it \
         or use another --out"
    )]
    HeldByOther {
        /// The campaign directory (`--out`).
        dir: PathBuf,
        /// The first differing setting, dotted.
        key: String,
    },
    /// Another run held the directory's settings for longer than a run may wait.
    #[error("{dir} stayed locked by another campaign run's settings check for 30 s")]
    Busy {
        /// The campaign directory (`--out`).
        dir: PathBuf,
    },
    /// The directory's collected `episodes.csv` has episodes outside this grid; collecting this
    /// run would silently lose them.
    #[error(
        "{dir}/episodes.csv records {count} episodes outside this grid, which this run would \
         drop (first: {first}): an earlier, larger grid or results merged in by `bkpbs report`; \
         run a grid that includes them, or use another --out"
    )]
    WouldDrop {
        /// The campaign directory (`--out`).
        dir: PathBuf,
        /// How many recorded episodes lie outside the grid.
        count: usize,
        /// The first of them, as a cell is displayed (`planner α=… λ=… seed=…`).
        first: String,
    },
    /// A campaign file (`campaign.toml`, a collected CSV) could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// The finished episodes could not be gathered into the collected files.
    #[error(transparent)]
    Collect(#[from] ResultsError),
}

/// What a campaign run did.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// Episodes in the whole grid.
    pub grid: usize,
    /// Episodes in this run's shard.
    pub shard: usize,
    /// Episodes of the shard found finished before this run.
    pub already_done: usize,
    /// Episodes run now.
    pub ran: usize,
    /// Episodes of the shard without result at the end (failed now, or not run).
    pub failed: usize,
    /// Rows of the collected `episodes.csv`.
    pub collected: usize,
    /// Wall-clock time of the run (s).
    pub wall_s: f64,
    /// The stop signal that ended the run early, if one did (the finished episodes are still
    /// collected; re-running resumes).
    pub interrupted: Option<i32>,
}

/// Runs (or resumes) a campaign in `out` with worker processes of `exe` (the `bkpbs` binary),
/// then collects the results. Prints one status line before and one after; draws a progress
/// bar on stderr only when stderr is a terminal.
pub fn run(settings: &Settings, out: &Path, exe: &Path) -> Result<RunSummary, CampaignError> {
    let start = Instant::now();
    let plan = tasks::prepare(settings, out)?;
    announce(settings, &plan);
    let (shard_size, already_done) = (plan.shard_size, plan.already_done);
    let _claim = plan.claim.clone();
    let names: Vec<String> = settings
        .grid
        .cells()
        .iter()
        .map(|c| c.to_string())
        .collect();
    let options = pool::PoolOptions {
        workers: settings.workers,
        episode_timeout: settings.episode_timeout,
    };
    let (ran, failed_now) = run_requests(&names, options, exe, plan.requests);
    let results = tasks::collect(settings, out)?;
    let summary = RunSummary {
        grid: settings.grid.len(),
        shard: shard_size,
        already_done,
        ran,
        failed: results.failures.rows.len(),
        collected: results.episodes.rows.len(),
        wall_s: start.elapsed().as_secs_f64(),
        interrupted: crate::io::interrupt::requested(),
    };
    println!(
        "campaign: ran {} episodes ({} failed) in {:.1} s; {} episodes collected in {}",
        summary.ran,
        failed_now,
        summary.wall_s,
        summary.collected,
        out.join("episodes.csv").display()
    );
    Ok(summary)
}

/// The status line before a run: the grid, the shard, what is done and what will run.
fn announce(settings: &Settings, plan: &tasks::Plan) {
    let g = &settings.grid;
    let profiles = match g.profiles.len() {
        1 => String::new(),
        n => format!(" × {n} HDV profiles"),
    };
    println!(
        "campaign: {} planners{profiles} × {} α × {} λ × {} seeds = {} episodes; shard {}: {}; already done: {}; to run: {}; workers: {}",
        g.planners.len(),
        g.alphas.len(),
        g.lambdas.len(),
        g.seeds.len(),
        g.len(),
        settings.shard,
        plan.shard_size,
        plan.already_done,
        plan.requests.len(),
        settings.workers.min(plan.requests.len()),
    );
}

/// Runs the episodes in the worker pool with a progress bar, naming each failure as it
/// happens (`names` are the cells' by grid position); returns how many ran and how many of
/// them failed.
fn run_requests(
    names: &[String],
    options: pool::PoolOptions,
    exe: &Path,
    requests: Vec<worker::Request>,
) -> (usize, usize) {
    let bar = progress_bar(requests.len() as u64);
    let mut failed_now = 0;
    let mut ran = 0;
    pool::run(exe, requests, options, |reply| {
        ran += 1;
        if let Outcome::Failed { error } = &reply.outcome {
            failed_now += 1;
            let line = format!(
                "campaign: episode {} failed: {error}",
                names[reply.position]
            );
            if bar.is_hidden() {
                eprintln!("{line}");
            } else {
                bar.println(line);
            }
            bar.set_message(format!("{failed_now} failed"));
        }
        bar.inc(1);
    });
    bar.finish_and_clear();
    (ran, failed_now)
}

fn progress_bar(len: u64) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30}] {pos}/{len} episodes, {msg}, ETA {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar.set_message("0 failed");
    bar
}
