//! Campaigns over scenarios of the user's own (`bkpbs campaign --sumocfg A,B`), on copies of
//! SUMO's shipped `ramp` and `A10KW` games, with real SUMO: each cell is the very episode
//! `bkpbs episode --sumocfg` runs, a re-run resumes, shards and another worker count collect
//! to the same bytes, and the report pairs the planners per region over the seeds.

mod common;

use std::path::{Path, PathBuf};

use common::{assert_ok, bkpbs, csv_rows, game_copy, refused_naming};

/// The game copied, with an A10KW configuration at the planners' step of 0.2 s.
fn games(dir: &Path) -> (PathBuf, PathBuf) {
    let game = game_copy(dir);
    let text = std::fs::read_to_string(game.join("A10KW.sumocfg")).unwrap();
    let a10kw = game.join("A10KW-0.2.sumocfg");
    std::fs::write(&a10kw, text.replace("value=\"0.5\"", "value=\"0.2\"")).unwrap();
    (game.join("ramp.sumocfg"), a10kw)
}

fn campaign(scenarios: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "campaign",
        "--sumocfg",
        scenarios,
        "--planners",
        "bk-pbs,sumo",
        "--alphas",
        "0.5",
        "--seeds",
        "2",
        "--steps",
        "100",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    bkpbs(&args)
}

fn read(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{}: {e}", dir.join(name).display()))
}

