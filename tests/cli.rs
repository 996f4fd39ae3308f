//! The `bkpbs` binary: results on disk, and one clear line plus a non-zero exit on bad input.

use std::path::Path;
use std::process::Output;

mod common;

use common::{bkpbs, one_error_line, stderr};

/// Asserts failure with exactly one `error:` line naming `culprit`, and no CSV in `out`.
fn assert_clear_failure(o: &Output, culprit: &str, out: &Path) {
    let line = one_error_line(o);
    assert!(line.contains(culprit), "'{culprit}' not named in: {line}");
    assert!(!out.join("episode.csv").exists() && !out.join("vehicles.csv").exists());
}

/// `bkpbs episode` with `flags` into `out`, refused as [`assert_clear_failure`] says and
/// within 10 s: the check comes before the episode runs (a hang or a full run would not).
fn assert_refused_at_once(out: &Path, flags: &[&str], culprit: &str) {
    let start = std::time::Instant::now();
    let o = episode_into(out, flags);
    assert_clear_failure(&o, culprit, out);
    assert!(
        start.elapsed().as_secs() < 10,
        "{culprit}: took {:?}",
        start.elapsed()
    );
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// `bkpbs episode` with `flags`, writing into `out`.
fn episode_into(out: &Path, flags: &[&str]) -> Output {
    let mut args = vec!["episode"];
    args.extend_from_slice(flags);
    args.extend(["--out", out.to_str().unwrap()]);
    bkpbs(&args)
}

/// A config file in `dir` holding `text`, and the output directory beside it.
fn config_file(dir: &Path, name: &str, text: &str) -> (String, std::path::PathBuf) {
    let cfg = dir.join(name);
    std::fs::write(&cfg, text).unwrap();
    (cfg.to_str().unwrap().to_string(), dir.join("out"))
}

#[test]
fn episode_writes_its_csv_files() {
    let d = tmp();
    let out = d.path().join("run");
    let o = episode_into(
        &out,
        &["--planner", "idm-mobil", "--seed", "3", "--steps", "100"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).is_empty(),
        "SUMO must stay quiet: {}",
        stderr(&o)
    );
    for f in [
        "episode.csv",
        "vehicles.csv",
        "collisions.csv",
        "timing.csv",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let episode = std::fs::read_to_string(out.join("episode.csv")).unwrap();
    let header = episode.lines().next().unwrap();
    for col in [
        "planner",
        "alpha",
        "lambda",
        "seed",
        "steps",
        "inserted",
        "arrived",
        "crashed",
        "controllable_collision_rate",
        "hdv_collisions",
        "mean_delay_s",
        "throughput_veh_h",
    ] {
        assert!(header.split(',').any(|h| h == col), "missing column {col}");
    }
    assert_eq!(episode.lines().count(), 2);
    let timing = std::fs::read_to_string(out.join("timing.csv")).unwrap();
    assert!(timing.starts_with("plan_ms_median,plan_ms_p99,plan_ms_max,sumo_ms_per_step"));
}

#[test]
fn same_seed_twice_gives_byte_identical_csv_across_processes() {
    let d = tmp();
    let run = |name: &str| {
        let out = d.path().join(name);
        let o = episode_into(
            &out,
            &[
                "--planner",
                "idm-mobil",
                "--alpha",
                "0.6",
                "--lambda",
                "3000",
                "--seed",
                "9",
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let (a, b) = (run("a"), run("b"));
    for f in ["episode.csv", "vehicles.csv", "collisions.csv"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn unknown_planner_is_refused() {
    let d = tmp();
    let o = episode_into(d.path(), &["--planner", "bk-pbz"]);
    assert_clear_failure(&o, "bk-pbz", d.path());
}

#[test]
fn alpha_outside_the_unit_interval_is_refused() {
    let d = tmp();
    let o = episode_into(d.path(), &["--alpha", "1.5"]);
    assert_clear_failure(&o, "scenario.alpha", d.path());
}

#[test]
fn a_negative_number_is_a_value_refused_with_its_range() {
    // Once parsed as a flag: "unexpected argument '-0' found", exit code 2.
    let d = tmp();
    let o = episode_into(d.path(), &["--alpha", "-0.1"]);
    assert_clear_failure(&o, "scenario.alpha", d.path());
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn a_usage_error_is_one_line_and_exit_code_1() {
    let d = tmp();
    let o = episode_into(d.path(), &["--bogus"]);
    assert_clear_failure(&o, "--bogus", d.path());
    assert_eq!(o.status.code(), Some(1));
    // A count of nothing to evaluate: once printed tables of 0.0 %.
    let o = bkpbs(&["eval-predictor", "--episodes", "0"]);
    assert_clear_failure(&o, "--episodes", d.path());
    assert_eq!(o.status.code(), Some(1));
    // clap names a missing argument on the line after its message: still one line.
    let o = bkpbs(&["demand", "--lambda", "2000"]);
    assert_clear_failure(&o, "--out", d.path());
    assert_eq!(o.status.code(), Some(1));
}

/// Settings that once exhausted memory (11–14 GB) or hung: one error naming the key, before
/// anything runs. The elapsed-time bound only catches a hang; the refusal takes milliseconds.
#[test]
fn absurd_sizes_are_refused_before_anything_runs() {
    let d = tmp();
    let flag_cases: [(&[&str], &str); 2] = [
        (&["--lambda", "1e12", "--steps", "10"], "scenario.lambda"),
        (&["--steps", "4294967295"], "scenario.steps"),
    ];
    for (flags, key) in flag_cases {
        assert_refused_at_once(d.path(), flags, key);
    }
    for (text, key) in [
        ("[scenario]\nv_max = 1e300\n", "scenario.v_max"),
        ("[planner]\nhorizon = 100000\n", "planner.horizon"),
        ("[idm]\ntime_headway = 0\n", "idm.time_headway"),
    ] {
        let (cfg, out) = config_file(d.path(), "absurd.toml", text);
        assert_refused_at_once(&out, &["--config", &cfg], key);
    }
}

#[test]
fn an_output_place_that_cannot_be_written_is_refused_before_the_episode_runs() {
    // Its parent is a file: once found only after the whole episode had run.
    let d = tmp();
    std::fs::write(d.path().join("file"), "x").unwrap();
    let out = d.path().join("file").join("run");
    assert_refused_at_once(&out, &["--steps", "400"], out.to_str().unwrap());
}

#[test]
fn sumo_s_own_reason_is_in_the_error_and_its_output_is_kept() {
    // libsumo says only "Process Error"; the reason is on SUMO's console, captured.
    let d = tmp();
    let (cfg, out) = config_file(
        d.path(),
        "add.toml",
        "[sumo]\nadditional_files = [\"no/such/extra.add.xml\"]\n",
    );
    let o = episode_into(&out, &["--config", &cfg, "--steps", "5"]);
    assert_clear_failure(&o, "is not accessible", &out);
    assert!(
        stderr(&o).contains("no/such/extra.add.xml"),
        "{}",
        stderr(&o)
    );
    let log = std::fs::read_to_string(out.join("sumo.log")).unwrap();
    assert!(log.contains("Error: File"), "{log}");
    // A net that is not XML at all.
    let net = d.path().join("garbage.net.xml");
    std::fs::write(&net, "garbage").unwrap();
    let out = d.path().join("garbage");
    let o = episode_into(&out, &["--net", net.to_str().unwrap(), "--steps", "5"]);
    assert_clear_failure(&o, "garbage.net.xml", &out);
    assert!(stderr(&o).contains("not valid XML"), "{}", stderr(&o));
}

#[test]
fn missing_config_file_is_refused() {
    let d = tmp();
    let o = episode_into(d.path(), &["--config", "no/such.toml"]);
    assert_clear_failure(&o, "no/such.toml", d.path());
    // Regression: the OS error was printed twice (once in the message, once as its source).
    assert_eq!(
        stderr(&o).matches("No such file").count(),
        1,
        "{}",
        stderr(&o)
    );
}

#[test]
fn malformed_config_file_is_refused() {
    let d = tmp();
    let (cfg, out) = config_file(d.path(), "bad.toml", "[scenario]\nalpha = \"lots\"\n");
    let o = episode_into(&out, &["--config", &cfg]);
    assert_clear_failure(&o, "bad.toml", &out);
}

#[test]
fn misspelt_config_key_is_refused() {
    let d = tmp();
    let (cfg, out) = config_file(d.path(), "typo.toml", "[scenario]\nlamda = 2500\n");
    let o = episode_into(&out, &["--config", &cfg]);
    assert_clear_failure(&o, "lamda", &out);
}

#[test]
fn missing_net_file_is_refused() {
    let d = tmp();
    let o = episode_into(d.path(), &["--net", "nowhere/merge.net.xml"]);
    assert_clear_failure(&o, "nowhere/merge.net.xml", d.path());
}

#[test]
fn a_net_without_the_merge_layout_is_refused() {
    let d = tmp();
    // Other edge ids are fine: the layout is found, not named.
    let net = d.path().join("other.net.xml");
    let text = bkpbs::model::road::EMBEDDED_NET
        .replace("\"acc\"", "\"acceleration\"")
        .replace("acc_", "acceleration_");
    std::fs::write(&net, text).unwrap();
    let out = d.path().join("out");
    let o = episode_into(&out, &["--net", net.to_str().unwrap(), "--steps", "50"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A two-way road is no merge: one line, before SUMO starts.
    let net = d.path().join("two-way.net.xml");
    std::fs::write(&net, common::TWO_WAY_NET).unwrap();
    let out = d.path().join("two-way");
    let o = episode_into(&out, &["--net", net.to_str().unwrap()]);
    assert_clear_failure(&o, "two-way.net.xml", &out);
    assert!(stderr(&o).contains("no merge to plan"), "{}", stderr(&o));
}

#[test]
fn sumo_error_mid_episode_is_reported_and_keeps_earlier_results() {
    let d = tmp();
    let out = d.path().join("out");
    // A finished episode first: its files must survive the failing run untouched.
    let ok = bkpbs(&["episode", "--steps", "50", "--out", out.to_str().unwrap()]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let before = std::fs::read(out.join("vehicles.csv")).unwrap();
    // A vehicle whose route is broken: SUMO fails when it is due to depart, at t = 3 s.
    let bad = d.path().join("bad.rou.xml");
    std::fs::write(
        &bad,
        "<routes>\n<route id=\"broken\" edges=\"main_in main_out\"/>\n<vehicle id=\"bad\" type=\"hdv\" route=\"broken\" depart=\"3\"/>\n</routes>\n",
    )
    .unwrap();
    let files = format!("[sumo]\nadditional_files = [\"{}\"]\n", bad.display());
    let (cfg, _) = config_file(d.path(), "cfg.toml", &files);
    let line = one_error_line(&episode_into(&out, &["--config", &cfg]));
    assert!(
        line.contains("SUMO failed at step") && line.contains("'bad'"),
        "{line}"
    );
    assert_eq!(std::fs::read(out.join("vehicles.csv")).unwrap(), before);
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn config_print_shows_the_defaults_and_round_trips() {
    let o = bkpbs(&["config", "--print"]);
    assert!(o.status.success());
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains("lambda = 3000.0") && text.contains("steps = 400"),
        "{text}"
    );
    let d = tmp();
    let p = d.path().join("c.toml");
    std::fs::write(&p, &text).unwrap();
    let again = bkpbs(&["config", "--print", "--config", p.to_str().unwrap()]);
    assert_eq!(String::from_utf8(again.stdout).unwrap(), text);
}

#[test]
fn an_interrupted_episode_removes_its_input_and_writes_nothing() {
    // Ctrl-C once left the episode's input directory in the temporary directory (46 after
    // one afternoon); a stop signal now ends the episode at its next step, tidied up.
    for (signal, code) in [(libc::SIGINT, 130), (libc::SIGTERM, 143)] {
        let (tmpdir, d) = (tmp(), tmp());
        let out = d.path().join("out");
        let child = std::process::Command::new(env!("CARGO_BIN_EXE_bkpbs"))
            .args(["episode", "--planner", "sumo", "--steps", "100000", "--out"])
            .arg(&out)
            .env("TMPDIR", tmpdir.path())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        common::wait_for("the input directory", 60, || {
            !common::input_dirs(tmpdir.path()).is_empty()
        });
        common::send_signal(child.id() as i32, signal);
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(code), "{}", stderr(&o));
        let line = one_error_line(&o);
        assert!(line.starts_with("error: interrupted by SIG"), "{line}");
        assert_eq!(
            common::input_dirs(tmpdir.path()),
            Vec::<std::path::PathBuf>::new()
        );
        assert!(!out.join("episode.csv").exists());
    }
}

#[test]
fn an_episode_that_cannot_replace_every_file_leaves_the_earlier_set_whole() {
    // An episode.csv that had become a directory once left new vehicles.csv and timing.csv
    // next to the old collisions.csv: a mixed set. Now nothing is replaced.
    let d = tmp();
    let out = d.path().join("out");
    let first = episode_into(&out, &["--planner", "sumo", "--steps", "30"]);
    assert!(first.status.success(), "{}", stderr(&first));
    let before: Vec<Vec<u8>> = ["vehicles.csv", "collisions.csv", "timing.csv"]
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    std::fs::remove_file(out.join("episode.csv")).unwrap();
    std::fs::create_dir(out.join("episode.csv")).unwrap();
    let line = one_error_line(&episode_into(&out, &["--planner", "sumo", "--steps", "40"]));
    assert!(
        line.contains("episode.csv") && line.contains("directory"),
        "{line}"
    );
    for (f, old) in ["vehicles.csv", "collisions.csv", "timing.csv"]
        .iter()
        .zip(&before)
    {
        assert_eq!(
            &std::fs::read(out.join(f)).unwrap(),
            old,
            "{f} was replaced"
        );
    }
}

#[test]
fn a_driver_profile_sumo_rejects_or_nobody_knows_is_one_error_line() {
    let d = tmp();
    let out = d.path().join("out");
    let o = episode_into(&out, &["--hdv-profile", "reckless", "--steps", "10"]);
    assert_clear_failure(&o, "unknown HDV profile 'reckless'", &out);
    assert!(stderr(&o).contains("sumo-safe, paper, heterogeneous, krauss, eidm"));
    // A negative reaction time is outside SUMO's range: refused naming the setting.
    let (cfg, out) = config_file(
        d.path(),
        "bad.toml",
        "[hdv]\nprofile = \"mine\"\n[hdv.profiles.mine]\nattributes = { tau = \"-1\" }\n",
    );
    let o = episode_into(&out, &["--config", &cfg, "--steps", "10"]);
    assert_clear_failure(&o, "hdv.profiles.mine.attributes.tau", &out);
    // SUMO itself refuses a reaction time that is no number; its reason is in the line.
    let (cfg, out) = config_file(
        d.path(),
        "text.toml",
        "[hdv]\nprofile = \"mine\"\n[hdv.profiles.mine]\nattributes = { tau = \"fast\" }\n",
    );
    let o = episode_into(&out, &["--config", &cfg, "--steps", "10"]);
    assert_clear_failure(
        &o,
        "SUMO said: Invalid Car-Following-Model Attribute tau",
        &out,
    );
}

#[test]
fn collect_takes_a_driver_profile_and_refuses_an_unknown_one() {
    let d = tmp();
    let out = d.path().join("x.bin");
    let o = bkpbs(&[
        "collect",
        "--hdv-profile",
        "reckless",
        "--episodes",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clear_failure(&o, "reckless", d.path());
    let o = bkpbs(&[
        "collect",
        "--hdv-profile",
        "krauss",
        "--episodes",
        "1",
        "--steps",
        "60",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.is_file());
}
