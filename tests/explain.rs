//! Collision forensics on real SUMO: `bkpbs episode --trace` on a staged crash, then
//! `bkpbs explain` tells its story; and the clear errors of `explain` on incomplete directories.

use std::path::Path;

use bkpbs::episode::trace::{self, TRACE_FILE};

mod common;

use common::{bkpbs, refused_naming, stderr};

/// A CAV inserted at t = 15 s, which the planner drives for 3 s, and an HDV inserted at t = 18 s
/// 4.6 m behind it at 30 m/s without SUMO's insertion checks: it cannot stop in time.
const STAGED: &str = r#"<routes>
<route id="staged" edges="main_in acc main_out"/>
<vehicle id="staged.a" type="cav" route="staged" depart="15" departLane="0" departPos="20" departSpeed="10"/>
<vehicle id="staged.b" type="hdv" route="staged" depart="18" departLane="0" departPos="50" departSpeed="30" insertionChecks="none"/>
</routes>
"#;

/// Runs the staged episode with `--trace` into `dir/out`; returns the output directory.
fn traced_crash(dir: &Path) -> std::path::PathBuf {
    let routes = dir.join("staged.rou.xml");
    std::fs::write(&routes, STAGED).unwrap();
    let cfg = dir.join("staged.toml");
    let text = format!("[sumo]\nadditional_files = [\"{}\"]\n", routes.display());
    std::fs::write(&cfg, text).unwrap();
    let out = dir.join("out");
    let o = bkpbs(&[
        "episode",
        "--config",
        cfg.to_str().unwrap(),
        "--lambda",
        "600",
        "--seed",
        "1",
        "--steps",
        "120",
        "--trace",
        "--trajectories",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

/// The rows (lines starting with a time) of the section of vehicle `id` in explain's output.
fn rows_of<'a>(text: &'a str, id: &str) -> Vec<&'a str> {
    let start = text
        .lines()
        .position(|l| l.starts_with(&format!("{id} (")))
        .unwrap_or_else(|| panic!("no section of {id} in:\n{text}"));
    text.lines()
        .skip(start + 2)
        .take_while(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .collect()
}

#[test]
fn a_staged_crash_is_traced_and_explained() {
    let d = tempfile::tempdir().unwrap();
    let out = traced_crash(d.path());
    let collisions = std::fs::read_to_string(out.join("collisions.csv")).unwrap();
    assert!(
        collisions.contains("staged.b,hdv,staged.a,cav"),
        "{collisions}"
    );
    let lines = trace::read(&out.join(TRACE_FILE)).unwrap();
    assert!(lines
        .iter()
        .any(|l| l.id == "staged.a" && l.planned.is_some()));

    let o = bkpbs(&["explain", out.to_str().unwrap(), "--plot"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    println!("{text}");
    assert!(text.contains("collision 1 at t = "), "{text}");
    assert!(text.contains("staged.b (hdv) hit staged.a (cav)"), "{text}");
    // The CAV: 3 s of 0.2 s steps before the collision, each with the source of its maneuver.
    let cav = rows_of(&text, "staged.a");
    assert_eq!(cav.len(), 15, "{text}");
    assert!(
        cav.iter().all(|r| r.contains("pbs-")
            || r.contains("repair")
            || r.contains("brake")
            || r.contains("shield")
            || r.contains("continuation")),
        "{text}"
    );
    let first: f64 = cav[0].split_whitespace().next().unwrap().parse().unwrap();
    let last: f64 = cav[14].split_whitespace().next().unwrap().parse().unwrap();
    assert!((last - first - 2.8).abs() < 1e-6, "{text}");
    // Once the HDV is in, the CAV's belief about it is shown.
    assert!(
        cav.last().is_some_and(|r| !r.contains("not seen")),
        "{text}"
    );
    // The HDV: not traced, seen through the CAV's predictions.
    assert!(text.contains("staged.b (hdv): not traced"), "{text}");
    let hdv = rows_of(&text, "staged.b");
    assert!(
        !hdv.is_empty() && hdv.iter().all(|r| r.contains("staged.a")),
        "{text}"
    );
    for ext in ["png", "svg"] {
        let p = out.join(format!("explain_1.{ext}"));
        assert!(
            std::fs::metadata(&p).is_ok_and(|m| m.len() > 1000),
            "{}",
            p.display()
        );
    }
}

#[test]
fn explain_names_what_a_directory_lacks() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().to_str().unwrap();
    refused_naming(&bkpbs(&["explain", dir]), &["collisions.csv", "--trace"]);
    // An episode run without --trace: collisions.csv but no trace.
    let header = "time_s,collider,collider_type,victim,victim_type,lane,position_m,controllable\n";
    std::fs::write(d.path().join("collisions.csv"), header).unwrap();
    refused_naming(&bkpbs(&["explain", dir]), &["trace.jsonl", "--trace"]);
    std::fs::write(d.path().join(TRACE_FILE), "").unwrap();
    let o = bkpbs(&["explain", dir]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("no collision"));
}

#[test]
fn a_traced_episode_that_fails_writes_no_trace() {
    let d = tempfile::tempdir().unwrap();
    // A vehicle whose route is broken: SUMO fails when it is due to depart, at t = 3 s.
    let bad = d.path().join("bad.rou.xml");
    std::fs::write(
        &bad,
        "<routes>\n<route id=\"broken\" edges=\"main_in main_out\"/>\n<vehicle id=\"bad\" type=\"hdv\" route=\"broken\" depart=\"3\"/>\n</routes>\n",
    )
    .unwrap();
    let cfg = d.path().join("bad.toml");
    let text = format!("[sumo]\nadditional_files = [\"{}\"]\n", bad.display());
    std::fs::write(&cfg, text).unwrap();
    let out = d.path().join("out");
    let o = bkpbs(&[
        "episode",
        "--config",
        cfg.to_str().unwrap(),
        "--trace",
        "--out",
        out.to_str().unwrap(),
    ]);
    refused_naming(&o, &["SUMO failed at step"]);
    assert!(!out.join(TRACE_FILE).exists() && !out.join("collisions.csv").exists());
}

#[test]
fn plot_marks_the_collision_and_draws_its_close_up() {
    let d = tempfile::tempdir().unwrap();
    let out = traced_crash(d.path());
    let o = bkpbs(&["plot", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("explain_1.png"), "{text}");
    let tracks = bkpbs::report::lane_tracks::read(&out).unwrap();
    assert_eq!(tracks.collisions.len(), 1, "{:?}", tracks.collisions);
    let svg = std::fs::read_to_string(out.join("time_space.svg")).unwrap();
    assert!(svg.contains("collision"), "legend");
}

/// `--trace` on a scenario of your own (refused before): each merge region's trace beside its
/// trajectories, no other file changed, and `bkpbs explain` on the episode's directory tells
/// the story of each collision region by region (the committed policy, unshielded, crashes on
/// SUMO's `ramp` game within 100 s).
#[test]
fn a_scenario_episode_is_traced_and_explained_region_by_region() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = common::game_copy(dir.path()).join("ramp.sumocfg");
    let run = |out: &Path, trace: bool| {
        let mut args = vec!["episode", "--sumocfg", cfg.to_str().unwrap()];
        args.extend(["--planner", "rl-ppo", "--alpha", "0.6", "--seed", "1"]);
        args.extend(["--steps", "500", "--out", out.to_str().unwrap()]);
        if trace {
            args.push("--trace");
        }
        common::assert_ok(&bkpbs(&args));
    };
    let (plain, traced) = (dir.path().join("plain"), dir.path().join("traced"));
    run(&plain, false);
    run(&traced, true);
    common::assert_same_files(&plain, &traced, &common::SCENARIO_FILES, "with --trace");
    let region = traced.join("trajectories/gneE7");
    let lines = trace::read(&region.join(TRACE_FILE)).unwrap();
    assert!(lines.iter().any(|l| l.source.as_str() == "policy"));
    let o = bkpbs(&["explain", traced.to_str().unwrap(), "--plot"]);
    common::assert_ok(&o);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.starts_with("region gneE7:\ncollision 1 at t = "),
        "{out}"
    );
    assert!(
        out.contains("(cav): SUMO's state, the maneuver sent"),
        "{out}"
    );
    assert!(region.join("explain_1.png").is_file(), "{out}");
}
