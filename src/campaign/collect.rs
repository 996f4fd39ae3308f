//! Resume state and collection: which cells of a campaign directory are finished, and the
//! gathering of their per-episode files into the directory's collected [`Results`].
//!
//! A cell is finished exactly when its files are whole and are this campaign's: `episode.csv`
//! (the worker writes it last, through a rename) holds the one row of this cell with the
//! campaign's steps, `vehicles.csv` has a row per scheduled vehicle, `timing.csv` its row, and
//! the cell's `settings.toml` records the very settings the campaign would run it with. So a
//! killed campaign never counts a half-written cell as done, a re-run never runs a finished one
//! again, and a damaged, foreign or edited cell is run again, with the reason printed.

use std::path::Path;

pub use super::cell::{cell_dir, EPISODES_DIR};
use super::cell::{
    check_run, check_settings_record, column_value, episode_row, failure_of, rows_counted,
    CellState,
};
use super::grid::{Cell, Grid};
use super::provenance::check_provenance;
use super::results::{self, episodes_header, Results, ResultsError};
use super::settings::Settings;
use super::table::{key, Axes, Row, CELL_COLUMNS};
use super::worker::DONE_FILE;
use crate::episode::rows::{TimingRow, VehicleRow};

/// A finished cell's files as read by the check, for the collection to gather.
#[derive(Debug, Clone, PartialEq)]
pub struct Finished {
    /// Its `episode.csv` row.
    pub row: csv::StringRecord,
    /// Its `vehicles.csv` rows.
    pub vehicles: Vec<csv::StringRecord>,
    /// Its `timing.csv` row.
    pub timing: Vec<csv::StringRecord>,
}

/// Where `cell` of the campaign `settings` stands in `out`.
pub fn cell_state(out: &Path, settings: &Settings, cell: &Cell) -> CellState<Finished> {
    CellState::of(&cell_dir(out, cell), |dir| {
        finished_row(dir, settings, cell)
    })
}

/// The files of `cell` in `dir` if they are whole and this campaign's; otherwise what is
/// wrong.
fn finished_row(dir: &Path, settings: &Settings, cell: &Cell) -> Result<Finished, String> {
    // An episode's own row names no predictor: its settings record below does.
    let header = episodes_header(Axes::default());
    let row = episode_row(dir, &header)?;
    let own = Cell {
        predictor: None,
        ..cell.clone()
    };
    if results::cell_of(Axes::default(), &row).map(|c| key(&c)) != Ok(key(&own)) {
        return Err(format!("{DONE_FILE} belongs to another cell"));
    }
    let column = |name: &str| column_value(&header, &row, name);
    check_run(column, settings.config.scenario.steps)?;
    let vehicles = rows_counted(
        dir,
        "vehicles.csv",
        &strings(VehicleRow::columns()),
        column("scheduled"),
    )?;
    let timing = rows_counted(dir, "timing.csv", &strings(TimingRow::columns()), 1)?;
    let config = settings.episode_config(cell);
    check_settings_record(dir, &config)?;
    check_provenance(dir, &config)?;
    Ok(Finished {
        row,
        vehicles,
        timing,
    })
}

/// The episodes `out`'s `episodes.csv` records that a collection for `grid` would leave out:
/// cells outside the grid (an earlier, larger grid; episodes merged in by `bkpbs report`).
/// Cells of the grid are run again if they are not finished on disk, so none of them is lost.
/// An unreadable `episodes.csv` records nothing.
pub fn recorded_outside(out: &Path, grid: &Grid) -> Vec<Cell> {
    let axes = axes_of(grid);
    let Ok(rows) = results::read_records(&out.join("episodes.csv"), &episodes_header(axes)) else {
        return Vec::new();
    };
    let in_grid: std::collections::HashSet<_> = grid.cells().iter().map(key).collect();
    rows.iter()
        .filter_map(|row| results::cell_of(axes, row).ok())
        .filter(|c| !in_grid.contains(&key(c)))
        .collect()
}

/// The optional axes of `grid`'s collected files.
pub fn axes_of(grid: &Grid) -> Axes {
    Axes {
        predictor: grid.has_predictor_axis(),
    }
}

/// Column names as owned strings (a header to compare a file's with).
pub(crate) fn strings(cols: &[&str]) -> Vec<String> {
    cols.iter().map(|s| s.to_string()).collect()
}

/// Gathers every finished cell of the campaign `settings` found in `out` (whichever shard ran
/// it) in grid order, and lists as failures the unfinished cells of its shard, with the
/// message of their `error.txt`.
pub fn collect(out: &Path, settings: &Settings) -> Result<Results, ResultsError> {
    let (grid, shard) = (&settings.grid, settings.shard);
    let axes = axes_of(grid);
    let mut res = Results {
        planners: grid.planners.clone(),
        profiles: grid.profiles.clone(),
        predictors: grid.predictors.iter().flatten().cloned().collect(),
        ..Results::empty(axes)
    };
    for (position, cell) in grid.cells().into_iter().enumerate() {
        if let CellState::Done(done) = cell_state(out, settings, &cell) {
            gather(&mut res, axes, &cell, &done);
        } else if shard.contains(position) {
            let error = failure_of(&cell_dir(out, &cell));
            let (alpha, lambda, seed) = (
                cell.alpha.to_string(),
                cell.lambda.to_string(),
                cell.seed.to_string(),
            );
            let lead = [&*cell.planner, &alpha, &lambda, &seed, &cell.hdv_profile];
            let fields = axes.row(&cell, lead.into_iter().chain([error.as_str()]));
            res.failures.rows.push(Row { cell, fields });
        }
    }
    Ok(res)
}

/// Adds a finished cell's rows to the collected files, each led by the cell columns exactly as
/// the episode wrote them (and the cell's values of the optional `axes`).
fn gather(res: &mut Results, axes: Axes, cell: &Cell, done: &Finished) {
    let lead: Vec<&str> = done.row.iter().take(CELL_COLUMNS.len()).collect();
    res.episodes.rows.push(Row {
        cell: cell.clone(),
        fields: axes.row(cell, done.row.iter()),
    });
    for (records, table) in [
        (&done.vehicles, &mut res.vehicles),
        (&done.timing, &mut res.timings),
    ] {
        for rec in records {
            table.rows.push(Row {
                cell: cell.clone(),
                fields: axes.row(cell, lead.iter().copied().chain(rec.iter())),
            });
        }
    }
}
