//! A campaign over a scenario of the user's own records the digest of every file the scenario
//! names (its configuration, net, routes, additional files) in each cell: a cell whose
//! scenario was edited runs again, saying which file changed, and a file that cannot be read
//! (a FIFO, a missing file) stops the campaign before any episode. On a copy of SUMO's `ramp`
//! game, with real SUMO.

mod common;

use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

use common::{assert_ok, bkpbs, game_copy, one_error_line, output_within};

/// `bkpbs campaign` of SUMO alone at α 0 on `cfg`, one seed of 30 steps, into `out`.
fn campaign(cfg: &Path, out: &Path) -> Output {
    bkpbs(
        &campaign_args(cfg, out)
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    )
}

fn campaign_args(cfg: &Path, out: &Path) -> Vec<String> {
    let args = [
        "campaign",
        "--sumocfg",
        "",
        "--planners",
        "sumo",
        "--alphas",
        "0",
        "--seeds",
        "1",
        "--steps",
        "30",
        "--out",
        "",
    ];
    let mut args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    args[2] = cfg.display().to_string();
    args[12] = out.display().to_string();
    args
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn a_cell_whose_route_file_was_edited_runs_again_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let game = game_copy(tmp.path());
    let (cfg, out) = (game.join("ramp.sumocfg"), tmp.path().join("out"));
    assert_ok(&campaign(&cfg, &out));
    let again = campaign(&cfg, &out);
    assert_ok(&again);
    assert!(
        stdout(&again).contains("already done: 1;"),
        "{}",
        stdout(&again)
    );

    // An edit SUMO would read differently; here a comment, which changes the file's bytes.
    let routes = game.join("ramp/ramp.rou.xml");
    let text = std::fs::read_to_string(&routes).unwrap();
    std::fs::write(&routes, format!("{text}\n<!-- edited -->\n")).unwrap();
    let edited = campaign(&cfg, &out);
    assert_ok(&edited);
    let said = stdout(&edited);
    assert!(
        said.contains(
            "runs again: its scenario's file 'ramp/ramp.rou.xml' is not the one it ran with"
        ),
        "{said}"
    );
    assert!(said.contains("already done: 0;"), "{said}");
    let settings =
        std::fs::read_to_string(out.join("episodes/sumo/ramp/a0_s0/settings.toml")).unwrap();
    assert!(
        settings.contains("[scenario.sumocfg_digests]"),
        "{settings}"
    );
    assert!(settings.contains("\"ramp/ramp.rou.xml\" = "), "{settings}");
}

#[test]
fn a_fifo_named_as_a_route_file_is_refused_at_once_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let game = game_copy(tmp.path());
    let routes = game.join("ramp/ramp.rou.xml");
    std::fs::remove_file(&routes).unwrap();
    let path = std::ffi::CString::new(routes.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(path.as_ptr(), 0o600) }, 0);
    let args = campaign_args(&game.join("ramp.sumocfg"), &tmp.path().join("out"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_bkpbs"));
    cmd.args(&args);
    let (o, took) = output_within(&mut cmd, Duration::from_secs(30));
    let e = one_error_line(&o);
    assert!(
        e.contains("'ramp/ramp.rou.xml'") && e.contains("not a regular file"),
        "{e}"
    );
    assert!(took < Duration::from_secs(2), "took {took:?}");
}
