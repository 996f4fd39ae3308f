//! Results of several SUMO versions in one report. Results move between SUMO versions, so
//! they are merged only with `--allow-mixed`; each row's planner then carries the version that
//! ran it (`bk-pbs@1.28.0`), so the tables show both side by side and
//! `--versus bk-pbs@1.15.0` pairs the versions cell by cell.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::PathBuf;

use super::ReportError;
use crate::campaign::results::Results;
use crate::campaign::table::{key, CellKey, Table};

/// Each cell's SUMO version, from the `sumo_version` column of `episodes.csv`.
fn versions_by_cell(results: &Results) -> HashMap<CellKey, String> {
    let Some(col) = results.episodes.column("sumo_version") else {
        return HashMap::new();
    };
    results
        .episodes
        .rows
        .iter()
        .map(|r| (key(&r.cell), r.fields.get(col).unwrap_or("").to_string()))
        .collect()
}

/// Refuses results of more than one SUMO version unless `allow_mixed`; with it, labels every
/// row's planner with its version.
pub fn label_if_mixed(
    parts: &mut [(PathBuf, Results)],
    allow_mixed: bool,
) -> Result<(), ReportError> {
    let by_cell: Vec<HashMap<CellKey, String>> =
        parts.iter().map(|(_, r)| versions_by_cell(r)).collect();
    let mut seen: BTreeMap<String, PathBuf> = BTreeMap::new();
    for ((dir, _), versions) in parts.iter().zip(&by_cell) {
        for v in versions.values() {
            seen.entry(v.clone()).or_insert_with(|| dir.clone());
        }
    }
    if seen.len() < 2 {
        return Ok(());
    }
    if !allow_mixed {
        let versions = seen
            .iter()
            .map(|(v, dir)| format!("{v} in {}", dir.display()))
            .collect::<Vec<_>>()
            .join(", ");
        let example = seen.keys().next().cloned().unwrap_or_default();
        return Err(ReportError::MixedVersions { versions, example });
    }
    for ((_, results), versions) in parts.iter_mut().zip(&by_cell) {
        label(results, versions);
    }
    Ok(())
}

/// `planner@version` for the rows of every table (a failed cell, which has no version, keeps
/// its name), and the planner order to match.
fn label(results: &mut Results, versions: &HashMap<CellKey, String>) {
    for table in [
        &mut results.episodes,
        &mut results.vehicles,
        &mut results.timings,
        &mut results.failures,
    ] {
        label_table(table, versions);
    }
    let present: BTreeSet<String> = versions.values().cloned().collect();
    results.planners = results
        .planners
        .iter()
        .flat_map(|p| present.iter().map(move |v| format!("{p}@{v}")))
        .filter(|p| results.episodes.rows.iter().any(|r| &r.cell.planner == p))
        .collect();
}

fn label_table(table: &mut Table, versions: &HashMap<CellKey, String>) {
    for row in &mut table.rows {
        let Some(v) = versions.get(&key(&row.cell)) else {
            continue;
        };
        let name = format!("{}@{v}", row.cell.planner);
        let mut fields = csv::StringRecord::new();
        fields.push_field(&name);
        for f in row.fields.iter().skip(1) {
            fields.push_field(f);
        }
        row.fields = fields;
        row.cell.planner = name;
    }
}
