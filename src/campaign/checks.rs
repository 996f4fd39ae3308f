//! Reading and checking the settings of either kind of campaign — on the paper's demand
//! ([`super::settings`]) or over scenarios of the user's own ([`super::settings::scenarios`]):
//! the campaign file split into its table and scenario settings, list flags, and values checked
//! with errors that name the flag, or the key and its file.

use std::path::{Path, PathBuf};
use std::time::Duration;

use super::comparison::PER_CELL_KEYS;
use super::grid::{Shard, ShardError};
use super::overrides::Overrides;
use crate::config::Config;
use crate::config::ConfigError;
use crate::controller::{PlannerKind, UnknownPlanner};

/// Why campaign settings cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum SettingsError {
    /// The campaign file could not be read.
    #[error("cannot read campaign file {path}: {error}")]
    Read {
        /// The file asked for.
        path: PathBuf,
        /// What the file system said.
        error: std::io::Error,
    },
    /// The campaign file is not TOML of the expected shape (syntax, wrong type, unknown key).
    #[error("malformed campaign file {path}: {message}")]
    Parse {
        /// The file read.
        path: PathBuf,
        /// The TOML parser's message (with the table or byte offset where known).
        message: String,
    },
    /// The file sets a scenario key that the campaign sets per cell.
    #[error("scenario.{key} in {path} is set by the campaign (use campaign.{replacement})")]
    PerCellKey {
        /// The campaign file.
        path: PathBuf,
        /// The `[scenario]` key set (`alpha`, `lambda`, `seed` or `steps`).
        key: String,
        /// The `[campaign]` key to use instead.
        replacement: &'static str,
    },
    /// The scenario settings fail validation for some cell of the grid.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A planner name is not a known controller.
    #[error("{origin}: {planner}")]
    Planner {
        /// Where the list came from: the flag, or the key and its file.
        origin: String,
        /// The unknown name, with the known ones.
        planner: UnknownPlanner,
    },
    /// An entry of the predictor axis names no predictor.
    #[error("{origin}: unknown predictor '{name}' (known: learned, constant)")]
    UnknownPredictor {
        /// Where the list came from: the flag, or the key and its file.
        origin: String,
        /// The name as given.
        name: String,
    },
    /// An entry of a numeric list flag does not parse.
    #[error("{origin}: '{value}' is not a number")]
    NotANumber {
        /// The flag (`--alphas`, …).
        origin: String,
        /// The entry as given.
        value: String,
    },
    /// A value lies outside what a campaign accepts.
    #[error("{origin}: {what} {value} {reason}")]
    OutOfRange {
        /// Where the value came from: the flag, or the key and its file.
        origin: String,
        /// What the value is (`alpha`, `workers`, `episode timeout`, …).
        what: &'static str,
        /// The value, as text.
        value: String,
        /// The rule it breaks.
        reason: &'static str,
    },
    /// A list setting (planners, α, λ) has no entry.
    #[error("{origin}: the list is empty")]
    Empty {
        /// Where the list came from: the flag, or the key and its file.
        origin: String,
    },
    /// The `--shard` value is not `k/n`.
    #[error(transparent)]
    Shard(#[from] ShardError),
    /// A scenario of a campaign over scenarios of the user's own cannot be run.
    #[error(transparent)]
    Scenario(#[from] crate::sumo::sumocfg::SumoConfigError),
    /// A setting of the paper's demand given to a campaign over scenarios of the user's own,
    /// which bring their own demand and drivers.
    #[error(
        "{origin}: a campaign over scenarios of your own (--sumocfg) takes {what} from the \
         scenarios; leave it out"
    )]
    NotWithScenarios {
        /// The flag, or the key and its file.
        origin: String,
        /// What the scenarios bring instead (`its demand`, `its drivers`, …).
        what: &'static str,
    },
    /// A scenario sets no end time and the campaign no `steps`.
    #[error("{path} sets no <end> time: give the campaign --steps (campaign.steps)")]
    NoInterval {
        /// The configuration file.
        path: PathBuf,
    },
    /// A scenario's name (its file name without `.sumocfg`) cannot name a directory.
    #[error(
        "{path}: its name '{name}' (the file name without .sumocfg) cannot name its cells' \
         directory: rename the file"
    )]
    BadName {
        /// The configuration file.
        path: PathBuf,
        /// The name it would give its cells.
        name: String,
    },
    /// A scenario names its own tripinfo output, which every episode of the campaign would
    /// write at once and read back as its own.
    #[error(
        "{path} names a tripinfo-output of its own ('{file}'): a campaign runs its episodes at \
         once, each would write that one file and read back another's trips; remove it from a \
         copy for the campaign (each episode keeps its own)"
    )]
    OwnTripinfo {
        /// The configuration file.
        path: PathBuf,
        /// The file it names.
        file: String,
    },
    /// Two scenarios share a name, so their cells would share directories.
    #[error("two scenarios are named '{name}' ({first} and {second}): rename one")]
    SameName {
        /// The shared name (the file name without `.sumocfg`).
        name: String,
        /// The first file.
        first: PathBuf,
        /// The second file.
        second: PathBuf,
    },
}

