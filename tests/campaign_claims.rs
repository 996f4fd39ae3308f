//! A campaign directory belongs to one set of settings at a time, and a cell counts as
//! finished only when its files are whole and are this campaign's (the second hardening's
//! finding 3). On the code before the claim, 3 of 33 races of two campaigns with different
//! `--steps` into one directory both exited 0, leaving mixed rows; a cell with another
//! `steps`, an edited `campaign.toml` or a truncated `vehicles.csv` counted as finished, and a
//! deleted `vehicles.csv` made every re-run fail.

mod common;

use std::path::Path;
use std::process::{Command, Output, Stdio};

use common::{assert_ok, csv_rows};

const BIN: &str = env!("CARGO_BIN_EXE_bkpbs");

/// `bkpbs campaign` of one `sumo` cell per seed, `steps` long, into `out`, then `extra`.
fn campaign(out: &Path, seeds: &str, steps: &str, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.args(["campaign", "--planners", "sumo", "--alphas", "0.5"])
        .args(["--lambdas", "3000", "--seeds", seeds, "--steps", steps])
        .arg("--out")
        .arg(out)
        .args(extra)
        .env_remove(bkpbs::campaign::worker::FAULT_ENV)
        .stdin(Stdio::null());
    c
}

fn run(c: &mut Command) -> Output {
    c.output().expect("the binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The `steps` of every collected episode row in `out`.
fn collected_steps(out: &Path) -> Vec<String> {
    let rows = csv_rows(&std::fs::read(out.join("episodes.csv")).unwrap());
    rows.iter().map(|r| r["steps"].clone()).collect()
}

#[test]
fn of_two_campaigns_with_other_settings_started_together_exactly_one_proceeds() {
    race_thirty_times(|out, steps| {
        let mut c = campaign(out, "1", steps, &[]);
        c.stdout(Stdio::piped()).stderr(Stdio::piped());
        c
    });
}

/// Starts the campaign `make(out, steps)` with `--steps 10` and with `--steps 13` into one
/// directory at once, 30 times: exactly one proceeds, the other is refused naming the
/// difference, and the directory holds only the winner's rows and settings.
fn race_thirty_times(make: impl Fn(&Path, &str) -> Command) {
    for trial in 0..30 {
        let d = tempfile::tempdir().unwrap();
        let (pa, pb) = (
            make(d.path(), "10").spawn().unwrap(),
            make(d.path(), "13").spawn().unwrap(),
        );
        let (oa, ob) = (
            pa.wait_with_output().unwrap(),
            pb.wait_with_output().unwrap(),
        );
        let (winner, loser, steps) = match (oa.status.success(), ob.status.success()) {
            (true, false) => (&oa, &ob, "10"),
            (false, true) => (&ob, &oa, "13"),
            _ => panic!(
                "trial {trial}: exactly one must proceed:\n{}\n{}",
                text(&oa.stderr),
                text(&ob.stderr)
            ),
        };
        assert_ok(winner);
        common::refused_naming(loser, &["campaign.steps differs"]);
        assert_eq!(collected_steps(d.path()), [steps], "trial {trial}");
        let toml = std::fs::read_to_string(d.path().join("campaign.toml")).unwrap();
        assert!(toml.contains(&format!("steps = {steps}")), "{toml}");
    }
}

/// The number of the campaign's first status line's "already done: N".
fn already_done(o: &Output) -> usize {
    let out = text(&o.stdout);
    let at = out.find("already done: ").expect("status line") + "already done: ".len();
    out[at..].split(';').next().unwrap().trim().parse().unwrap()
}

#[test]
fn a_cell_of_other_steps_or_with_damaged_files_runs_again_saying_why() {
    let d = tempfile::tempdir().unwrap();
    assert_ok(&run(&mut campaign(d.path(), "4", "40", &[])));
    let whole = std::fs::read(d.path().join("vehicles.csv")).unwrap();
    let cell = |seed: u32| d.path().join(format!("episodes/sumo/a0.5_l3000_s{seed}"));
    // Seed 0: its episode.csv says another length. Seed 1: vehicles.csv cut at a line end.
    // Seed 2: vehicles.csv deleted. Seed 3 untouched.
    let episode = std::fs::read_to_string(cell(0).join("episode.csv")).unwrap();
    let edited = episode.replacen(",40,", ",30,", 1);
    assert_ne!(episode, edited);
    std::fs::write(cell(0).join("episode.csv"), edited).unwrap();
    let vehicles = std::fs::read_to_string(cell(1).join("vehicles.csv")).unwrap();
    let lines: Vec<&str> = vehicles.lines().collect();
    let cut = lines[..lines.len() - 2].join("\n") + "\n";
    std::fs::write(cell(1).join("vehicles.csv"), cut).unwrap();
    std::fs::remove_file(cell(2).join("vehicles.csv")).unwrap();

    let o = run(&mut campaign(d.path(), "4", "40", &[]));
    assert_ok(&o);
    assert_eq!(already_done(&o), 1, "{}", text(&o.stdout));
    let out = text(&o.stdout);
    for why in [
        "seed=0 runs again: episode.csv has steps 30, the campaign 40",
        "seed=1 runs again: vehicles.csv has",
        "seed=2 runs again: cannot read",
    ] {
        assert!(out.contains(why), "'{why}' not in:\n{out}");
    }
    assert_eq!(std::fs::read(d.path().join("vehicles.csv")).unwrap(), whole);
}

#[test]
fn an_edited_campaign_file_does_not_pass_off_old_cells_as_its_own() {
    let d = tempfile::tempdir().unwrap();
    assert_ok(&run(&mut campaign(d.path(), "2", "40", &[])));
    let settings = d.path().join("campaign.toml");
    let toml = std::fs::read_to_string(&settings).unwrap();
    // A time headway the cells did not run with, written into the file by hand.
    let edited = toml.replacen("time_headway = 1.5\n", "time_headway = 1.7\n", 1);
    assert_ne!(edited, toml, "{toml}");
    std::fs::write(&settings, edited).unwrap();
    let o = run(Command::new(BIN)
        .args(["campaign", "--config"])
        .arg(&settings)
        .arg("--out")
        .arg(d.path()));
    assert_ok(&o);
    assert_eq!(already_done(&o), 0, "{}", text(&o.stdout));
    assert!(
        text(&o.stdout).contains("settings.toml records other settings"),
        "{}",
        text(&o.stdout)
    );
}

/// `bkpbs campaign --sumocfg` of one `sumo` cell on `sumocfg`, `steps` long, into `out`.
fn scenario_campaign(sumocfg: &Path, out: &Path, steps: &str) -> Command {
    let mut c = Command::new(BIN);
    c.arg("campaign")
        .arg("--sumocfg")
        .arg(sumocfg)
        .args(["--planners", "sumo", "--alphas", "0.5", "--seeds", "1"])
        .args(["--steps", steps, "--out"])
        .arg(out)
        .env_remove(bkpbs::campaign::worker::FAULT_ENV)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

/// The same for campaigns over a scenario of the user's own: on the code before they shared
/// the paper campaign's claim, both of two such campaigns with other `--steps` ran in 4 of 15
/// races, `campaign.toml` saying one length over cells of the other.
#[test]
fn of_two_scenario_campaigns_with_other_settings_started_together_exactly_one_proceeds() {
    let games = tempfile::tempdir().unwrap();
    let ramp = common::game_copy(games.path()).join("ramp.sumocfg");
    race_thirty_times(|out, steps| scenario_campaign(&ramp, out, steps));
}
