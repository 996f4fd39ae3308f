//! Per-(planner, α, λ) statistics over seeds, computed from a campaign's `episodes.csv` rows.

use std::path::{Path, PathBuf};

use super::stats::Estimate;
use crate::campaign::grid::Cell;
use crate::campaign::results::Results;
use crate::campaign::table::Table;

/// A column missing from, or a value unreadable in, `episodes.csv`.
#[derive(Debug, thiserror::Error)]
pub enum SummaryError {
    /// A column the summary averages is missing.
    #[error("{path}: no column '{column}'")]
    Column {
        /// The file (`episodes.csv`).
        path: PathBuf,
        /// The missing column.
        column: &'static str,
    },
    /// A field of an averaged column is neither empty nor a number.
    #[error("{path}: cell {cell}: '{value}' in column {column} is not a number")]
    Value {
        /// The file (`episodes.csv`).
        path: PathBuf,
        /// The grid cell (episode) of the row.
        cell: String,
        /// The column.
        column: &'static str,
        /// The field's text.
        value: String,
    },
}

/// Statistics of the seeds of one (planner, α, λ).
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// The planner, with its HDV profile in brackets when the results hold several profiles
    /// (`bk-pbs (paper)`).
    pub planner: String,
    /// CAV penetration α (probability that an inserted vehicle is a CAV).
    pub alpha: f64,
    /// Total arrival rate λ (veh/h).
    pub lambda: f64,
    /// Episodes (seeds) found.
    pub episodes: usize,
    /// System delay (s): per episode the mean over every vehicle not crashed, arrived or not.
    pub system_delay: Option<Estimate>,
    /// The part of the system delay no controller can remove (s): own desired speeds.
    pub own_speed_delay: Option<Estimate>,
    /// The paper's mean travel delay (s) of the vehicles that arrived, over the episodes that
    /// had arrivals.
    pub delay: Option<Estimate>,
    /// Controllable collision rate (a fraction of inserted vehicles).
    pub collision_rate: Option<Estimate>,
    /// Throughput (veh/h).
    pub throughput: Option<Estimate>,
    /// Mean speed of the vehicles in the network (m/s).
    pub mean_speed: Option<Estimate>,
    /// Vehicles standing on the acceleration lane at the end.
    pub stranded: Option<Estimate>,
    /// Vehicles scheduled but never inserted.
    pub never_inserted: Option<Estimate>,
    /// The episodes' values behind the estimates, in seed order: what a figure draws instead of
    /// an interval when the seeds are too few for one to mean much.
    pub samples: Samples,
}

/// Each episode's value of the averaged columns, in seed order (empty fields left out).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Samples {
    /// System delay (s) of each episode.
    pub system_delay: Vec<f64>,
    /// Mean travel delay (s) of each episode with arrivals.
    pub delay: Vec<f64>,
    /// Controllable collision rate of each episode.
    pub collision_rate: Vec<f64>,
    /// Throughput (veh/h) of each episode.
    pub throughput: Vec<f64>,
    /// Mean speed (m/s) of each episode.
    pub mean_speed: Vec<f64>,
}

/// All groups of a campaign, in grid order, with the axes they span.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The planner labels (as in [`Group::planner`]) in grid order, those with a group only.
    pub planners: Vec<String>,
    /// The CAV penetrations α found, ascending.
    pub alphas: Vec<f64>,
    /// The arrival rates λ found (veh/h), ascending.
    pub lambdas: Vec<f64>,
    /// One group per (planner, α, λ) with at least one episode, in grid order.
    pub groups: Vec<Group>,
    /// The largest number of seeds of any group: what a complete group has.
    pub seeds: usize,
}

fn column(t: &Table, path: &Path, name: &'static str) -> Result<usize, SummaryError> {
    t.column(name).ok_or_else(|| SummaryError::Column {
        path: path.to_path_buf(),
        column: name,
    })
}

/// The `episodes.csv` columns (of [`crate::episode::summary::Summary::columns`]) averaged per
/// group, in the order of [`Group`]'s estimates.
const SAMPLED: [&str; N] = [
    "system_delay_s",
    "own_speed_delay_s",
    "mean_delay_s",
    "controllable_collision_rate",
    "throughput_veh_h",
    "mean_speed_mps",
    "stranded",
    "never_inserted",
];
/// How many columns are averaged.
const N: usize = 8;

/// A row's values in the [`SAMPLED`] columns (at `columns`); empty fields are `None`.
fn sampled_values(
    row: &crate::campaign::table::Row,
    columns: &[usize; N],
    path: &Path,
) -> Result<[Option<f64>; N], SummaryError> {
    let mut out = [None; N];
    for ((slot, &i), name) in out.iter_mut().zip(columns).zip(SAMPLED) {
        let text = row.fields.get(i).unwrap_or("");
        if text.is_empty() {
            continue;
        }
        *slot = Some(text.parse().map_err(|_| SummaryError::Value {
            path: path.to_path_buf(),
            cell: row.cell.to_string(),
            column: name,
            value: text.to_string(),
        })?);
    }
    Ok(out)
}

