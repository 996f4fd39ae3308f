//! Which settings decide an episode's results, and where two sets of settings first differ:
//! what lets campaigns share a directory (their `campaign.toml`), and what a finished cell must
//! have run with.

use serde::Serialize;

use crate::config::Config;

/// Scenario keys a campaign sets itself, per cell.
pub(super) const PER_CELL_KEYS: [&str; 6] = [
    "alpha",
    "lambda",
    "seed",
    "steps",
    "sumocfg",
    "sumocfg_digests",
];

/// The keys of either kind of `[campaign]` table that change what a cell runs, in the order
/// they are compared; the others add cells (the axes) or change only how cells are run.
const RUN_KEYS: [&str; 2] = ["steps", "sumo_version"];

/// The configuration without how SUMO is watched (its console output, sumo-gui, the stall
/// bound), which does not change what SUMO computes.
pub(super) fn unwatched(config: &Config) -> Config {
    let mut c = config.clone();
    c.sumo.verbose = false;
    c.sumo.gui = false;
    c.sumo.gui_delay_ms = None;
    c.sumo.stall_timeout_s = None;
    c
}

/// Everything in an episode's configuration that decides its results, as TOML: the whole
/// configuration, cell keys included, without how SUMO is watched and without the optional
/// outputs. A campaign's worker records it in the cell (`settings.toml`), and a cell whose
/// record differs from what the campaign would run is not finished (an edited
/// `campaign.toml` cannot pass off old episodes as its own).
pub fn results_settings(config: &Config) -> String {
    toml::to_string_pretty(&config_table(&unwatched(config))).expect("config serialises")
}

/// The configuration as a TOML table without the optional outputs.
fn config_table(config: &Config) -> toml::Table {
    let mut doc = match toml::Value::try_from(config).expect("config serialises") {
        toml::Value::Table(t) => t,
        _ => unreachable!("a struct serialises to a table"),
    };
    doc.remove("output");
    doc
}

/// The configuration as a TOML table without the per-cell scenario keys and without the
/// optional outputs, which do not change results (runs with and without trajectories may
/// share a directory).
pub(super) fn scenario_table(config: &Config) -> toml::Table {
    let mut doc = config_table(config);
    if let Some(toml::Value::Table(s)) = doc.get_mut("scenario") {
        for key in PER_CELL_KEYS {
            s.remove(key);
        }
    }
    doc
}

/// A campaign's `campaign.toml`: the `comment` line, then the shared settings of `config` and
/// the `[campaign]` `table` (either kind, without what does not change results), so that
/// feeding it back with `--config` reproduces the campaign.
pub(super) fn campaign_file(comment: &str, table: &impl Serialize, config: &Config) -> String {
    let mut doc = scenario_table(config);
    doc.insert(
        "campaign".into(),
        toml::Value::try_from(table).expect("campaign table serialises"),
    );
    format!(
        "{comment}\n{}",
        toml::to_string_pretty(&doc).expect("campaign file serialises")
    )
}

/// The first setting, dotted, in which two campaigns of either kind (each its configuration
/// and `[campaign]` table) run a cell differently: a shared setting, else one of [`RUN_KEYS`].
/// Campaigns that agree may share a directory, whatever their grids.
pub(super) fn run_difference<T: Serialize>(a: (&Config, &T), b: (&Config, &T)) -> Option<String> {
    let shared = |c: &Config| toml::Value::Table(scenario_table(&unwatched(c)));
    first_difference(&shared(a.0), &shared(b.0), "").or_else(|| {
        let table = |t: &T| toml::Value::try_from(t).expect("campaign table serialises");
        let (x, y) = (table(a.1), table(b.1));
        RUN_KEYS
            .iter()
            .find(|k| x.get(**k) != y.get(**k))
            .map(|k| format!("campaign.{k}"))
    })
}

/// The first dotted key in which `a` and `b` differ, if any.
pub(crate) fn first_difference(a: &toml::Value, b: &toml::Value, path: &str) -> Option<String> {
    match (a, b) {
        (toml::Value::Table(x), toml::Value::Table(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            keys.into_iter().find_map(|k| {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match (x.get(k), y.get(k)) {
                    (Some(u), Some(v)) => first_difference(u, v, &p),
                    _ => Some(p),
                }
            })
        }
        _ => (a != b).then(|| path.to_string()),
    }
}
