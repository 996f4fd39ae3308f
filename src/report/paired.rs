//! Paired comparisons of planners (`bkpbs report --versus REF`): per cell (α, λ, HDV profile)
//! and pooled over cells, each planner's episodes against a reference's of the same cell and
//! seed.
//!
//! A seed fixes the traffic (arrivals, vehicle types, drivers), so the two episodes of a seed
//! differ only by the planner: the per-seed difference removes the traffic's variance, which
//! dominates the spread of a metric over seeds. Means with overlapping intervals can thus still
//! differ clearly, and the paired test is the one that sees it. Tables: [`super::paired_tables`].

use std::collections::BTreeMap;
use std::path::Path;

use super::signif::{fisher_exact, signed_rank, SignedRank};
use super::stats::Estimate;
use super::summary::SummaryError;
use crate::campaign::results::Results;
use crate::campaign::table::{Row, Table};
use crate::episode::metrics::mean;

/// The `episodes.csv` columns compared seed by seed, in report order. One list, so that a new
/// metric is one more name; a column the results lack (older campaigns) is skipped.
pub const METRICS: [&str; 4] = ["system_delay_s", "mean_delay_s", "arrived", "stranded"];

/// The column whose positive value makes an episode a collision episode.
pub const COLLISIONS: &str = "controllable_crashed";

/// A cell of the grid without planner and seed: what the two episodes of a pair share.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// CAV penetration α.
    pub alpha: f64,
    /// Total arrival rate λ (veh/h).
    pub lambda: f64,
    /// The HDV driver profile.
    pub hdv_profile: String,
}

/// The paired difference of one metric.
#[derive(Debug, Clone, PartialEq)]
pub struct MetricDiff {
    /// Pairs in which both episodes have a value (an episode without arrivals has no delay).
    pub pairs: usize,
    /// The planner's mean over those pairs.
    pub mean_planner: f64,
    /// The reference's mean over those pairs.
    pub mean_reference: f64,
    /// Mean of planner − reference with Student's 95 % interval (paired t).
    pub diff: Estimate,
    /// Wilcoxon's signed-rank test; `None` when every difference is zero.
    pub test: Option<SignedRank>,
}

/// Collision episodes of the pairs and Fisher's exact test of the 2×2 table (planner,
/// reference) × (collision, none).
#[derive(Debug, Clone, PartialEq)]
pub struct Collisions {
    /// The planner's episodes with a controllable collision.
    pub planner: usize,
    /// The reference's.
    pub reference: usize,
    /// Fisher's two-sided p.
    pub p: f64,
}

/// One comparison in one cell, or pooled over cells (`cell` = `None`).
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// The planner compared.
    pub planner: String,
    /// The reference it is compared with.
    pub reference: String,
    /// The cell, or `None` for all cells pooled.
    pub cell: Option<Cell>,
    /// Matched (cell, seed) pairs.
    pub pairs: usize,
    /// Episodes of either side without a partner of the same cell and seed (dropped).
    pub unmatched: usize,
    /// Per [`Paired::metrics`] entry; `None` when no pair has values of it.
    pub metrics: Vec<Option<MetricDiff>>,
    /// The collision episodes of the pairs.
    pub collisions: Collisions,
}

/// All paired comparisons of a report.
#[derive(Debug, Clone, PartialEq)]
pub struct Paired {
    /// The compared columns present in the results ([`METRICS`] in order).
    pub metrics: Vec<&'static str>,
    /// Per reference, per planner: its cells in grid order, then the pooled block.
    pub blocks: Vec<Block>,
}

/// One episode's compared values and whether it had a collision.
struct Episode {
    values: Vec<Option<f64>>,
    collided: bool,
}

/// A cell's identity for lookups: profile rank, α and λ (by value).
type CellKey = (usize, u64, u64);

/// Per planner, per cell (in grid order), per seed: the episode.
type Index = BTreeMap<String, BTreeMap<CellKey, BTreeMap<u64, Episode>>>;

