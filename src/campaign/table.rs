//! One collected CSV file in memory: a header and rows, each row led by the cell (planner, α,
//! λ, seed, HDV profile) it belongs to. Apart from the reading and merging of results
//! ([`super::results`]) so that the checks of the rows ([`super::validate`]) can use it without
//! the two importing each other.

use super::grid::Cell;

/// The columns that name a cell; every collected file starts with them (and an episode's own
/// `episode.csv`), with [`PREDICTOR_COLUMN`] after the planner on a grid with that axis.
pub const CELL_COLUMNS: [&str; 5] = ["planner", "alpha", "lambda", "seed", "hdv_profile"];

/// The lead column of the predictor axis (`--predictors`).
pub const PREDICTOR_COLUMN: &str = "predictor";

/// Which optional axes a campaign's collected files name in their lead columns; a grid without
/// them keeps the columns (and directory names) it always had.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Axes {
    /// The predictor axis: a `predictor` column after `planner`.
    pub predictor: bool,
}

impl Axes {
    /// The axes of a file with `header`.
    pub fn of_header(header: &[String]) -> Axes {
        Axes {
            predictor: header.get(1).is_some_and(|c| c == PREDICTOR_COLUMN),
        }
    }

    /// `columns` (led by [`CELL_COLUMNS`], as an episode writes them) with these axes' lead
    /// columns.
    pub fn header(self, columns: &[&str]) -> Vec<String> {
        let mut out: Vec<String> = columns.iter().map(|c| c.to_string()).collect();
        if self.predictor {
            out.insert(1, PREDICTOR_COLUMN.to_string());
        }
        out
    }

    /// `fields` (led by the [`CELL_COLUMNS`] values) with `cell`'s values of these axes.
    pub fn row<'a>(
        self,
        cell: &Cell,
        fields: impl IntoIterator<Item = &'a str>,
    ) -> csv::StringRecord {
        let mut fields: Vec<&str> = fields.into_iter().collect();
        if self.predictor {
            fields.insert(1, cell.predictor.as_deref().unwrap_or(""));
        }
        csv::StringRecord::from(fields)
    }

    /// How many lead columns name the cell.
    pub fn lead_len(self) -> usize {
        CELL_COLUMNS.len() + usize::from(self.predictor)
    }
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
/// predictor.
pub type CellKey = (String, u64, u64, u64, String, Option<String>);

/// Identity of a cell for lookups (α and λ by value).
pub fn key(c: &Cell) -> CellKey {
    (
        c.planner.clone(),
        c.alpha.to_bits(),
        c.lambda.to_bits(),
        c.seed,
        c.hdv_profile.clone(),
        c.predictor.clone(),
    )
}
