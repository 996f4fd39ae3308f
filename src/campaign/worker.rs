//! The worker side of a campaign: a long-lived child process (`bkpbs worker`) that runs
//! episodes one after another in-process, because libsumo allows one simulation per process.
//!
//! Protocol: one JSON [`Request`] per line on stdin, one JSON [`Reply`] per line back on the
//! protocol channel (the process's original stdout; anything else printing to stdout, SUMO
//! included, is sent to stderr so it cannot corrupt the channel). End of stdin ends the worker.
//!
//! The worker writes the episode's files into the cell directory itself, atomically, with
//! `episode.csv` last: its presence marks a finished cell. A failed episode (SUMO error, planner
//! panic) leaves `error.txt` with the message instead. Either way the worker goes on with the
//! next request. A stop signal ends the episode early (its input removed) and the worker with
//! it, without a reply: the cell is unfinished and runs again next time.

use std::collections::BTreeMap;
use std::io::{BufRead, Write};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use crate::config::Config;
use crate::{episode, io};

/// Name of the file that records why a cell's episode failed.
pub const ERROR_FILE: &str = "error.txt";
/// Name of the file whose presence marks a finished cell.
pub const DONE_FILE: &str = "episode.csv";
/// Name of the cell's record of the settings its episode ran with
/// ([`super::comparison::results_settings`]).
pub const SETTINGS_RECORD: &str = "settings.toml";

/// Test hook: `BKPBS_WORKER_FAULT=panic:<seed>` makes the planner "panic" in every episode
/// with that seed, `exit:<seed>` makes the worker process die there, `hang:<seed>` makes the
/// episode wait for a stop signal (for the episode timeout and stop tests). Used by the test
/// suite to exercise failure handling; unset in normal use.
pub const FAULT_ENV: &str = "BKPBS_WORKER_FAULT";

/// One episode to run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Request {
    /// The cell's position in the grid, echoed in the reply.
    pub position: usize,
    /// The controller to run, as the CLI names it (`bk-pbs`, `idm-mobil`, …).
    pub planner: String,
    /// The cell directory to write the results into.
    pub dir: PathBuf,
    /// The episode's full configuration (α, λ, seed and steps set).
    pub config: Config,
}

/// How the episode went.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Outcome {
    /// The episode finished and its files are written (`episode.csv` last).
    Done,
    /// The episode failed (SUMO error, planner panic, a worker that died or ran over the
    /// timeout); the cell's `error.txt` records the text.
    Failed {
        /// What went wrong, as recorded in `error.txt`.
        error: String,
    },
}

/// The answer to one [`Request`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Reply {
    /// The grid position of the request answered.
    pub position: usize,
    /// How its episode went.
    pub outcome: Outcome,
}

/// Why the worker loop itself stopped (not an episode failure: those are replies).
#[derive(Debug, thiserror::Error)]
pub enum WorkerError {
    /// Reading the next request line from stdin failed.
    #[error("worker: cannot read requests: {0}")]
    Read(std::io::Error),
    /// A request line is not a JSON [`Request`].
    #[error("worker: malformed request: {0}")]
    Request(serde_json::Error),
    /// Writing a reply to the protocol channel failed (the campaign went away).
    #[error("worker: cannot send reply: {0}")]
    Reply(std::io::Error),
    /// The original stdout could not be kept for replies while stdout goes to stderr.
    #[error("worker: cannot set up the protocol channel: {0}")]
    Channel(std::io::Error),
}

/// The last panic's message and location, recorded by the hook instead of printed.
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);
/// Set while an episode runs: its panics become failed replies, others are printed.
static IN_EPISODE: AtomicBool = AtomicBool::new(false);

/// Runs the worker on the process's stdin/stdout until stdin closes.
pub fn serve_stdio() -> Result<(), WorkerError> {
    let channel = crate::io::child::protocol_channel().map_err(WorkerError::Channel)?;
    panic::set_hook(Box::new(|info| {
        if IN_EPISODE.load(Ordering::SeqCst) {
            *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(info.to_string());
        } else {
            eprintln!("bkpbs worker: {info}");
        }
    }));
    serve(std::io::stdin().lock(), channel)
}

/// Answers requests from `input` on `output` until `input` ends.
pub fn serve(mut input: impl BufRead, mut output: impl Write) -> Result<(), WorkerError> {
    let mut line = String::new();
    loop {
        line.clear();
        if input.read_line(&mut line).map_err(WorkerError::Read)? == 0 {
            return Ok(());
        }
        if line.trim().is_empty() {
            continue;
        }
        let req: Request = serde_json::from_str(&line).map_err(WorkerError::Request)?;
        let result = run_cell(&req);
        if crate::io::interrupt::requested().is_some() {
            // Stopped by a signal (the campaign's, passed on): the cell is simply unfinished,
            // neither done nor failed, and the worker ends without a reply.
            return Ok(());
        }
        let outcome = match result {
            Ok(()) => Outcome::Done,
            Err(error) => {
                record_failure(&req.dir, &error);
                Outcome::Failed { error }
            }
        };
        let reply = Reply {
            position: req.position,
            outcome,
        };
        let mut text = serde_json::to_string(&reply).expect("reply serialises");
        text.push('\n');
        output
            .write_all(text.as_bytes())
            .and_then(|()| output.flush())
            .map_err(WorkerError::Reply)?;
    }
}