/// Longest accepted episode timeout: a week, far beyond any episode, and small enough to be a
/// valid `Duration`.
pub(crate) const MAX_EPISODE_TIMEOUT_S: f64 = 7.0 * 24.0 * 3600.0;

pub(crate) fn parse_error(path: &Path, message: impl Into<String>) -> SettingsError {
    SettingsError::Parse {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// A campaign file as a TOML table.
pub(crate) fn read_doc(path: &Path) -> Result<toml::Table, SettingsError> {
    let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Config).map_err(
        |error| SettingsError::Read {
            path: path.to_path_buf(),
            error,
        },
    )?;
    toml::from_str(&text).map_err(|e| {
        parse_error(
            path,
            e.message().to_string()
                + &e.span()
                    .map(|s| format!(" (at byte {})", s.start))
                    .unwrap_or_default(),
        )
    })
}

/// A campaign file's `[campaign]` table (of either kind of campaign) and its scenario settings,
/// which must not set the keys the campaign sets per cell.
pub(crate) fn read_parts<T: serde::de::DeserializeOwned + Default>(
    mut doc: toml::Table,
    path: &Path,
) -> Result<(T, Config), SettingsError> {
    let table = match doc.remove("campaign") {
        Some(v) => v
            .try_into::<T>()
            .map_err(|e| parse_error(path, format!("[campaign]: {}", e.message())))?,
        None => T::default(),
    };
    if let Some(toml::Value::Table(s)) = doc.get("scenario") {
        for key in PER_CELL_KEYS {
            if s.contains_key(key) {
                return Err(SettingsError::PerCellKey {
                    path: path.to_path_buf(),
                    key: key.to_string(),
                    replacement: match key {
                        "alpha" => "alphas",
                        "lambda" => "lambdas",
                        "seed" => "seed_base",
                        "sumocfg" | "sumocfg_digests" => "scenarios",
                        _ => "steps",
                    },
                });
            }
        }
    }
    let config = toml::Value::Table(doc)
        .try_into::<Config>()
        .map_err(|e| parse_error(path, e.message().to_string()))?;
    Ok((table, config))
}

/// The entries of a comma-separated flag, trimmed, empty ones skipped. Text entries (planner
/// names) always parse; only a numeric list can fail, hence the error's wording.
pub(crate) fn parse_list<T: std::str::FromStr>(
    origin: &str,
    text: &str,
) -> Result<Vec<T>, SettingsError> {
    text.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse().map_err(|_| SettingsError::NotANumber {
                origin: origin.to_string(),
                value: s.to_string(),
            })
        })
        .collect()
}

/// Where a value came from, for error messages: the flag, or the key and its file.
pub(crate) fn origin(flag_set: bool, flag: &str, key: &str, file: Option<&Path>) -> String {
    match (flag_set, file) {
        (true, _) => flag.to_string(),
        (false, Some(p)) => format!("campaign.{key} in {}", p.display()),
        (false, None) => format!("campaign.{key} (default)"),
    }
}

/// The planner list must name at least one controller, and only known ones.
pub(crate) fn check_planners(planners: &[String], origin: String) -> Result<(), SettingsError> {
    if planners.is_empty() {
        return Err(SettingsError::Empty { origin });
    }
    match planners.iter().find_map(|p| p.parse::<PlannerKind>().err()) {
        Some(planner) => Err(SettingsError::Planner { origin, planner }),
        None => Ok(()),
    }
}

