//! Captures what SUMO writes to standard error while a simulation runs.
//!
//! SUMO prints some messages ("Error: ... will not be able to depart") to stderr even with
//! `--no-warnings`, and no option silences them. Unless the user asks for SUMO's output, the
//! process's stderr is pointed at a temporary file for the simulation's lifetime and restored
//! afterwards; what was captured is handed back so it can be saved next to the results.
//!
//! libsumo can also abort the whole process (Debian builds it with assertions on). So that such
//! a death is never silent, a SIGABRT handler restores stderr and replays the captured text
//! before the process dies.

use std::io::{Read, Seek, SeekFrom};
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicI32, Ordering};

/// The original stderr and the capture file while a capture is active (−1 otherwise), for the
/// signal handler, which may only use async-signal-safe calls.
static SAVED_STDERR: AtomicI32 = AtomicI32::new(-1);
static CAPTURE_FD: AtomicI32 = AtomicI32::new(-1);

extern "C" fn replay_on_abort(_signal: libc::c_int) {
    let saved = SAVED_STDERR.load(Ordering::SeqCst);
    let capture = CAPTURE_FD.load(Ordering::SeqCst);
    // SAFETY: only async-signal-safe calls (dup2, write, lseek, read, signal, raise).
    unsafe {
        if saved >= 0 {
            libc::dup2(saved, 2);
            let head = b"error: SUMO aborted the process; it said:\n";
            libc::write(2, head.as_ptr() as *const libc::c_void, head.len());
            if capture >= 0 {
                libc::lseek(capture, 0, libc::SEEK_SET);
                let mut buf = [0u8; 4096];
                loop {
                    let n = libc::read(capture, buf.as_mut_ptr() as *mut libc::c_void, buf.len());
                    if n <= 0 {
                        break;
                    }
                    libc::write(2, buf.as_ptr() as *const libc::c_void, n as usize);
                }
            }
        }
        libc::signal(libc::SIGABRT, libc::SIG_DFL);
        libc::raise(libc::SIGABRT);
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
            let handler: extern "C" fn(libc::c_int) = replay_on_abort;
            libc::signal(libc::SIGABRT, handler as libc::sighandler_t);
            Some(StderrCapture { saved, file })
        }
    }

    fn restore(&mut self) {
        if self.saved >= 0 {
            // SAFETY: `saved` is a valid duplicate of the original stderr.
            unsafe {
                libc::signal(libc::SIGABRT, libc::SIG_DFL);
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

    #[test]
    fn abort_while_capturing_replays_the_capture() {
        if std::env::var_os("BKPBS_ABORT_CHILD").is_some() {
            let _c = StderrCapture::start();
            let line = b"last words\n";
            // SAFETY: writing a valid buffer to fd 2.
            unsafe { libc::write(2, line.as_ptr() as *const libc::c_void, line.len()) };
            // SAFETY: this child process is meant to die here.
            unsafe { libc::abort() };
        }
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "sumo::quiet::tests::abort_while_capturing_replays_the_capture",
                "--nocapture",
            ])
            .env("BKPBS_ABORT_CHILD", "1")
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("SUMO aborted the process") && err.contains("last words"),
            "{err}"
        );
    }
}
