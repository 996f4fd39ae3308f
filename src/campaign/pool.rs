//! The campaign side of the workers: W long-lived child processes of the same binary, fed one
//! episode at a time from a shared queue.
//!
//! Each child is driven by its own thread: send a [`Request`], wait for the [`Reply`]. A child
//! that dies (crash, kill, a planner aborting the process) fails the episode it was running,
//! which is recorded in the cell directory like any failure, and a fresh child takes its place.
//! Children stay in the campaign's process group and end when their stdin closes.
//!
//! With a wall-clock limit per episode, a worker that has not replied in time is stopped (and
//! killed if it does not stop) and the episode recorded as failed ("exceeded the episode
//! timeout"), so one runaway episode cannot hold a campaign forever. Replies are read on a
//! thread of their own per worker, so that the wait can end.
//!
//! A stop signal to the campaign ([`crate::io::interrupt`]) stops the queue: each worker is
//! passed the signal, ends its episode early (removing its input) and exits; its cell stays
//! unfinished, not failed. A worker that does not exit within [`STOP_GRACE`] is killed.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{mpsc, Mutex};
use std::time::{Duration, Instant};

use crate::io::interrupt;

use super::worker::{record_failure, Outcome, Reply, Request};

/// The hidden subcommand that turns the binary into a worker.
pub const WORKER_SUBCOMMAND: &str = "worker";

struct Worker {
    child: Child,
    stdin: ChildStdin,
    /// The worker's reply lines, read by [`forward_lines`]; closed when its stdout ends.
    replies: mpsc::Receiver<std::io::Result<String>>,
}

/// Forwards each line of `stdout` to `tx` until it ends (end or error), then stops.
fn forward_lines(mut stdout: BufReader<ChildStdout>, tx: mpsc::Sender<std::io::Result<String>>) {
    loop {
        let mut line = String::new();
        let read = stdout.read_line(&mut line);
        let stop = !matches!(read, Ok(n) if n > 0);
        if stop {
            if let Err(e) = read {
                let _ = tx.send(Err(e));
            }
            return;
        }
        if tx.send(Ok(line)).is_err() {
            return;
        }
    }
}

/// Why an exchange with a worker went wrong.
enum ExchangeError {
    /// The worker is gone or sent something unreadable.
    Broken(String),
    /// No reply within the episode timeout.
    TimedOut(Duration),
    /// The campaign was asked to stop (and passed the signal on).
    Stopped,
}

/// How long a worker passed a stop signal may take to end its episode and exit.
pub const STOP_GRACE: Duration = Duration::from_secs(10);
/// How often a wait for a reply looks at the clock and for stop signals.
const POLL: Duration = Duration::from_millis(100);

impl Worker {
    fn spawn(exe: &Path) -> std::io::Result<Worker> {
        let mut command = Command::new(exe);
        command
            .arg(WORKER_SUBCOMMAND)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit());
        crate::io::child::die_with_parent(&mut command);
        let mut child = command.spawn()?;
        let stdin = child.stdin.take().expect("piped stdin");
        let stdout = BufReader::new(child.stdout.take().expect("piped stdout"));
        let (tx, replies) = mpsc::channel();
        std::thread::spawn(move || forward_lines(stdout, tx));
        Ok(Worker {
            child,
            stdin,
            replies,
        })
    }

    /// Sends one request and waits for its reply, at most `timeout` if one is given.
    fn exchange(
        &mut self,
        req: &Request,
        timeout: Option<Duration>,
    ) -> Result<Reply, ExchangeError> {
        let broken = ExchangeError::Broken;
        let mut line = serde_json::to_string(req).expect("request serialises");
        line.push('\n');
        self.stdin
            .write_all(line.as_bytes())
            .and_then(|()| self.stdin.flush())
            .map_err(|e| broken(format!("cannot send the episode: {e}")))?;
        let received = self.wait_for_reply(timeout)?;
        let line = received.map_err(|e| broken(format!("cannot read the reply: {e}")))?;
        let reply: Reply = serde_json::from_str(&line)
            .map_err(|e| broken(format!("malformed reply ({e}): {}", line.trim())))?;
        if reply.position != req.position {
            return Err(broken(format!(
                "reply for cell {} while waiting for cell {}",
                reply.position, req.position
            )));
        }
        Ok(reply)
    }

    /// The next line from the worker, waiting at most `timeout`; a stop signal to the campaign
    /// is passed on, and the wait ends when the worker exits or [`STOP_GRACE`] is over.
    fn wait_for_reply(
        &self,
        timeout: Option<Duration>,
    ) -> Result<std::io::Result<String>, ExchangeError> {
        let start = Instant::now();
        let mut stop_passed_on: Option<Instant> = None;
        loop {
            match self.replies.recv_timeout(POLL) {
                Ok(line) => return Ok(line),
                Err(mpsc::RecvTimeoutError::Disconnected) if stop_passed_on.is_some() => {
                    return Err(ExchangeError::Stopped)
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(ExchangeError::Broken("no reply".into()))
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
            if let Some(signal) = interrupt::requested() {
                match stop_passed_on {
                    None => {
                        interrupt::forward(self.child.id(), signal);
                        stop_passed_on = Some(Instant::now());
                    }
                    Some(at) if at.elapsed() > STOP_GRACE => return Err(ExchangeError::Stopped),
                    Some(_) => {}
                }
            }
            if let Some(t) = timeout.filter(|&t| start.elapsed() >= t) {
                return Err(ExchangeError::TimedOut(t));
            }
        }
    }

    /// Asks the worker to stop (SIGTERM: it ends its episode at the next step and removes the
    /// episode's input), kills it if it has not exited within [`STOP_GRACE`].
    fn stop(mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            interrupt::forward(self.child.id(), libc::SIGTERM);
            let start = Instant::now();
            while matches!(self.child.try_wait(), Ok(None)) && start.elapsed() < STOP_GRACE {
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        self.kill();
    }

    /// Kills the worker (if still alive) and says how it ended.
    fn kill(mut self) -> String {
        let _ = self.child.kill();
        match self.child.wait() {
            Ok(status) => status.to_string(),
            Err(e) => format!("unknown exit ({e})"),
        }
    }

    /// Closes its stdin, so it finishes, and waits for it.
    fn finish(self) {
        let Worker {
            mut child, stdin, ..
        } = self;
        drop(stdin);
        let _ = child.wait();
    }
}

/// How the pool runs: how many workers, and how long one episode may take.
#[derive(Debug, Clone, Copy)]
pub struct PoolOptions {
    /// Most worker processes running at once.
    pub workers: usize,
    /// Longest one episode may take before its worker is stopped and the episode recorded as
    /// failed; `None`: no limit.
    pub episode_timeout: Option<Duration>,
}

/// Runs every request on up to `options.workers` child processes of `exe`, calling `on_reply`
/// on the calling thread as episodes finish (in completion order). Every request gets exactly
/// one reply, unless a stop signal ends the run first; failures to start or keep a worker, and
/// episodes over the timeout, are failed replies, never errors.
pub fn run(
    exe: &Path,
    requests: Vec<Request>,
    options: PoolOptions,
    mut on_reply: impl FnMut(Reply),
) {
    let workers = options.workers;
    let threads = workers.max(1).min(requests.len());
    let queue = Mutex::new(VecDeque::from(requests));
    let (tx, rx) = mpsc::channel::<Reply>();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            let tx = tx.clone();
            let queue = &queue;
            scope.spawn(move || drive(exe, queue, options.episode_timeout, &tx));
        }
        drop(tx);
        for reply in rx {
            on_reply(reply);
        }
    });
}

