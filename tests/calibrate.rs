//! `bkpbs calibrate` on real SUMO: the fitted IDM beats constant speed on held-out episodes,
//! per-vehicle fits recover heterogeneous drivers' drawn parameters, the output is reproducible,
//! and bad input is one error line.

mod common;

use common::{bkpbs, refused_naming, stderr};

/// Runs `args` again and asserts it rewrites `file` to the same `text`: calibration is
/// reproducible.
fn rerun_rewrites_the_same(args: &[&str], file: &std::path::Path, text: &str) {
    let o = bkpbs(args);
    assert!(o.status.success());
    assert_eq!(std::fs::read_to_string(file).unwrap(), text);
}

/// `(rmse_speed_1s, rmse_speed_3s, rmse_gap_3s)` of the report line of `model`.
fn errors(report: &str, model: &str) -> [f64; 3] {
    let line = report
        .lines()
        .find(|l| l.starts_with(&format!("longitudinal {model} ")))
        .unwrap_or_else(|| panic!("no line for {model} in:\n{report}"));
    let value = |key: &str| -> f64 {
        let at = line.find(&format!("{key}=")).unwrap() + key.len() + 1;
        line[at..].split(' ').next().unwrap().parse().unwrap()
    };
    ["rmse_speed_1s", "rmse_speed_3s", "rmse_gap_3s"].map(value)
}

#[test]
fn the_fitted_idm_beats_constant_speed_and_recovers_heterogeneous_drivers() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("cal");
    let args = [
        "calibrate",
        "--profile",
        "heterogeneous",
        "--episodes",
        "4",
        "--held-out",
        "2",
        "--seed-base",
        "700",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = bkpbs(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = String::from_utf8_lossy(&o.stdout).to_string();
    let (constant, idm) = (
        errors(&report, "constant-speed"),
        errors(&report, "idm-fitted"),
    );
    assert!(idm[1] < constant[1] && idm[2] < constant[2], "{report}");
    for parameter in ["tau", "accel", "decel"] {
        let line = report
            .lines()
            .find(|l| l.starts_with(&format!("per-vehicle recovery {parameter}:")))
            .unwrap_or_else(|| panic!("{report}"));
        let pct: f64 = line
            .split("error ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(pct < 10.0, "{line}");
    }
    let json = std::fs::read_to_string(out.join("calibration.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["format"], "bkpbs-calibration");
    assert_eq!(v["profile"], "heterogeneous");
    // The same command gives the same file.
    rerun_rewrites_the_same(&args, &out.join("calibration.json"), &json);
}

#[test]
fn bad_calibration_input_is_one_error_line() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("cal");
    for (extra, culprit) in [
        (vec!["--profile", "reckless"], "reckless"),
        (vec!["--episodes", "0"], "--episodes"),
        (vec!["--held-out", "-1"], "--held-out"),
    ] {
        let mut args = vec!["calibrate", "--out", out.to_str().unwrap()];
        args.extend(extra);
        refused_naming(&bkpbs(&args), &[culprit]);
    }
}

#[test]
fn a_shipped_calibration_drives_the_planner_only_for_its_own_profile() {
    let d = tempfile::tempdir().unwrap();
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("models/profiles/paper/calibration.json");
    let config = |profile: &str, file: &std::path::Path| {
        let path = d.path().join(format!("{profile}.toml"));
        let text = format!(
            "[hdv]\nprofile = \"{profile}\"\n[predictor]\ncalibration = \"{}\"\n",
            file.display()
        );
        std::fs::write(&path, text).unwrap();
        path
    };
    let run = |cfg: &std::path::Path| {
        bkpbs(&[
            "episode",
            "--planner",
            "bk-pbs",
            "--steps",
            "60",
            "--config",
            cfg.to_str().unwrap(),
            "--out",
            d.path().join("out").to_str().unwrap(),
        ])
    };
    let o = run(&config("paper", &shipped));
    assert!(o.status.success(), "{}", stderr(&o));
    for (cfg, culprit) in [
        (config("sumo-safe", &shipped), "SUMO runs 'sumo-safe'"),
        (
            config("paper", &d.path().join("nope.json")),
            "predictor.calibration",
        ),
    ] {
        refused_naming(&run(&cfg), &[culprit]);
    }
}

#[test]
fn the_generalisation_matrix_holds_every_pair_and_constant_speed_is_worst() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("m");
    let args = [
        "calibrate",
        "--matrix",
        "--profiles",
        "sumo-safe,krauss",
        "--episodes",
        "3",
        "--held-out",
        "2",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = bkpbs(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = std::fs::read_to_string(out.join("longitudinal_matrix.csv")).unwrap();
    let rows: Vec<Vec<&str>> = table
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 3 * 2, "{table}");
    for evaluated in ["sumo-safe", "krauss"] {
        let speed_3s = |model: &str| -> f64 {
            rows.iter()
                .find(|r| r[0] == model && r[1] == evaluated)
                .unwrap()[3]
                .parse()
                .unwrap()
        };
        let constant = speed_3s("constant speed");
        for fitted in ["IDM fitted on sumo-safe", "IDM fitted on krauss"] {
            assert!(
                speed_3s(fitted) < constant,
                "{fitted} on {evaluated}: {table}"
            );
        }
    }
    assert!(std::fs::read(out.join("longitudinal_matrix.png"))
        .unwrap()
        .starts_with(b"\x89PNG"));
    rerun_rewrites_the_same(&args, &out.join("longitudinal_matrix.csv"), &table);
}

#[test]
fn a_directory_of_calibrations_serves_the_profile_sumo_runs() {
    let d = tempfile::tempdir().unwrap();
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/profiles");
    let run = |profile: &str, dir: &std::path::Path| {
        let cfg = d.path().join("c.toml");
        let text = format!(
            "[hdv]\nprofile = \"{profile}\"\n[predictor]\ncalibrations = \"{}\"\n",
            dir.display()
        );
        std::fs::write(&cfg, text).unwrap();
        bkpbs(&[
            "episode",
            "--planner",
            "bk-mastar",
            "--steps",
            "40",
            "--config",
            cfg.to_str().unwrap(),
            "--out",
            d.path().join("out").to_str().unwrap(),
        ])
    };
    for profile in ["krauss", "paper"] {
        let o = run(profile, &shipped);
        assert!(o.status.success(), "{profile}: {}", stderr(&o));
    }
    let o = run("krauss", d.path());
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("krauss/calibration.json"),
        "{}",
        stderr(&o)
    );
}