#[test]
fn a_campaign_over_scenarios_resumes_and_collects_the_same_bytes_however_it_is_run() {
    let dir = tempfile::tempdir().unwrap();
    let (ramp, a10kw) = games(dir.path());
    let scenarios = format!("{},{}", ramp.display(), a10kw.display());
    let a = dir.path().join("a");
    let o = campaign(&scenarios, &a, &["--workers", "2"]);
    assert_ok(&o);

    // Grid order: planner, scenario, α, seed; every vehicle inserted is a collected row.
    let episodes = csv_rows(&read(&a, "episodes.csv"));
    let order: Vec<(&str, &str, &str)> = episodes
        .iter()
        .map(|r| {
            (
                r["planner"].as_str(),
                r["scenario"].as_str(),
                r["seed"].as_str(),
            )
        })
        .collect();
    assert_eq!(
        order,
        [
            ("bk-pbs", "ramp.sumocfg", "0"),
            ("bk-pbs", "ramp.sumocfg", "1"),
            ("bk-pbs", "A10KW-0.2.sumocfg", "0"),
            ("bk-pbs", "A10KW-0.2.sumocfg", "1"),
            ("sumo", "ramp.sumocfg", "0"),
            ("sumo", "ramp.sumocfg", "1"),
            ("sumo", "A10KW-0.2.sumocfg", "0"),
            ("sumo", "A10KW-0.2.sumocfg", "1"),
        ]
    );
    let inserted: usize = episodes
        .iter()
        .map(|r| r["inserted"].parse::<usize>().unwrap())
        .sum();
    assert!(inserted > 0);
    assert_eq!(csv_rows(&read(&a, "vehicles.csv")).len(), inserted);
    let regions = csv_rows(&read(&a, "regions.csv"));
    assert_eq!(
        regions.len(),
        2 * 2 * (1 + 2),
        "ramp has one region, A10KW two"
    );
    // Per region its main carriageway and each on-ramp, adding up to the region's vehicles.
    let entries = csv_rows(&read(&a, "entries.csv"));
    let cell = |r: &std::collections::BTreeMap<String, String>| {
        ["scenario", "planner", "alpha", "seed", "region"].map(|c| r[c].clone())
    };
    for region in &regions {
        let mine: Vec<_> = entries.iter().filter(|e| cell(e) == cell(region)).collect();
        let ramps = region["region"].split(' ').count();
        assert_eq!(mine.len(), 1 + ramps, "{region:?}");
        let sum: usize = mine
            .iter()
            .map(|e| e["vehicles"].parse::<usize>().unwrap())
            .sum();
        assert_eq!(sum.to_string(), region["vehicles"], "{region:?}");
    }

    // A cell is the episode `bkpbs episode --sumocfg` runs, byte for byte.
    let single = dir.path().join("single");
    let o = bkpbs(&[
        "episode",
        "--sumocfg",
        a10kw.to_str().unwrap(),
        "--planner",
        "bk-pbs",
        "--alpha",
        "0.5",
        "--seed",
        "1",
        "--steps",
        "100",
        "--out",
        single.to_str().unwrap(),
    ]);
    assert_ok(&o);
    let cell = a.join("episodes/bk-pbs/A10KW-0.2/a0.5_s1");
    for f in common::SCENARIO_FILES {
        assert_eq!(read(&cell, f), read(&single, f), "{f}");
    }

    // A re-run finds everything done; a cell without its entries.csv (an earlier bkpbs's) runs
    // again, saying why, and comes back the same.
    let collected = read(&a, "entries.csv");
    std::fs::remove_file(cell.join("entries.csv")).unwrap();
    let o = campaign(&scenarios, &a, &["--workers", "2"]);
    assert_ok(&o);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(said.contains("already done: 7; to run: 1"), "{said}");
    assert!(
        said.contains("runs again: ") && said.contains("entries.csv"),
        "{said}"
    );
    assert_eq!(read(&a, "entries.csv"), collected);

    // A narrower grid would drop collected episodes: refused, nothing lost.
    let o = bkpbs(&[
        "campaign",
        "--sumocfg",
        &scenarios,
        "--planners",
        "sumo",
        "--alphas",
        "0.5",
        "--seeds",
        "2",
        "--steps",
        "100",
        "--out",
        a.to_str().unwrap(),
    ]);
    refused_naming(
        &o,
        &["4 episodes outside this grid", "bk-pbs ramp α=0.5 seed=0"],
    );
    assert_eq!(csv_rows(&read(&a, "episodes.csv")).len(), 8);

    // Two shards of one worker each collect what the whole grid on two workers did.
    let b = dir.path().join("b");
    for shard in ["2/2", "1/2"] {
        assert_ok(&campaign(
            &scenarios,
            &b,
            &["--workers", "1", "--shard", shard],
        ));
    }
    for f in ["episodes.csv", "regions.csv", "entries.csv", "vehicles.csv"] {
        assert_eq!(read(&a, f), read(&b, f), "{f}");
    }

    // Shards run apart (other machines) and merged by `report` collect the same bytes.
    let (c1, c2, merged) = (
        dir.path().join("c1"),
        dir.path().join("c2"),
        dir.path().join("m"),
    );
    assert_ok(&campaign(&scenarios, &c1, &["--shard", "1/2"]));
    assert_ok(&campaign(&scenarios, &c2, &["--shard", "2/2"]));
    let o = bkpbs(&[
        "report",
        c2.to_str().unwrap(),
        c1.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_ok(&o);
    for f in [
        "episodes.csv",
        "regions.csv",
        "entries.csv",
        "vehicles.csv",
        "failures.csv",
    ] {
        assert_eq!(read(&a, f), read(&merged, f), "{f}");
    }
    assert_eq!(
        read(&a, "report/paired_regions.csv"),
        read(&merged, "report/paired_regions.csv")
    );

    // The report pairs bk-pbs with sumo per region over the two seeds.
    let paired = csv_rows(&read(&a, "report/paired_regions.csv"));
    assert_eq!(paired.len(), 3, "{paired:?}");
    for row in &paired {
        assert_eq!(
            (row["reference"].as_str(), row["planner"].as_str()),
            ("bk-pbs", "sumo")
        );
        assert_eq!(row["pairs"], "2");
    }
    let o = bkpbs(&["report", a.to_str().unwrap(), "--versus", "idm-mobil"]);
    refused_naming(&o, &["idm-mobil", "bk-pbs, sumo"]);
}

#[test]
fn a_campaign_over_scenarios_refuses_bad_settings_before_any_episode() {
    let dir = tempfile::tempdir().unwrap();
    let (ramp, _) = games(dir.path());
    let out = dir.path().join("out");
    let ramp = ramp.to_str().unwrap();

    let o = campaign(ramp, &out, &["--lambdas", "2500"]);
    refused_naming(&o, &["--lambdas", "its demand"]);
    let game = dir.path().join("game");
    let o = campaign(game.join("A10KW.sumocfg").to_str().unwrap(), &out, &[]);
    refused_naming(&o, &["A10KW.sumocfg", "step-length 0.5"]);
    let o = campaign(
        &format!("{ramp},{}", game.join("nowhere.sumocfg").display()),
        &out,
        &[],
    );
    refused_naming(&o, &["nowhere.sumocfg"]);
    let other = dir.path().join("ramp.sumocfg");
    std::fs::copy(ramp, &other).unwrap();
    let o = campaign(&format!("{ramp},{}", other.display()), &out, &[]);
    refused_naming(&o, &["two scenarios are named 'ramp'"]);
    // Once a scenario named '..' put every planner's cells in one directory, and α = 1e-300
    // made every cell fail with "File name too long".
    let dots = game.join("...sumocfg");
    std::fs::copy(ramp, &dots).unwrap();
    let o = campaign(dots.to_str().unwrap(), &out, &[]);
    refused_naming(&o, &["...sumocfg", "its name '..'", "rename the file"]);
    let out_arg = out.to_str().unwrap();
    let o = bkpbs(&[
        "campaign",
        "--sumocfg",
        ramp,
        "--alphas",
        "1e-300",
        "--out",
        out_arg,
    ]);
    refused_naming(&o, &["--alphas", "α 1e-300", "too many digits"]);
    // A tripinfo output of the configuration's own would be one file for every episode.
    let text = std::fs::read_to_string(ramp).unwrap();
    let own = game.join("own.sumocfg");
    let output = "<output><tripinfo-output value=\"t.xml\"/></output></configuration>";
    std::fs::write(&own, text.replace("</configuration>", output)).unwrap();
    let o = campaign(own.to_str().unwrap(), &out, &[]);
    refused_naming(&o, &["own.sumocfg", "tripinfo-output", "t.xml"]);
    assert!(!out.join("episodes").exists(), "no episode ran");

    // A campaign file with a scenario list is one too, and its paper keys are refused.
    let file = dir.path().join("c.toml");
    std::fs::write(
        &file,
        format!("[campaign]\nscenarios = [\"{ramp}\"]\nlambdas = [2500.0]\n"),
    )
    .unwrap();
    let o = bkpbs(&[
        "campaign",
        "--config",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    refused_naming(&o, &["campaign.lambdas", "c.toml"]);
}

#[test]
fn plots_draw_each_cells_merge_regions() {
    let dir = tempfile::tempdir().unwrap();
    let (ramp, _) = games(dir.path());
    let out = dir.path().join("plots");
    let o = bkpbs(&[
        "campaign",
        "--sumocfg",
        ramp.to_str().unwrap(),
        "--planners",
        "bk-pbs",
        "--alphas",
        "0.5",
        "--seeds",
        "1",
        "--steps",
        "100",
        "--plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_ok(&o);
    let region = out.join("episodes/bk-pbs/ramp/a0.5_s0/trajectories/gneE7");
    for f in ["trajectories.csv", "time_space.png", "speed_field.png"] {
        assert!(region.join(f).is_file(), "{f}");
    }
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(said.contains("speed field of 1 cells"), "{said}");
}

/// The predictor axis over a scenario: one campaign runs each planner under each predictor,
/// each cell the very episode of a campaign whose configuration names that predictor, its
/// files naming the predictor after the planner, and the report pairs the arms per region.
#[test]
fn the_predictor_axis_runs_over_scenarios_as_one_campaign() {
    let dir = tempfile::tempdir().unwrap();
    let (ramp, _) = games(dir.path());
    let ramp = ramp.to_str().unwrap();
    let (both, alone) = (dir.path().join("both"), dir.path().join("constant"));
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec!["campaign", "--sumocfg", ramp, "--planners", "bk-pbs"];
        args.extend_from_slice(&["--alphas", "0.5", "--seeds", "2", "--steps", "100"]);
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        args.extend_from_slice(extra);
        bkpbs(&args)
    };
    let axis = ["--predictors", "learned,constant"];
    assert_ok(&run(&both, &axis));
    let config = dir.path().join("constant.toml");
    std::fs::write(&config, "[predictor]\nkind = \"constant\"\n").unwrap();
    assert_ok(&run(&alone, &["--config", config.to_str().unwrap()]));

    for file in ["episodes.csv", "regions.csv", "entries.csv", "vehicles.csv"] {
        let rows = raw_rows(&read(&both, file));
        let header = &rows[0];
        let at = header.iter().position(|c| c == "predictor").expect(file);
        assert_eq!(header[at - 1], "planner", "{file}");
        // The constant arm's rows, without the predictor column, are the other campaign's.
        let constant: Vec<Vec<String>> = (rows.iter().skip(1))
            .filter(|r| r[at] == "constant")
            .map(|r| [&r[..at], &r[at + 1..]].concat())
            .collect();
        let other = raw_rows(&read(&alone, file));
        assert_eq!(constant, other[1..], "{file}");
        assert_eq!(rows.len() - 1, 2 * constant.len(), "{file}");
    }
    let again = run(&both, &axis);
    assert_ok(&again);
    let said = String::from_utf8_lossy(&again.stdout) + String::from_utf8_lossy(&again.stderr);
    assert!(said.contains("× 2 predictors"), "{said}");
    assert!(said.contains("already done: 4"), "{said}");

    let o = bkpbs(&[
        "report",
        both.to_str().unwrap(),
        "--versus",
        "bk-pbs+constant",
    ]);
    assert_ok(&o);
    let paired = csv_rows(&read(&both, "report/paired_regions.csv"));
    let arms: Vec<(&str, &str)> = (paired.iter())
        .map(|r| (r["reference"].as_str(), r["planner"].as_str()))
        .collect();
    assert_eq!(arms, [("bk-pbs+constant", "bk-pbs+learned")]);
}

/// A CSV file's rows, header first, as text.
fn raw_rows(bytes: &[u8]) -> Vec<Vec<String>> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(bytes);
    r.records()
        .map(|rec| rec.unwrap().iter().map(String::from).collect())
        .collect()
}