/// One thread's loop: keep one worker busy until the queue is empty.
fn drive(
    exe: &Path,
    queue: &Mutex<VecDeque<Request>>,
    timeout: Option<Duration>,
    tx: &mpsc::Sender<Reply>,
) {
    let mut worker: Option<Worker> = None;
    loop {
        if interrupt::requested().is_some() {
            break;
        }
        let next = queue.lock().unwrap_or_else(|e| e.into_inner()).pop_front();
        let Some(req) = next else { break };
        match serve(exe, worker.take(), &req, timeout) {
            Turn::NoWorker(reply) => {
                let _ = tx.send(reply);
            }
            Turn::Done(reply, kept) => {
                worker = kept;
                if tx.send(reply).is_err() {
                    break;
                }
            }
            Turn::Stop => break,
        }
    }
    if let Some(w) = worker {
        w.finish();
    }
}

/// What one request came to on a pool thread.
enum Turn {
    /// No worker could be started: the failed reply.
    NoWorker(Reply),
    /// The reply, and the worker if it can take the next request.
    Done(Reply, Option<Worker>),
    /// A stop signal ended the run (the worker is stopped).
    Stop,
}

/// A failed reply to `req`, recorded in its episode directory.
fn failed(req: &Request, error: String) -> Reply {
    record_failure(&req.dir, &error);
    Reply {
        position: req.position,
        outcome: Outcome::Failed { error },
    }
}

/// Runs `req` on `worker` (started from `exe` if there is none yet); a worker that broke or
/// overran the timeout is ended.
fn serve(exe: &Path, worker: Option<Worker>, req: &Request, timeout: Option<Duration>) -> Turn {
    let mut w = match worker {
        Some(w) => w,
        None => match Worker::spawn(exe) {
            Ok(w) => w,
            Err(e) => {
                return Turn::NoWorker(failed(
                    req,
                    format!(
                        "cannot start worker {} {WORKER_SUBCOMMAND}: {e}",
                        exe.display()
                    ),
                ))
            }
        },
    };
    match w.exchange(req, timeout) {
        Ok(reply) => Turn::Done(reply, Some(w)),
        Err(ExchangeError::Stopped) => {
            w.stop();
            Turn::Stop
        }
        Err(ExchangeError::Broken(_)) if interrupt::requested().is_some() => {
            w.kill();
            Turn::Stop
        }
        Err(ExchangeError::Broken(why)) => {
            let status = w.kill();
            let why = format!("worker process died during the episode ({why}; {status})");
            Turn::Done(failed(req, why), None)
        }
        Err(ExchangeError::TimedOut(t)) => {
            w.stop();
            let why = format!(
                "episode exceeded the episode timeout of {} s and was stopped",
                t.as_secs_f64()
            );
            Turn::Done(failed(req, why), None)
        }
    }
}
