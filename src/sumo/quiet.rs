//! Captures what SUMO writes to standard error while a simulation runs.
//!
//! SUMO prints some messages ("Error: ... will not be able to depart") to stderr even with
//! `--no-warnings`, and no option silences them. Unless the user asks for SUMO's output, the
//! process's stderr is pointed at a temporary file for the simulation's lifetime and restored
//! afterwards; what was captured is handed back so it can be saved next to the results.

use std::io::{Read, Seek, SeekFrom};
use std::os::fd::AsRawFd;

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
            Some(StderrCapture { saved, file })
        }
    }

    fn restore(&mut self) {
        if self.saved >= 0 {
            // SAFETY: `saved` is a valid duplicate of the original stderr.
            unsafe {
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
