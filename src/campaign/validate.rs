//! Checks of a collected `episodes.csv` (and, over scenarios, `regions.csv` and
//! `entries.csv`) before `bkpbs report` counts it: a hand-edited or damaged file once went into the tables as it was (a row
//! twice counted twice, `NaN` shown as `NaN ± NaN`, a delay of −999 s bolded as the best, a
//! collision rate of 7.5; over scenarios a seed of `x` counted as seed 0). Both grids' rows
//! pass the same rules ([`problem`]), each file naming its own text and optional columns.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use super::table::{key, Axes, Table, ANY_CELL_COLUMN};

/// The first thing wrong with a collected `episodes.csv`.
#[derive(Debug, thiserror::Error)]
pub enum RowError {
    /// A cell has a second row (it would be counted twice).
    #[error("{path}, line {line}: cell {cell} appears twice")]
    Duplicate {
        /// The `episodes.csv` checked.
        path: PathBuf,
        /// Line of the second row in the file (1 is the header).
        line: u64,
        /// The cell, as it is displayed (`planner α=… λ=… seed=…`).
        cell: String,
    },
    /// A value is empty, not a finite number, or out of its column's range.
    #[error("{path}, line {line}: {column} = '{value}' {reason}")]
    Value {
        /// The `episodes.csv` checked.
        path: PathBuf,
        /// Line of the row in the file (1 is the header).
        line: u64,
        /// The column of the value.
        column: String,
        /// The value as written.
        value: String,
        /// The rule it breaks (`is negative`, `is a rate above 1`, …).
        reason: &'static str,
    },
}

/// The rules below name columns of [`Summary`] (a test checks they exist); every other
/// column must hold a non-negative number.
///
/// Delays may be empty (an episode without arrivals, or without a vehicle to count) and
/// slightly negative (a vehicle inserted faster than its drawn speed beats t* by rounding),
/// never by a second (nor, as a total, by a vehicle-hour).
const DELAYS: [&str; 6] = [
    "system_delay_s",
    "system_delay_veh_h",
    "own_speed_delay_s",
    "mean_delay_s",
    "mean_delay_cav_s",
    "mean_delay_hdv_s",
];
const LOWEST_DELAY: f64 = -1.0;
/// A fraction of the inserted vehicles: at most 1.
const RATE: &str = "controllable_collision_rate";
/// Above any value an episode records (the largest, search-node counts, stay below 1e10), and
/// low enough that sums of squares stay finite: a delay of 1e308 once made the report print
/// "± inf".
const LARGEST: f64 = 1e15;

/// The columns that are names, not numbers: the SUMO version (any text SUMO reported).
const TEXT: [&str; 1] = ["sumo_version"];

/// Which columns of a file are names rather than numbers (`text`: any text, `names`: never
/// empty), which are flags (`true` or `false`), and which are delays (may be empty, and down
/// to [`LOWEST_DELAY`]); every other column holds a non-negative number, and [`RATE`] at
/// most 1.
#[derive(Debug, Clone, Copy)]
pub struct Rules<'a> {
    /// Columns of text that must not be empty.
    pub names: &'a [&'a str],
    /// Columns of text that may be empty.
    pub text: &'a [&'a str],
    /// Columns of `true` or `false`.
    pub flags: &'a [&'a str],
    /// Columns of delays.
    pub delays: &'a [&'a str],
}

/// The rules of the paper grid's `episodes.csv`.
const EPISODES: Rules<'static> = Rules {
    names: &TEXT,
    text: &[],
    flags: &[],
    delays: &DELAYS,
};

/// The rules of a scenario campaign's `episodes.csv`.
const SCENARIO_EPISODES: Rules<'static> = Rules {
    names: &["sumo_version"],
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
const REGIONS: Rules<'static> = Rules {
    names: &["region"],
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
const ENTRIES: Rules<'static> = Rules {
    names: &["region", "entry", "origin"],
    text: &[],
    flags: &[],
    delays: &["mean_delay_s", "mean_delay_own_s"],
};

/// The checks of a collected file: its rules, and the columns besides the cell's that make a
/// row's key (each key once).
#[derive(Debug, Clone, Copy)]
pub struct Checks {
    rules: &'static Rules<'static>,
    key: &'static [&'static str],
}

/// The checks of the collected file `name` of a campaign with `axes`; none for the files the
/// report does not count (`vehicles.csv`, `timings.csv`, `failures.csv`).
pub fn checks_of(name: &str, axes: Axes) -> Option<Checks> {
    let (rules, key) = match (name, axes.scenario) {
        ("episodes.csv", false) => (&EPISODES, &[][..]),
        ("episodes.csv", true) => (&SCENARIO_EPISODES, &[][..]),
        ("regions.csv", _) => (&REGIONS, &["region"][..]),
        ("entries.csv", _) => (&ENTRIES, &["region", "entry", "origin"][..]),
        _ => return None,
    };
    Some(Checks { rules, key })
}

