//! Each campaign cell records what produced it (`provenance.toml`: the bkpbs build, SUMO and
//! the digest of every model file its settings name): a cell whose model file was replaced
//! since it ran runs again, saying which setting's file changed; an unchanged one is done.
//! On the paper's merge with real SUMO.

mod common;

use std::path::Path;
use std::process::Output;

use common::{assert_ok, bkpbs};

/// `bkpbs campaign` of idm-mobil with `config`, one seed of 20 steps, into `out`.
fn campaign(config: &Path, out: &Path) -> Output {
    let (config, out) = (config.display().to_string(), out.display().to_string());
    bkpbs(&[
        "campaign",
        "--config",
        &config,
        "--planners",
        "idm-mobil",
        "--alphas",
        "0.5",
        "--lambdas",
        "3000",
        "--seeds",
        "1",
        "--steps",
        "20",
        "--out",
        &out,
    ])
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn a_cell_whose_model_file_was_replaced_runs_again_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("gcn.json");
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/gcn-conditioned.json");
    std::fs::copy(&shipped, &model).unwrap();
    let config = tmp.path().join("config.toml");
    let setting = format!("[predictor]\nconditioned_model = {:?}\n", model.display());
    std::fs::write(&config, setting).unwrap();
    let out = tmp.path().join("out");
    assert_ok(&campaign(&config, &out));
    let cell = out.join("episodes/idm-mobil/a0.5_l3000_s0");
    let record = std::fs::read_to_string(cell.join("provenance.toml")).unwrap();
    assert!(record.contains(env!("BKPBS_COMMIT")), "{record}");
    assert!(
        record.contains("\"predictor.conditioned_model\" = \""),
        "{record}"
    );

    let again = campaign(&config, &out);
    assert_ok(&again);
    assert!(
        stdout(&again).contains("already done: 1;"),
        "{}",
        stdout(&again)
    );

    // Retrained in place: the same name, other bytes.
    let text = std::fs::read_to_string(&model).unwrap();
    std::fs::write(&model, format!("{text}\n")).unwrap();
    let replaced = campaign(&config, &out);
    assert_ok(&replaced);
    let said = stdout(&replaced);
    assert!(
        said.contains(
            "runs again: its predictor.conditioned_model file is not the one it ran with"
        ),
        "{said}"
    );
    assert!(said.contains("already done: 0;"), "{said}");
    let after = campaign(&config, &out);
    assert!(
        stdout(&after).contains("already done: 1;"),
        "{}",
        stdout(&after)
    );
}

#[test]
fn a_cell_of_another_build_runs_again_naming_both() {
    let tmp = tempfile::tempdir().unwrap();
    let config = tmp.path().join("config.toml");
    std::fs::write(&config, "").unwrap();
    let out = tmp.path().join("out");
    assert_ok(&campaign(&config, &out));
    let record = out.join("episodes/idm-mobil/a0.5_l3000_s0/provenance.toml");
    let text = std::fs::read_to_string(&record).unwrap();
    let other = text.replace(
        env!("BKPBS_COMMIT"),
        "0123456789abcdef0123456789abcdef01234567",
    );
    assert_ne!(text, other, "the record names the commit");
    std::fs::write(&record, other).unwrap();
    let again = campaign(&config, &out);
    assert_ok(&again);
    let said = stdout(&again);
    assert!(
        said.contains("runs again: bkpbs ") && said.contains("(commit 0123456789ab) ran it"),
        "{said}"
    );
}
