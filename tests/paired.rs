//! `bkpbs report --versus`: paired comparisons of a tiny real campaign (SUMO), recomputed from
//! its `episodes.csv`; unmatched seeds dropped and counted; an unknown reference refused.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::OnceLock;

use bkpbs::report::signif::{fisher_exact, signed_rank};
use bkpbs::report::stats::Estimate;

mod common;

use common::{bkpbs, csv_rows, refused_naming};

/// A CSV file as rows of (column → text).
fn rows(path: &Path) -> Vec<BTreeMap<String, String>> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    csv_rows(&bytes)
}

fn assert_ok(o: &std::process::Output) {
    assert!(
        o.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// sumo and idm-mobil × α 0.4 × λ 3000 × 3 seeds × 100 steps, shared by the tests.
fn campaign() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().to_str().unwrap();
        assert_ok(&bkpbs(&[
            "campaign",
            "--out",
            out,
            "--planners",
            "sumo,idm-mobil",
            "--alphas",
            "0.4",
            "--lambdas",
            "3000",
            "--seeds",
            "3",
            "--steps",
            "100",
            "--workers",
            "2",
        ]));
        d
    })
    .path()
}

/// Per seed, (sumo's value, idm-mobil's value) of `column` in the campaign's episodes.
fn by_seed(episodes: &[BTreeMap<String, String>], column: &str) -> BTreeMap<String, [f64; 2]> {
    let mut out: BTreeMap<String, [f64; 2]> = BTreeMap::new();
    for e in episodes {
        let side = usize::from(e["planner"] == "idm-mobil");
        out.entry(e["seed"].clone()).or_default()[side] = e[column].parse().unwrap();
    }
    out
}

fn num(row: &BTreeMap<String, String>, column: &str) -> f64 {
    row[column]
        .parse()
        .unwrap_or_else(|_| panic!("{column}: '{}'", row[column]))
}

#[test]
fn paired_csv_matches_the_episodes_recomputed() {
    let dir = campaign();
    let o = bkpbs(&["report", dir.to_str().unwrap(), "--versus", "idm-mobil"]);
    assert_ok(&o);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("### sumo − idm-mobil"), "{stdout}");
    let tables = std::fs::read_to_string(dir.join("report/tables.md")).unwrap();
    assert!(tables.contains("## Paired comparisons"));
    let episodes = rows(&dir.join("episodes.csv"));
    let paired = rows(&dir.join("report/paired.csv"));
    // One cell and the pooled block, each with the two metrics this campaign has.
    let metrics: Vec<&str> = ["system_delay_s", "mean_delay_s", "arrived", "stranded"]
        .into_iter()
        .filter(|m| episodes[0].contains_key(*m))
        .collect();
    assert_eq!(paired.len(), 2 * metrics.len());
    for (i, row) in paired.iter().enumerate() {
        let cell = [&row["alpha"], &row["lambda"], &row["hdv_profile"]];
        match i < metrics.len() {
            true => assert_eq!(cell, ["0.4", "3000", "sumo-safe"]),
            false => assert_eq!(cell, ["all", "all", "all"]),
        }
        assert_eq!(row["metric"], metrics[i % metrics.len()]);
        assert_eq!(
            (&*row["planner"], &*row["reference"]),
            ("sumo", "idm-mobil")
        );
        assert_eq!(row["unmatched"], "0");
        let values = by_seed(&episodes, &row["metric"]);
        let d: Vec<f64> = values.values().map(|[p, r]| p - r).collect();
        assert_eq!(num(row, "pairs"), 3.0);
        let e = Estimate::of(&d).unwrap();
        assert!((num(row, "mean_diff") - e.mean).abs() < 1e-12, "{row:?}");
        let h = e.ci95.unwrap();
        assert!((num(row, "ci95_low") - (e.mean - h)).abs() < 1e-12);
        assert!((num(row, "ci95_high") - (e.mean + h)).abs() < 1e-12);
        let mean_p = values.values().map(|v| v[0]).sum::<f64>() / 3.0;
        assert!((num(row, "mean_planner") - mean_p).abs() < 1e-12);
        let zeros = d.iter().filter(|x| **x == 0.0).count();
        assert_eq!(num(row, "zeros"), zeros as f64);
        match signed_rank(&d) {
            Some(t) => {
                assert_eq!(num(row, "wilcoxon_v"), t.v);
                assert_eq!(num(row, "wilcoxon_p"), t.p);
                assert_eq!(row["test"], t.method.name());
                assert!(t.p > 0.0 && t.p <= 1.0);
            }
            None => assert_eq!((&*row["wilcoxon_p"], &*row["test"]), ("", "none")),
        }
    }
    let collisions = rows(&dir.join("report/paired_collisions.csv"));
    assert_eq!(collisions.len(), 2);
    let crashed = by_seed(&episodes, "controllable_crashed");
    let count = |side: usize| crashed.values().filter(|v| v[side] > 0.0).count();
    for row in &collisions {
        assert_eq!(num(row, "planner_collision_episodes"), count(0) as f64);
        assert_eq!(num(row, "reference_collision_episodes"), count(1) as f64);
        let (a, c) = (count(0) as u64, count(1) as u64);
        assert_eq!(num(row, "fisher_p"), fisher_exact(a, 3 - a, c, 3 - c));
    }
}

#[test]
fn unmatched_seeds_are_dropped_and_counted_and_unknown_references_refused() {
    let src = campaign();
    let d = tempfile::tempdir().unwrap();
    for f in ["episodes.csv", "vehicles.csv", "campaign.toml"] {
        if src.join(f).exists() {
            std::fs::copy(src.join(f), d.path().join(f)).unwrap();
        }
    }
    // Without idm-mobil's seed 2, sumo's seed 2 has no partner.
    let text = std::fs::read_to_string(src.join("episodes.csv")).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with("idm-mobil,0.4,3000,2,"))
        .collect();
    assert_eq!(kept.len(), text.lines().count() - 1);
    std::fs::write(d.path().join("episodes.csv"), kept.join("\n") + "\n").unwrap();
    let dir = d.path().to_str().unwrap();
    let o = bkpbs(&["report", dir, "--versus", "idm-mobil"]);
    assert_ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("1 episode(s) without a partner"));
    for row in rows(&d.path().join("report/paired.csv")) {
        assert_eq!((&*row["pairs"], &*row["unmatched"]), ("2", "1"), "{row:?}");
    }
    refused_naming(
        &bkpbs(&["report", dir, "--versus", "nope"]),
        &["--versus", "'nope'"],
    );
}
