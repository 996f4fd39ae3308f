//! Captures what SUMO writes to standard error while a simulation runs.
//!
//! SUMO prints some messages ("Error: ... will not be able to depart") to stderr even with
//! `--no-warnings`, and no option silences them. Unless the user asks for SUMO's output, the
//! process's stderr is pointed at a temporary file for the simulation's lifetime and restored
//! afterwards; what was captured is handed back so it can be saved next to the results.
//!
//! libsumo can also abort the whole process (Debian builds it with assertions on). So that such
//! a death is one `error:` line like every other failure, a SIGABRT handler restores stderr,
//! prints SUMO's last captured line and exits with code 1.

use std::io::{Read, Seek, SeekFrom};
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicI32, Ordering};

/// The original stderr and the capture file while a capture is active (−1 otherwise), for the
/// signal handler, which may only use async-signal-safe calls.
static SAVED_STDERR: AtomicI32 = AtomicI32::new(-1);
static CAPTURE_FD: AtomicI32 = AtomicI32::new(-1);

extern "C" fn report_abort(_signal: libc::c_int) {
    let saved = SAVED_STDERR.load(Ordering::SeqCst);
    let capture = CAPTURE_FD.load(Ordering::SeqCst);
    let mut tail = [0u8; 4096];
    // SAFETY: only async-signal-safe calls (dup2, lseek, read, write, _exit) on valid buffers.
    unsafe {
        let mut n = 0;
        if saved >= 0 {
            libc::dup2(saved, 2);
            if capture >= 0 {
                let size = libc::lseek(capture, 0, libc::SEEK_END);
                let from = (size - tail.len() as libc::off_t).max(0);
                libc::lseek(capture, from, libc::SEEK_SET);
                n = libc::read(capture, tail.as_mut_ptr() as *mut libc::c_void, tail.len()).max(0)
                    as usize;
            }
        }
        let said = last_line(&tail[..n]);
        let head: &[u8] = if said.is_empty() {
            b"error: SUMO aborted the process (its own message is on the line above)"
        } else {
            b"error: SUMO aborted the process: "
        };
        for part in [head, said, b"\n"] {
            libc::write(2, part.as_ptr() as *const libc::c_void, part.len());
        }
        libc::_exit(1);
    }
}

/// The last non-empty line of `text`, without its line end (allocation-free, for the handler).
fn last_line(text: &[u8]) -> &[u8] {
    let trimmed = match text.iter().rposition(|b| !b.is_ascii_whitespace()) {
        Some(end) => &text[..=end],
        None => return &[],
    };
    match trimmed.iter().rposition(|&b| b == b'\n') {
        Some(start) => &trimmed[start + 1..],
        None => trimmed,
    }
}

/// The SIGABRT action in place before [`report_aborts`] took over (Python's faulthandler, say),
/// put back when it lets go.
static PREVIOUS_ABORT_ACTION: std::sync::Mutex<Option<libc::sigaction>> =
    std::sync::Mutex::new(None);

/// Makes a libsumo abort (an assertion inside SUMO) one `error:` line and exit code 1, with
/// SUMO's last words when they were captured; `false` puts back the action that was there
/// before (an abort outside SUMO is not SUMO's). [`super::Simulation`] turns it on while a
/// simulation is open.
pub fn report_aborts(on: bool) {
    let mut previous = PREVIOUS_ABORT_ACTION
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    // SAFETY: sigaction with zeroed, filled-in structs; the handler installed only makes
    // async-signal-safe calls.
    unsafe {
        if on && previous.is_none() {
            let handler: extern "C" fn(libc::c_int) = report_abort;
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = handler as libc::sighandler_t;
            libc::sigemptyset(&mut action.sa_mask);
            let mut old: libc::sigaction = std::mem::zeroed();
            libc::sigaction(libc::SIGABRT, &action, &mut old);
            *previous = Some(old);
        } else if let (false, Some(old)) = (on, previous.take()) {
            libc::sigaction(libc::SIGABRT, &old, std::ptr::null_mut());
        }
    }
}

/// Redirects fd 2 to a temporary file until [`StderrCapture::finish`] or drop.
pub struct StderrCapture {
    saved: libc::c_int,
    file: std::fs::File,
}

