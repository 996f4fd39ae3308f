//! Resume state and collection: which cells of a campaign directory are finished, and the
//! gathering of their per-episode files into the directory's collected [`Results`].
//!
//! A cell is finished exactly when its `episode.csv` exists (the worker writes it last, through
//! a rename), so a killed campaign never counts a half-written cell as done, and a re-run never
//! runs a finished one again.

use std::path::{Path, PathBuf};

use super::grid::{Cell, Grid, Shard};
use super::results::{self, episodes_header, Results, ResultsError};
use super::table::{key, Row, CELL_COLUMNS};
use super::worker::{DONE_FILE, ERROR_FILE};
use crate::episode::output::{TIMING_COLUMNS, VEHICLE_COLUMNS};

/// Directory of the per-episode files below a campaign directory.
pub const EPISODES_DIR: &str = "episodes";

/// A cell's directory: `<out>/episodes/<planner>/a<α>_l<λ>_s<seed>`.
pub fn cell_dir(out: &Path, cell: &Cell) -> PathBuf {
    out.join(EPISODES_DIR).join(cell.dir_name())
}

/// Has this cell's episode finished: its `episode.csv` exists and holds the one row of this
/// cell? A corrupt or foreign one does not count, so the cell is run again.
pub fn is_done(out: &Path, cell: &Cell) -> bool {
    finished_row(&cell_dir(out, cell), cell).is_some()
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

/// The row of `cell`'s `episode.csv` in `dir`, if the file holds exactly that.
fn finished_row(dir: &Path, cell: &Cell) -> Option<csv::StringRecord> {
    let rows = results::read_records(&dir.join(DONE_FILE), &episodes_header()).ok()?;
    let [row] = rows.as_slice() else {
        return None;
    };
    (results::cell_of(row).map(|c| key(&c)) == Ok(key(cell))).then(|| row.clone())
}

fn strings(cols: &[&str]) -> Vec<String> {
    cols.iter().map(|s| s.to_string()).collect()
}

/// Gathers every finished cell of `grid` found in `out` (whichever shard ran it) in grid order,
/// and lists as failures the unfinished cells of `shard`, with the message of their
/// `error.txt`.
pub fn collect(out: &Path, grid: &Grid, shard: Shard) -> Result<Results, ResultsError> {
    let mut res = Results {
        planners: grid.planners.clone(),
        profiles: grid.profiles.clone(),
        ..Results::default()
    };
    for (position, cell) in grid.cells().into_iter().enumerate() {
        let dir = cell_dir(out, &cell);
        if let Some(row) = finished_row(&dir, &cell) {
            let row = &row;
            // The cell columns exactly as the episode wrote them.
            let lead: Vec<&str> = row.iter().take(CELL_COLUMNS.len()).collect();
            res.episodes.rows.push(Row {
                cell: cell.clone(),
                fields: row.clone(),
            });
            for (name, cols, table) in [
                ("vehicles.csv", &VEHICLE_COLUMNS[..], &mut res.vehicles),
                ("timing.csv", &TIMING_COLUMNS[..], &mut res.timings),
            ] {
                for rec in results::read_records(&dir.join(name), &strings(cols))? {
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
