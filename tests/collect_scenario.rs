//! `bkpbs collect --sumocfg` on a SUMO scenario nobody here wrote (SUMO's `ramp` game): the
//! episodes run the scenario's own routes, each merge region's scenes give samples, the data
//! file says what it was collected on, the same command writes the same bytes, and a λ is
//! refused (the scenario's routes are its demand); `eval-predictor --sumocfg` evaluates on fresh
//! episodes of it.

use bkpbs::train::collect::meta_of;
use bkpbs::train::dataset::Dataset;

mod common;

use common::{bkpbs, game_copy, one_error_line, stderr};

/// `bkpbs collect` of two 400-step episodes on the game's `ramp` into `out`.
fn collect(cfg: &std::path::Path, out: &std::path::Path) -> std::process::Output {
    bkpbs(&[
        "collect",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--episodes",
        "2",
        "--steps",
        "400",
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn collect_runs_on_a_scenario_of_your_own_and_records_what_it_ran() {
    let d = tempfile::tempdir().unwrap();
    let cfg = game_copy(d.path()).join("ramp.sumocfg");
    let out = d.path().join("ramp.bin");
    let o = collect(&cfg, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let data = Dataset::read(&out).unwrap();
    let meta = meta_of(&data).expect("the file has its metadata");
    assert!(
        meta.plan.lambdas.is_empty(),
        "no λ on a scenario: {:?}",
        meta.plan
    );
    let on = serde_json::to_string(&meta.trained_on).unwrap();
    assert!(
        on.contains("\"sumocfg\"") && on.contains("ramp.sumocfg"),
        "{on}"
    );
    let ramp_changes = (data.samples.iter())
        .filter(|s| s.label && s.subset == bkpbs::predict::features::Subset::Ramp)
        .count();
    assert!(
        ramp_changes > 0,
        "the ramp's vehicles merged: {}",
        data.samples.len()
    );
    assert!(data.samples.iter().all(|s| s.episode < 2));
    let first = std::fs::read(&out).unwrap();
    let o = collect(&cfg, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        first,
        std::fs::read(&out).unwrap(),
        "the same command, the same bytes"
    );
}

#[test]
fn a_lambda_with_a_scenario_of_your_own_is_one_error_line() {
    let d = tempfile::tempdir().unwrap();
    let cfg = game_copy(d.path()).join("ramp.sumocfg");
    let out = d.path().join("x.bin");
    let o = bkpbs(&[
        "collect",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--lambdas",
        "3000",
        "--episodes",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let line = one_error_line(&o);
    assert!(
        line.contains("--lambdas") && line.contains("--sumocfg"),
        "{line}"
    );
    assert!(!out.exists());
}

#[test]
fn eval_predictor_evaluates_on_fresh_episodes_of_a_scenario_of_your_own() {
    let d = tempfile::tempdir().unwrap();
    let cfg = game_copy(d.path()).join("ramp.sumocfg");
    let o = bkpbs(&[
        "eval-predictor",
        "--sumocfg",
        cfg.to_str().unwrap(),
        "--episodes",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("evaluation data: 1 episodes from seed 90000"),
        "{err}"
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("ramp b_θ (GCN)"), "{out}");
    let o = bkpbs(&["eval-predictor", "--sumocfg", "missing.sumocfg"]);
    assert!(one_error_line(&o).contains("missing.sumocfg"));
}
