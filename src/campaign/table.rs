//! One collected CSV file in memory: a header and rows, each row led by the cell it belongs to
//! (on the paper's demand planner, α, λ, seed, HDV profile; over scenarios scenario, planner,
//! α, seed). Apart from the reading and merging of results
//! ([`super::results`]) so that the checks of the rows ([`super::validate`]) can use it without
//! the two importing each other.

use std::path::PathBuf;

use super::grid::{file_name_of, Cell};
use crate::config::hdv::DEFAULT_PROFILE;

/// The columns that name a cell on the paper's demand; every collected file starts with them
/// (and an episode's own `episode.csv`), with [`PREDICTOR_COLUMN`] after the planner on a grid
/// with that axis (as in every file of a campaign over scenarios with it).
pub const CELL_COLUMNS: [&str; 5] = ["planner", "alpha", "lambda", "seed", "hdv_profile"];

/// The lead column of the predictor axis (`--predictors`).
pub const PREDICTOR_COLUMN: &str = "predictor";

/// The columns that name a cell of a campaign over scenarios of the user's own in its led
/// collected files (`vehicles.csv`, `timings.csv`); its episodes', regions' and entries' rows
/// name them already, among their own columns.
pub const SCENARIO_CELL_COLUMNS: [&str; 4] = ["scenario", "planner", "alpha", "seed"];

/// Every column that can name a cell, whatever the campaign's axes.
pub const ANY_CELL_COLUMN: [&str; 7] = [
    "planner",
    PREDICTOR_COLUMN,
    "alpha",
    "lambda",
    "seed",
    "hdv_profile",
    "scenario",
];

/// The lead columns of a scenario campaign's `failures.csv` (before `error`).
const SCENARIO_FAILURE_COLUMNS: [&str; 4] = ["planner", "scenario", "alpha", "seed"];

/// Which axes beyond the paper grid's a campaign's collected files name in their lead columns;
/// a grid without them keeps the columns (and directory names) it always had.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Axes {
    /// The predictor axis: a `predictor` column after `planner`.
    pub predictor: bool,
    /// The scenario axis (a campaign over scenarios of the user's own): the cell is named by
    /// [`SCENARIO_CELL_COLUMNS`] (no λ, no HDV profile).
    pub scenario: bool,
}

impl Axes {
    /// The axes of a collected `episodes.csv` with `header`.
    pub fn of_header(header: &[String]) -> Axes {
        Axes {
            predictor: header.iter().any(|c| c == PREDICTOR_COLUMN),
            scenario: header.first().is_some_and(|c| c == "scenario"),
        }
    }

    /// `columns` (an episode's own, led by the cell columns) with these axes' lead columns.
    pub fn header<S: AsRef<str>>(self, columns: &[S]) -> Vec<String> {
        let mut out: Vec<String> = columns.iter().map(|c| c.as_ref().to_string()).collect();
        if self.predictor {
            out.insert(predictor_at(columns), PREDICTOR_COLUMN.to_string());
        }
        out
    }

    /// `fields` (a row of an episode's own file whose columns are, or begin with, `columns`)
    /// with `cell`'s values of these axes.
    pub fn row<'a, S: AsRef<str>>(
        self,
        cell: &Cell,
        columns: &[S],
        fields: impl IntoIterator<Item = &'a str>,
    ) -> csv::StringRecord {
        let mut fields: Vec<&str> = fields.into_iter().collect();
        if self.predictor {
            let predictor = cell.predictor.as_deref().unwrap_or("");
            fields.insert(predictor_at(columns), predictor);
        }
        csv::StringRecord::from(fields)
    }

    /// The columns that lead a row of `vehicles.csv` and `timings.csv`, naming its cell.
    pub fn lead(self) -> Vec<String> {
        match self.scenario {
            true => self.header(&SCENARIO_CELL_COLUMNS),
            false => self.header(&CELL_COLUMNS),
        }
    }

    /// The columns that lead a row of `failures.csv` (before its `error`).
    pub fn failure_lead(self) -> Vec<String> {
        match self.scenario {
            true => self.header(&SCENARIO_FAILURE_COLUMNS),
            false => self.lead(),
        }
    }

    /// The values of `columns` (cell columns, as in [`Axes::lead`]) for `cell`, as the
    /// episodes write them.
    pub fn values(cell: &Cell, columns: &[String]) -> Vec<String> {
        columns.iter().map(|c| cell_value(cell, c)).collect()
    }
}