/// The value of column `i` named `name` in `row`: empty is `None`, else a number.
fn value(
    row: &Row,
    i: usize,
    name: &'static str,
    path: &Path,
) -> Result<Option<f64>, SummaryError> {
    let text = row.fields.get(i).unwrap_or("");
    if text.is_empty() {
        return Ok(None);
    }
    text.parse().map(Some).map_err(|_| SummaryError::Value {
        path: path.to_path_buf(),
        cell: row.cell.to_string(),
        column: name,
        value: text.to_string(),
    })
}

/// A compared column: its name and index.
type Column = (&'static str, usize);

/// The present [`METRICS`] with their column indices, and the collision column's index.
fn columns(t: &Table, path: &Path) -> Result<(Vec<Column>, usize), SummaryError> {
    let metrics = METRICS
        .iter()
        .filter_map(|&m| Some((m, t.column(m)?)))
        .collect();
    let crashed = t.column(COLLISIONS).ok_or_else(|| SummaryError::Column {
        path: path.to_path_buf(),
        column: COLLISIONS,
    })?;
    Ok((metrics, crashed))
}

/// Indexes the episodes by planner, cell and seed; also returns the cells by key.
fn index(
    res: &Results,
    metrics: &[Column],
    crashed: usize,
    path: &Path,
) -> Result<(Index, BTreeMap<CellKey, Cell>), SummaryError> {
    let mut by = Index::new();
    let mut cells = BTreeMap::new();
    for row in &res.episodes.rows {
        let c = &row.cell;
        let profile = res.profiles.iter().position(|p| *p == c.hdv_profile);
        let key = (
            profile.unwrap_or(usize::MAX),
            c.alpha.to_bits(),
            c.lambda.to_bits(),
        );
        let mut values = Vec::new();
        for &(name, i) in metrics {
            values.push(value(row, i, name, path)?);
        }
        let collided = value(row, crashed, COLLISIONS, path)?.is_some_and(|v| v > 0.0);
        cells.entry(key).or_insert_with(|| Cell {
            alpha: c.alpha,
            lambda: c.lambda,
            hdv_profile: c.hdv_profile.clone(),
        });
        let seeds = by
            .entry(c.planner.clone())
            .or_default()
            .entry(key)
            .or_default();
        seeds.insert(c.seed, Episode { values, collided });
    }
    Ok((by, cells))
}

/// The paired difference of metric `m` over `pairs`, if any pair has both values.
fn metric_diff(pairs: &[(&Episode, &Episode)], m: usize) -> Option<MetricDiff> {
    let both: Vec<(f64, f64)> = pairs
        .iter()
        .filter_map(|(p, r)| Some((p.values[m]?, r.values[m]?)))
        .collect();
    let diffs: Vec<f64> = both.iter().map(|(p, r)| p - r).collect();
    Some(MetricDiff {
        pairs: both.len(),
        mean_planner: mean(both.iter().map(|b| b.0))?,
        mean_reference: mean(both.iter().map(|b| b.1))?,
        diff: Estimate::of(&diffs)?,
        test: signed_rank(&diffs),
    })
}

/// The block of `pairs` (planner episode, reference episode).
fn block(
    (planner, reference): (&str, &str),
    cell: Option<Cell>,
    pairs: &[(&Episode, &Episode)],
    unmatched: usize,
    metrics: usize,
) -> Block {
    let count = |f: fn(&(&Episode, &Episode)) -> bool| pairs.iter().filter(|p| f(p)).count();
    let (p, r) = (count(|e| e.0.collided), count(|e| e.1.collided));
    let n = pairs.len();
    Block {
        planner: planner.to_string(),
        reference: reference.to_string(),
        cell,
        pairs: n,
        unmatched,
        metrics: (0..metrics).map(|m| metric_diff(pairs, m)).collect(),
        collisions: Collisions {
            planner: p,
            reference: r,
            p: fisher_exact(p as u64, (n - p) as u64, r as u64, (n - r) as u64),
        },
    }
}

/// The blocks of one planner against one reference: each cell with a pair, then all pooled.
fn compare(
    by: &Index,
    cells: &BTreeMap<CellKey, Cell>,
    names: (&str, &str),
    m: usize,
) -> Vec<Block> {
    let empty = BTreeMap::new();
    let (mine, theirs) = (
        by.get(names.0).unwrap_or(&empty),
        by.get(names.1).unwrap_or(&empty),
    );
    let none = BTreeMap::new();
    let (mut blocks, mut all, mut all_unmatched) = (Vec::new(), Vec::new(), 0);
    for (key, cell) in cells {
        let (a, b) = (
            mine.get(key).unwrap_or(&none),
            theirs.get(key).unwrap_or(&none),
        );
        let pairs: Vec<(&Episode, &Episode)> = a
            .iter()
            .filter_map(|(seed, e)| Some((e, b.get(seed)?)))
            .collect();
        let unmatched = a.len() + b.len() - 2 * pairs.len();
        all_unmatched += unmatched;
        if !pairs.is_empty() {
            blocks.push(block(names, Some(cell.clone()), &pairs, unmatched, m));
        }
        all.extend(pairs);
    }
    blocks.push(block(names, None, &all, all_unmatched, m));
    blocks
}

impl Paired {
    /// Every planner of the results against each reference of `versus`, in grid order; a
    /// planner that is itself an earlier reference is not compared again the other way round.
    /// `path` names `episodes.csv` in errors.
    pub fn of(res: &Results, versus: &[String], path: &Path) -> Result<Paired, PairedError> {
        let (metrics, crashed) = columns(&res.episodes, path)?;
        let (by, cells) = index(res, &metrics, crashed, path)?;
        let planners: Vec<&String> = res
            .planners
            .iter()
            .filter(|p| by.contains_key(*p))
            .collect();
        let mut blocks = Vec::new();
        for (i, reference) in versus.iter().enumerate() {
            if !by.contains_key(reference) {
                let known: Vec<&str> = planners.iter().map(|p| p.as_str()).collect();
                return Err(PairedError::Reference {
                    name: reference.clone(),
                    known: known.join(", "),
                });
            }
            if versus[..i].contains(reference) {
                continue;
            }
            for p in &planners {
                if *p != reference && !versus[..i].contains(p) {
                    blocks.extend(compare(&by, &cells, (p, reference), metrics.len()));
                }
            }
        }
        Ok(Paired {
            metrics: metrics.iter().map(|m| m.0).collect(),
            blocks,
        })
    }
}

/// Why paired comparisons could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PairedError {
    /// A reference named by `--versus` ran in none of the episodes.
    #[error("--versus {name}: no episodes of planner '{name}' in the results (planners: {known})")]
    Reference {
        /// The name given.
        name: String,
        /// The planners that are there, comma-separated.
        known: String,
    },
    /// `episodes.csv` lacks the collision column or holds a non-number.
    #[error(transparent)]
    Summary(#[from] SummaryError),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::grid::Cell;

    /// Results of `rows` (planner, α, seed, mean delay, arrived, crashed) at λ 3000.
    fn results(rows: &[(&str, f64, u64, &str, u32, u32)]) -> Results {
        let header = [
            "planner",
            "alpha",
            "lambda",
            "seed",
            "hdv_profile",
            "mean_delay_s",
            "arrived",
            COLLISIONS,
        ];
        let mut t = Table::new(header.iter().map(|h| h.to_string()).collect());
        for &(planner, alpha, seed, delay, arrived, crashed) in rows {
            let cell = Cell {
                planner: planner.into(),
                alpha,
                lambda: 3000.0,
                seed,
                hdv_profile: "h".into(),
                predictor: None,
                scenario: None,
            };
            let fields = [
                planner.to_string(),
                alpha.to_string(),
                "3000".into(),
                seed.to_string(),
                "h".into(),
                delay.into(),
                arrived.to_string(),
                crashed.to_string(),
            ];
            t.rows.push(Row {
                cell,
                fields: csv::StringRecord::from(fields.to_vec()),
            });
        }
        Results {
            planners: vec!["a".into(), "b".into(), "c".into()],
            profiles: vec!["h".into()],
            episodes: t,
            ..Results::default()
        }
    }

    #[test]
    fn pairs_match_cell_and_seed_pool_over_cells_and_skip_missing_columns() {
        let res = results(&[
            ("a", 0.4, 1, "10", 5, 1),
            ("a", 0.4, 2, "", 4, 0),
            ("a", 0.8, 1, "7", 6, 0),
            ("a", 0.8, 9, "7", 6, 0),
            ("b", 0.4, 1, "8", 5, 0),
            ("b", 0.4, 2, "6", 5, 0),
            ("b", 0.8, 1, "8", 6, 0),
            ("c", 0.4, 1, "8", 5, 0),
        ]);
        let refs = ["b".to_string(), "a".to_string(), "b".to_string()];
        let p = Paired::of(&res, &refs, Path::new("episodes.csv")).unwrap();
        // system_delay_s and stranded are not in these rows: skipped.
        assert_eq!(p.metrics, ["mean_delay_s", "arrived"]);
        let names: Vec<(&str, &str, Option<f64>)> = p
            .blocks
            .iter()
            .map(|b| (&*b.planner, &*b.reference, b.cell.as_ref().map(|c| c.alpha)))
            .collect();
        // b is not compared with a again, nor with itself; c has a cell at α 0.4 only.
        let expected = [
            ("a", "b", Some(0.4)),
            ("a", "b", Some(0.8)),
            ("a", "b", None),
            ("c", "b", Some(0.4)),
            ("c", "b", None),
            ("c", "a", Some(0.4)),
            ("c", "a", None),
        ];
        assert_eq!(names, expected);
        let cell = &p.blocks[0];
        assert_eq!((cell.pairs, cell.unmatched), (2, 0));
        // Seed 2 of a has no delay: one delay pair (10 − 8), two arrival pairs (0, −1).
        let delay = cell.metrics[0].as_ref().unwrap();
        assert_eq!(
            (delay.pairs, delay.diff.mean, delay.diff.ci95),
            (1, 2.0, None)
        );
        let arrived = cell.metrics[1].as_ref().unwrap();
        assert_eq!((arrived.pairs, arrived.diff.mean), (2, -0.5));
        assert_eq!(arrived.test.unwrap().zeros, 1);
        assert_eq!((cell.collisions.planner, cell.collisions.reference), (1, 0));
        assert_eq!(cell.collisions.p, 1.0);
        // α 0.8: seed 9 of a has no partner. Pooled: 3 pairs, that one unmatched.
        assert_eq!((p.blocks[1].pairs, p.blocks[1].unmatched), (1, 1));
        let pooled = &p.blocks[2];
        assert_eq!((pooled.pairs, pooled.unmatched), (3, 1));
        let delay = pooled.metrics[0].as_ref().unwrap();
        assert_eq!((delay.pairs, delay.diff.mean), (2, 0.5));
        // c against b at α 0.4: b's seed 2 is unmatched, and every difference is zero.
        let c = &p.blocks[3];
        assert_eq!((c.pairs, c.unmatched), (1, 1));
        assert_eq!(c.metrics[0].as_ref().unwrap().test, None);
    }

    #[test]
    fn an_unknown_reference_is_refused_naming_the_planners() {
        let res = results(&[("a", 0.4, 1, "1", 1, 0)]);
        let e = Paired::of(&res, &["z".into()], Path::new("e.csv")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--versus z: no episodes of planner 'z' in the results (planners: a)"
        );
    }
}
