//! `bkpbs episode --gui`: the same episode through sumo-gui (libtraci), under a virtual X
//! server (Debian's xvfb, installed by `make deps`).

use std::process::Command;

mod common;

const BIN: &str = env!("CARGO_BIN_EXE_bkpbs");

/// Runs the episode of `args(out)` into `plain` in this process and into `shown` through
/// sumo-gui under a virtual X server, each asserted to succeed.
fn run_plain_and_shown(
    args: impl Fn(&std::path::Path) -> Vec<String>,
    plain: &std::path::Path,
    shown: &std::path::Path,
) {
    let o = Command::new(BIN).args(args(plain)).output().unwrap();
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = Command::new("xvfb-run")
        .args(["-a", BIN])
        .args(args(shown))
        .args(["--gui-delay", "0"])
        .output()
        .expect("xvfb-run (Debian's xvfb; `make deps` installs it)");
    assert!(o.status.success(), "{}", common::stderr(&o));
}

#[test]
fn an_episode_shown_in_sumo_gui_gives_the_same_results() {
    let d = tempfile::tempdir().unwrap();
    let (plain, shown) = (d.path().join("plain"), d.path().join("gui"));
    let args = |out: &std::path::Path| {
        let mut a: Vec<String> = [
            "episode",
            "--planner",
            "bk-pbs",
            "--steps",
            "200",
            "--seed",
            "3",
        ]
        .map(String::from)
        .to_vec();
        a.extend([
            "--trajectories".into(),
            "--out".into(),
            out.display().to_string(),
        ]);
        a
    };
    run_plain_and_shown(args, &plain, &shown);
    let files = [
        "episode.csv",
        "vehicles.csv",
        "collisions.csv",
        "trajectories.csv",
    ];
    common::assert_same_files(&plain, &shown, &files, "with the GUI");
}

#[test]
fn without_a_display_the_gui_is_refused_in_one_line() {
    let d = tempfile::tempdir().unwrap();
    let o = Command::new(BIN)
        .args(["episode", "--gui", "--steps", "20", "--out"])
        .arg(d.path().join("x"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let line = common::one_error_line(&o);
    assert!(
        line.starts_with("error: cannot show the episode: no display"),
        "{line}"
    );
    let o = common::bkpbs(&["episode", "--gui-delay", "-5", "--steps", "20"]);
    assert!(
        common::stderr(&o).contains("sumo.gui_delay_ms"),
        "{}",
        common::stderr(&o)
    );
}

/// `--gui` on a scenario of your own (refused before): SUMO's `ramp` game shown in sumo-gui
/// gives the files of the same episode run in this process.
#[test]
fn a_scenario_shown_in_sumo_gui_gives_the_same_results() {
    let d = tempfile::tempdir().unwrap();
    let cfg = common::game_copy(d.path()).join("ramp.sumocfg");
    let (plain, shown) = (d.path().join("plain"), d.path().join("gui"));
    let args = |out: &std::path::Path| {
        let mut a: Vec<String> = ["episode", "--sumocfg"].map(String::from).to_vec();
        a.push(cfg.display().to_string());
        a.extend(["--planner", "bk-pbs", "--steps", "200", "--seed", "3"].map(String::from));
        a.extend(["--out".into(), out.display().to_string()]);
        a
    };
    run_plain_and_shown(args, &plain, &shown);
    common::assert_same_files(&plain, &shown, &common::SCENARIO_FILES, "with the GUI");
}
