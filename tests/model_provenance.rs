//! What a model or policy file was trained on decides where it may be used: under another step
//! length it is refused (one `error:` line, exit 1); on another scenario the episode warns once
//! and runs; on its own scenario it is quiet. Real SUMO, the binary as a user runs it.

mod common;

use std::path::{Path, PathBuf};

use common::{bkpbs, game_copy, refused_naming, scenario_run, stderr};

/// A copy of the committed file `name` (under `models/`) in `dir` as `copy`, its record's
/// field `key` set to `value`.
fn copy_with(dir: &Path, name: &str, copy: &str, key: &str, value: serde_json::Value) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let text = std::fs::read_to_string(root.join(name)).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["trained_on"][key] = value;
    let path = dir.join(copy);
    std::fs::write(&path, serde_json::to_string(&json).unwrap()).unwrap();
    path
}

/// A `--config` file of `section` naming `path` as `key`.
fn config_naming(dir: &Path, section: &str, key: &str, path: &Path) -> PathBuf {
    let cfg = dir.join(format!("{section}.toml"));
    std::fs::write(
        &cfg,
        format!("[{section}]\n{key} = {:?}\n", path.to_str().unwrap()),
    )
    .unwrap();
    cfg
}

/// `bkpbs episode` of `planner` on the paper's merge for a few steps, with `--config cfg`.
fn paper_episode(planner: &str, cfg: Option<&Path>, out: &Path) -> std::process::Output {
    let mut args = vec![
        "episode",
        "--planner",
        planner,
        "--steps",
        "20",
        "--seed",
        "3",
    ];
    if let Some(c) = cfg {
        args.extend(["--config", c.to_str().unwrap()]);
    }
    args.extend(["--out", out.to_str().unwrap()]);
    bkpbs(&args)
}

#[test]
fn a_model_trained_at_another_step_length_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let model = copy_with(
        dir.path(),
        "gcn-conditioned.json",
        "at-0.1s.json",
        "step_length_s",
        0.1.into(),
    );
    let cfg = config_naming(dir.path(), "predictor", "conditioned_model", &model);
    let o = paper_episode("bk-pbs", Some(&cfg), &dir.path().join("out"));
    refused_naming(&o, &["at-0.1s.json", "0.1 s", "scenario.dt is 0.2 s"]);
}

/// `eval-predictor` and `bench-predictor` refuse it too, before any episode runs.
#[test]
fn evaluating_a_model_of_another_step_length_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let model = copy_with(
        dir.path(),
        "gcn-conditioned.json",
        "at-0.1s.json",
        "step_length_s",
        0.1.into(),
    );
    let m = model.to_str().unwrap();
    let o = bkpbs(&["eval-predictor", "--model", m, "--episodes", "1"]);
    refused_naming(&o, &["at-0.1s.json", "0.1 s", "0.2 s"]);
    let cfg = config_naming(dir.path(), "predictor", "conditioned_model", &model);
    let o = bkpbs(&["bench-predictor", "--config", cfg.to_str().unwrap()]);
    refused_naming(&o, &["at-0.1s.json", "0.1 s", "0.2 s"]);
}

#[test]
fn a_policy_trained_at_another_step_length_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let policy = copy_with(
        dir.path(),
        "rl-ppo.json",
        "policy-0.1s.json",
        "step_length_s",
        0.1.into(),
    );
    let cfg = config_naming(dir.path(), "rl", "policy", &policy);
    let o = paper_episode("rl-ppo", Some(&cfg), &dir.path().join("out"));
    refused_naming(&o, &["rl.policy", "policy-0.1s.json", "0.1 s", "0.2 s"]);
}

/// On the paper's merge the shipped models are quiet, and `models.toml` lists them with their
/// record.
#[test]
fn the_shipped_models_are_quiet_on_the_paper_s_merge_and_listed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = paper_episode("bk-pbs", None, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("trained on"), "{}", stderr(&o));
    let record = std::fs::read_to_string(out.join("models.toml")).unwrap();
    let value: toml::Value = toml::from_str(&record).unwrap();
    let models = value["model"].as_array().unwrap();
    assert_eq!(models.len(), 2, "{record}");
    assert_eq!(
        models[0]["source"].as_str(),
        Some("embedded:gcn-conditioned.json")
    );
    assert_eq!(
        models[0]["trained_on"]["scenarios"][0]["kind"].as_str(),
        Some("paper-merge")
    );
}

