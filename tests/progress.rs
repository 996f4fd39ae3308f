//! Long runs say how far they are: a line a minute on a stderr that is no terminal (here every
//! step or episode, through the test hook), for an episode on a scenario of the user's own, an
//! episode of the paper's demand and a campaign; none in a campaign's workers.

mod common;

use std::process::{Command, Output};

use bkpbs::io::progress::EVERY_ENV;

fn run(args: &[&str]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args(args)
        .env(EVERY_ENV, "0")
        .env_remove(bkpbs::campaign::worker::FAULT_ENV)
        .output()
        .expect("the binary runs");
    common::assert_ok(&o);
    o
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn episodes_print_their_progress() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = common::game_copy(dir.path()).join("ramp.sumocfg");
    let out = dir.path().join("scenario");
    let o = run(&[
        "episode",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--planner",
        "sumo",
        "--steps",
        "150",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(err.contains("episode: 100/150 steps (67 %), "), "{err}");
    assert!(err.contains(" elapsed, about "), "{err}");
    let out = dir.path().join("paper");
    let o = run(&[
        "episode",
        "--planner",
        "idm-mobil",
        "--steps",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        stderr(&o).contains("episode: 49/50 steps (98 %)"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_campaign_prints_its_progress_and_not_its_workers_episodes() {
    let dir = tempfile::tempdir().unwrap();
    let o = run(&[
        "campaign",
        "--planners",
        "sumo",
        "--alphas",
        "0.5",
        "--lambdas",
        "3000",
        "--seeds",
        "3",
        "--steps",
        "30",
        "--workers",
        "1",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(
        err.contains("campaign: 1/3 episodes (33 %), 0 failed, "),
        "{err}"
    );
    assert!(!err.contains("episode: "), "{err}");
}
