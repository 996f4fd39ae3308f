//! RL rollouts in worker processes (`bkpbs rl-worker`): libsumo runs one simulation per
//! process, so parallel episodes need processes. Protocol as the campaign's workers: one JSON
//! request per line on stdin, one JSON reply per line on the original stdout; end of stdin ends
//! the worker. The policy travels as a file path (its weights are megabytes).
//!
//! Replies are put back in request order, so what a trainer receives does not depend on the
//! number of workers or which finished first.

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::env::Agents;
use super::reward::RewardSettings;
use super::rollout::{self, Rollout};
use crate::config::Config;
use crate::controller::rl_ppo::Choice;
use crate::policy::model_file::PolicyFile;

/// One episode to roll out.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RolloutRequest {
    /// Position of the request in its batch; the reply carries it back.
    pub index: usize,
    /// The episode (α, λ, seed and steps set).
    pub config: Config,
    /// The policy file to act with.
    pub policy: PathBuf,
    /// How the CAVs choose their primitives.
    pub acting: Acting,
    /// The reward's terms and weights.
    pub reward: RewardSettings,
    /// One CAV among HDVs (the paper's training set-up) instead of every CAV.
    #[serde(default)]
    pub single_cav: bool,
}

/// How the CAVs of a rollout choose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Acting {
    /// Sampling from the policy, with this seed (training).
    Sample(u64),
    /// The policy's most probable primitive (evaluation).
    Greedy,
    /// Uniform over the allowed primitives, with this seed (reference).
    Random(u64),
    /// Always idle (reference).
    Idle,
}

impl Acting {
    /// The controller's way of choosing, seeded as given.
    pub fn choice(self) -> Choice {
        match self {
            Acting::Sample(seed) => Choice::Sample(ChaCha8Rng::seed_from_u64(seed)),
            Acting::Greedy => Choice::Greedy,
            Acting::Random(seed) => Choice::Random(ChaCha8Rng::seed_from_u64(seed)),
            Acting::Idle => Choice::Idle,
        }
    }
}

/// The answer to one request.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RolloutReply {
    /// The request's [`RolloutRequest::index`].
    pub index: usize,
    /// The episode's experience, or its error as text.
    pub result: Result<Rollout, String>,
}

/// Why rollouts could not be gathered.
#[derive(Debug, thiserror::Error)]
pub enum PoolError {
    /// A worker process could not be started.
    #[error("cannot start RL worker: {0}")]
    Spawn(std::io::Error),
    /// A worker (by number) exited or closed its pipes before replying.
    #[error("RL worker {0} ended unexpectedly")]
    Died(usize),
    /// A reply was not valid JSON or named an unknown request.
    #[error("RL worker sent a malformed reply: {0}")]
    Reply(String),
    /// The worker could not run a requested episode.
    #[error("rollout episode {index} failed: {error}")]
    Episode {
        /// The request's index in its batch.
        index: usize,
        /// The episode's error, as text.
        error: String,
    },
    /// The trainer was asked to stop by this signal (SIGINT, SIGTERM).
    #[error("stopped by signal {0}")]
    Interrupted(i32),
}

/// Answers requests from stdin until it closes.
pub fn serve_stdio() -> std::io::Result<()> {
    let mut out = crate::io::child::protocol_channel()?;
    let mut line = String::new();
    let mut input = std::io::stdin().lock();
    loop {
        line.clear();
        if input.read_line(&mut line)? == 0 {
            return Ok(());
        }
        let reply = match serde_json::from_str::<RolloutRequest>(&line) {
            Ok(req) => RolloutReply {
                index: req.index,
                result: serve_one(&req),
            },
            Err(e) => RolloutReply {
                index: usize::MAX,
                result: Err(format!("malformed request: {e}")),
            },
        };
        if crate::io::interrupt::requested().is_some() {
            return Ok(());
        }
        let text = serde_json::to_string(&reply).expect("a reply serialises");
        writeln!(out, "{text}")?;
        out.flush()?;
    }
}

