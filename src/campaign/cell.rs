//! A cell's files in a campaign directory, for every kind of campaign: where they lie, where
//! the cell stands, and the checks of a finished cell's files ([`super::collect`] puts them
//! together).

use std::fmt;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use super::comparison::{first_difference, results_settings};
use super::grid::Cell;
use super::results::read_records;
use super::worker::{DONE_FILE, ERROR_FILE, SETTINGS_RECORD};
use crate::config::Config;
use crate::io::bounded::{read_text, FileKind};

/// Directory of the per-episode files below a campaign directory.
pub const EPISODES_DIR: &str = "episodes";

/// A cell's directory: `<out>/episodes/` and its [`Cell::dir_name`].
pub fn cell_dir(out: &Path, cell: &Cell) -> PathBuf {
    out.join(EPISODES_DIR).join(cell.dir_name())
}

/// Where a cell stands; `F` is a finished cell's files as its campaign's check read them.
#[derive(Debug, Clone, PartialEq)]
pub enum CellState<F> {
    /// Finished, with its files.
    Done(F),
    /// No `episode.csv`: not run, or stopped before it was written.
    NotRun,
    /// An `episode.csv` is there but the cell is not finished as this campaign's: why.
    Stale(String),
}

impl<F> CellState<F> {
    /// The state without the finished cell's files.
    pub fn without_files(self) -> CellState<()> {
        match self {
            CellState::Done(_) => CellState::Done(()),
            CellState::NotRun => CellState::NotRun,
            CellState::Stale(why) => CellState::Stale(why),
        }
    }

    /// Where the cell whose files are in `dir` stands: not run without its `episode.csv`,
    /// otherwise as `finished` finds its files (the campaign's own checks), so that both kinds
    /// of campaign decide "not run" the same way.
    pub fn of(dir: &Path, finished: impl FnOnce(&Path) -> Result<F, String>) -> CellState<F> {
        if !dir.join(DONE_FILE).exists() {
            return CellState::NotRun;
        }
        match finished(dir) {
            Ok(files) => CellState::Done(files),
            Err(why) => CellState::Stale(why),
        }
    }
}

/// The one row of the cell's `episode.csv` in `dir`, read with `header`; otherwise what is
/// wrong.
pub fn episode_row(dir: &Path, header: &[String]) -> Result<csv::StringRecord, String> {
    let rows = read_records(&dir.join(DONE_FILE), header).map_err(|e| e.to_string())?;
    match <[csv::StringRecord; 1]>::try_from(rows) {
        Ok([row]) => Ok(row),
        Err(rows) => Err(format!("{DONE_FILE} holds {} rows, not 1", rows.len())),
    }
}

/// The value of column `name` in `row` (read with `header`); empty if there is none.
pub fn column_value(header: &[String], row: &csv::StringRecord, name: &str) -> String {
    let i = header.iter().position(|c| c == name);
    i.and_then(|i| row.get(i)).unwrap_or("").to_string()
}

/// Was the `episode.csv` row (its `column`s) run for the campaign's `steps` by this SUMO? A
/// cell of a shorter run or of another SUMO is not the campaign's.
pub fn check_run(column: impl Fn(&str) -> String, steps: u32) -> Result<(), String> {
    if column("steps") != steps.to_string() {
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
    Ok(())
}

/// The rows of the cell's file `name` in `dir`, read with `header`, if there are `expected` of
/// them; otherwise what is wrong. The count is compared as text, as `episode.csv` writes it
/// (an unreadable count is never met).
pub fn rows_counted(
    dir: &Path,
    name: &str,
    header: &[String],
    expected: impl fmt::Display,
) -> Result<Vec<csv::StringRecord>, String> {
    let expected = expected.to_string();
    rows_where(
        dir,
        (name, header),
        |n| n.to_string() == expected,
        &expected,
    )
}

/// The rows of the cell's file `name` in `dir`, read with `header`, if their number is within
/// `counts`; otherwise what is wrong.
pub fn rows_within(
    dir: &Path,
    name: &str,
    header: &[String],
    counts: RangeInclusive<usize>,
) -> Result<Vec<csv::StringRecord>, String> {
    let wanted = format!("{} to {}", counts.start(), counts.end());
    rows_where(dir, (name, header), |n| counts.contains(&n), &wanted)
}

/// The rows of file `name` (read with `header`) in `dir` if their number passes `fits`;
/// otherwise what is wrong, saying the `wanted` number.
fn rows_where(
    dir: &Path,
    (name, header): (&str, &[String]),
    fits: impl Fn(usize) -> bool,
    wanted: &str,
) -> Result<Vec<csv::StringRecord>, String> {
    let rows = read_records(&dir.join(name), header).map_err(|e| e.to_string())?;
    if !fits(rows.len()) {
        return Err(format!("{name} has {} rows, not {wanted}", rows.len()));
    }
    Ok(rows)
}

/// Does the cell's `settings.toml` in `dir` record `config`, the very settings the campaign
/// would run it with? An edited `campaign.toml` cannot pass off old episodes as its own.
pub fn check_settings_record(dir: &Path, config: &Config) -> Result<(), String> {
    let recorded = read_text(&dir.join(SETTINGS_RECORD), FileKind::Config)
        .map_err(|_| format!("{SETTINGS_RECORD} is missing or unreadable"))?;
    let expected = results_settings(config);
    if recorded == expected {
        return Ok(());
    }
    let parse = |text: &str| text.parse::<toml::Table>().map(toml::Value::Table).ok();
    let first = parse(&recorded)
        .zip(parse(&expected))
        .and_then(|(a, b)| first_difference(&a, &b, ""));
    Err(match first {
        Some(key) => match key.strip_prefix("scenario.sumocfg_digests.") {
            Some(file) => format!("its scenario's file '{file}' is not the one it ran with"),
            None => format!("{SETTINGS_RECORD} records other settings ({key} differs)"),
        },
        None => format!("{SETTINGS_RECORD} records other settings"),
    })
}

/// Why the unfinished cell in `dir` has no result, for `failures.csv`: its `error.txt`, or
/// `not run`.
pub fn failure_of(dir: &Path) -> String {
    read_text(&dir.join(ERROR_FILE), FileKind::Data)
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|_| "not run".into())
}
