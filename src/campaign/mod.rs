//! Experiment campaigns: every episode of a planners × predictors × HDV profiles × scenarios ×
//! α × λ × seeds grid, run in parallel worker processes, resumable after any interruption,
//! collected into one set of CSV files. A campaign on the paper's demand has no scenario axis; a
//! campaign over scenarios of the user's own (`bkpbs campaign --sumocfg A.sumocfg,B.sumocfg`)
//! has one, and no λ nor HDV profiles (its routes and drivers are its own).
//!
//! Layout of a campaign directory `<out>`:
//!
//! ```text
//! campaign.toml                      the settings (grid and scenario); a re-run must agree
//! episodes/<planner>/[hdv-<profile>/]a<α>_l<λ>_s<seed>/   (hdv-<profile>/: a profile other than sumo-safe)
//! episodes/<planner>/<scenario>/a<α>_s<seed>/             (over scenarios)
//!     episode.csv vehicles.csv collisions.csv timing.csv settings.toml provenance.toml [sumo.log]   a finished cell
//!     (over scenarios regions.csv entries.csv besides)
//!     error.txt                                                       a failed one
//! episodes.csv [regions.csv entries.csv] vehicles.csv timings.csv failures.csv   collected, grid order
//! report/                                                             tables and figures
//! ```
//!
//! Modules: [`grid`] (cells, order, shards), [`settings`] (file and flags, over scenarios
//! resolved in [`settings::scenarios`]), [`claim`] (one set of settings per directory at a
//! time), [`worker`] and [`pool`] (the two ends of the worker processes), [`cell`] (a cell's
//! files), [`collect`] (resume state, gathering), [`results`] (the collected files, read,
//! checked, merged), [`tasks`] (the same run for other schedulers), [`portable`] (an episode
//! whose inputs and results travel as bytes, for a cluster without shared storage).

pub mod cell;
mod checks;
pub mod claim;
pub mod collect;
pub mod comparison;
pub mod grid;
pub mod overrides;
#[doc(hidden)] // worker-process plumbing: the campaign runs it, a library user never does
pub mod pool;
pub mod portable;
pub mod provenance;
pub mod results;
pub mod settings;
pub mod spec;
pub mod table;
pub mod tasks;
pub mod validate;
#[doc(hidden)] // the worker processes' protocol (`bkpbs worker`, the Ray runner)
pub mod worker;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::io::progress::Progress;
use crate::io::WriteError;
use results::ResultsError;
pub use settings::{Overrides, Settings, SettingsError};
pub use spec::{CampaignSpec, Collected, Readiness};
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
/// then collects the results: the paper's demand or scenarios of the user's own alike (one
/// [`Settings`]). Prints one status line before and one after; draws a
/// progress bar on stderr only when stderr is a terminal.
///
/// # Errors
/// As [`tasks::prepare`] and [`CampaignSpec::collect`]; failed episodes are counted in the
/// summary, not errors.
pub fn run<S: CampaignSpec>(
    settings: &S,
    out: &Path,
    exe: &Path,
) -> Result<RunSummary, CampaignError> {
    let start = Instant::now();
    let plan = tasks::prepare(settings, out)?;
    let cells = settings.cells();
    println!(
        "campaign: {} = {} episodes; shard {}: {}; already done: {}; to run: {}; workers: {}",
        settings.axes(),
        cells.len(),
        settings.shard(),
        plan.shard_size,
        plan.already_done,
        plan.requests.len(),
        settings.workers().min(plan.requests.len()),
    );
    let (shard_size, already_done) = (plan.shard_size, plan.already_done);
    let _claim = plan.claim.clone();
    let names: Vec<String> = cells.iter().map(|c| c.to_string()).collect();
    let options = pool::PoolOptions {
        workers: settings.workers(),
        episode_timeout: settings.episode_timeout(),
    };
    let (ran, failed_now) = run_requests(&names, options, exe, plan.requests);
    let collected = settings.collect(out)?;
    let summary = RunSummary {
        grid: cells.len(),
        shard: shard_size,
        already_done,
        ran,
        failed: collected.failures,
        collected: collected.episodes,
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

/// Runs the episodes in the worker pool with their progress (a bar on a terminal, a line a
/// minute elsewhere), naming each failure as it happens (`names` are the cells' by grid
/// position); returns how many ran and how many of them failed.
fn run_requests(
    names: &[String],
    options: pool::PoolOptions,
    exe: &Path,
    requests: Vec<worker::Request>,
) -> (usize, usize) {
    let mut progress = Progress::new("campaign", requests.len() as u64, "episodes");
    progress.set_note("0 failed".into());
    let mut failed_now = 0;
    let mut ran = 0;
    pool::run(exe, requests, options, |reply| {
        ran += 1;
        if let Outcome::Failed { error } = &reply.outcome {
            failed_now += 1;
            progress.println(&format!(
                "campaign: episode {} failed: {error}",
                names[reply.position]
            ));
            progress.set_note(format!("{failed_now} failed"));
        }
        progress.advance(1);
    });
    progress.finish();
    (ran, failed_now)
}
