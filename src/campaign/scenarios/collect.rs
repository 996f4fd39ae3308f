//! Resume state and collection of a campaign over scenarios.
//!
//! A cell is finished exactly when its files are whole and this campaign's: `episode.csv` (the
//! worker writes it last) holds the one row of this cell — its scenario, planner, α, seed, the
//! campaign's steps, this SUMO — `vehicles.csv` a row per vehicle inserted or never inserted, `regions.csv` a
//! row per region, `entries.csv` a row per region and entry (its main carriageway and each of
//! its on-ramps), and `settings.toml` the very settings the campaign would run it with. A
//! damaged, foreign or edited cell runs again, with the reason printed (a cell of an earlier
//! bkpbs, without `entries.csv` or with fewer columns, among them).
//!
//! The collected files, in grid order: `episodes.csv`, `regions.csv` and `entries.csv` (their
//! rows name their scenario, planner, α and seed already), `vehicles.csv` and `timings.csv`
//! (each row led by those four), `failures.csv`.

use std::path::{Path, PathBuf};

pub use crate::campaign::cell::cell_dir;
use crate::campaign::cell::{
    check_run, check_settings_record, column_value, episode_row, failure_of, rows_counted,
    CellState,
};
use crate::campaign::collect::strings;
use crate::campaign::grid::{file_name_of, Cell, Grid};
use crate::campaign::provenance::check_provenance;
use crate::campaign::results::{read_records, ResultsError};
use crate::campaign::settings::Settings;
use crate::campaign::validate::{check_rows, Rules};
use crate::campaign::worker::DONE_FILE;
use crate::episode::rows::TimingRow;
use crate::episode::summary::{Summary, Traffic};
use crate::episode::sumocfg::{RegionEntryRow, RegionRow, ScenarioVehicle};
use crate::io::WriteError;

/// The columns that lead the collected vehicle and timing rows.
pub const CELL_COLUMNS: [&str; 4] = ["scenario", "planner", "alpha", "seed"];

/// The header `T`'s rows are written with.
pub fn header_of<T: serde::Serialize + Default>() -> Vec<String> {
    strings(&crate::episode::cells::columns_of(&T::default()))
}

/// A finished cell's files, for the collection.
#[derive(Debug, Clone, PartialEq)]
pub struct Finished {
    /// Its `episode.csv` row.
    pub episode: csv::StringRecord,
    /// Its `regions.csv` rows.
    pub regions: Vec<csv::StringRecord>,
    /// Its `entries.csv` rows.
    pub entries: Vec<csv::StringRecord>,
    /// Its `vehicles.csv` rows.
    pub vehicles: Vec<csv::StringRecord>,
    /// Its `timing.csv` row.
    pub timing: Vec<csv::StringRecord>,
}

/// Where `cell` stands in `out`.
pub fn cell_state(out: &Path, settings: &Settings, cell: &Cell) -> CellState<Finished> {
    CellState::of(&cell_dir(out, cell), |dir| finished(dir, settings, cell))
}

/// How many `vehicles.csv` rows the `episode.csv` row (its `column`s) announces: one per
/// vehicle inserted and one per vehicle never inserted; a count that is no number is never met.
fn vehicle_rows(column: impl Fn(&str) -> String) -> String {
    let count = |name| column(name).parse::<usize>().ok();
    match (count("inserted"), count("never_inserted")) {
        (Some(a), Some(b)) => (a + b).to_string(),
        _ => "not a count".into(),
    }
}

/// How many `entries.csv` rows the `episode.csv` row's `regions` announces: per region one
/// for its main carriageway and one per on-ramp, which its name lists by the edge each joins.
fn entry_rows(regions: &str) -> usize {
    (regions.split("; "))
        .filter(|r| !r.is_empty())
        .map(|r| 1 + r.split(' ').count())
        .sum()
}

