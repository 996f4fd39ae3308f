//! The collected results of a campaign directory, for every kind of campaign: `episodes.csv`,
//! `vehicles.csv`, `timings.csv` and `failures.csv` (over scenarios `regions.csv` and
//! `entries.csv` besides), each row naming its cell (the lead columns of the grid's axes,
//! [`Axes`]), in grid order. Read and checked, merged across shard directories, and written
//! atomically here.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::grid::{file_name_of, Cell};
use super::table::{cell_of, key, Axes, CellKey, Row, Table};
use crate::episode::cells::columns_of;
use crate::episode::output::{self, WriteError};
use crate::episode::rows::{TimingRow, VehicleRow};
use crate::episode::summary::{Summary, Traffic};
use crate::episode::sumocfg::{RegionEntryRow, RegionRow};

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
    /// Merged directories differ in their axes (one has the predictor axis, one not; one is a
    /// campaign over scenarios of the user's own, one on the paper's demand).
    #[error("{first} and {second} have different axes (one names a predictor or a scenario per cell): report them apart")]
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

/// The traffic of a campaign with `axes`: a scenario axis means scenarios of the user's own.
fn traffic_of(axes: Axes) -> Traffic {
    match axes.scenario {
        true => Traffic::Scenario,
        false => Traffic::Demand,
    }
}

/// Header of `episodes.csv` (an episode's columns already start with its cell).
pub fn episodes_header(axes: Axes) -> Vec<String> {
    axes.header(Summary::columns(traffic_of(axes)))
}
/// Header of `vehicles.csv`.
pub fn vehicles_header(axes: Axes) -> Vec<String> {
    led(axes.lead(), VehicleRow::columns(traffic_of(axes)))
}
/// Header of `timings.csv`.
pub fn timings_header(axes: Axes) -> Vec<String> {
    led(axes.lead(), TimingRow::columns())
}
/// Header of `failures.csv`.
pub fn failures_header(axes: Axes) -> Vec<String> {
    led(axes.failure_lead(), &["error"])
}
/// Header of `regions.csv` (a campaign over scenarios; its rows name their cell already).
pub fn regions_header(axes: Axes) -> Vec<String> {
    axes.header(&columns_of(&RegionRow::default()))
}
/// Header of `entries.csv` (likewise).
pub fn entries_header(axes: Axes) -> Vec<String> {
    axes.header(&columns_of(&RegionEntryRow::default()))
}

/// Column names as owned strings (a header to compare a file's with).
pub fn strings(cols: &[&str]) -> Vec<String> {
    cols.iter().map(|s| s.to_string()).collect()
}

fn led(lead: Vec<String>, rest: &[&str]) -> Vec<String> {
    lead.into_iter().chain(strings(rest)).collect()
}

/// The collected files of one directory (or of several, merged).
#[derive(Debug, Clone, PartialEq)]
pub struct Results {
    /// The axes the files' lead columns name.
    pub axes: Axes,
    /// Planner order of the grid (rows are sorted by it, then predictor, HDV profile,
    /// scenario, α, λ, seed).
    pub planners: Vec<String>,
    /// HDV profile order of the grid.
    pub profiles: Vec<String>,
    /// Predictor order of the grid (empty without the predictor axis).
    pub predictors: Vec<String>,
    /// Scenario order of the grid, by configuration file name (empty on the paper's demand).
    pub scenarios: Vec<String>,
    /// `episodes.csv`: one summary row per finished episode.
    pub episodes: Table,
    /// `vehicles.csv`: one row per vehicle of every finished episode.
    pub vehicles: Table,
    /// `timings.csv`: one row of computation times (planning, SUMO, wall) per finished episode.
    pub timings: Table,
    /// `failures.csv`: one row per unfinished episode, with its error message.
    pub failures: Table,
    /// `regions.csv` over scenarios: one row per merge region of every finished episode
    /// (empty, and not written, on the paper's demand).
    pub regions: Table,
    /// `entries.csv` over scenarios: one row per region and entry of every finished episode.
    pub entries: Table,
}

