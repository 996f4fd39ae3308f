//! Helpers shared by the integration tests. Each test binary includes this module and uses only
//! part of it, hence the `dead_code` allowance.
#![allow(dead_code)]

use std::process::{Command, Output};

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use bkpbs::config::Config;
use bkpbs::episode::{self, EpisodeResult};
use bkpbs::predict::features::{Observation, CAV_NODES};

/// A default-length episode of `planner` on real SUMO at (α, λ, seed), the paper's other settings.
pub fn episode_of(planner: &str, alpha: f64, lambda: f64, seed: u64) -> EpisodeResult {
    let mut c = Config::default();
    c.scenario.alpha = alpha;
    c.scenario.lambda = lambda;
    c.scenario.seed = seed;
    episode::run(&c, planner).unwrap()
}

/// Random observations with a mix of present and absent nodes.
pub fn random_obs(rng: &mut ChaCha8Rng) -> Observation {
    let mut o = Observation::default();
    o.ego.lane = rng.gen_range(0..3);
    o.ego.speed = rng.gen_range(5.0..35.0);
    o.ego.accel = rng.gen_range(-3.0..3.0);
    o.ego.to_merge_end = rng.gen_range(-50.0..300.0);
    o.ego.from_ramp = rng.gen_bool(0.3);
    for n in &mut o.neighbours {
        if rng.gen_bool(0.7) {
            n.present = true;
            n.ds = rng.gen_range(-90.0..90.0);
            n.dy = rng.gen_range(-5.0..5.0);
            n.speed = rng.gen_range(0.0..35.0);
            n.is_cav = rng.gen_bool(0.5);
        }
    }
    let cavs = rng.gen_range(1..=CAV_NODES);
    for step in o.cavs.iter_mut() {
        for c in step.iter_mut().take(cavs) {
            c.present = true;
            c.ds = rng.gen_range(-60.0..60.0);
            c.dy = rng.gen_range(-5.0..5.0);
            c.speed = rng.gen_range(0.0..35.0);
        }
    }
    o
}

/// The `bkpbs` binary run with `args`.
pub fn bkpbs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// What a run printed to stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The episode input directories (`bkpbs-episode-…`) in the temporary directory `tmp`.
pub fn input_dirs(tmp: &std::path::Path) -> Vec<std::path::PathBuf> {
    std::fs::read_dir(tmp)
        .unwrap()
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with("bkpbs-episode-")
        })
        .map(|e| e.path())
        .collect()
}

/// Waits until `done` holds, polling; panics naming `what` after `seconds`.
pub fn wait_for(what: &str, seconds: u64, mut done: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(seconds);
    while !done() {
        assert!(
            std::time::Instant::now() < deadline,
            "timed out waiting for {what}"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Sends `signal` to process `pid` (a negative `pid`: to its process group).
pub fn send_signal(pid: i32, signal: i32) {
    // SAFETY: plain kill(2) on a process the test started.
    assert_eq!(
        unsafe { libc::kill(pid, signal) },
        0,
        "kill({pid}, {signal})"
    );
}