/// The files of `cell` in `dir` if they are whole and this campaign's; otherwise what is
/// wrong.
fn finished(dir: &Path, settings: &Settings, cell: &Cell) -> Result<Finished, String> {
    let header = Summary::header(Traffic::Scenario);
    let row = episode_row(dir, &header)?;
    let column = |name: &str| column_value(&header, &row, name);
    let config = settings.episode_config(cell);
    is_this_cell(&column, cell)?;
    check_run(column, config.scenario.steps)?;
    let regions = match column("regions") {
        r if r.is_empty() => 0,
        r => r.split("; ").count(),
    };
    let entries = entry_rows(&column("regions"));
    let vehicles = rows_counted(
        dir,
        "vehicles.csv",
        &header_of::<ScenarioVehicle>(),
        vehicle_rows(column),
    )?;
    let region_rows = rows_counted(dir, "regions.csv", &header_of::<RegionRow>(), regions)?;
    let entries = rows_counted(dir, "entries.csv", &header_of::<RegionEntryRow>(), entries)?;
    let timing_header = strings(TimingRow::columns());
    let timing = rows_counted(dir, "timing.csv", &timing_header, 1)?;
    check_settings_record(dir, &config)?;
    check_provenance(dir, &config)?;
    Ok(Finished {
        episode: row,
        regions: region_rows,
        entries,
        vehicles,
        timing,
    })
}

/// Does the `episode.csv` row (its `column`s) belong to `cell`?
fn is_this_cell(column: &dyn Fn(&str) -> String, cell: &Cell) -> Result<(), String> {
    let own = [
        ("scenario", file_name(cell)),
        ("planner", cell.planner.clone()),
        ("alpha", cell.alpha.to_string()),
        ("seed", cell.seed.to_string()),
    ];
    if own.iter().any(|(name, value)| column(name) != *value) {
        return Err(format!("{DONE_FILE} belongs to another cell"));
    }
    Ok(())
}

/// The cell's configuration file name, as `episode.csv` names its scenario.
fn file_name(cell: &Cell) -> String {
    file_name_of(cell.scenario.as_deref().unwrap_or(Path::new("")))
}

/// The episodes `out`'s collected `episodes.csv` records outside `grid` (a larger grid run
/// there before), as cells are displayed; collecting this grid would drop them. An unreadable
/// file records nothing.
pub fn recorded_outside(out: &Path, grid: &Grid) -> Vec<String> {
    let header = Summary::header(Traffic::Scenario);
    let Ok(rows) = read_records(&out.join("episodes.csv"), &header) else {
        return Vec::new();
    };
    let at = |name: &str| header.iter().position(|c| c == name).expect("a column");
    let (s, p, a, seed) = (at("scenario"), at("planner"), at("alpha"), at("seed"));
    let key = |r: &csv::StringRecord, i: usize| r.get(i).unwrap_or("").to_string();
    let in_grid: std::collections::HashSet<[String; 4]> = grid
        .cells()
        .iter()
        .map(|c| {
            [
                file_name(c),
                c.planner.clone(),
                c.alpha.to_string(),
                c.seed.to_string(),
            ]
        })
        .collect();
    rows.iter()
        .map(|r| [key(r, s), key(r, p), key(r, a), key(r, seed)])
        .filter(|k| !in_grid.contains(k))
        .map(|[s, p, a, seed]| format!("{p} {s} α={a} seed={seed}"))
        .collect()
}

/// The collected files of a campaign over scenarios, each a header and its rows.
#[derive(Debug, Clone, Default)]
pub struct ScenarioResults {
    /// `episodes.csv`.
    pub episodes: Vec<csv::StringRecord>,
    /// `regions.csv`.
    pub regions: Vec<csv::StringRecord>,
    /// `entries.csv`.
    pub entries: Vec<csv::StringRecord>,
    /// `vehicles.csv`, each row led by [`CELL_COLUMNS`].
    pub vehicles: Vec<csv::StringRecord>,
    /// `timings.csv`, each row led by [`CELL_COLUMNS`].
    pub timings: Vec<csv::StringRecord>,
    /// `failures.csv`: planner, scenario, α, seed, error.
    pub failures: Vec<csv::StringRecord>,
}

