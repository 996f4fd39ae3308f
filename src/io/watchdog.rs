//! The last line of defence against a run that can no longer stop itself: SUMO looping inside
//! one call (sumo-gui retrying a display that never answers, a simulation step that never
//! returns), where no Rust code runs to look at a stop signal.
//!
//! A thread watches two things:
//! - a stop signal ([`super::interrupt`]) that no loop has noticed within [`GRACE`]: the run
//!   is stuck in a call, so the process ends at once with the signal's exit code;
//! - a SUMO call marked [`busy`] that has run longer than its bound: the process ends with one
//!   `error:` line and exit code 1.
//!
//! Either way the process `_exit`s: results already written stay whole (every result file is
//! written by rename), an episode's own unfinished outputs are simply absent, and its input
//! directory is swept by the next run (its name carries the process id).

use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::{Mutex, Once};
use std::time::{Duration, Instant};

/// How long a stop signal may go unnoticed before the watchdog ends the process.
pub const GRACE: Duration = Duration::from_secs(1);
/// How often the watchdog looks.
const TICK: Duration = Duration::from_millis(50);

/// Where the watchdog's line goes: the process's stderr unless SUMO's output is being
/// captured ([`crate::sumo::StderrCapture`] points fd 2 at a file, and sets this to the
/// original).
static REPORT_FD: AtomicI32 = AtomicI32::new(2);

/// The SUMO call under way, if one is marked: what it is, when it began, its bound.
static BUSY: Mutex<Option<Section>> = Mutex::new(None);

static STARTED: Once = Once::new();

struct Section {
    what: &'static str,
    /// SUMO's time when the call began, for the message, if it is a step.
    at: Option<f64>,
    since: Instant,
    limit: Duration,
}

impl Section {
    /// "the simulation step at t = 12.4 s", "starting sumo-gui".
    fn describe(&self) -> String {
        match self.at {
            Some(t) => format!("{} at t = {t} s", self.what),
            None => self.what.to_string(),
        }
    }
}

/// A marked call; the mark ends when this is dropped.
#[must_use = "the call is watched only while the guard lives"]
pub struct Busy(());

impl Drop for Busy {
    fn drop(&mut self) {
        *BUSY.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }
}

/// Marks a call that must return within `limit`: `what` names it in the error line, with
/// SUMO's time `at` when it is a step ("the simulation step at t = 12.4 s"). Allocates
/// nothing, as it runs every step. Starts the watchdog if it is not running.
pub fn busy(what: &'static str, at: Option<f64>, limit: Duration) -> Busy {
    start();
    *BUSY.lock().unwrap_or_else(|e| e.into_inner()) = Some(Section {
        what,
        at,
        since: Instant::now(),
        limit,
    });
    Busy(())
}

/// Sends the watchdog's line to `fd` (−1: back to fd 2).
pub fn report_to(fd: i32) {
    REPORT_FD.store(if fd < 0 { 2 } else { fd }, Ordering::SeqCst);
}

/// The descriptor that reaches the user's stderr: 2, or its duplicate while SUMO's output is
/// captured (see [`report_to`]), so that progress shown during an episode is not captured.
pub fn user_stderr() -> i32 {
    REPORT_FD.load(Ordering::SeqCst)
}

/// Starts the watchdog thread (once per process).
pub fn start() {
    STARTED.call_once(|| {
        std::thread::Builder::new()
            .name("bkpbs-watchdog".into())
            .spawn(watch)
            .expect("the watchdog thread starts");
    });
}

fn watch() {
    let mut signalled_at: Option<Instant> = None;
    loop {
        std::thread::sleep(TICK);
        if let Some(signal) = super::interrupt::received() {
            let at = *signalled_at.get_or_insert_with(Instant::now);
            if !super::interrupt::noticed() && at.elapsed() >= GRACE {
                end(
                    &format!(
                        "stopped by {} while {}, which did not return within {} s of the signal",
                        super::interrupt::name(signal),
                        busy_now().unwrap_or_else(|| "in a long computation".into()),
                        GRACE.as_secs()
                    ),
                    super::interrupt::exit_code(signal).into(),
                );
            }
        }
        if let Some(message) = overrun() {
            end(&message, 1);
        }
    }
}

/// What is under way, if a call is marked.
fn busy_now() -> Option<String> {
    let guard = BUSY.lock().unwrap_or_else(|e| e.into_inner());
    guard.as_ref().map(Section::describe)
}

/// The error line of a marked call past its bound, if there is one.
fn overrun() -> Option<String> {
    let guard = BUSY.lock().unwrap_or_else(|e| e.into_inner());
    let s = guard.as_ref()?;
    (s.since.elapsed() > s.limit).then(|| {
        format!(
            "SUMO is stuck: {} has not ended after {} s (sumo.stall_timeout_s); stopped",
            s.describe(),
            s.limit.as_secs_f64()
        )
    })
}

/// Writes `error: <message>` and ends the process with `code`, running nothing else.
fn end(message: &str, code: i32) -> ! {
    let line = format!("error: {message}\n");
    let fd = REPORT_FD.load(Ordering::SeqCst);
    // SAFETY: write(2) of a valid buffer, then _exit(2), which runs no destructors or atexit
    // handlers (libsumo's may not be safe while another thread is inside it).
    unsafe {
        libc::write(fd, line.as_ptr() as *const libc::c_void, line.len());
        libc::_exit(code);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_call_within_its_bound_is_not_reported() {
        let guard = busy("a quick call", None, Duration::from_secs(60));
        assert_eq!(overrun(), None);
        assert_eq!(busy_now().as_deref(), Some("a quick call"));
        drop(guard);
        assert_eq!(busy_now(), None);
    }

    #[test]
    fn a_call_past_its_bound_ends_the_process_with_one_line() {
        if std::env::var_os("BKPBS_WATCHDOG_CHILD").is_some() {
            let _guard = busy("a stuck call", Some(3.2), Duration::from_millis(200));
            std::thread::sleep(Duration::from_secs(30));
            return;
        }
        let started = Instant::now();
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "io::watchdog::tests::a_call_past_its_bound_ends_the_process_with_one_line",
                "--nocapture",
            ])
            .env("BKPBS_WATCHDOG_CHILD", "1")
            .output()
            .unwrap();
        assert!(started.elapsed() < Duration::from_secs(10));
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8_lossy(&out.stderr);
        let line = err.lines().find(|l| l.starts_with("error:")).unwrap();
        assert!(
            line.contains("a stuck call at t = 3.2 s has not ended after 0.2 s"),
            "{err}"
        );
    }
}
