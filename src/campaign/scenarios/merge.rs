//! Several directories of one campaign over scenarios (its shards, run apart on other machines)
//! gathered into one set of collected files, as `bkpbs report DIR… --out DIR` does for the
//! paper's campaigns: each cell once (a cell in several directories must have the same rows in
//! each), in grid order — planners and scenarios in their first-seen order, α and seeds
//! ascending.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::collect::{header_of, ScenarioResults, CELL_COLUMNS};
use crate::campaign::collect::strings;
use crate::campaign::comparison::first_difference;
use crate::campaign::results::{read_records, ResultsError};
use crate::campaign::SETTINGS_FILE;
use crate::episode::rows::TimingRow;
use crate::episode::summary::{Summary, Traffic};

/// Why directories could not be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A collected file is missing, unreadable or has other columns.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// A directory's `campaign.toml` is missing or not TOML.
    #[error("{path}: {message}")]
    Settings {
        /// The settings file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Two directories ran with other settings than the grid's axes.
    #[error(
        "{other} was run with other settings than {first} ({key} differs): its episodes would \
         mix into the same tables; pass --allow-mixed to merge them anyway"
    )]
    Mixed {
        /// The first directory.
        first: PathBuf,
        /// The one that differs.
        other: PathBuf,
        /// The first differing key, dotted.
        key: String,
    },
    /// A cell appears in two directories with different rows.
    #[error("{cell} is in {first} and in {other} with different results")]
    Conflict {
        /// The cell, as `planner scenario α=… seed=…`.
        cell: String,
        /// The first directory holding it.
        first: PathBuf,
        /// The other.
        other: PathBuf,
    },
}

/// A cell's key: its scenario (file name), planner, α and seed, as the rows write them.
type Key = [String; 4];

/// The settings of `dir` without the grid's axes and how it was run, for comparison.
fn settings_without_axes(dir: &Path) -> Result<toml::Value, MergeError> {
    let path = dir.join(SETTINGS_FILE);
    let bad = |message: String| MergeError::Settings {
        path: path.clone(),
        message,
    };
    let text = crate::io::bounded::read_text(&path, crate::io::bounded::FileKind::Config)
        .map_err(|e| bad(e.to_string()))?;
    let mut doc: toml::Table = toml::from_str(&text).map_err(|e| bad(e.message().to_string()))?;
    if let Some(toml::Value::Table(c)) = doc.get_mut("campaign") {
        for key in ["scenarios", "planners", "alphas", "seeds", "seed_base"] {
            c.remove(key);
        }
    }
    Ok(toml::Value::Table(doc))
}

/// One directory's collected files.
struct Part {
    dir: PathBuf,
    results: ScenarioResults,
}

fn read_part(dir: &Path) -> Result<Part, MergeError> {
    let led = |cols: Vec<String>| {
        let mut h: Vec<String> = CELL_COLUMNS.iter().map(|s| s.to_string()).collect();
        h.extend(cols);
        h
    };
    let mut results = ScenarioResults::read(dir)?;
    let vehicles = led(header_of::<crate::episode::sumocfg::ScenarioVehicle>());
    let timings = led(strings(TimingRow::columns()));
    let failures = super::collect::FAILURE_COLUMNS.map(String::from).to_vec();
    results.vehicles = read_records(&dir.join("vehicles.csv"), &vehicles)?;
    results.timings = read_records(&dir.join("timings.csv"), &timings)?;
    results.failures = read_records(&dir.join("failures.csv"), &failures)?;
    Ok(Part {
        dir: dir.to_path_buf(),
        results,
    })
}

/// The key of a row whose scenario, planner, α and seed stand at `at`.
fn key_at(r: &csv::StringRecord, at: [usize; 4]) -> Key {
    at.map(|i| r.get(i).unwrap_or("").to_string())
}