/// The rules of a scenario campaign's `episodes.csv` ([`check_rows`]).
const EPISODE_RULES: Rules<'static> = Rules {
    names: &["scenario", "planner", "sumo_version"],
    text: &["cav_types", "regions"],
    flags: &[],
    delays: &[
        "mean_time_loss_s",
        "mean_time_loss_region_s",
        "mean_time_loss_with_wait_s",
        "mean_time_loss_crashes_charged_s",
        "mean_region_delay_s",
    ],
};

/// The rules of its `regions.csv`.
const REGION_RULES: Rules<'static> = Rules {
    names: &["scenario", "planner", "region"],
    text: &[],
    flags: &["ramp_traffic"],
    delays: &[
        "mean_delay_s",
        "mean_delay_cav_s",
        "mean_delay_hdv_s",
        "mean_delay_main_s",
        "mean_delay_ramp_s",
        "mean_time_loss_s",
        "mean_delay_own_s",
    ],
};

/// The rules of its `entries.csv`.
const ENTRY_RULES: Rules<'static> = Rules {
    names: &["scenario", "planner", "region", "entry", "origin"],
    text: &[],
    flags: &[],
    delays: &["mean_delay_s", "mean_delay_own_s"],
};

/// The header of `failures.csv`.
pub const FAILURE_COLUMNS: [&str; 5] = ["planner", "scenario", "alpha", "seed", "error"];

/// Gathers every finished cell in grid order; the unfinished cells of this run's shard are
/// failures, with their `error.txt`.
pub fn collect(out: &Path, settings: &Settings) -> ScenarioResults {
    let mut res = ScenarioResults::default();
    for (position, cell) in settings.grid.cells().iter().enumerate() {
        let lead = [
            file_name(cell),
            cell.planner.clone(),
            cell.alpha.to_string(),
            cell.seed.to_string(),
        ];
        match cell_state(out, settings, cell) {
            CellState::Done(done) => {
                res.episodes.push(done.episode);
                res.regions.extend(done.regions);
                res.entries.extend(done.entries);
                for (rows, into) in [
                    (&done.vehicles, &mut res.vehicles),
                    (&done.timing, &mut res.timings),
                ] {
                    for r in rows {
                        let mut fields = csv::StringRecord::from(lead.to_vec());
                        fields.extend(r.iter());
                        into.push(fields);
                    }
                }
            }
            _ if settings.shard.contains(position) => {
                let error = failure_of(&cell_dir(out, cell));
                let [scenario, planner, alpha, seed] = lead;
                res.failures.push(csv::StringRecord::from(vec![
                    planner, scenario, alpha, seed, error,
                ]));
            }
            _ => {}
        }
    }
    res
}

impl ScenarioResults {
    /// Writes the six files into `dir`, each atomically; their paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, WriteError> {
        let led = |cols: Vec<String>| {
            let mut h: Vec<String> = CELL_COLUMNS.iter().map(|s| s.to_string()).collect();
            h.extend(cols);
            h
        };
        let timing = strings(TimingRow::columns());
        let failures: Vec<String> = FAILURE_COLUMNS.iter().map(|s| s.to_string()).collect();
        let files = [
            (
                "episodes.csv",
                Summary::header(Traffic::Scenario),
                &self.episodes,
            ),
            ("regions.csv", header_of::<RegionRow>(), &self.regions),
            ("entries.csv", header_of::<RegionEntryRow>(), &self.entries),
            (
                "vehicles.csv",
                led(header_of::<ScenarioVehicle>()),
                &self.vehicles,
            ),
            ("timings.csv", led(timing), &self.timings),
            ("failures.csv", failures, &self.failures),
        ];
        let mut paths = Vec::new();
        for (name, header, rows) in files {
            let path = dir.join(name);
            crate::io::write_atomic(&path, &to_csv(&header, rows))?;
            paths.push(path);
        }
        Ok(paths)
    }

    /// Reads the collected files of a campaign directory (as [`ScenarioResults::write`] wrote
    /// them).
    ///
    /// # Errors
    /// A file is missing, unreadable or has other columns.
    /// Checks every row: each cell (and each cell's region) once, every value in range.
    ///
    /// # Errors
    /// A file is unreadable, has other columns, or a row fails its checks.
    pub fn read(dir: &Path) -> Result<ScenarioResults, ResultsError> {
        let checked = |name: &str, header: Vec<String>, key: &[&str], rules: &Rules| {
            let path = dir.join(name);
            let rows = read_records(&path, &header)?;
            check_rows(&path, &header, &rows, key, rules)?;
            Ok::<_, ResultsError>(rows)
        };
        let cell = ["scenario", "planner", "alpha", "seed"];
        Ok(ScenarioResults {
            episodes: checked(
                "episodes.csv",
                Summary::header(Traffic::Scenario),
                &cell,
                &EPISODE_RULES,
            )?,
            regions: checked(
                "regions.csv",
                header_of::<RegionRow>(),
                &[&cell[..], &["region"]].concat(),
                &REGION_RULES,
            )?,
            entries: checked(
                "entries.csv",
                header_of::<RegionEntryRow>(),
                &[&cell[..], &["region", "entry", "origin"]].concat(),
                &ENTRY_RULES,
            )?,
            ..ScenarioResults::default()
        })
    }
}

