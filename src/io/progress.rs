//! Progress of a long run on the user's stderr: on a terminal a bar (a campaign) or a line
//! redrawn in place each second (an episode, whose SUMO output may be captured meanwhile), and
//! elsewhere (a log file, a batch job) a line every [`LINE_EVERY`] (or [`EVERY_ENV`]), so a
//! 30-minute scenario or a campaign never runs in silence. A run shorter than the interval
//! prints no line at all.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How often a line is printed where stderr is no terminal.
pub const LINE_EVERY: Duration = Duration::from_secs(60);

/// How often a line on a terminal is redrawn in place.
const REDRAW_EVERY: Duration = Duration::from_secs(1);

/// Test hook: `BKPBS_PROGRESS_EVERY_S=<seconds>` prints the lines that often instead (the
/// test suite's short runs); unset in normal use.
pub const EVERY_ENV: &str = "BKPBS_PROGRESS_EVERY_S";

/// The interval between two lines: [`LINE_EVERY`], or the test hook's.
fn line_every() -> Duration {
    std::env::var(EVERY_ENV)
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .map_or(LINE_EVERY, Duration::from_secs_f64)
}

/// How the progress is shown.
enum Display {
    /// indicatif's bar on stderr (a terminal).
    Bar(ProgressBar),
    /// Lines written to descriptor `fd`: redrawn in place on a terminal, else one a line.
    Lines { fd: i32, in_place: bool },
}

/// Progress of `total` units of work (`what`: "steps", "episodes").
pub struct Progress {
    what: &'static str,
    /// The label of each line (`episode`, `campaign`).
    label: &'static str,
    total: u64,
    done: u64,
    started: Instant,
    every: Duration,
    next_line: Instant,
    display: Display,
    /// Extra words after the count (`3 failed`).
    note: String,
}

impl Progress {
    /// Progress of `total` `what` on stderr, its lines led by `label`; a bar on a terminal.
    pub fn new(label: &'static str, total: u64, what: &'static str) -> Progress {
        let display = if std::io::stderr().is_terminal() {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
            let template = format!(
                "{{elapsed_precise}} [{{bar:30}}] {{pos}}/{{len}} {what}{{msg}}, ETA {{eta}}"
            );
            bar.set_style(
                ProgressStyle::with_template(&template)
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            Display::Bar(bar)
        } else {
            Display::Lines {
                fd: 2,
                in_place: false,
            }
        };
        Progress::shown(label, total, what, display)
    }

    /// Progress of `total` `what` on descriptor `fd` (the user's stderr while fd 2 may be
    /// captured): a line redrawn in place on a terminal, a line a minute elsewhere.
    pub fn on_fd(label: &'static str, total: u64, what: &'static str, fd: i32) -> Progress {
        // SAFETY: isatty on any descriptor number only reads.
        let in_place = unsafe { libc::isatty(fd) } == 1;
        Progress::shown(label, total, what, Display::Lines { fd, in_place })
    }

    fn shown(label: &'static str, total: u64, what: &'static str, display: Display) -> Progress {
        let started = Instant::now();
        let every = match display {
            Display::Lines { in_place: true, .. } => REDRAW_EVERY,
            _ => line_every(),
        };
        Progress {
            what,
            label,
            total,
            done: 0,
            started,
            every,
            next_line: started + every,
            display,
            note: String::new(),
        }
    }

    /// Prints `line` above the bar, or as it is.
    pub fn println(&self, line: &str) {
        match &self.display {
            Display::Bar(bar) => bar.println(line),
            Display::Lines { fd, in_place } => {
                let clear = if *in_place { "\r\x1b[K" } else { "" };
                write_fd(*fd, &format!("{clear}{line}\n"));
            }
        }
    }

    /// Sets the words after the count (`3 failed`).
    pub fn set_note(&mut self, note: String) {
        if let Display::Bar(bar) = &self.display {
            bar.set_message(format!(", {note}"));
        }
        self.note = note;
    }

    /// `n` more units done.
    pub fn advance(&mut self, n: u64) {
        self.done += n;
        let (fd, in_place) = match &self.display {
            Display::Bar(bar) => return bar.inc(n),
            Display::Lines { fd, in_place } => (*fd, *in_place),
        };
        let now = Instant::now();
        if now >= self.next_line && self.done < self.total {
            self.next_line = now + self.every;
            let line = self.line(now - self.started);
            match in_place {
                true => write_fd(fd, &format!("\r\x1b[K{line}")),
                false => write_fd(fd, &format!("{line}\n")),
            }
        }
    }

    /// The line after `elapsed`: count, share, time, and the time left at this pace.
    fn line(&self, elapsed: Duration) -> String {
        let share = self.done as f64 / self.total.max(1) as f64;
        let left = (share > 0.0).then(|| elapsed.as_secs_f64() * (1.0 - share) / share);
        let note = match self.note.as_str() {
            "" => String::new(),
            n => format!(", {n}"),
        };
        format!(
            "{}: {}/{} {} ({:.0} %){note}, {} elapsed, about {} left",
            self.label,
            self.done,
            self.total,
            self.what,
            100.0 * share,
            minutes(elapsed.as_secs_f64()),
            left.map_or("?".into(), minutes),
        )
    }

    /// Removes the bar, or the line drawn in place.
    pub fn finish(&self) {
        match &self.display {
            Display::Bar(bar) => bar.finish_and_clear(),
            Display::Lines { fd, in_place: true } => write_fd(*fd, "\r\x1b[K"),
            Display::Lines { .. } => {}
        }
    }
}

/// Writes `text` to descriptor `fd` whole (a progress line is best effort: errors are dropped).
fn write_fd(fd: i32, text: &str) {
    let mut rest = text.as_bytes();
    while !rest.is_empty() {
        // SAFETY: write(2) of a valid buffer of the given length.
        let n = unsafe { libc::write(fd, rest.as_ptr() as *const libc::c_void, rest.len()) };
        if n <= 0 {
            return;
        }
        rest = &rest[n as usize..];
    }
}

/// `75 s` or `12.5 min`.
fn minutes(s: f64) -> String {
    if s < 90.0 {
        format!("{s:.0} s")
    } else {
        format!("{:.1} min", s / 60.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_says_how_far_and_how_long_is_left() {
        let mut p = Progress::on_fd("episode", 9000, "steps", -1);
        p.done = 3000;
        assert_eq!(
            p.line(Duration::from_secs(60)),
            "episode: 3000/9000 steps (33 %), 60 s elapsed, about 2.0 min left"
        );
        p.set_note("2 failed".into());
        p.done = 0;
        assert_eq!(
            p.line(Duration::from_secs(600)),
            "episode: 0/9000 steps (0 %), 2 failed, 10.0 min elapsed, about ? left"
        );
    }
}
