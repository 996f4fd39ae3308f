//! Resume state and collection: which cells of a campaign directory are finished, and the
//! gathering of their per-episode files into the directory's collected [`Results`].
//!
//! A cell is finished exactly when its files are whole and are this campaign's: `episode.csv`
//! (the worker writes it last, through a rename) holds the one row of this cell with the
//! campaign's steps, `vehicles.csv` has a row per scheduled vehicle, `timing.csv` its row, and
//! the cell's `settings.toml` records the very settings the campaign would run it with. So a
//! killed campaign never counts a half-written cell as done, a re-run never runs a finished one
//! again, and a damaged, foreign or edited cell is run again, with the reason printed.

use std::path::{Path, PathBuf};

use super::comparison::results_settings;
use super::grid::{Cell, Grid};
use super::results::{self, episodes_header, Results, ResultsError};
use super::settings::Settings;
use super::table::{key, Row, CELL_COLUMNS};
use super::worker::{DONE_FILE, ERROR_FILE, SETTINGS_RECORD};
use crate::episode::output::{TIMING_COLUMNS, VEHICLE_COLUMNS};

/// Directory of the per-episode files below a campaign directory.
pub const EPISODES_DIR: &str = "episodes";

/// A cell's directory: `<out>/episodes/<planner>/a<α>_l<λ>_s<seed>`.
pub fn cell_dir(out: &Path, cell: &Cell) -> PathBuf {
    out.join(EPISODES_DIR).join(cell.dir_name())
}

/// Has this cell's episode finished, as the campaign `settings` would run it?
pub fn is_done(out: &Path, settings: &Settings, cell: &Cell) -> bool {
    matches!(cell_state(out, settings, cell), CellState::Done(_))
}

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

/// Where a cell stands.
#[derive(Debug, Clone, PartialEq)]
pub enum CellState {
    /// Finished, with its files.
    Done(Finished),
    /// No `episode.csv`: not run, or stopped before it was written.
    NotRun,
    /// An `episode.csv` is there but the cell is not finished as this campaign's: why.
    Stale(String),
}

/// Where `cell` of the campaign `settings` stands in `out`.
pub fn cell_state(out: &Path, settings: &Settings, cell: &Cell) -> CellState {
    let dir = cell_dir(out, cell);
    if !dir.join(DONE_FILE).exists() {
        return CellState::NotRun;
    }
    match finished_row(&dir, settings, cell) {
        Ok(row) => CellState::Done(row),
        Err(why) => CellState::Stale(why),
    }
}

/// The files of `cell` in `dir` if they are whole and this campaign's; otherwise what is
/// wrong.
fn finished_row(dir: &Path, settings: &Settings, cell: &Cell) -> Result<Finished, String> {
    let header = episodes_header();
    let rows = results::read_records(&dir.join(DONE_FILE), &header).map_err(|e| e.to_string())?;
    let [row] = rows.as_slice() else {
        return Err(format!("{DONE_FILE} holds {} rows, not 1", rows.len()));
    };
    if results::cell_of(row).map(|c| key(&c)) != Ok(key(cell)) {
        return Err(format!("{DONE_FILE} belongs to another cell"));
    }
    let column = |name: &str| {
        let i = header.iter().position(|c| c == name);
        i.and_then(|i| row.get(i)).unwrap_or("").to_string()
    };
    let steps = settings.config.scenario.steps.to_string();
    if column("steps") != steps {
        let found = column("steps");
        return Err(format!(
            "{DONE_FILE} has steps {found}, the campaign {steps}"
        ));
    }
    let version = crate::sumo::version::BUILT;
    if column("sumo_version") != version {
        let found = column("sumo_version");
        return Err(format!("SUMO {found} ran it, this is SUMO {version}"));
    }
    let vehicles = rows_counted(dir, "vehicles.csv", &VEHICLE_COLUMNS, &column("scheduled"))?;
    let timing = rows_counted(dir, "timing.csv", &TIMING_COLUMNS, "1")?;
    let recorded = crate::io::bounded::read_text(
        &dir.join(SETTINGS_RECORD),
        crate::io::bounded::FileKind::Config,
    )
    .map_err(|_| format!("{SETTINGS_RECORD} is missing or unreadable"))?;
    if recorded != results_settings(&settings.episode_config(cell)) {
        return Err(format!("{SETTINGS_RECORD} records other settings"));
    }
    Ok(Finished {
        row: row.clone(),
        vehicles,
        timing,
    })
}

