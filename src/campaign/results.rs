//! The collected results of a campaign directory: `episodes.csv`, `vehicles.csv`,
//! `timings.csv` and `failures.csv`, each row led by its cell (planner, alpha, lambda, seed),
//! in grid order. Read, merged across shard directories, and written atomically here.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::grid::Cell;
use super::table::{key, Axes, CellKey, Row, Table};
use crate::episode::output::{self, WriteError};
use crate::episode::rows::{TimingRow, VehicleRow};
use crate::episode::summary::{Summary, Traffic};

/// The collected files of a campaign directory.
pub const FILES: [&str; 4] = [
    "episodes.csv",
    "vehicles.csv",
    "timings.csv",
    "failures.csv",
];

/// Why collected results cannot be read or merged.
#[derive(Debug, thiserror::Error)]
pub enum ResultsError {
    /// A file could not be opened or is not valid CSV.
    #[error("cannot read {path}: {message}")]
    Read {
        /// The CSV file.
        path: PathBuf,
        /// The CSV reader's message.
        message: String,
    },
    /// A file's header is not the one this version writes.
    #[error("{path}: unexpected columns (written by another version of bkpbs?): {header}")]
    Columns {
        /// The CSV file.
        path: PathBuf,
        /// The header found, comma-separated.
        header: String,
    },
    /// A row's cell columns (planner, alpha, lambda, seed, hdv_profile) do not parse.
    #[error("{path}, line {line}: bad cell value '{value}'")]
    Cell {
        /// The CSV file.
        path: PathBuf,
        /// Line of the row in the file (1 is the header).
        line: u64,
        /// The value that does not parse.
        value: String,
    },
    /// Two merged directories hold the same cell with different rows.
    #[error("cell {cell} has different results in {first} and {second}")]
    Conflict {
        /// The cell, as it is displayed (`planner α=… λ=… seed=…`).
        cell: String,
        /// The file of the first directory holding it.
        first: PathBuf,
        /// The file of the later directory that disagrees.
        second: PathBuf,
    },
    /// Merged directories differ in their axes (one has the predictor axis, one not).
    #[error("{first} and {second} have different axes (one names a predictor per cell): report them apart")]
    Axes {
        /// The first directory's `episodes.csv`.
        first: PathBuf,
        /// The directory that differs.
        second: PathBuf,
    },
    /// A collected file could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// A row of a collected `episodes.csv` fails its checks (duplicate, value out of range).
    #[error(transparent)]
    Row(#[from] super::validate::RowError),
}

/// Header of `episodes.csv` (the episode columns already start with the cell).
pub fn episodes_header(axes: Axes) -> Vec<String> {
    axes.header(Summary::columns(Traffic::Demand))
}
/// Header of `vehicles.csv`.
pub fn vehicles_header(axes: Axes) -> Vec<String> {
    with_cell_columns(axes, VehicleRow::columns())
}
/// Header of `timings.csv`.
pub fn timings_header(axes: Axes) -> Vec<String> {
    with_cell_columns(axes, TimingRow::columns())
}
/// Header of `failures.csv`.
pub fn failures_header(axes: Axes) -> Vec<String> {
    with_cell_columns(axes, &["error"])
}

fn with_cell_columns(axes: Axes, rest: &[&str]) -> Vec<String> {
    let columns: Vec<&str> = super::table::CELL_COLUMNS
        .iter()
        .chain(rest)
        .copied()
        .collect();
    axes.header(&columns)
}

/// The four collected files of one directory (or of several, merged).
#[derive(Debug, Clone, PartialEq)]
pub struct Results {
    /// The optional axes the files' lead columns name.
    pub axes: Axes,
    /// Planner order of the grid (rows are sorted by it, then HDV profile, α, λ, seed).
    pub planners: Vec<String>,
    /// HDV profile order of the grid.
    pub profiles: Vec<String>,
    /// Predictor order of the grid (empty without the predictor axis).
    pub predictors: Vec<String>,
    /// `episodes.csv`: one summary row per finished episode.
    pub episodes: Table,
    /// `vehicles.csv`: one row per vehicle of every finished episode.
    pub vehicles: Table,
    /// `timings.csv`: one row of computation times (planning, SUMO, wall) per finished episode.
    pub timings: Table,
    /// `failures.csv`: one row per unfinished episode, with its error message.
    pub failures: Table,
}

impl Default for Results {
    fn default() -> Self {
        Results::empty(Axes::default())
    }
}

/// The cell columns of a row of a file with these `axes` as a [`Cell`]; the offending text if
/// a value does not parse.
pub fn cell_of(axes: Axes, fields: &csv::StringRecord) -> Result<Cell, String> {
    let skip = usize::from(axes.predictor);
    let get = |i: usize| fields.get(if i == 0 { 0 } else { i + skip }).unwrap_or("");
    let num = |i: usize| get(i).parse::<f64>().map_err(|_| get(i).to_string());
    Ok(Cell {
        planner: get(0).to_string(),
        alpha: num(1)?,
        lambda: num(2)?,
        seed: get(3).parse().map_err(|_| get(3).to_string())?,
        hdv_profile: get(4).to_string(),
        predictor: axes
            .predictor
            .then(|| fields.get(1).unwrap_or("").to_string()),
        scenario: None,
    })
}

/// The CSV file at `path` opened for reading (bounded), with its header.
fn open_csv(
    path: &Path,
) -> Result<(csv::Reader<crate::io::bounded::BoundedFile>, Vec<String>), ResultsError> {
    let mut r = csv::Reader::from_reader(
        crate::io::bounded::open(path, crate::io::bounded::FileKind::Data)
            .map_err(|e| read_error(path, e.into()))?,
    );
    let header = r.headers().map_err(|e| read_error(path, e))?;
    let header = header.iter().map(String::from).collect();
    Ok((r, header))
}

fn read_error(path: &Path, e: csv::Error) -> ResultsError {
    ResultsError::Read {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// The header of the CSV file at `path`.
pub fn header_of(path: &Path) -> Result<Vec<String>, ResultsError> {
    open_csv(path).map(|(_, header)| header)
}

/// Reads the records of a CSV file that must have exactly `header`.
pub fn read_records(
    path: &Path,
    header: &[String],
) -> Result<Vec<csv::StringRecord>, ResultsError> {
    let (mut r, found) = open_csv(path)?;
    if found != header {
        return Err(ResultsError::Columns {
            path: path.to_path_buf(),
            header: found.join(","),
        });
    }
    r.records()
        .map(|rec| rec.map_err(|e| read_error(path, e)))
        .collect()
}

/// Reads a collected CSV file that must have exactly `header` (starting with the cell columns
/// of `axes`).
pub fn read_table(path: &Path, axes: Axes, header: &[String]) -> Result<Table, ResultsError> {
    let mut table = Table::new(header.to_vec());
    for fields in read_records(path, header)? {
        let cell = cell_of(axes, &fields).map_err(|value| ResultsError::Cell {
            path: path.to_path_buf(),
            line: fields.position().map_or(0, |p| p.line()),
            value,
        })?;
        table.rows.push(Row { cell, fields });
    }
    Ok(table)
}

/// A table's rows grouped by cell, in file order within a cell.
fn rows_by_cell(table: &Table) -> HashMap<CellKey, Vec<&csv::StringRecord>> {
    let mut by_cell: HashMap<CellKey, Vec<&csv::StringRecord>> = HashMap::new();
    for r in &table.rows {
        by_cell.entry(key(&r.cell)).or_default().push(&r.fields);
    }
    by_cell
}

impl Results {
    /// Empty files whose lead columns name `axes`.
    pub fn empty(axes: Axes) -> Results {
        Results {
            axes,
            planners: Vec::new(),
            profiles: Vec::new(),
            predictors: Vec::new(),
            episodes: Table::new(episodes_header(axes)),
            vehicles: Table::new(vehicles_header(axes)),
            timings: Table::new(timings_header(axes)),
            failures: Table::new(failures_header(axes)),
        }
    }

    /// Reads a campaign directory's collected files; `failures.csv` and `timings.csv` may be
    /// missing. `planners` and `profiles` give the grid's order (those seen only in the rows
    /// follow in order of appearance). The axes are those `episodes.csv`'s header names.
    pub fn read(
        dir: &Path,
        planners: &[String],
        profiles: &[String],
    ) -> Result<Results, ResultsError> {
        let episodes_path = dir.join("episodes.csv");
        let axes = Axes::of_header(&header_of(&episodes_path)?);
        let episodes = read_table(&episodes_path, axes, &episodes_header(axes))?;
        super::validate::check_episodes(&episodes_path, axes, &episodes)?;
        let mut res = Results {
            planners: planners.to_vec(),
            profiles: profiles.to_vec(),
            episodes,
            vehicles: read_table(&dir.join("vehicles.csv"), axes, &vehicles_header(axes))?,
            ..Results::empty(axes)
        };
        for (name, table, header) in [
            ("timings.csv", &mut res.timings, timings_header(axes)),
            ("failures.csv", &mut res.failures, failures_header(axes)),
        ] {
            let p = dir.join(name);
            if p.exists() {
                *table = read_table(&p, axes, &header)?;
            }
        }
        res.note_order();
        Ok(res)
    }

    /// Appends the planners, profiles and predictors seen in the rows but not yet in the order.
    fn note_order(&mut self) {
        for t in [
            &self.episodes,
            &self.vehicles,
            &self.timings,
            &self.failures,
        ] {
            for r in &t.rows {
                if !self.planners.contains(&r.cell.planner) {
                    self.planners.push(r.cell.planner.clone());
                }
                if !self.profiles.contains(&r.cell.hdv_profile) {
                    self.profiles.push(r.cell.hdv_profile.clone());
                }
                if let Some(p) = &r.cell.predictor {
                    if !self.predictors.contains(p) {
                        self.predictors.push(p.clone());
                    }
                }
            }
        }
    }

    /// Sorts every table into grid order; rows of one cell keep their order.
    pub fn sort(&mut self) {
        self.note_order();
        let rank = |names: &[String]| -> HashMap<String, usize> {
            names
                .iter()
                .enumerate()
                .map(|(i, p)| (p.clone(), i))
                .collect()
        };
        let (planner_rank, profile_rank) = (rank(&self.planners), rank(&self.profiles));
        let predictor_rank = rank(&self.predictors);
        let predictor = |r: &Row| r.cell.predictor.as_ref().map(|p| predictor_rank[p]);
        let order = |a: &Row, b: &Row| {
            planner_rank[&a.cell.planner]
                .cmp(&planner_rank[&b.cell.planner])
                .then(predictor(a).cmp(&predictor(b)))
                .then(profile_rank[&a.cell.hdv_profile].cmp(&profile_rank[&b.cell.hdv_profile]))
                .then(a.cell.alpha.total_cmp(&b.cell.alpha))
                .then(a.cell.lambda.total_cmp(&b.cell.lambda))
                .then(a.cell.seed.cmp(&b.cell.seed))
        };
        for t in [
            &mut self.episodes,
            &mut self.vehicles,
            &mut self.timings,
            &mut self.failures,
        ] {
            t.rows.sort_by(order);
        }
    }

    /// Merges the results of several directories (shards). A cell present in more than one must
    /// have identical `episodes.csv` rows and identical `vehicles.csv` rows (it is then taken
    /// once, from the first directory); any difference is an error naming the file. Timings may
    /// differ (they are wall-clock). A failure is kept only for cells nobody finished.
    pub fn merge(parts: &[(PathBuf, Results)]) -> Result<Results, ResultsError> {
        let axes = parts.first().map(|(_, p)| p.axes).unwrap_or_default();
        if let Some((dir, _)) = parts.iter().find(|(_, p)| p.axes != axes) {
            return Err(ResultsError::Axes {
                first: parts[0].0.join("episodes.csv"),
                second: dir.join("episodes.csv"),
            });
        }
        let mut merged = Results::empty(axes);
        for (_, part) in parts {
            for (mine, theirs) in [
                (&mut merged.planners, &part.planners),
                (&mut merged.profiles, &part.profiles),
                (&mut merged.predictors, &part.predictors),
            ] {
                for name in theirs {
                    if !mine.contains(name) {
                        mine.push(name.clone());
                    }
                }
            }
        }
        let owner = merged.take_episodes(parts)?;
        merged.take_the_rest(parts, owner);
        merged.sort();
        Ok(merged)
    }

    /// Takes each cell's episode row from the first part that has it; returns which part
    /// supplies each cell. A later part's row for the same cell must be identical, and so must
    /// its vehicle rows.
    fn take_episodes(
        &mut self,
        parts: &[(PathBuf, Results)],
    ) -> Result<HashMap<CellKey, usize>, ResultsError> {
        let mut owner: HashMap<CellKey, usize> = HashMap::new();
        let vehicles: Vec<HashMap<CellKey, Vec<&csv::StringRecord>>> = parts
            .iter()
            .map(|(_, part)| rows_by_cell(&part.vehicles))
            .collect();
        for (i, (dir, part)) in parts.iter().enumerate() {
            for row in &part.episodes.rows {
                let k = key(&row.cell);
                let Some(&j) = owner.get(&k) else {
                    owner.insert(k, i);
                    self.episodes.rows.push(row.clone());
                    continue;
                };
                let first = parts[j]
                    .1
                    .episodes
                    .rows
                    .iter()
                    .find(|r| key(&r.cell) == k)
                    .expect("owner holds the cell");
                let conflict = |file: &str| ResultsError::Conflict {
                    cell: row.cell.to_string(),
                    first: parts[j].0.join(file),
                    second: dir.join(file),
                };
                if first.fields != row.fields {
                    return Err(conflict("episodes.csv"));
                }
                if vehicles[j].get(&k) != vehicles[i].get(&k) {
                    return Err(conflict("vehicles.csv"));
                }
            }
        }
        Ok(owner)
    }

    /// Takes the vehicle and timing rows of each cell from the part that supplied its episode
    /// row, and the failures of cells nobody finished (the first part's).
    fn take_the_rest(&mut self, parts: &[(PathBuf, Results)], mut owner: HashMap<CellKey, usize>) {
        for (i, (_, part)) in parts.iter().enumerate() {
            for (mine, theirs) in [
                (&mut self.vehicles, &part.vehicles),
                (&mut self.timings, &part.timings),
            ] {
                mine.rows.extend(
                    theirs
                        .rows
                        .iter()
                        .filter(|r| owner.get(&key(&r.cell)) == Some(&i))
                        .cloned(),
                );
            }
            for r in &part.failures.rows {
                if let std::collections::hash_map::Entry::Vacant(v) = owner.entry(key(&r.cell)) {
                    v.insert(usize::MAX);
                    self.failures.rows.push(r.clone());
                }
            }
        }
    }

    /// Writes the four files into `dir`, each atomically.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, ResultsError> {
        let mut paths = Vec::new();
        for (name, table) in FILES.iter().zip([
            &self.episodes,
            &self.vehicles,
            &self.timings,
            &self.failures,
        ]) {
            let p = dir.join(name);
            output::write_atomic(&p, &table.to_csv())?;
            paths.push(p);
        }
        Ok(paths)
    }
}