/// Merges the collected files of `dirs` (each a directory of one campaign over scenarios).
///
/// # Errors
/// A directory's files are unreadable, its settings differ (unless `allow_mixed`), or a cell
/// differs between two directories.
pub fn merge(dirs: &[PathBuf], allow_mixed: bool) -> Result<ScenarioResults, MergeError> {
    let parts: Vec<Part> = dirs
        .iter()
        .map(|d| read_part(d))
        .collect::<Result<_, _>>()?;
    if !allow_mixed {
        let first = settings_without_axes(&parts[0].dir)?;
        for p in &parts[1..] {
            if let Some(key) = first_difference(&first, &settings_without_axes(&p.dir)?, "") {
                return Err(MergeError::Mixed {
                    first: parts[0].dir.clone(),
                    other: p.dir.clone(),
                    key,
                });
            }
        }
    }
    let h = Summary::header(Traffic::Scenario);
    let col = |name: &str| h.iter().position(|c| c == name).expect("a column");
    let episode_at = [col("scenario"), col("planner"), col("alpha"), col("seed")];
    // Each cell's owner: the first directory holding it.
    let mut owner: BTreeMap<Key, usize> = BTreeMap::new();
    for (k, p) in parts.iter().enumerate() {
        for row in &p.results.episodes {
            let key = key_at(row, episode_at);
            match owner.get(&key) {
                None => {
                    owner.insert(key, k);
                }
                Some(&o) => same_cell(&parts[o], p, &key, episode_at)?,
            }
        }
    }
    let order = grid_order(&parts, episode_at);
    let mut merged = ScenarioResults::default();
    let take = |rows: &dyn Fn(&ScenarioResults) -> &Vec<csv::StringRecord>,
                at: [usize; 4],
                into: &mut Vec<csv::StringRecord>| {
        for key in &order {
            let p = &parts[owner[key]];
            into.extend(
                rows(&p.results)
                    .iter()
                    .filter(|r| key_at(r, at) == *key)
                    .cloned(),
            );
        }
    };
    // regions.csv and entries.csv lead with scenario, planner, alpha, seed; the led files with
    // the same four.
    take(&|r| &r.episodes, episode_at, &mut merged.episodes);
    take(&|r| &r.regions, [0, 1, 2, 3], &mut merged.regions);
    take(&|r| &r.entries, [0, 1, 2, 3], &mut merged.entries);
    take(&|r| &r.vehicles, [0, 1, 2, 3], &mut merged.vehicles);
    take(&|r| &r.timings, [0, 1, 2, 3], &mut merged.timings);
    merged.failures = failures_outside(&parts, &owner);
    Ok(merged)
}

/// The failure rows of cells no directory finished, each once.
fn failures_outside(parts: &[Part], owner: &BTreeMap<Key, usize>) -> Vec<csv::StringRecord> {
    let mut seen = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for p in parts {
        for r in &p.results.failures {
            // failures.csv: planner, scenario, alpha, seed, error.
            let key = key_at(r, [1, 0, 2, 3]);
            if !owner.contains_key(&key) && seen.insert(key) {
                out.push(r.clone());
            }
        }
    }
    out
}

/// Whether cell `key` has the same episode row in both parts (an error naming both if not).
fn same_cell(a: &Part, b: &Part, key: &Key, at: [usize; 4]) -> Result<(), MergeError> {
    let row = |p: &Part| {
        p.results
            .episodes
            .iter()
            .find(|r| key_at(r, at) == *key)
            .cloned()
    };
    if row(a) == row(b) {
        return Ok(());
    }
    Err(MergeError::Conflict {
        cell: format!("{} {} α={} seed={}", key[1], key[0], key[2], key[3]),
        first: a.dir.clone(),
        other: b.dir.clone(),
    })
}

/// The planners and the scenarios' file names in the order `dir`'s `campaign.toml` lists them
/// (none where it cannot be read: the merge is then checked on settings already).
fn listed_axes(dir: &Path) -> (Vec<String>, Vec<String>) {
    let doc = crate::io::bounded::read_text(
        &dir.join(SETTINGS_FILE),
        crate::io::bounded::FileKind::Config,
    )
    .ok()
    .and_then(|t| toml::from_str::<toml::Table>(&t).ok());
    let list = |key: &str| -> Vec<String> {
        let values = doc
            .as_ref()
            .and_then(|d| d.get("campaign"))
            .and_then(|c| c.get(key))
            .and_then(|v| v.as_array().cloned())
            .unwrap_or_default();
        values
            .iter()
            .filter_map(|v| v.as_str())
            .map(|v| crate::campaign::grid::file_name_of(Path::new(v)))
            .collect()
    };
    (list("planners"), list("scenarios"))
}

/// Every cell in grid order: planners and scenarios as the first directory's `campaign.toml`
/// lists them (others as first seen after them), then α and seed ascending.
fn grid_order(parts: &[Part], at: [usize; 4]) -> Vec<Key> {
    let mut keys: Vec<Key> = Vec::new();
    for p in parts {
        for r in &p.results.episodes {
            let k = key_at(r, at);
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
    }
    let (listed_planners, listed_scenarios) = listed_axes(&parts[0].dir);
    let rank = |i: usize| {
        let mut seen = if i == 0 {
            listed_scenarios.clone()
        } else {
            listed_planners.clone()
        };
        for k in &keys {
            if !seen.contains(&k[i]) {
                seen.push(k[i].clone());
            }
        }
        seen
    };
    let (scenarios, planners) = (rank(0), rank(1));
    let num = |s: &str| s.parse::<f64>().unwrap_or(f64::NAN);
    keys.sort_by(|x, y| {
        let pos = |list: &[String], v: &String| list.iter().position(|s| s == v);
        pos(&planners, &x[1])
            .cmp(&pos(&planners, &y[1]))
            .then(pos(&scenarios, &x[0]).cmp(&pos(&scenarios, &y[0])))
            .then(num(&x[2]).total_cmp(&num(&y[2])))
            .then(num(&x[3]).total_cmp(&num(&y[3])))
    });
    keys
}