/// The rows of the cell's `name`, read with `cols`, if there are `expected` of them.
fn rows_counted(
    dir: &Path,
    name: &str,
    cols: &[&str],
    expected: &str,
) -> Result<Vec<csv::StringRecord>, String> {
    let rows = results::read_records(&dir.join(name), &strings(cols)).map_err(|e| e.to_string())?;
    if rows.len().to_string() != expected {
        return Err(format!("{name} has {} rows, not {expected}", rows.len()));
    }
    Ok(rows)
}

/// The episodes `out`'s `episodes.csv` records that a collection for `grid` would leave out:
/// cells outside the grid (an earlier, larger grid; episodes merged in by `bkpbs report`).
/// Cells of the grid are run again if they are not finished on disk, so none of them is lost.
/// An unreadable `episodes.csv` records nothing.
pub fn recorded_outside(out: &Path, grid: &Grid) -> Vec<Cell> {
    let Ok(rows) = results::read_records(&out.join("episodes.csv"), &episodes_header()) else {
        return Vec::new();
    };
    let in_grid: std::collections::HashSet<_> = grid.cells().iter().map(key).collect();
    rows.iter()
        .filter_map(|row| results::cell_of(row).ok())
        .filter(|c| !in_grid.contains(&key(c)))
        .collect()
}

fn strings(cols: &[&str]) -> Vec<String> {
    cols.iter().map(|s| s.to_string()).collect()
}

/// Gathers every finished cell of the campaign `settings` found in `out` (whichever shard ran
/// it) in grid order, and lists as failures the unfinished cells of its shard, with the
/// message of their `error.txt`.
pub fn collect(out: &Path, settings: &Settings) -> Result<Results, ResultsError> {
    let (grid, shard) = (&settings.grid, settings.shard);
    let mut res = Results {
        planners: grid.planners.clone(),
        profiles: grid.profiles.clone(),
        ..Results::default()
    };
    for (position, cell) in grid.cells().into_iter().enumerate() {
        let dir = cell_dir(out, &cell);
        if let CellState::Done(done) = cell_state(out, settings, &cell) {
            // The cell columns exactly as the episode wrote them.
            let lead: Vec<&str> = done.row.iter().take(CELL_COLUMNS.len()).collect();
            res.episodes.rows.push(Row {
                cell: cell.clone(),
                fields: done.row.clone(),
            });
            for (records, table) in [
                (&done.vehicles, &mut res.vehicles),
                (&done.timing, &mut res.timings),
            ] {
                for rec in records {
                    let mut fields = csv::StringRecord::from(lead.clone());
                    fields.extend(rec.iter());
                    table.rows.push(Row {
                        cell: cell.clone(),
                        fields,
                    });
                }
            }
        } else if shard.contains(position) {
            let error = crate::io::bounded::read_text(
                &dir.join(ERROR_FILE),
                crate::io::bounded::FileKind::Data,
            )
            .map(|s| s.trim().to_string())
            .unwrap_or_else(|_| "not run".into());
            let mut fields = csv::StringRecord::new();
            fields.push_field(&cell.planner);
            fields.push_field(&cell.alpha.to_string());
            fields.push_field(&cell.lambda.to_string());
            fields.push_field(&cell.seed.to_string());
            fields.push_field(&cell.hdv_profile);
            fields.push_field(&error);
            res.failures.rows.push(Row { cell, fields });
        }
    }
    Ok(res)
}
