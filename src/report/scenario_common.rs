//! What the reports of scenario campaigns share: reading a column of a collected file, a cell
//! of an optional number, and the paired t-test of per-seed differences.

use statrs::distribution::{ContinuousCDF, StudentsT};

use super::stats::{t_975, Estimate};
use crate::campaign::table::Table;

/// The index of column `name` in `header`.
pub(super) fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|c| c == name)
        .expect("a column of the record")
}

/// An optional number with `decimals` decimals, or an empty cell.
pub(super) fn fmt_opt(x: Option<f64>, decimals: usize) -> String {
    x.map_or(String::new(), |x| format!("{x:.decimals$}"))
}

/// A paired comparison of per-seed differences.
#[derive(Debug, Clone, Copy)]
pub(super) struct PairedT {
    pub(super) n: usize,
    pub(super) mean: f64,
    pub(super) half: Option<f64>,
    pub(super) p: Option<f64>,
}

impl PairedT {
    /// The 95 % interval's ends, when there is one.
    pub(super) fn interval(&self) -> (Option<f64>, Option<f64>) {
        match self.half {
            Some(h) => (Some(self.mean - h), Some(self.mean + h)),
            None => (None, None),
        }
    }

    /// The interval in a Markdown cell: `[lo, hi]`, or `-`.
    pub(super) fn interval_md(&self) -> String {
        match self.interval() {
            (Some(lo), Some(hi)) => format!("[{lo:+.2}, {hi:+.2}]"),
            _ => "-".into(),
        }
    }
}

/// The paired t-test of `d` (two-sided): the mean, its 95 % half-width, p; none below 2 pairs.
pub(super) fn paired_t(d: &[f64]) -> Option<PairedT> {
    let e = Estimate::of(d)?;
    let n = d.len();
    let p = e.ci95.and_then(|half| {
        let se = half / t_975(n - 1);
        if se == 0.0 {
            return Some(if e.mean == 0.0 { 1.0 } else { 0.0 });
        }
        let t = StudentsT::new(0.0, 1.0, (n - 1) as f64).ok()?;
        Some(2.0 * t.sf((e.mean / se).abs()))
    });
    Some(PairedT {
        n,
        mean: e.mean,
        half: e.ci95,
        p,
    })
}

/// The rows of `table`, as read.
pub(super) fn records(table: &Table) -> Vec<csv::StringRecord> {
    table.rows.iter().map(|r| r.fields.clone()).collect()
}