impl Default for Results {
    fn default() -> Self {
        Results::empty(Axes::default())
    }
}

/// The cell a row of a file with `header` names ([`super::table::cell_of`]), or the error
/// naming the file and line.
fn cell_in(
    path: &Path,
    header: &[String],
    fields: &csv::StringRecord,
) -> Result<Cell, ResultsError> {
    cell_of(header, fields).map_err(|value| ResultsError::Cell {
        path: path.to_path_buf(),
        line: fields.position().map_or(0, |p| p.line()),
        value,
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

/// Reads a collected CSV file that must have exactly `header` (naming each row's cell).
pub fn read_table(path: &Path, header: &[String]) -> Result<Table, ResultsError> {
    let mut table = Table::new(header.to_vec());
    for fields in read_records(path, header)? {
        let cell = cell_in(path, header, &fields)?;
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

/// The grid order a campaign directory was run with (its `campaign.toml`): names seen only in
/// the rows follow in order of appearance.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Order {
    /// Planners, as given.
    pub planners: Vec<String>,
    /// HDV profiles, as given.
    pub profiles: Vec<String>,
    /// Scenarios, by their configuration's file name.
    pub scenarios: Vec<String>,
}

impl Results {
    /// Empty files whose lead columns name `axes`.
    pub fn empty(axes: Axes) -> Results {
        Results {
            axes,
            planners: Vec::new(),
            profiles: Vec::new(),
            predictors: Vec::new(),
            scenarios: Vec::new(),
            episodes: Table::new(episodes_header(axes)),
            vehicles: Table::new(vehicles_header(axes)),
            timings: Table::new(timings_header(axes)),
            failures: Table::new(failures_header(axes)),
            regions: Table::new(regions_header(axes)),
            entries: Table::new(entries_header(axes)),
        }
    }

    /// The collected files, by name, in the order they are written: a campaign over scenarios
    /// has `regions.csv` and `entries.csv` besides.
    pub fn files(&self) -> Vec<(&'static str, &Table)> {
        let mut files = vec![("episodes.csv", &self.episodes)];
        if self.axes.scenario {
            files.extend([
                ("regions.csv", &self.regions),
                ("entries.csv", &self.entries),
            ]);
        }
        files.extend([
            ("vehicles.csv", &self.vehicles),
            ("timings.csv", &self.timings),
            ("failures.csv", &self.failures),
        ]);
        files
    }

    fn tables_mut(&mut self) -> [&mut Table; 6] {
        [
            &mut self.episodes,
            &mut self.vehicles,
            &mut self.timings,
            &mut self.failures,
            &mut self.regions,
            &mut self.entries,
        ]
    }

    /// Reads a campaign directory's collected files, the rows the report counts checked
    /// ([`super::validate::check_table`]); `failures.csv` and `timings.csv` may be missing.
    /// `order` gives the grid's order. The axes are those `episodes.csv`'s header names.
    pub fn read(dir: &Path, order: &Order) -> Result<Results, ResultsError> {
        let episodes_path = dir.join("episodes.csv");
        let axes = Axes::of_header(&header_of(&episodes_path)?);
        let mut res = Results {
            planners: order.planners.clone(),
            profiles: order.profiles.clone(),
            scenarios: order.scenarios.clone(),
            ..Results::empty(axes)
        };
        let optional = ["timings.csv", "failures.csv"];
        for (name, table) in res.files_mut() {
            let path = dir.join(name);
            if optional.contains(&name) && !path.exists() {
                continue;
            }
            *table = read_table(&path, &table.header)?;
            if let Some(checks) = super::validate::checks_of(name, axes) {
                super::validate::check_table(&path, table, checks)?;
            }
        }
        res.note_order();
        Ok(res)
    }

    /// [`Results::files`], to fill.
    fn files_mut(&mut self) -> Vec<(&'static str, &mut Table)> {
        let scenario = self.axes.scenario;
        let names = [
            "episodes.csv",
            "vehicles.csv",
            "timings.csv",
            "failures.csv",
        ];
        let [e, v, t, f, r, n] = self.tables_mut();
        let mut files: Vec<_> = names.into_iter().zip([e, v, t, f]).collect();
        if scenario {
            files.extend([("regions.csv", r), ("entries.csv", n)]);
        }
        files
    }

    /// Appends the planners, profiles, predictors and scenarios seen in the rows but not yet in
    /// the order.
    fn note_order(&mut self) {
        let seen = |names: &mut Vec<String>, name: &str| {
            if !names.iter().any(|n| n == name) {
                names.push(name.to_string());
            }
        };
        for t in [
            &self.episodes,
            &self.vehicles,
            &self.timings,
            &self.failures,
            &self.regions,
            &self.entries,
        ] {
            for r in &t.rows {
                seen(&mut self.planners, &r.cell.planner);
                seen(&mut self.profiles, &r.cell.hdv_profile);
                if let Some(p) = &r.cell.predictor {
                    seen(&mut self.predictors, p);
                }
                if let Some(s) = &r.cell.scenario {
                    seen(&mut self.scenarios, &file_name_of(s));
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
        let (predictor_rank, scenario_rank) = (rank(&self.predictors), rank(&self.scenarios));
        let predictor = |r: &Row| r.cell.predictor.as_ref().map(|p| predictor_rank[p]);
        let scenario = |r: &Row| {
            r.cell
                .scenario
                .as_ref()
                .map(|s| scenario_rank[&file_name_of(s)])
        };
        let order = |a: &Row, b: &Row| {
            planner_rank[&a.cell.planner]
                .cmp(&planner_rank[&b.cell.planner])
                .then(predictor(a).cmp(&predictor(b)))
                .then(profile_rank[&a.cell.hdv_profile].cmp(&profile_rank[&b.cell.hdv_profile]))
                .then(scenario(a).cmp(&scenario(b)))
                .then(a.cell.alpha.total_cmp(&b.cell.alpha))
                .then(a.cell.lambda.total_cmp(&b.cell.lambda))
                .then(a.cell.seed.cmp(&b.cell.seed))
        };
        for t in self.tables_mut() {
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
                (&mut merged.scenarios, &part.scenarios),
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
                (&mut self.regions, &part.regions),
                (&mut self.entries, &part.entries),
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

    /// Writes the collected files ([`Results::files`]) into `dir`, each atomically.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, ResultsError> {
        let mut paths = Vec::new();
        for (name, table) in self.files() {
            let p = dir.join(name);
            output::write_atomic(&p, &table.to_csv())?;
            paths.push(p);
        }
        Ok(paths)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::episode::sumocfg::{csv_of, RegionKey};

    /// A collected directory of a campaign over scenarios: one episode row, one region row and
    /// its two entry rows, each file edited by `edit`, and no vehicle.
    fn collected(edit: impl Fn(String) -> String) -> tempfile::TempDir {
        let d = tempfile::tempdir().unwrap();
        let episode = Summary {
            scenario: Some("ramp.sumocfg".into()),
            planner: "bk-pbs".into(),
            sumo_version: "1.15.0".into(),
            ..Summary::template(Traffic::Scenario)
        };
        let key = RegionKey {
            scenario: "ramp.sumocfg".into(),
            planner: "bk-pbs".into(),
            region: "gneE7".into(),
            ..RegionKey::default()
        };
        let region = RegionRow {
            key: key.clone(),
            ..RegionRow::default()
        };
        let entry = |entry: &str, origin: &str| RegionEntryRow {
            key: key.clone(),
            entry: entry.into(),
            origin: origin.into(),
            ..RegionEntryRow::default()
        };
        let entries = [entry("main", "main"), entry("gneE14", "ramp")];
        let axes = Axes {
            scenario: true,
            ..Axes::default()
        };
        for (name, text) in [
            ("episodes.csv", Summary::csv(Traffic::Scenario, &[episode])),
            ("regions.csv", csv_of(&[region])),
            ("entries.csv", csv_of(&entries)),
            ("vehicles.csv", Table::new(vehicles_header(axes)).to_csv()),
        ] {
            let text = edit(String::from_utf8(text).unwrap());
            std::fs::write(d.path().join(name), text).unwrap();
        }
        d
    }

    fn read_error(dir: &tempfile::TempDir) -> String {
        Results::read(dir.path(), &Order::default())
            .unwrap_err()
            .to_string()
    }

    /// The scenario report once counted a region row of seed `x` as seed 0, and a row twice
    /// twice.
    #[test]
    fn collected_rows_out_of_range_or_twice_are_refused_naming_them() {
        let res = Results::read(collected(|t| t).path(), &Order::default()).unwrap();
        assert!(res.axes.scenario);
        assert_eq!(res.scenarios, ["ramp.sumocfg"]);
        let bad_seed = collected(|t| {
            t.replace("gneE7", "gneE7-")
                .replacen(",0,gneE7-", ",x,gneE7-", 1)
        });
        let e = read_error(&bad_seed);
        assert!(e.contains("regions.csv, line 2: bad cell value 'x'"), "{e}");
        let twice = collected(|t| match t.lines().nth(1) {
            Some(row) => format!("{t}{row}\n"),
            None => t,
        });
        let e = read_error(&twice);
        assert!(
            e.contains("episodes.csv, line 3: cell bk-pbs ramp α=0 seed=0 appears twice"),
            "{e}"
        );
        let negative =
            collected(|t| t.replacen("bk-pbs,0,,0,1.15.0,0,,0,", "bk-pbs,0,,0,1.15.0,0,,-3,", 1));
        assert!(read_error(&negative).contains("inserted = '-3' is negative"));
        let maybe = collected(|t| t.replace(",false,", ",maybe,"));
        let e = read_error(&maybe);
        assert!(
            e.contains("regions.csv, line 2: ramp_traffic = 'maybe' is neither true nor false"),
            "{e}"
        );
        let entry_twice = collected(|t| t.replace("gneE14,ramp", "main,main"));
        let e = read_error(&entry_twice);
        assert!(
            e.contains("entries.csv, line 3: cell bk-pbs ramp α=0 seed=0 gneE7 main main"),
            "{e}"
        );
    }

    /// A paper row and a scenario row name their cells by the columns of their axes.
    #[test]
    fn cells_are_read_by_the_names_of_their_columns() {
        let paper = Axes::default();
        let cell = Cell {
            planner: "bk-pbs".into(),
            alpha: 0.4,
            lambda: 2500.0,
            seed: 3,
            hdv_profile: "paper".into(),
            predictor: None,
            scenario: None,
        };
        let lead = paper.lead();
        let row = csv::StringRecord::from(Axes::values(&cell, &lead));
        assert_eq!(cell_of(&lead, &row), Ok(cell.clone()));
        let over = Axes {
            scenario: true,
            ..Axes::default()
        };
        let cell = Cell {
            scenario: Some("ramp.sumocfg".into()),
            lambda: 0.0,
            hdv_profile: crate::config::hdv::DEFAULT_PROFILE.into(),
            ..cell
        };
        for lead in [over.lead(), over.failure_lead()] {
            let row = csv::StringRecord::from(Axes::values(&cell, &lead));
            assert_eq!(cell_of(&lead, &row), Ok(cell.clone()), "{lead:?}");
        }
        assert_eq!(
            over.failure_lead(),
            ["planner", "scenario", "alpha", "seed"]
        );
    }
}