/// The lines of `o`'s stderr that warn of a model's scenario.
fn scenario_warnings(o: &std::process::Output) -> Vec<String> {
    stderr(o)
        .lines()
        .filter(|l| l.starts_with("warning:") && l.contains("trained on"))
        .map(str::to_string)
        .collect()
}

/// The paper's models on a scenario of the user's: one warning naming both, and the episode
/// runs; a model whose record names that very scenario is quiet; one trained on another
/// scenario of the user's warns naming both.
#[test]
fn a_model_of_another_scenario_warns_once_and_the_episode_runs() {
    let dir = tempfile::tempdir().unwrap();
    let ramp = game_copy(dir.path()).join("ramp.sumocfg");
    let flags = ["--steps", "100", "--seed", "3"];
    let o = scenario_run(&ramp, "bk-pbs", &flags, &dir.path().join("paper"));
    assert!(o.status.success(), "{}", stderr(&o));
    let w = scenario_warnings(&o);
    assert_eq!(w.len(), 1, "{}", stderr(&o));
    for word in [
        "the paper's merge",
        "ramp.sumocfg",
        "gcn-conditioned",
        "gcn-unconditioned",
    ] {
        assert!(w[0].contains(word), "'{word}' not in {}", w[0]);
    }

    let s = bkpbs::config::Scenario {
        sumocfg: Some(ramp.clone()),
        ..Default::default()
    };
    let own = bkpbs::sumo::scenario_record::scenario_record(&s).unwrap();
    let own = serde_json::to_value(vec![own]).unwrap();
    let w = ramp_episode_with_model(dir.path(), &ramp, &flags, "ramp.json", own);
    assert_eq!(
        w.len(),
        1,
        "only the embedded unconditioned model warns: {w:?}"
    );
    assert!(!w[0].contains("ramp.json"), "{}", w[0]);

    let other = serde_json::json!([{"kind": "sumocfg", "file": "other.sumocfg",
                                     "sha256": {"other.sumocfg": "00"}}]);
    let w = ramp_episode_with_model(dir.path(), &ramp, &flags, "other.json", other);
    assert!(
        w.iter().any(|l| l.contains("other.json")
            && l.contains("scenario other.sumocfg")
            && l.contains("ramp.sumocfg")),
        "{w:?}"
    );
}

/// A bk-pbs episode on `ramp` (with `flags`) whose conditioned model is a copy of the shipped
/// one named `copy` (in `dir`) recording `scenarios`; the warnings it printed.
fn ramp_episode_with_model(
    dir: &Path,
    ramp: &Path,
    flags: &[&str],
    copy: &str,
    scenarios: serde_json::Value,
) -> Vec<String> {
    let model = copy_with(dir, "gcn-conditioned.json", copy, "scenarios", scenarios);
    let cfg = config_naming(dir, "predictor", "conditioned_model", &model);
    let o = scenario_run(
        ramp,
        "bk-pbs",
        &[flags, &["--config", cfg.to_str().unwrap()]].concat(),
        &dir.join(copy.trim_end_matches(".json")),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    scenario_warnings(&o)
}

/// An episode whose predictor follows an HDV calibration lists that file in `models.toml`
/// (bk-mastar with the constant predictor: the calibration is its one learned file).
#[test]
fn the_calibration_an_episode_follows_is_listed() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let calibration = root.join("models/profiles/paper/calibration.json");
    let cfg = dir.path().join("c.toml");
    let text = format!(
        "[hdv]\nprofile = \"paper\"\n[predictor]\nkind = \"constant\"\ncalibration = {:?}\n",
        calibration.to_str().unwrap()
    );
    std::fs::write(&cfg, text).unwrap();
    let out = dir.path().join("out");
    let o = paper_episode("bk-mastar", Some(&cfg), &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let record = std::fs::read_to_string(out.join("models.toml")).unwrap();
    let value: toml::Value = toml::from_str(&record).unwrap();
    let models = value["model"].as_array().unwrap();
    assert_eq!(models.len(), 1, "{record}");
    assert_eq!(models[0]["setting"].as_str(), Some("predictor.calibration"));
    assert_eq!(
        models[0]["source"].as_str(),
        calibration.to_str(),
        "{record}"
    );
    assert_eq!(models[0]["sha256"].as_str().unwrap().len(), 64, "{record}");
}