/// What `column` may hold under the paper grid's rules, as a reason if `value` breaks it.
#[cfg(test)]
fn problem(column: &str, value: &str) -> Option<&'static str> {
    problem_under(&EPISODES, column, value)
}

/// What `column` may hold under `rules`, as a reason if `value` breaks it.
fn problem_under(rules: &Rules, column: &str, value: &str) -> Option<&'static str> {
    if rules.text.contains(&column) {
        return None;
    }
    if rules.names.contains(&column) {
        return value.is_empty().then_some("is empty");
    }
    if rules.flags.contains(&column) {
        return (!matches!(value, "true" | "false")).then_some("is neither true nor false");
    }
    let delay = rules.delays.contains(&column);
    if value.is_empty() {
        return (!delay).then_some("is empty");
    }
    let Ok(x) = value.parse::<f64>() else {
        return Some("is not a number");
    };
    if !x.is_finite() {
        Some("is not a finite number")
    } else if delay && x < LOWEST_DELAY {
        Some("is below -1 s, shorter than the free-flow time allows")
    } else if !delay && x < 0.0 {
        Some("is negative")
    } else if column == RATE && x > 1.0 {
        Some("is a rate above 1")
    } else if x > LARGEST {
        Some("is above 1e15, beyond any value an episode records")
    } else {
        None
    }
}

/// Checks every row of `table`, read from `path`, under `checks`: each key (the cell and the
/// key columns) once, every other value in range.
///
/// # Errors
/// The first row that repeats a key or holds a value out of range, naming line, column and
/// value.
pub fn check_table(path: &Path, table: &Table, checks: Checks) -> Result<(), RowError> {
    let at: Vec<usize> = (checks.key.iter())
        .filter_map(|k| table.column(k))
        .collect();
    let mut seen = HashSet::new();
    for row in &table.rows {
        let line = row.fields.position().map_or(0, |p| p.line());
        let within: Vec<&str> = at
            .iter()
            .map(|&i| row.fields.get(i).unwrap_or(""))
            .collect();
        if !seen.insert((key(&row.cell), within.join("\u{0}"))) {
            let cell = [row.cell.to_string()]
                .into_iter()
                .chain(within.iter().map(|s| s.to_string()));
            return Err(RowError::Duplicate {
                path: path.to_path_buf(),
                line,
                cell: cell.collect::<Vec<_>>().join(" "),
            });
        }
        let values = table.header.iter().zip(row.fields.iter());
        // The cell's columns are checked when the row is read.
        let cell = |c: &String| ANY_CELL_COLUMN.contains(&c.as_str());
        for (column, value) in values.filter(|(c, _)| !cell(c)) {
            if let Some(reason) = problem_under(checks.rules, column, value) {
                return Err(RowError::Value {
                    path: path.to_path_buf(),
                    line,
                    column: column.to_string(),
                    value: value.to_string(),
                    reason,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::results::{entries_header, regions_header};
    use crate::episode::summary::{Summary, Traffic};

    #[test]
    fn rules_name_summary_columns() {
        for column in DELAYS.iter().chain([&RATE]) {
            assert!(
                Summary::columns(Traffic::Demand).contains(column),
                "{column}"
            );
        }
        let lead = crate::campaign::table::CELL_COLUMNS;
        assert_eq!(&Summary::columns(Traffic::Demand)[..lead.len()], lead);
        let named = |rules: &Rules, header: &[String]| {
            let all = [rules.names, rules.text, rules.flags, rules.delays].concat();
            for column in all {
                assert!(header.iter().any(|h| h == column), "{column}");
            }
        };
        named(&SCENARIO_EPISODES, &Summary::header(Traffic::Scenario));
        named(&REGIONS, &regions_header(Axes::default()));
        named(&ENTRIES, &entries_header(Axes::default()));
    }

    #[test]
    fn values_out_of_range_are_named() {
        assert_eq!(problem("mean_delay_s", ""), None);
        assert_eq!(problem("mean_delay_s", "-0.002"), None);
        assert!(problem("mean_delay_s", "-999").is_some());
        assert_eq!(problem("system_delay_s", "-0.01"), None);
        assert!(problem("system_delay_s", "-5").is_some());
        assert!(problem("never_inserted", "-1").is_some());
        assert!(problem("mean_delay_s", "NaN").is_some());
        assert!(problem("arrived", "").is_some());
        assert!(problem("arrived", "-1").is_some());
        assert!(problem("controllable_collision_rate", "7.5").is_some());
        assert_eq!(problem("controllable_collision_rate", "0.025"), None);
        assert!(problem("throughput_veh_h", "inf").is_some());
        assert!(problem("steps", "many").is_some());
    }
}