/// The planners and α of either kind of campaign's table: known controllers, each α in
/// [0, 1]. Both kinds check them first, in this order, with the same messages.
pub(crate) fn check_planners_and_alphas(
    planners: &[String],
    alphas: &[f64],
    o: &Overrides,
    file: Option<&Path>,
) -> Result<(), SettingsError> {
    check_planners(
        planners,
        origin(o.planners.is_some(), "--planners", "planners", file),
    )?;
    let alpha_origin = origin(o.alphas.is_some(), "--alphas", "alphas", file);
    check_values(
        &alpha_origin,
        "α",
        alphas,
        |a| (0.0..=1.0).contains(&a),
        "must lie in [0, 1]",
    )?;
    check_values(&alpha_origin, "α", alphas, names_a_cell, TOO_LONG)
}

/// What [`names_a_cell`] refuses.
pub(crate) const TOO_LONG: &str =
    "has too many digits to name a cell's directory (at most 16 characters as written)";

/// Whether `x` names a cell's directory as Rust's shortest round-trip form writes it
/// (`a0.4_…`): 16 characters at most. α = 1e-300 once made every cell fail with "File name too
/// long".
pub(crate) fn names_a_cell(x: f64) -> bool {
    x.to_string().len() <= 16
}

/// The seed count and the steps (where the table sets them) of either kind of campaign's
/// table: each at least 1.
pub(crate) fn check_seeds_and_steps(
    seeds: u64,
    steps: Option<u32>,
    o: &Overrides,
    file: Option<&Path>,
) -> Result<(), SettingsError> {
    at_least_one(
        origin(o.seeds.is_some(), "--seeds", "seeds", file),
        "seed count",
        seeds,
    )?;
    match steps {
        Some(n) => at_least_one(
            origin(o.steps.is_some(), "--steps", "steps", file),
            "steps",
            n.into(),
        ),
        None => Ok(()),
    }
}

/// The slice of the grid `--shard` names; the whole grid without it.
pub(crate) fn shard_of(o: &Overrides) -> Result<Shard, SettingsError> {
    match &o.shard {
        Some(s) => Ok(s.parse()?),
        None => Ok(Shard::ALL),
    }
}

/// A count must be at least 1; `what` names it in the error.
pub(crate) fn at_least_one(
    origin: String,
    what: &'static str,
    n: u64,
) -> Result<(), SettingsError> {
    if n == 0 {
        Err(SettingsError::OutOfRange {
            origin,
            what,
            value: "0".into(),
            reason: "must be at least 1",
        })
    } else {
        Ok(())
    }
}

/// The table's worker count, else one per core.
pub(crate) fn worker_count(
    workers: Option<usize>,
    flag_set: bool,
    file: Option<&Path>,
) -> Result<usize, SettingsError> {
    match workers {
        Some(w) => {
            let origin = origin(flag_set, "--workers", "workers", file);
            at_least_one(origin.clone(), "workers", w as u64)?;
            if w > crate::io::cores::max_parallel() {
                return Err(SettingsError::OutOfRange {
                    origin,
                    what: "workers",
                    value: w.to_string(),
                    reason: "is more than four per core of this machine",
                });
            }
            Ok(w)
        }
        None => Ok(crate::io::cores::available()),
    }
}

/// The table's episode timeout, checked: positive seconds, at most [`MAX_EPISODE_TIMEOUT_S`].
pub(crate) fn episode_timeout(
    timeout: Option<f64>,
    flag_set: bool,
    file: Option<&Path>,
) -> Result<Option<Duration>, SettingsError> {
    let Some(t) = timeout else {
        return Ok(None);
    };
    check_values(
        &origin(flag_set, "--episode-timeout", "episode_timeout", file),
        "episode timeout",
        &[t],
        |t| t > 0.0 && t <= MAX_EPISODE_TIMEOUT_S,
        "must lie in (0, 604800] seconds (a week)",
    )?;
    Ok(Some(Duration::from_secs_f64(t)))
}

pub(crate) fn check_values(
    origin: &str,
    what: &'static str,
    values: &[f64],
    ok: impl Fn(f64) -> bool,
    reason: &'static str,
) -> Result<(), SettingsError> {
    if values.is_empty() {
        return Err(SettingsError::Empty {
            origin: origin.to_string(),
        });
    }
    match values.iter().find(|&&v| !ok(v)) {
        Some(v) => Err(SettingsError::OutOfRange {
            origin: origin.to_string(),
            what,
            value: shown(*v),
            reason,
        }),
        None => Ok(()),
    }
}

/// A value as an error message shows it: as written, or in scientific notation when that is
/// long (1e-300 rather than 302 digits).
fn shown(v: f64) -> String {
    let plain = v.to_string();
    if plain.len() > 24 {
        format!("{v:e}")
    } else {
        plain
    }
}
