//! The campaign side of the workers: W long-lived child processes of the same binary, fed one
//! episode at a time from a shared queue.
//!
//! Each child is driven by its own thread: send a [`Request`], wait for the [`Reply`]. A child
//! that dies (crash, kill, a planner aborting the process) fails the episode it was running,
//! which is recorded in the cell directory like any failure, and a fresh child takes its place.
//! Children stay in the campaign's process group and end when their stdin closes.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{mpsc, Mutex};

use super::worker::{record_failure, Outcome, Reply, Request};

/// The hidden subcommand that turns the binary into a worker.
pub const WORKER_SUBCOMMAND: &str = "worker";

struct Worker {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

/// On Linux, the kernel kills the worker when the campaign dies, set up in the child before it
/// runs the binary, so there is no moment in which a killed campaign can leave it orphaned (a
/// worker that asked for this itself, once started, could miss a parent killed in its first
/// milliseconds and then run its episode to the end). Elsewhere a worker ends when its stdin
/// closes.
fn die_with_campaign(command: &mut Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        let campaign = std::process::id() as libc::pid_t;
        // SAFETY: the closure runs in the forked child before exec and calls only prctl,
        // getppid and _exit, which are async-signal-safe.
        unsafe {
            command.pre_exec(move || {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
                if libc::getppid() != campaign {
                    libc::_exit(1);
                }
                Ok(())
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = command;
}

impl Worker {
    fn spawn(exe: &Path) -> std::io::Result<Worker> {
        let mut command = Command::new(exe);
        command
            .arg(WORKER_SUBCOMMAND)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit());
        die_with_campaign(&mut command);
        let mut child = command.spawn()?;
        let stdin = child.stdin.take().expect("piped stdin");
        let stdout = BufReader::new(child.stdout.take().expect("piped stdout"));
        Ok(Worker {
            child,
            stdin,
            stdout,
        })
    }

    /// Sends one request and waits for its reply; `Err` if the worker is gone or garbled.
    fn exchange(&mut self, req: &Request) -> Result<Reply, String> {
        let mut line = serde_json::to_string(req).expect("request serialises");
        line.push('\n');
        self.stdin
            .write_all(line.as_bytes())
            .and_then(|()| self.stdin.flush())
            .map_err(|e| format!("cannot send the episode: {e}"))?;
        line.clear();
        match self.stdout.read_line(&mut line) {
            Ok(0) => Err("no reply".into()),
            Ok(_) => {
                let reply: Reply = serde_json::from_str(&line)
                    .map_err(|e| format!("malformed reply ({e}): {}", line.trim()))?;
                if reply.position != req.position {
                    return Err(format!(
                        "reply for cell {} while waiting for cell {}",
                        reply.position, req.position
                    ));
                }
                Ok(reply)
            }
            Err(e) => Err(format!("cannot read the reply: {e}")),
        }
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

/// Runs every request on up to `workers` child processes of `exe`, calling `on_reply` on the
/// calling thread as episodes finish (in completion order). Every request gets exactly one
/// reply; failures to start or keep a worker are failed replies, never errors.
pub fn run(exe: &Path, requests: Vec<Request>, workers: usize, mut on_reply: impl FnMut(Reply)) {
    let threads = workers.max(1).min(requests.len());
    let queue = Mutex::new(VecDeque::from(requests));
    let (tx, rx) = mpsc::channel::<Reply>();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            let tx = tx.clone();
            let queue = &queue;
            scope.spawn(move || drive(exe, queue, &tx));
        }
        drop(tx);
        for reply in rx {
            on_reply(reply);
        }
    });
}

/// One thread's loop: keep one worker busy until the queue is empty.
fn drive(exe: &Path, queue: &Mutex<VecDeque<Request>>, tx: &mpsc::Sender<Reply>) {
    let mut worker: Option<Worker> = None;
    loop {
        let next = queue.lock().unwrap_or_else(|e| e.into_inner()).pop_front();
        let Some(req) = next else { break };
        let failed = |error: String| {
            record_failure(&req.dir, &error);
            Reply {
                position: req.position,
                outcome: Outcome::Failed { error },
            }
        };
        let w = match worker.take() {
            Some(w) => w,
            None => match Worker::spawn(exe) {
                Ok(w) => w,
                Err(e) => {
                    let _ = tx.send(failed(format!(
                        "cannot start worker {} {WORKER_SUBCOMMAND}: {e}",
                        exe.display()
                    )));
                    continue;
                }
            },
        };
        let mut w = w;
        let reply = match w.exchange(&req) {
            Ok(reply) => {
                worker = Some(w);
                reply
            }
            Err(why) => {
                let status = w.kill();
                failed(format!(
                    "worker process died during the episode ({why}; {status})"
                ))
            }
        };
        if tx.send(reply).is_err() {
            break;
        }
    }
    if let Some(w) = worker {
        w.finish();
    }
}