impl StderrCapture {
    /// Starts capturing; `None` if the redirection is impossible (then stderr is left alone).
    pub fn start() -> Option<Self> {
        let file = tempfile::tempfile().ok()?;
        // SAFETY: plain fd calls; `saved` is checked and restored on every path.
        unsafe {
            let saved = libc::dup(2);
            if saved < 0 {
                return None;
            }
            if libc::dup2(file.as_raw_fd(), 2) < 0 {
                libc::close(saved);
                return None;
            }
            SAVED_STDERR.store(saved, Ordering::SeqCst);
            CAPTURE_FD.store(file.as_raw_fd(), Ordering::SeqCst);
            crate::io::watchdog::report_to(saved);
            Some(StderrCapture { saved, file })
        }
    }

    fn restore(&mut self) {
        if self.saved >= 0 {
            // SAFETY: `saved` is a valid duplicate of the original stderr.
            unsafe {
                crate::io::watchdog::report_to(-1);
                SAVED_STDERR.store(-1, Ordering::SeqCst);
                CAPTURE_FD.store(-1, Ordering::SeqCst);
                libc::dup2(self.saved, 2);
                libc::close(self.saved);
            }
            self.saved = -1;
        }
    }

    /// Restores stderr and returns what was written meanwhile.
    pub fn finish(mut self) -> String {
        self.restore();
        let mut text = String::new();
        if self.file.seek(SeekFrom::Start(0)).is_ok() {
            let _ = self.file.read_to_string(&mut text);
        }
        text
    }
}

impl Drop for StderrCapture {
    fn drop(&mut self) {
        self.restore();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capture_returns_what_was_written_and_restores_stderr() {
        let c = StderrCapture::start().expect("redirect works here");
        // Straight to fd 2, as SUMO writes (the test harness captures eprintln! itself).
        let line = b"captured line\n";
        // SAFETY: writing a valid buffer to fd 2.
        unsafe { libc::write(2, line.as_ptr() as *const libc::c_void, line.len()) };
        let text = c.finish();
        assert!(text.contains("captured line"));
    }

    extern "C" fn someone_elses(_signal: libc::c_int) {}

    /// The SIGABRT handler now in place.
    fn current_abort_handler() -> libc::sighandler_t {
        // SAFETY: sigaction with a null new action only reads the current one.
        unsafe {
            let mut now: libc::sigaction = std::mem::zeroed();
            libc::sigaction(libc::SIGABRT, std::ptr::null(), &mut now);
            now.sa_sigaction
        }
    }

    #[test]
    fn the_abort_handler_puts_back_the_one_it_replaced() {
        let theirs: extern "C" fn(libc::c_int) = someone_elses;
        // SAFETY: installs a handler that does nothing.
        unsafe { libc::signal(libc::SIGABRT, theirs as libc::sighandler_t) };
        report_aborts(true);
        let ours: extern "C" fn(libc::c_int) = report_abort;
        assert_eq!(current_abort_handler(), ours as libc::sighandler_t);
        report_aborts(false);
        assert_eq!(current_abort_handler(), theirs as libc::sighandler_t);
        // SAFETY: back to the default.
        unsafe { libc::signal(libc::SIGABRT, libc::SIG_DFL) };
    }

    #[test]
    fn abort_while_capturing_is_one_line_with_sumos_last_words() {
        if std::env::var_os("BKPBS_ABORT_CHILD").is_some() {
            let _c = StderrCapture::start();
            report_aborts(true);
            let line = b"earlier words\nlast words\n\n";
            // SAFETY: writing a valid buffer to fd 2.
            unsafe { libc::write(2, line.as_ptr() as *const libc::c_void, line.len()) };
            // SAFETY: this child process is meant to die here.
            unsafe { libc::abort() };
        }
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "sumo::quiet::tests::abort_while_capturing_is_one_line_with_sumos_last_words",
                "--nocapture",
            ])
            .env("BKPBS_ABORT_CHILD", "1")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8_lossy(&out.stderr);
        let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(
            errors,
            ["error: SUMO aborted the process: last words"],
            "{err}"
        );
        assert!(!err.contains("earlier words"), "{err}");
    }
}
