//! A campaign as independent tasks, for schedulers other than the worker pool (Ray through the
//! Python bindings, a batch system): prepare the directory and list the unfinished episodes,
//! run any one of them in the calling process, collect.
//!
//! [`super::run`] is these three steps with [`super::pool`] in the middle; another scheduler
//! replaces only the middle and produces the same directory, byte for byte.

use std::path::Path;
use std::sync::Arc;

use super::cell::cell_dir;
use super::claim::{self, Claim};
use super::spec::{CampaignSpec, Readiness};
use super::worker::{self, Outcome, Request};
use super::{CampaignError, SETTINGS_FILE};
use crate::episode::output;

/// The episodes of a campaign run that still need running.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Unfinished cells of the shard, in grid order.
    pub requests: Vec<Request>,
    /// Cells in this run's shard.
    pub shard_size: usize,
    /// Cells of the shard found finished.
    pub already_done: usize,
    /// The directory's settings, claimed while this is held ([`claim`]).
    pub claim: Arc<Claim>,
}

/// Readies `out` for a run of `settings` and lists its unfinished episodes, printing why a
/// cell found there runs again.
///
/// # Errors
/// `out` holds a campaign with other settings, or is in use by a running one with other
/// settings, or `campaign.toml` cannot be written.
pub fn prepare<S: CampaignSpec>(settings: &S, out: &Path) -> Result<Plan, CampaignError> {
    let claim = claim::claim(settings, out, || check_and_record(settings, out))?;
    // Left by a campaign killed while collecting.
    worker::remove_stale_temporaries(out);

    let shard = settings.shard();
    let mut shard_size = 0;
    let mut requests = Vec::new();
    for (position, cell) in settings.cells().iter().enumerate() {
        if !shard.contains(position) {
            continue;
        }
        shard_size += 1;
        match settings.readiness(out, cell) {
            Readiness::Done(()) => continue,
            Readiness::Stale(why) => println!("campaign: {cell} runs again: {why}"),
            Readiness::NotRun => {}
        }
        requests.push(Request {
            position,
            planner: cell.planner.clone(),
            dir: cell_dir(out, cell),
            config: settings.episode_config(cell),
        });
    }
    Ok(Plan {
        already_done: shard_size - requests.len(),
        requests,
        shard_size,
        claim: Arc::new(claim),
    })
}

/// The first run's part of the claim: `out` must not hold a campaign of other settings, nor
/// recorded episodes this grid would drop; then this run's settings are written.
fn check_and_record<S: CampaignSpec>(settings: &S, out: &Path) -> Result<(), CampaignError> {
    let settings_path = out.join(SETTINGS_FILE);
    if settings_path.exists() {
        if let Some(key) = settings.difference_from_file(&settings_path)? {
            return Err(CampaignError::OtherSettings {
                dir: out.to_path_buf(),
                key,
            });
        }
    }
    let dropped = settings.recorded_outside(out);
    if let Some(first) = dropped.first() {
        return Err(CampaignError::WouldDrop {
            dir: out.to_path_buf(),
            count: dropped.len(),
            first: first.clone(),
        });
    }
    output::write_atomic(&settings_path, settings.to_toml().as_bytes())?;
    Ok(())
}

/// Runs one episode in this process as a worker does: its files in the cell directory, or
/// `error.txt` with the message (also returned). libsumo allows one simulation per process, so
/// callers run one at a time per process.
pub fn run_request(req: &Request) -> Outcome {
    match worker::run_cell(req) {
        Ok(()) => Outcome::Done,
        Err(error) => {
            worker::record_failure(&req.dir, &error);
            Outcome::Failed { error }
        }
    }
}
