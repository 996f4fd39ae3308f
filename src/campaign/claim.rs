//! A campaign directory's settings, claimed for the run, so that two runs with different
//! settings can never both proceed in one directory.
//!
//! The claim is an advisory lock (`flock`) on the directory itself (no file is added to it),
//! which the kernel drops when the process ends however it ends, so a killed campaign never
//! leaves a directory locked.
//! - A run that finds the directory free takes the lock exclusively, checks the settings an
//!   earlier run left (`campaign.toml`) against its own, writes its own, and keeps the lock
//!   shared for the rest of the run.
//! - A run that finds it held waits for the exclusive phase to end, takes the lock shared, and
//!   proceeds only if the running campaign's `campaign.toml` is exactly its own (a second
//!   shard, or the same command twice, as before); anything else is refused naming the first
//!   difference.

use std::fs::File;
use std::os::fd::AsRawFd;
use std::path::Path;
use std::time::{Duration, Instant};

use super::spec::CampaignSpec;
use super::{CampaignError, SETTINGS_FILE};

/// How long a run waits for another's exclusive phase (a settings check and one write).
const WAIT: Duration = Duration::from_secs(30);

/// The held claim; released when dropped (or when the process ends).
#[derive(Debug)]
pub struct Claim {
    _dir: File,
}

/// Claims `out` for a run of `settings`; `check` is the rest of the exclusive phase (the
/// checks that need the earlier settings, and writing the new ones), run only when this run
/// is the first.
///
/// # Errors
/// The directory is held by a running campaign with other settings, or `check` fails, or the
/// directory cannot be made or opened.
pub fn claim<S: CampaignSpec>(
    settings: &S,
    out: &Path,
    check: impl FnOnce() -> Result<(), CampaignError>,
) -> Result<Claim, CampaignError> {
    let write_err = |cause| crate::io::WriteError {
        path: out.to_path_buf(),
        cause,
    };
    std::fs::create_dir_all(out).map_err(write_err)?;
    let lock = File::open(out).map_err(write_err)?;
    let started = Instant::now();
    loop {
        // A file system without flock (some network ones) cannot be claimed: the run goes on
        // as before the claim existed.
        if try_lock(&lock, libc::LOCK_EX).unwrap_or(true) {
            check()?;
            // Shared from now on: runs of the same settings may join. (Converting cannot fail
            // while the lock is held; if it did, the claim would simply stay exclusive.)
            let _ = try_lock(&lock, libc::LOCK_SH);
            return Ok(Claim { _dir: lock });
        }
        if try_lock(&lock, libc::LOCK_SH).unwrap_or(false) {
            return join_running(settings, out).map(|()| Claim { _dir: lock });
        }
        if started.elapsed() > WAIT {
            return Err(CampaignError::Busy {
                dir: out.to_path_buf(),
            });
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Whether `flock(op | LOCK_NB)` took the lock (`false`: another process holds it, or a signal
/// came; try again), or why the file system cannot lock.
fn try_lock(file: &File, op: libc::c_int) -> std::io::Result<bool> {
    // SAFETY: flock on a valid open descriptor.
    if unsafe { libc::flock(file.as_raw_fd(), op | libc::LOCK_NB) } == 0 {
        return Ok(true);
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EWOULDBLOCK | libc::EINTR) => Ok(false),
        _ => Err(e),
    }
}

/// A run that found the directory in use proceeds only with exactly the running settings.
fn join_running<S: CampaignSpec>(settings: &S, out: &Path) -> Result<(), CampaignError> {
    let path = out.join(SETTINGS_FILE);
    let running = crate::io::bounded::read_text(&path, crate::io::bounded::FileKind::Config).ok();
    if running.as_deref() == Some(settings.to_toml().as_str()) {
        return Ok(());
    }
    let key = settings
        .difference_from_file(&path)
        .ok()
        .flatten()
        .unwrap_or_else(|| "the campaign grid".into());
    Err(CampaignError::HeldByOther {
        dir: out.to_path_buf(),
        key,
    })
}