/// Names a group's planner: with its HDV profile in brackets when the rows hold several.
struct Labels {
    several_profiles: bool,
}

impl Labels {
    fn of(t: &Table) -> Labels {
        let several_profiles = t
            .rows
            .iter()
            .any(|r| r.cell.hdv_profile != t.rows[0].cell.hdv_profile);
        Labels { several_profiles }
    }

    fn label(&self, planner: &str, profile: &str) -> String {
        match self.several_profiles {
            true => format!("{planner} ({profile})"),
            false => planner.to_string(),
        }
    }
}

/// A group being filled: its episodes so far and their [`SAMPLED`] values.
type Filling = (Group, [Vec<f64>; N]);

/// Adds one row's values to the last group, or starts a group when the row's (planner, α, λ)
/// differs from the last one's (the rows are sorted, so a group's rows are adjacent).
fn add_row(groups: &mut Vec<Filling>, name: String, c: &Cell, vals: [Option<f64>; N]) {
    let same = |g: &Group| g.planner == name && g.alpha == c.alpha && g.lambda == c.lambda;
    if !groups.last().is_some_and(|(g, _)| same(g)) {
        let group = Group {
            planner: name.clone(),
            alpha: c.alpha,
            lambda: c.lambda,
            episodes: 0,
            system_delay: None,
            own_speed_delay: None,
            delay: None,
            collision_rate: None,
            throughput: None,
            mean_speed: None,
            stranded: None,
            never_inserted: None,
            samples: Samples::default(),
        };
        groups.push((group, Default::default()));
    }
    let (g, samples) = groups.last_mut().expect("just pushed");
    g.episodes += 1;
    for (s, v) in samples.iter_mut().zip(vals) {
        s.extend(v);
    }
}

/// A filled group with its estimates.
fn estimated((mut g, [sd, own, d, r, tp, v, st, ni]): Filling) -> Group {
    g.system_delay = Estimate::of(&sd);
    g.own_speed_delay = Estimate::of(&own);
    g.stranded = Estimate::of(&st);
    g.never_inserted = Estimate::of(&ni);
    g.delay = Estimate::of(&d);
    g.collision_rate = Estimate::of(&r);
    g.throughput = Estimate::of(&tp);
    g.mean_speed = Estimate::of(&v);
    g.samples = Samples {
        system_delay: sd,
        delay: d,
        collision_rate: r,
        throughput: tp,
        mean_speed: v,
    };
    g
}

/// The distinct values of one axis of the rows, sorted.
fn axis(t: &Table, of: impl Fn(&Cell) -> f64) -> Vec<f64> {
    let mut values: Vec<f64> = Vec::new();
    for row in &t.rows {
        let x = of(&row.cell);
        if !values.contains(&x) {
            values.push(x);
        }
    }
    values.sort_by(f64::total_cmp);
    values
}

/// The planner labels in grid order (planner, then HDV profile), those with a group only.
fn planner_order(res: &Results, labels: &Labels, groups: &[Group]) -> Vec<String> {
    let mut seen: Vec<String> = Vec::new();
    for p in &res.planners {
        for h in &res.profiles {
            let name = labels.label(p, h);
            if groups.iter().any(|g| g.planner == name) && !seen.contains(&name) {
                seen.push(name);
            }
        }
    }
    seen
}

impl Summary {
    /// Groups the (sorted) episode rows; `path` names the file in errors.
    pub fn from_results(res: &Results, path: &Path) -> Result<Summary, SummaryError> {
        let t = &res.episodes;
        let mut columns = [0; N];
        for (slot, name) in columns.iter_mut().zip(SAMPLED) {
            *slot = column(t, path, name)?;
        }
        let labels = Labels::of(t);
        let mut groups: Vec<Filling> = Vec::new();
        for row in &t.rows {
            let vals = sampled_values(row, &columns, path)?;
            let name = labels.label(&row.cell.planner, &row.cell.hdv_profile);
            add_row(&mut groups, name, &row.cell, vals);
        }
        let groups: Vec<Group> = groups.into_iter().map(estimated).collect();
        Ok(Summary {
            planners: planner_order(res, &labels, &groups),
            alphas: axis(t, |c| c.alpha),
            lambdas: axis(t, |c| c.lambda),
            seeds: groups.iter().map(|g| g.episodes).max().unwrap_or(0),
            groups,
        })
    }

    /// The group of (planner, α, λ), if any episode of it finished.
    pub fn get(&self, planner: &str, alpha: f64, lambda: f64) -> Option<&Group> {
        self.groups
            .iter()
            .find(|g| g.planner == planner && g.alpha == alpha && g.lambda == lambda)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_columns_are_episode_summary_columns() {
        let columns =
            crate::episode::summary::Summary::columns(crate::episode::summary::Traffic::Demand);
        for name in SAMPLED {
            assert!(columns.contains(&name), "{name}");
        }
    }
}
