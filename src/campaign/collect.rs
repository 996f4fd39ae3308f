//! Resume state and collection, for every kind of campaign: which cells of a campaign directory
//! are finished, and the gathering of their per-episode files into the directory's collected
//! [`Results`].
//!
//! A cell is finished exactly when its files are whole and are this campaign's: `episode.csv`
//! (the worker writes it last, through a rename) holds the one row of this cell with the
//! campaign's steps and this SUMO, `vehicles.csv` has the row per vehicle it announces (every
//! vehicle scheduled; over scenarios every vehicle inserted or never inserted), `timing.csv`
//! its row, over scenarios `regions.csv` a row per merge region and `entries.csv` a row per
//! region and entry (its main carriageway and each of its on-ramps), and the cell's
//! `settings.toml` records the very settings the campaign would run it with. So a killed
//! campaign never counts a half-written cell as done, a re-run never runs a finished one
//! again, and a damaged, foreign or edited cell is run again, with the reason printed (a cell
//! of an earlier bkpbs, without a file or with fewer columns, among them).

use std::ops::RangeInclusive;
use std::path::Path;

pub use super::cell::{cell_dir, EPISODES_DIR};
use super::cell::{
    check_run, check_settings_record, column_value, episode_row, failure_of, rows_counted,
    rows_within, CellState,
};
use super::grid::{Cell, Grid};
use super::provenance::check_provenance;
use super::results::{self, Results, ResultsError};
use super::settings::Settings;
use super::table::{cell_of, key, Axes, Row, Table};
use super::worker::DONE_FILE;

/// A finished cell's files as read by the check, for the collection to gather.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Finished {
    /// Its `episode.csv` row.
    pub row: csv::StringRecord,
    /// Its `vehicles.csv` rows.
    pub vehicles: Vec<csv::StringRecord>,
    /// Its `timing.csv` row.
    pub timing: Vec<csv::StringRecord>,
    /// Its `regions.csv` rows (over scenarios).
    pub regions: Vec<csv::StringRecord>,
    /// Its `entries.csv` rows (over scenarios).
    pub entries: Vec<csv::StringRecord>,
}

/// Where `cell` of the campaign `settings` stands in `out`.
pub fn cell_state(out: &Path, settings: &Settings, cell: &Cell) -> CellState<Finished> {
    CellState::of(&cell_dir(out, cell), |dir| finished(dir, settings, cell))
}

/// The axes an episode's own files name: its predictor is in its settings record, not in its
/// rows.
fn episode_axes(cell: &Cell) -> Axes {
    Axes {
        predictor: false,
        scenario: cell.scenario.is_some(),
    }
}

/// How many `vehicles.csv` rows the `episode.csv` row (its `column`s) announces: on the paper's
/// demand one per vehicle scheduled; over scenarios one per vehicle inserted and one per vehicle
/// never inserted. A count that is no number is never met.
fn vehicle_rows(axes: Axes, column: impl Fn(&str) -> String) -> String {
    if !axes.scenario {
        return column("scheduled");
    }
    let count = |name| column(name).parse::<usize>().ok();
    match (count("inserted"), count("never_inserted")) {
        (Some(a), Some(b)) => (a + b).to_string(),
        _ => "not a count".into(),
    }
}

/// How many `regions.csv` rows the `episode.csv` row's `regions` announces, one per region, and
/// how many `entries.csv` rows it allows: per region one for its main carriageway and at most
/// one per name its name lists (the edges its on-ramps join, one entry each, and those its lanes
/// drop on, none: a region of lane drops alone has its main entry only).
fn region_rows(regions: &str) -> (usize, RangeInclusive<usize>) {
    let names = || regions.split("; ").filter(|r| !r.is_empty());
    let most = names().map(|r| 1 + r.split(' ').count()).sum();
    (names().count(), names().count()..=most)
}

