//! What a learned part was trained on: the record every model file (b_θ) and policy file
//! (RL-PPO) carries as its `trained_on` field, and a data file of `bkpbs collect` in its
//! metadata, from which `bkpbs train` carries it into the model.
//!
//! It lives here, below `predict` and `policy`, because both file formats hold it; it is plain
//! data. Which scenario an episode runs is computed from the files in `crate::sumo`
//! (`scenario_record`); whether a file may be used under a run's settings is decided where the
//! file is loaded (the step length) and at an episode's start (the scenario).
//!
//! Where a fact was not kept when a committed file was trained, the record says
//! [`NOT_RECORDED`] instead of a guess.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// What a record says of a fact nobody kept.
pub const NOT_RECORDED: &str = "not recorded";

/// What a model or policy file was trained on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainedOn {
    /// SUMO's step length of the episodes the data came from (s): `scenario.dt`. A file is used
    /// only under this step length.
    pub step_length_s: f64,
    /// The scenario(s) of those episodes.
    pub scenarios: Vec<TrainingScenario>,
    /// Demand seeds of the episodes (`10000-10499`), or [`NOT_RECORDED`].
    pub episode_seeds: String,
    /// How many episodes, or [`NOT_RECORDED`].
    pub episodes: String,
    /// Seed of the training itself (initial weights, shuffling, sampling), or [`NOT_RECORDED`];
    /// `-` for a data file, which is not trained yet.
    pub training_seed: String,
    /// The command lines as run, in order (`bkpbs collect …`, then `bkpbs train …`).
    pub commands: Vec<String>,
    /// The SUMO version the episodes ran on.
    pub sumo_version: String,
    /// The bkpbs version that collected and trained, or [`NOT_RECORDED`].
    pub bkpbs_version: String,
    /// The git commit of that bkpbs (`BKPBS_COMMIT`), or [`NOT_RECORDED`].
    pub bkpbs_commit: String,
}

/// The world of training episodes: the paper's merge, the paper's demand on a network file, or
/// a SUMO configuration of the user's. Files are known by their SHA-256, so a copy elsewhere
/// is the same scenario and an edited one is not.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum TrainingScenario {
    /// The paper's merge network embedded in the binary, with the paper's demand.
    PaperMerge,
    /// The paper's demand on a network file (`scenario.net_file`, `--net`).
    Network {
        /// The network's file name (no directory).
        file: String,
        /// Its SHA-256 (hex).
        sha256: String,
    },
    /// A SUMO configuration (`scenario.sumocfg`, `--sumocfg`).
    Sumocfg {
        /// The configuration's file name (no directory).
        file: String,
        /// SHA-256 (hex) of the configuration and every file it names, by the name it gives
        /// them.
        sha256: BTreeMap<String, String>,
    },
}

impl TrainingScenario {
    /// Whether `self` and `other` are the same world: the same kind and the same file
    /// contents (names are for people).
    pub fn same_as(&self, other: &TrainingScenario) -> bool {
        match (self, other) {
            (TrainingScenario::PaperMerge, TrainingScenario::PaperMerge) => true,
            (
                TrainingScenario::Network { sha256: a, .. },
                TrainingScenario::Network { sha256: b, .. },
            ) => a == b,
            (
                TrainingScenario::Sumocfg { sha256: a, .. },
                TrainingScenario::Sumocfg { sha256: b, .. },
            ) => sorted_digests(a) == sorted_digests(b),
            _ => false,
        }
    }
}

/// The digests of a scenario's files, sorted (their names aside).
fn sorted_digests(files: &BTreeMap<String, String>) -> Vec<&String> {
    let mut d: Vec<&String> = files.values().collect();
    d.sort();
    d
}

impl std::fmt::Display for TrainingScenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TrainingScenario::PaperMerge => write!(f, "the paper's merge"),
            TrainingScenario::Network { file, .. } => write!(f, "network {file}"),
            TrainingScenario::Sumocfg { file, .. } => write!(f, "scenario {file}"),
        }
    }
}

impl TrainedOn {
    /// Whether the record names `scenario` among its scenarios.
    pub fn covers(&self, scenario: &TrainingScenario) -> bool {
        self.scenarios.iter().any(|s| s.same_as(scenario))
    }

    /// The scenarios as one phrase (`the paper's merge`, `scenario a.sumocfg and …`).
    pub fn scenarios_text(&self) -> String {
        let names: Vec<String> = self.scenarios.iter().map(|s| s.to_string()).collect();
        if names.is_empty() {
            NOT_RECORDED.into()
        } else {
            names.join(" and ")
        }
    }

    /// Whether a run of step length `dt` (s) may use the file: the same step, to a
    /// millisecond's thousandth (both are decimal settings).
    pub fn fits_step_length(&self, dt: f64) -> bool {
        (self.step_length_s - dt).abs() < 1e-6
    }
}

/// The command line of this process as a user would type it again: its arguments joined by
/// spaces, the program as `bkpbs`, an argument with a space or a quote in single quotes.
pub fn command_line() -> String {
    let mut args = std::env::args_os().map(|a| a.to_string_lossy().into_owned());
    let _program = args.next();
    let quoted = args.map(|a| {
        if a.is_empty() || a.contains([' ', '\'', '"', '\t', '\n']) {
            format!("'{}'", a.replace('\'', r"'\''"))
        } else {
            a
        }
    });
    std::iter::once("bkpbs".to_string())
        .chain(quoted)
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(files: &[(&str, &str)]) -> TrainingScenario {
        TrainingScenario::Sumocfg {
            file: files[0].0.into(),
            sha256: files
                .iter()
                .map(|(n, d)| (n.to_string(), d.to_string()))
                .collect(),
        }
    }

    /// The same files under other names are the same scenario; one changed file is not.
    #[test]
    fn scenarios_are_known_by_their_contents() {
        let a = cfg(&[("a.sumocfg", "1"), ("a.net.xml", "2")]);
        assert!(a.same_as(&cfg(&[("b.sumocfg", "1"), ("b.net.xml", "2")])));
        assert!(!a.same_as(&cfg(&[("a.sumocfg", "1"), ("a.net.xml", "3")])));
        assert!(!a.same_as(&TrainingScenario::PaperMerge));
        assert!(TrainingScenario::PaperMerge.same_as(&TrainingScenario::PaperMerge));
    }

    /// The record's JSON names the scenario's kind, and reads back.
    #[test]
    fn the_record_round_trips_through_json() {
        let r = TrainedOn {
            step_length_s: 0.2,
            scenarios: vec![TrainingScenario::PaperMerge],
            episode_seeds: "10000-10499".into(),
            episodes: "500".into(),
            training_seed: "1".into(),
            commands: vec!["bkpbs collect".into()],
            sumo_version: "1.15.0".into(),
            bkpbs_version: NOT_RECORDED.into(),
            bkpbs_commit: NOT_RECORDED.into(),
        };
        let text = serde_json::to_string(&r).unwrap();
        assert!(
            text.contains(r#""scenarios":[{"kind":"paper-merge"}]"#),
            "{text}"
        );
        assert_eq!(serde_json::from_str::<TrainedOn>(&text).unwrap(), r);
        assert!(r.fits_step_length(0.2) && !r.fits_step_length(0.1));
    }
}