fn to_csv(header: &[String], rows: &[csv::StringRecord]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header).expect("writing to memory");
    for r in rows {
        w.write_record(r).expect("writing to memory");
    }
    w.into_inner().expect("writing to memory")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::episode::sumocfg::{csv_of, RegionKey};

    /// A region's name lists the edges its on-ramps join: one entry row for its main
    /// carriageway and one per ramp.
    #[test]
    fn the_regions_announce_their_entry_rows() {
        assert_eq!(entry_rows(""), 0);
        assert_eq!(entry_rows("gneE7"), 2);
        assert_eq!(entry_rows("264308374; 4054057 4054058"), 2 + 3);
    }

    /// A collected directory of one episode row, one region row and its two entry rows, each
    /// file edited by `edit`.
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
        for (name, text) in [
            ("episodes.csv", Summary::csv(Traffic::Scenario, &[episode])),
            ("regions.csv", csv_of(&[region])),
            ("entries.csv", csv_of(&entries)),
        ] {
            let text = edit(String::from_utf8(text).unwrap());
            std::fs::write(d.path().join(name), text).unwrap();
        }
        d
    }

    /// The report once counted a region row of seed `x` as seed 0, and a row twice twice.
    #[test]
    fn collected_rows_out_of_range_or_twice_are_refused_naming_them() {
        assert!(ScenarioResults::read(collected(|t| t).path()).is_ok());
        let bad_seed = collected(|t| {
            t.replace("gneE7", "gneE7-")
                .replacen(",0,gneE7-", ",x,gneE7-", 1)
        });
        let e = ScenarioResults::read(bad_seed.path())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("regions.csv, line 2: seed = 'x' is not a number"),
            "{e}"
        );
        let twice = collected(|t| {
            let row = t.lines().nth(1).unwrap().to_string();
            format!("{t}{row}\n")
        });
        let e = ScenarioResults::read(twice.path()).unwrap_err().to_string();
        assert!(
            e.contains("episodes.csv, line 3: cell ramp.sumocfg bk-pbs 0 0 appears twice"),
            "{e}"
        );
        let negative =
            collected(|t| t.replacen("bk-pbs,0,,0,1.15.0,0,,0,", "bk-pbs,0,,0,1.15.0,0,,-3,", 1));
        let e = ScenarioResults::read(negative.path())
            .unwrap_err()
            .to_string();
        assert!(e.contains("inserted = '-3' is negative"), "{e}");
        let maybe = collected(|t| t.replace(",false,", ",maybe,"));
        let e = ScenarioResults::read(maybe.path()).unwrap_err().to_string();
        assert!(
            e.contains("regions.csv, line 2: ramp_traffic = 'maybe' is neither true nor false"),
            "{e}"
        );
        let entry_twice = collected(|t| t.replace("gneE14,ramp", "main,main"));
        let e = ScenarioResults::read(entry_twice.path())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("entries.csv, line 3: cell ramp.sumocfg bk-pbs 0 0 gneE7 main main"),
            "{e}"
        );
    }
}