/// The files of `cell` in `dir` if they are whole and this campaign's; otherwise what is
/// wrong.
fn finished(dir: &Path, settings: &Settings, cell: &Cell) -> Result<Finished, String> {
    let axes = episode_axes(cell);
    let header = results::episodes_header(axes);
    let row = episode_row(dir, &header)?;
    let own = Cell {
        predictor: None,
        ..cell.clone()
    };
    if cell_of(&header, &row).map(|c| key(&c)) != Ok(key(&own)) {
        return Err(format!("{DONE_FILE} belongs to another cell"));
    }
    let column = |name: &str| column_value(&header, &row, name);
    let config = settings.episode_config(cell);
    check_run(column, config.scenario.steps)?;
    // The episode's own files: the collected header without the cell columns.
    let lead = axes.lead().len();
    let own = |collected: Vec<String>| collected[lead..].to_vec();
    let vehicles = vehicle_rows(axes, column);
    let vehicles = rows_counted(
        dir,
        "vehicles.csv",
        &own(results::vehicles_header(axes)),
        vehicles,
    )?;
    let timing = rows_counted(dir, "timing.csv", &own(results::timings_header(axes)), 1)?;
    let (mut regions, mut entries) = (Vec::new(), Vec::new());
    if axes.scenario {
        let (region_count, entry_counts) = region_rows(&column("regions"));
        let (region_columns, entry_columns) =
            (results::regions_header(axes), results::entries_header(axes));
        regions = rows_counted(dir, "regions.csv", &region_columns, region_count)?;
        entries = rows_within(dir, "entries.csv", &entry_columns, entry_counts)?;
    }
    check_settings_record(dir, &config)?;
    check_provenance(dir, &config)?;
    Ok(Finished {
        row,
        vehicles,
        timing,
        regions,
        entries,
    })
}

/// The episodes `out`'s `episodes.csv` records that a collection for `grid` would leave out:
/// cells outside the grid (an earlier, larger grid; episodes merged in by `bkpbs report`).
/// Cells of the grid are run again if they are not finished on disk, so none of them is lost.
/// An unreadable `episodes.csv` records nothing.
pub fn recorded_outside(out: &Path, grid: &Grid) -> Vec<Cell> {
    let header = results::episodes_header(axes_of(grid));
    let Ok(rows) = results::read_records(&out.join("episodes.csv"), &header) else {
        return Vec::new();
    };
    let in_grid: std::collections::HashSet<_> = grid.cells().iter().map(key).collect();
    rows.iter()
        .filter_map(|row| cell_of(&header, row).ok())
        .filter(|c| !in_grid.contains(&key(c)))
        .collect()
}

/// The axes of `grid`'s collected files.
pub fn axes_of(grid: &Grid) -> Axes {
    Axes {
        predictor: grid.has_predictor_axis(),
        scenario: !grid.scenarios.is_empty(),
    }
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
            gather(&mut res, &cell, &done);
        } else if shard.contains(position) {
            let error = failure_of(&cell_dir(out, &cell));
            let mut fields = Axes::values(&cell, &axes.failure_lead());
            fields.push(error);
            let fields = csv::StringRecord::from(fields);
            res.failures.rows.push(Row { cell, fields });
        }
    }
    Ok(res)
}

/// Adds a finished cell's rows to the collected files, each with the cell's values of the
/// campaign's axes: its episode row; its vehicle and timing rows, each led by the cell columns
/// exactly as the episode wrote them; its region and entry rows (which name their cell).
fn gather(res: &mut Results, cell: &Cell, done: &Finished) {
    let axes = res.axes;
    let own = episode_axes(cell);
    let header = results::episodes_header(own);
    let lead_columns = own.lead();
    let lead: Vec<String> = (lead_columns.iter())
        .map(|c| column_value(&header, &done.row, c))
        .collect();
    let push = |table: &mut Table, fields: csv::StringRecord| {
        let cell = cell.clone();
        table.rows.push(Row { cell, fields });
    };
    push(&mut res.episodes, axes.row(cell, &header, done.row.iter()));
    for (records, table) in [
        (&done.vehicles, &mut res.vehicles),
        (&done.timing, &mut res.timings),
    ] {
        for rec in records {
            let fields = lead.iter().map(String::as_str).chain(rec.iter());
            push(table, axes.row(cell, &lead_columns, fields));
        }
    }
    for (records, table, columns) in [
        (
            &done.regions,
            &mut res.regions,
            results::regions_header(own),
        ),
        (
            &done.entries,
            &mut res.entries,
            results::entries_header(own),
        ),
    ] {
        for rec in records {
            push(table, axes.row(cell, &columns, rec.iter()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A region's name lists the edges its on-ramps join and its lanes drop on: one entry row
    /// for its main carriageway and one per ramp, so at most one per name.
    #[test]
    fn the_regions_announce_their_entry_rows() {
        assert_eq!(region_rows(""), (0, 0..=0));
        assert_eq!(region_rows("gneE7"), (1, 1..=2));
        assert_eq!(region_rows("264308374; 4054057 4054058"), (2, 2..=2 + 3));
    }
}