/// Writes `error.txt` into a cell directory (best effort: the reply carries the message too).
pub fn record_failure(dir: &Path, error: &str) {
    let _ = io::write_atomic(&dir.join(ERROR_FILE), format!("{error}\n").as_bytes());
}

fn injected_fault(req: &Request) {
    let Ok(spec) = std::env::var(FAULT_ENV) else {
        return;
    };
    let seed = req.config.scenario.seed.to_string();
    match spec.split_once(':') {
        Some(("panic", s)) if s == seed => panic!("injected planner fault ({FAULT_ENV})"),
        Some(("exit", s)) if s == seed => std::process::exit(101),
        Some(("hang", s)) if s == seed => {
            // Until stopped; the episode then starts and ends at its first step.
            while crate::io::interrupt::requested().is_none() {
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
        }
        _ => {}
    }
}

/// Runs one episode and writes its files; the error text on failure.
pub(crate) fn run_cell(req: &Request) -> Result<(), String> {
    run_cell_recording(req, &req.config)
}

/// Runs one episode and writes its files, recording `record` as the settings it ran with:
/// the campaign's configuration, when `req.config` is the same one pointed at copies of its
/// input files elsewhere ([`super::portable`]). The error text on failure.
pub(crate) fn run_cell_recording(req: &Request, record: &Config) -> Result<(), String> {
    // A retried cell: the old failure note and a stale episode.csv (a cell is only asked for
    // when it is not finished) go first. A kill from here on leaves neither, and the cell
    // simply runs again next time.
    for name in [ERROR_FILE, DONE_FILE] {
        match std::fs::remove_file(req.dir.join(name)) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => {
                return Err(format!(
                    "cannot clear {}: {e}",
                    req.dir.join(name).display()
                ))
            }
        }
    }
    remove_stale_temporaries(&req.dir);
    let provenance = super::provenance::Provenance::of(&req.config)?;
    IN_EPISODE.store(true, Ordering::SeqCst);
    let run = panic::catch_unwind(AssertUnwindSafe(|| {
        injected_fault(req);
        run_episode(req)
    }));
    IN_EPISODE.store(false, Ordering::SeqCst);
    let result = match run {
        Ok(r) => r?,
        Err(payload) => {
            let recorded = LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()).take();
            let message = recorded.unwrap_or_else(|| {
                payload
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic payload".into())
            });
            return Err(format!("planner {} panicked: {message}", req.planner));
        }
    };
    let record = super::comparison::results_settings(record);
    let provenance_file = req.dir.join(super::provenance::PROVENANCE_RECORD);
    io::write_atomic(&req.dir.join(SETTINGS_RECORD), record.as_bytes())
        .and_then(|()| io::write_atomic(&provenance_file, provenance.to_toml().as_bytes()))
        .and_then(|()| result.write(&req.dir).map(drop))
        .map_err(|e| e.to_string())
}

/// Runs the request's episode (a scenario's files first checked against the campaign's record).
fn run_episode(req: &Request) -> Result<episode::Ran, String> {
    let config = &req.config;
    if let Some(cfg) = &config.scenario.sumocfg {
        same_scenario(cfg, &config.scenario.sumocfg_digests)?;
    }
    episode::ran::run(config, &req.planner).map_err(|e| e.to_string())
}

/// Refuses to run a scenario whose files are not those the campaign recorded when it started
/// (`digests`; none recorded: nothing to check): a route file edited mid-campaign would mix two
/// scenarios under one name.
fn same_scenario(cfg: &Path, digests: &BTreeMap<String, String>) -> Result<(), String> {
    if digests.is_empty() {
        return Ok(());
    }
    match crate::sumo::scenario_files::first_change(cfg, digests) {
        Ok(None) => Ok(()),
        Ok(Some(change)) => Err(format!(
            "the scenario {} is not the one the campaign started with: {change}",
            cfg.display()
        )),
        Err(e) => Err(e.to_string()),
    }
}

/// Removes the temporary files an earlier, killed write left in `dir`: those whose writer
/// (the process id in their name) is gone. Another campaign writing into the same directory
/// (a shard, or the same command twice) keeps its own in-flight files; removing them made its
/// rename fail ("cannot write …/campaign.toml: No such file or directory").
pub(crate) fn remove_stale_temporaries(dir: &Path) {
    crate::io::sweep_stale(dir, crate::io::TEMPORARY_PREFIX);
}