fn serve_one(req: &RolloutRequest) -> Result<Rollout, String> {
    let net = PolicyFile::read(&req.policy)
        .map_err(|e| e.to_string())?
        .networks();
    let agents = if req.single_cav {
        Agents::Single
    } else {
        Agents::AllCavs
    };
    rollout::run(
        &req.config,
        Arc::new(net),
        req.acting.choice(),
        &req.reward,
        agents,
    )
    .map_err(|e| e.to_string())
}

struct Worker {
    child: Child,
    stdin: ChildStdin,
}

/// Long-lived worker processes.
pub struct Pool {
    workers: Vec<Worker>,
    replies: mpsc::Receiver<(usize, Option<String>)>,
}

impl Pool {
    /// Starts `n` workers (`bkpbs rl-worker`).
    pub fn start(n: usize) -> Result<Pool, PoolError> {
        let exe = std::env::current_exe().map_err(PoolError::Spawn)?;
        let (tx, replies) = mpsc::channel();
        let mut workers = Vec::new();
        for k in 0..n.max(1) {
            let mut cmd = Command::new(&exe);
            cmd.arg("rl-worker")
                .stdin(Stdio::piped())
                .stdout(Stdio::piped())
                .stderr(Stdio::inherit());
            crate::io::child::die_with_parent(&mut cmd);
            let mut child = cmd.spawn().map_err(PoolError::Spawn)?;
            let stdin = child.stdin.take().expect("piped stdin");
            let stdout = BufReader::new(child.stdout.take().expect("piped stdout"));
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in stdout.lines() {
                    let Ok(line) = line else { break };
                    if tx.send((k, Some(line))).is_err() {
                        return;
                    }
                }
                let _ = tx.send((k, None));
            });
            workers.push(Worker { child, stdin });
        }
        Ok(Pool { workers, replies })
    }

    /// Runs every request, returning the rollouts in request order.
    pub fn run(&mut self, requests: Vec<RolloutRequest>) -> Result<Vec<Rollout>, PoolError> {
        let n = requests.len();
        let mut results: Vec<Option<Rollout>> = vec![None; n];
        let mut queue = requests.into_iter();
        let mut busy = 0;
        for k in 0..self.workers.len() {
            if let Some(r) = queue.next() {
                self.send(k, &r)?;
                busy += 1;
            }
        }
        while busy > 0 {
            if let Some(sig) = crate::io::interrupt::requested() {
                return Err(PoolError::Interrupted(sig));
            }
            let (k, line) = match self.replies.recv_timeout(Duration::from_millis(100)) {
                Ok(x) => x,
                Err(mpsc::RecvTimeoutError::Timeout) => continue,
                Err(mpsc::RecvTimeoutError::Disconnected) => return Err(PoolError::Died(0)),
            };
            let Some(line) = line else {
                // A worker stopped by the same signal as the trainer ends without a reply.
                return Err(match crate::io::interrupt::requested() {
                    Some(sig) => PoolError::Interrupted(sig),
                    None => PoolError::Died(k),
                });
            };
            let reply: RolloutReply =
                serde_json::from_str(&line).map_err(|e| PoolError::Reply(e.to_string()))?;
            let index = reply.index;
            let rollout = reply
                .result
                .map_err(|error| PoolError::Episode { index, error })?;
            *results
                .get_mut(index)
                .ok_or_else(|| PoolError::Reply(format!("unknown index {index}")))? = Some(rollout);
            busy -= 1;
            if let Some(r) = queue.next() {
                self.send(k, &r)?;
                busy += 1;
            }
        }
        Ok(results.into_iter().map(Option::unwrap_or_default).collect())
    }

    fn send(&mut self, k: usize, r: &RolloutRequest) -> Result<(), PoolError> {
        let text = serde_json::to_string(r).expect("a request serialises");
        writeln!(self.workers[k].stdin, "{text}").map_err(|_| PoolError::Died(k))
    }
}

impl Drop for Pool {
    fn drop(&mut self) {
        for w in &mut self.workers {
            let _ = w.child.kill();
            let _ = w.child.wait();
        }
    }
}
