//! SIGINT, SIGTERM and SIGHUP as a request to stop, so that an interrupted run can tidy up
//! (close SUMO, remove its temporary input directory, let a campaign's workers do the same)
//! instead of dying where it stands.
//!
//! The handler only records the signal; long loops (an episode's steps, a campaign's queue)
//! ask [`requested`] and stop at the next safe point. A second signal while the first is still
//! being handled ends the process at once, as an impatient second Ctrl-C should. Nothing is
//! installed unless a command asks ([`install`]): the Python bindings keep Python's own
//! KeyboardInterrupt.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

/// The first stop signal received, 0 if none.
static RECEIVED: AtomicI32 = AtomicI32::new(0);
/// Whether a second signal ends the process at once.
static ESCALATE: AtomicBool = AtomicBool::new(true);
/// Whether some loop has seen the signal ([`requested`]), so the run is tidying up; a signal
/// nobody notices means the run is stuck in a call, and the watchdog (`io::watchdog`, which
/// runs while a SUMO call is under way) ends it.
static NOTICED: AtomicBool = AtomicBool::new(false);

/// The signals that ask a run to stop.
const STOP_SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

extern "C" fn note(signal: libc::c_int) {
    let first = RECEIVED
        .compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst)
        .is_ok();
    if !first && ESCALATE.load(Ordering::SeqCst) {
        // SAFETY: signal and raise are async-signal-safe; the default action ends the process.
        unsafe {
            libc::signal(signal, libc::SIG_DFL);
            libc::raise(signal);
        }
    }
}

/// Turns the stop signals into requests. `escalate`: whether a second signal kills at once
/// (interactive commands); a campaign's worker says no, since a Ctrl-C reaches it both from
/// the terminal and forwarded by the campaign.
pub fn install(escalate: bool) {
    ESCALATE.store(escalate, Ordering::SeqCst);
    for signal in STOP_SIGNALS {
        // SAFETY: installs a handler that only touches atomics (and, on a second signal,
        // restores the default action and re-raises); sigaction is given a zeroed, filled-in
        // struct.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = note as extern "C" fn(libc::c_int) as libc::sighandler_t;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(signal, &action, std::ptr::null_mut());
        }
    }
}

/// The stop signal received so far, if any; the caller is taken to act on it (a loop at a
/// safe point), which tells the watchdog that the run is not stuck.
pub fn requested() -> Option<i32> {
    let signal = received();
    if signal.is_some() {
        NOTICED.store(true, Ordering::SeqCst);
    }
    signal
}

/// The stop signal received so far, without noticing it (for the watchdog).
pub(super) fn received() -> Option<i32> {
    match RECEIVED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// Whether a loop has noticed the stop signal.
pub(super) fn noticed() -> bool {
    NOTICED.load(Ordering::SeqCst)
}

/// The signal's usual name ("SIGINT"), for messages.
pub fn name(signal: i32) -> String {
    match signal {
        libc::SIGINT => "SIGINT".into(),
        libc::SIGTERM => "SIGTERM".into(),
        libc::SIGHUP => "SIGHUP".into(),
        s => format!("signal {s}"),
    }
}

/// The exit code of a process stopped by `signal`: 128 + its number, as shells report it.
pub fn exit_code(signal: i32) -> u8 {
    (128 + signal).clamp(0, 255) as u8
}

/// Sends `signal` to process `pid` (a campaign passing a stop on to its workers).
pub fn forward(pid: u32, signal: i32) {
    // SAFETY: plain kill(2); a process already gone gives ESRCH, which is fine.
    unsafe {
        libc::kill(pid as libc::pid_t, signal);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_exit_codes_follow_the_shell() {
        assert_eq!(name(libc::SIGINT), "SIGINT");
        assert_eq!(exit_code(libc::SIGINT), 130);
        assert_eq!(exit_code(libc::SIGTERM), 143);
    }
}