/// Where the predictor column goes among an episode's own `columns`: right after `planner`.
fn predictor_at<S: AsRef<str>>(columns: &[S]) -> usize {
    let planner = columns.iter().position(|c| c.as_ref() == "planner");
    planner.map_or(1, |i| i + 1)
}

/// The value of the cell column `column` for `cell`, as the episodes write it: α and λ in
/// Rust's shortest round-trip form, the scenario by its configuration's file name.
fn cell_value(cell: &Cell, column: &str) -> String {
    match column {
        "planner" => cell.planner.clone(),
        "alpha" => cell.alpha.to_string(),
        "lambda" => cell.lambda.to_string(),
        "seed" => cell.seed.to_string(),
        "hdv_profile" => cell.hdv_profile.clone(),
        PREDICTOR_COLUMN => cell.predictor.clone().unwrap_or_default(),
        "scenario" => cell
            .scenario
            .as_deref()
            .map(file_name_of)
            .unwrap_or_default(),
        _ => String::new(),
    }
}

/// The cell a row of a file with `header` names: its cell columns found by name (a file
/// without λ or HDV profile, a scenario's, has 0 and the default drivers); the offending text
/// if a value does not parse.
pub fn cell_of(header: &[String], fields: &csv::StringRecord) -> Result<Cell, String> {
    let get = |name: &str| {
        let i = header.iter().position(|c| c == name)?;
        Some(fields.get(i).unwrap_or(""))
    };
    let num = |name: &str| match get(name) {
        None => Ok(0.0),
        Some(v) => v.parse::<f64>().map_err(|_| v.to_string()),
    };
    let seed = get("seed").unwrap_or("");
    Ok(Cell {
        planner: get("planner").unwrap_or("").to_string(),
        alpha: num("alpha")?,
        lambda: num("lambda")?,
        seed: seed.parse().map_err(|_| seed.to_string())?,
        hdv_profile: get("hdv_profile").unwrap_or(DEFAULT_PROFILE).to_string(),
        predictor: get(PREDICTOR_COLUMN).map(String::from),
        scenario: get("scenario").map(PathBuf::from),
    })
}

/// One CSV row and the cell it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The cell the row's leading columns name.
    pub cell: Cell,
    /// The whole row, cell columns included.
    pub fields: csv::StringRecord,
}

/// One collected file: its header and rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Column names, cell columns first.
    pub header: Vec<String>,
    /// The rows, in file (for collected files: grid) order.
    pub rows: Vec<Row>,
}

impl Table {
    /// An empty table with `header`.
    pub fn new(header: Vec<String>) -> Table {
        Table {
            header,
            rows: Vec::new(),
        }
    }

    /// Index of a column, if present.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The table as CSV bytes, header first.
    pub fn to_csv(&self) -> Vec<u8> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&self.header).expect("writing to memory");
        for r in &self.rows {
            w.write_record(&r.fields).expect("writing to memory");
        }
        w.into_inner().expect("writing to memory")
    }
}

/// Identity of a cell for lookups: planner, α and λ (by value), seed, HDV profile,
/// predictor, scenario (by its configuration's file name, as the rows name it).
pub type CellKey = (
    String,
    u64,
    u64,
    u64,
    String,
    Option<String>,
    Option<String>,
);

/// Identity of a cell for lookups (α and λ by value).
pub fn key(c: &Cell) -> CellKey {
    (
        c.planner.clone(),
        c.alpha.to_bits(),
        c.lambda.to_bits(),
        c.seed,
        c.hdv_profile.clone(),
        c.predictor.clone(),
        c.scenario.as_deref().map(file_name_of),
    )
}
