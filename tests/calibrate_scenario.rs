//! `bkpbs calibrate --sumocfg` and `bkpbs train-rl --sumocfg` on a SUMO scenario nobody here
//! wrote (SUMO's `ramp` game): the episodes run the scenario's own routes and drivers, the
//! calibration and the policy say what they ran on (the configuration as given, its files'
//! SHA-256), the same command writes the same bytes, and a profile, the matrix or a missing
//! file is one error line.

use sha2::{Digest, Sha256};

mod common;

use common::{bkpbs, game_copy, refused_naming, stderr};

/// `bkpbs calibrate --sumocfg cfg` of two episodes and one held out into `out`.
fn calibrate(cfg: &std::path::Path, out: &std::path::Path) -> std::process::Output {
    bkpbs(&[
        "calibrate",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--episodes",
        "2",
        "--held-out",
        "1",
        "--out",
        out.to_str().unwrap(),
    ])
}

/// The SHA-256 of `path`, in hex.
fn sha256(path: &std::path::Path) -> String {
    let digest = Sha256::digest(std::fs::read(path).unwrap());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn calibrate_runs_on_a_scenario_of_your_own_and_records_what_it_ran() {
    let d = tempfile::tempdir().unwrap();
    let game = game_copy(d.path());
    let cfg = game.join("ramp.sumocfg");
    let out = d.path().join("cal");
    let o = calibrate(&cfg, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        report.contains(&format!("(scenario {})", cfg.display())),
        "{report}"
    );
    assert!(
        report.contains("per-vehicle recovery: not applicable"),
        "{report}"
    );
    let path = out.join("calibration.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(v["fit_samples"].as_u64().unwrap() > 100, "{text}");
    assert!(v["held_out_samples"].as_u64().unwrap() > 100, "{text}");
    assert!(
        v.get("profile").is_none(),
        "no profile on a scenario: {text}"
    );
    assert!(v["recovery"].as_array().unwrap().is_empty(), "{text}");
    assert!(v["recovery_not_applicable"].is_string(), "{text}");
    let scenario = &v["scenario"];
    assert_eq!(scenario["sumocfg"], cfg.to_str().unwrap());
    assert_eq!(scenario["files"]["kind"], "sumocfg");
    let digests = &scenario["files"]["sha256"];
    assert_eq!(digests["ramp.sumocfg"], sha256(&cfg));
    assert_eq!(
        digests["ramp/ramp.rou.xml"],
        sha256(&game.join("ramp/ramp.rou.xml"))
    );
    let o = calibrate(&cfg, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        text,
        "the same command, the same bytes"
    );
}

#[test]
fn a_profile_the_matrix_or_a_missing_scenario_is_one_error_line() {
    let d = tempfile::tempdir().unwrap();
    let cfg = game_copy(d.path()).join("ramp.sumocfg");
    let cfg = cfg.to_str().unwrap();
    let out = d.path().join("cal");
    let out_s = out.to_str().unwrap();
    let o = bkpbs(&[
        "calibrate",
        "--profile",
        "paper",
        "--sumocfg",
        cfg,
        "--out",
        out_s,
    ]);
    refused_naming(&o, &["--profile", "--sumocfg"]);
    let o = bkpbs(&["calibrate", "--sumocfg", cfg, "--matrix", "--out", out_s]);
    refused_naming(&o, &["--matrix", "--sumocfg"]);
    // A scenario named by the config file: the flags of the paper's drivers still refused.
    let toml = d.path().join("ramp.toml");
    std::fs::write(&toml, format!("[scenario]\nsumocfg = {cfg:?}\n")).unwrap();
    let toml = toml.to_str().unwrap();
    let o = bkpbs(&["calibrate", "--config", toml, "--matrix", "--out", out_s]);
    refused_naming(&o, &["--matrix", "ramp.sumocfg"]);
    let missing = d.path().join("nope.sumocfg");
    let missing = missing.to_str().unwrap();
    let o = bkpbs(&["calibrate", "--sumocfg", missing, "--out", out_s]);
    refused_naming(&o, &["nope.sumocfg"]);
    assert!(!out.exists());
    let o = bkpbs(&["train-rl", "--sumocfg", missing, "--out", out_s]);
    refused_naming(&o, &["nope.sumocfg"]);
    assert!(!out.exists(), "refused before any worker started");
}

/// `bkpbs train-rl --sumocfg cfg` of one update of one episode, no evaluation, into `out`.
fn train_rl(cfg: &std::path::Path, out: &std::path::Path) -> std::process::Output {
    bkpbs(&[
        "train-rl",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--steps",
        "1",
        "--episodes-per-update",
        "1",
        "--eval-episodes",
        "0",
        "--workers",
        "1",
        "--threads",
        "1",
    ])
}

#[test]
fn train_rl_trains_on_a_scenario_of_your_own_and_its_policy_records_it() {
    let d = tempfile::tempdir().unwrap();
    let cfg = game_copy(d.path()).join("ramp.sumocfg");
    let out = d.path().join("rl");
    let o = train_rl(&cfg, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let curve = std::fs::read_to_string(out.join("learning_curve.csv")).unwrap();
    let row: Vec<&str> = curve.lines().nth(1).unwrap().split(',').collect();
    let env_steps: u64 = row[1].parse().unwrap();
    assert!(env_steps > 100, "the ramp's CAVs decided: {curve}");
    let policy = std::fs::read_to_string(out.join("policy.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&policy).unwrap();
    let scenarios = v["trained_on"]["scenarios"].as_array().unwrap();
    assert_eq!(scenarios.len(), 1, "{policy}");
    assert_eq!(scenarios[0]["kind"], "sumocfg");
    assert_eq!(scenarios[0]["file"], "ramp.sumocfg");
    assert_eq!(scenarios[0]["sha256"]["ramp.sumocfg"], sha256(&cfg));
    // Another run directory, the same command otherwise: the same experience and weights.
    let again = d.path().join("rl2");
    let o = train_rl(&cfg, &again);
    assert!(o.status.success(), "{}", stderr(&o));
    let curve2 = std::fs::read_to_string(again.join("learning_curve.csv")).unwrap();
    assert_eq!(curve, curve2);
}
