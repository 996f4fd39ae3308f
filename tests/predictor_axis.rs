//! The predictor axis of a campaign (`--predictors learned,constant`): one campaign compares
//! b_θ with the constant-speed predictor, each arm's episodes exactly those of a campaign run
//! with that `[predictor] kind`, and the report pairs the arms seed by seed. On real SUMO.

use std::path::Path;

mod common;

use common::{assert_ok, bkpbs, csv_rows, one_error_line};

/// The grid of these tests: bk-pbs × α 0.6 × λ 3000 × 2 seeds × 200 steps, then `extra`.
fn campaign(out: &Path, extra: &[&str]) -> std::process::Output {
    campaign_of(out, "200", extra)
}

/// [`campaign`] of `steps` steps.
fn campaign_of(out: &Path, steps: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "campaign",
        "--out",
        out.to_str().unwrap(),
        "--planners",
        "bk-pbs",
        "--alphas",
        "0.6",
        "--lambdas",
        "3000",
        "--seeds",
        "2",
        "--steps",
        steps,
        "--workers",
        "2",
    ];
    args.extend(extra);
    bkpbs(&args)
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The rows of `dir`'s `file` whose `predictor` is `arm`, without that column.
fn arm_rows(dir: &Path, file: &str, arm: &str) -> Vec<std::collections::BTreeMap<String, String>> {
    csv_rows(&read(&dir.join(file)))
        .into_iter()
        .filter(|r| r["predictor"] == arm)
        .map(|mut r| {
            r.remove("predictor");
            r
        })
        .collect()
}

#[test]
fn each_predictor_arm_is_the_campaign_of_that_predictor_and_the_report_pairs_them() {
    let tmp = tempfile::tempdir().unwrap();
    let (both, learned, constant) = (
        tmp.path().join("both"),
        tmp.path().join("learned"),
        tmp.path().join("constant"),
    );
    assert_ok(&campaign(&both, &["--predictors", "learned,constant"]));
    assert_ok(&campaign(&learned, &[]));
    let config = tmp.path().join("constant.toml");
    std::fs::write(&config, "[predictor]\nkind = \"constant\"\n").unwrap();
    assert_ok(&campaign(
        &constant,
        &["--config", config.to_str().unwrap()],
    ));

    let episodes = String::from_utf8(read(&both.join("episodes.csv"))).unwrap();
    assert!(episodes.starts_with("planner,predictor,alpha,lambda,seed,hdv_profile,"));
    assert!(both
        .join("episodes/bk-pbs/predictor-constant/a0.6_l3000_s1/episode.csv")
        .is_file());
    for file in ["episodes.csv", "vehicles.csv"] {
        assert_eq!(
            arm_rows(&both, file, "learned"),
            csv_rows(&read(&learned.join(file))),
            "{file}"
        );
        assert_eq!(
            arm_rows(&both, file, "constant"),
            csv_rows(&read(&constant.join(file))),
            "{file}"
        );
    }
    // Without the axis a campaign keeps the columns it always had.
    assert!(String::from_utf8(read(&learned.join("episodes.csv")))
        .unwrap()
        .starts_with("planner,alpha,lambda,seed,hdv_profile,"));
    assert_ne!(
        arm_rows(&both, "vehicles.csv", "learned"),
        arm_rows(&both, "vehicles.csv", "constant"),
        "the two predictors drove the same trajectories: the axis changed nothing"
    );

    let o = bkpbs(&[
        "report",
        both.to_str().unwrap(),
        "--versus",
        "bk-pbs+learned",
    ]);
    assert_ok(&o);
    let paired = csv_rows(&read(&both.join("report/paired.csv")));
    let pooled = paired
        .iter()
        .find(|r| r["planner"] == "bk-pbs+constant" && r["alpha"] == "all")
        .unwrap_or_else(|| panic!("no pooled bk-pbs+constant row: {paired:?}"));
    assert_eq!(pooled["reference"], "bk-pbs+learned");
    assert_eq!(pooled["pairs"], "2");
}

#[test]
fn shards_of_a_predictor_campaign_merge_and_other_axes_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let whole = tmp.path().join("whole");
    let axis = ["--predictors", "constant,learned"];
    assert_ok(&campaign_of(&whole, "40", &axis));
    let mut shards = Vec::new();
    for k in ["1/2", "2/2"] {
        let dir = tmp.path().join(k.replace('/', "of"));
        assert_ok(&campaign_of(
            &dir,
            "40",
            &[&axis[..], &["--shard", k]].concat(),
        ));
        shards.push(dir);
    }
    let merged = tmp.path().join("merged");
    let o = bkpbs(&[
        "report",
        shards[0].to_str().unwrap(),
        shards[1].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_ok(&o);
    for file in ["episodes.csv", "vehicles.csv", "failures.csv"] {
        assert_eq!(read(&merged.join(file)), read(&whole.join(file)), "{file}");
    }
    // Grid order: the predictors as given.
    let rows = csv_rows(&read(&whole.join("episodes.csv")));
    let order: Vec<&str> = rows.iter().map(|r| r["predictor"].as_str()).collect();
    assert_eq!(order, ["constant", "constant", "learned", "learned"]);

    let o = campaign_of(&whole, "40", &[]);
    let e = one_error_line(&o);
    assert!(e.contains("campaign.predictors"), "{e}");
    let o = campaign(&tmp.path().join("bad"), &["--predictors", "learned,gcn"]);
    let e = one_error_line(&o);
    assert_eq!(
        e,
        "error: --predictors: unknown predictor 'gcn' (known: learned, constant)"
    );
}
